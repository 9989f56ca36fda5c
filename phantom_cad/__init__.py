"""phantom_cad: the open, parametric source of the PHANTOM Hand.

    from phantom_cad import load_hand
    hand = load_hand()                      # params/phantom.toml
    q = hand.forward(u, compensated=True)   # (..., 6) rad -> (..., 15) rad, the printed routing's statics
    u = hand.inverse(q_d)                   # (..., 15) rad -> (..., 6) rad
    paper = load_hand(compensation="paper") # the paper's eq. (11)-(14) instead

This module is where the layers meet (docs/architecture.md): it loads the parameters with the
effect library handed to the params layer (which checks a file's [effects.*] tables and loads its
plugins), builds the library's stack for a calibrated file and hands both to the model. Importing it imports
numpy only; CAD (OCP) is imported by the commands that build geometry.
"""

from __future__ import annotations

import os

from .calibration.pipeline import PARAMS_EFFECTS, build_effect_stack
from .kinematics.model import Hand
from .params import HandParams, ParamError
from .params import load_params as _load_params

__version__ = "0.1.0"


def make_hand(params: HandParams, compensation: str | None = None) -> Hand:
    """The kinematic model of validated parameters, with the fitted effects they carry (if any).
    ``compensation``: "routed" (the printed routing's statics, the default without fitted effects)
    or "paper" (eq. 11-14, the base of fitted effects)."""
    return Hand(params, build_effect_stack(params) if params.effects else None, compensation)


def load_params(path: str | os.PathLike | None = None) -> HandParams:
    """Read and validate a parameter file (default: params/phantom.toml), its plugins and
    ``[effects.*]`` tables included (checked by the calibration layer's effect library)."""
    return _load_params(path, effects=PARAMS_EFFECTS)


def load_hand(path: str | os.PathLike | None = None, compensation: str | None = None) -> Hand:
    """The kinematic model of the hand described by ``path`` (default: params/phantom.toml);
    ``compensation`` as for :func:`make_hand`."""
    return make_hand(load_params(path), compensation)


__all__ = ["load_hand", "load_params", "make_hand", "Hand", "HandParams", "ParamError", "__version__"]
