"""Kinematics: topology (records and indices), closed-form equations, frames and the Hand model.
numpy only; never imports the params layer (the model reads parameters by duck typing)."""

from .model import Hand
from .topology import JOINT_NAMES, Q_COLUMNS, SERVO_NAMES, U_COLUMNS

__all__ = ["Hand", "JOINT_NAMES", "SERVO_NAMES", "Q_COLUMNS", "U_COLUMNS"]
