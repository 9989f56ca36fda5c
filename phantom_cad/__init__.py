"""phantom_cad: the open, parametric source of the PHANTOM Hand.

    from phantom_cad import load_hand
    hand = load_hand()                      # params/phantom.toml
    q = hand.forward(u, compensated=True)   # (..., 6) rad -> (..., 15) rad
    u = hand.inverse(q_d)                   # (..., 15) rad -> (..., 6) rad

Importing this package imports numpy only; CAD (OCP) is imported by the commands
that build geometry.
"""

from __future__ import annotations

import os

from .kinematics.model import Hand
from .params import HandParams, ParamError, load_params

__version__ = "0.1.0"


def load_hand(path: str | os.PathLike | None = None) -> Hand:
    """The kinematic model of the hand described by ``path`` (default: params/phantom.toml)."""
    return Hand(load_params(path))


__all__ = ["load_hand", "load_params", "Hand", "HandParams", "ParamError", "__version__"]
