"""The effect library's public face (docs/effects.md): one import for a user's script or plugin,

    from phantom_cad.calibration.effects import Effect, Param, Signature, register_effect

Its one job is to gather what the library's modules define, and importing it registers the
built-in effects:

    framework.py  Param, Signature, History, Runs, Context, Effect, the registry
                  (register_effect, get_effect, REGISTRY, ...)
    library.py    the built-in effects (tendon_slack, backlash, ..., camera_scale)
    pipeline.py   run_pipeline, EffectStack, effect_values, validate_effects, PARAMS_EFFECTS
    plugins.py    load_plugin, unload_plugin, PluginError
"""

from __future__ import annotations

from .framework import (ALL_JOINTS, CHAIN_SERVOS, JOINT_SERVO, MEASUREMENT, REGISTRY, SIGNATURE_FEATURES,
                        STAGES, Context, Effect, History, Param, Runs, Signature, get_effect, has_invert,
                        register_effect, unregister_effect)
from .library import (Backlash, CameraScale, DriveFriction, FrictionHysteresis, JointOffset, PulleyRadiusError,
                      TendonElasticity, TendonElasticityPerFinger, TendonSlack, apply_play, play, play_start)
from .pipeline import (PARAMS_EFFECTS, EffectStack, build_effect_stack, couple, effect_values, reference_angles,
                       run_pipeline, validate_effects)
from .plugins import PLUGINS, PluginError, load_plugin, unload_plugin

__all__ = [
    "ALL_JOINTS", "CHAIN_SERVOS", "JOINT_SERVO", "MEASUREMENT", "REGISTRY", "SIGNATURE_FEATURES", "STAGES",
    "Context", "Effect", "History", "Param", "Runs", "Signature", "get_effect", "has_invert", "register_effect",
    "unregister_effect",
    "Backlash", "CameraScale", "DriveFriction", "FrictionHysteresis", "JointOffset", "PulleyRadiusError",
    "TendonElasticity", "TendonElasticityPerFinger", "TendonSlack", "apply_play", "play", "play_start",
    "PARAMS_EFFECTS", "EffectStack", "build_effect_stack", "couple", "effect_values", "reference_angles",
    "run_pipeline", "validate_effects",
    "PLUGINS", "PluginError", "load_plugin", "unload_plugin",
]
