"""Where the model meets the calibration effect library (phantom_cad.calibration.effects).

A parameter file may carry fitted effects (``[effects.<name>]``); the model applies them
in forward and inverse (``Hand.forward`` -> ``EffectStack.forward``, ``Hand.inverse`` ->
``EffectStack.inverse``). Without effects nothing is imported and ``Hand.effects`` is None,
so the plain path costs one truth test. An unknown effect or a bad effect parameter raises
ParamError (``effects.<name>.<key>``) when the Hand is built, i.e. in ``load_hand``.
"""

from __future__ import annotations


def resolve_effects(params):
    if not params.effects:
        return None
    from ..calibration.effects import build_effect_stack  # numpy only

    return build_effect_stack(params)
