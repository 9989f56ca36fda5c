"""Where the model meets the calibration effect library (phantom_cad.calibration.effects).

A parameter file may carry fitted effects (``[effects.<name>]``); the model applies them
in forward and inverse. Without effects nothing is imported and nothing is applied.
"""

from __future__ import annotations


def resolve_effects(params):
    if not params.effects:
        return None
    from ..calibration.effects import build_effect_stack  # numpy/scipy only

    return build_effect_stack(params)
