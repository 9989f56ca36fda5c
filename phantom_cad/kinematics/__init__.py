"""Kinematics: topology (indices), closed-form equations, and the Hand model. numpy only."""

from .model import Hand
from .topology import JOINT_NAMES, Q_COLUMNS, SERVO_NAMES, U_COLUMNS

__all__ = ["Hand", "JOINT_NAMES", "SERVO_NAMES", "Q_COLUMNS", "U_COLUMNS"]
