"""The effect pipeline: servo angles ``u`` (N, 6) to joint angles ``q`` (N, 15) through the
effects' stages (docs/effects.md), and the fitted effects of a parameter file as the stack the
model applies (:class:`EffectStack`):

    servo      u_eff = f(u)                 e.g. tendon slack (dead band)
    reference  r_eff = r * radius_scale     e.g. pulley radius error; then s = cosine law (eq. 6, 8)
    tension    kappa = k_s / EA felt by the chain's elastic tendon segments
               (tendon elasticity, eq. 11-14; friction along the tendon path); or the routed
               statics at a fitted compliance scale (routed elasticity: s then from their servo law)
    coupling   q_chain = s * M(kappa)^-1 A  (eq. 13-14, per sample, closed form); with the routed
               statics, their coupling plus what kappa adds to A
    joint      q += delta                   e.g. joint zero offsets

The analytic model is the pipeline with no effect (kappa = 0). The paper's compensation
(``Hand(params, compensation="paper").forward(u, compensated=True)``) is the pipeline with kappa =
the parameter file's k_s / EA: fitted effects build on it (a calibrated hand's base), unless they
hold a routed elasticity, whose scale 1 is the plain hand's default, the routed compensation (a
calibrated hand's ``compensation`` is then "routed"). Parameters are held in *file units*
(the unit is in the key, as everywhere in a parameter file: ``u2_deg``, ``compliance_per_m``).
:func:`validate_effects` is the check of ``[effects.*]`` tables the params layer is handed
(:data:`PARAMS_EFFECTS`). numpy only.
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from dataclasses import replace

from ..kinematics.model import couple_routed, project_routed
from ..kinematics.statics import servo_angle
from ..kinematics.topology import CMC_SERVO, N_JOINTS, N_SERVOS, TENDON_SERVOS
from ..params.errors import ParamError
from ..params.schema import plugin_paths
from . import library as _library  # noqa: F401  (the built-in effects are registered before any name is looked up)
from .library import RoutedElasticity, RoutedElasticityPerFinger, routed_reference_angles
from .framework import MEASUREMENT, STAGES, Context, Effect, History, get_effect, has_invert
from .plugins import load_plugin

def run_pipeline(hand, items: Sequence[tuple[Effect, np.ndarray]], u, direction=None,
                 compliance: float = 0.0, history: History | None = None, rows=None) -> np.ndarray:
    """q (N, 15) for servo angles u (N, 6) with the effects ``items`` ((effect, x) pairs).

    ``compliance``: the base k_s / EA (0 = the analytic model); a ``tendon_elasticity`` item
    replaces it. ``direction`` (N, 6) of +1/-1/0, or None (unknown: friction is not applied).
    ``history``: the whole recording (:class:`History`) and ``rows`` the rows of it that ``u``
    holds (default: all, in order); None: unknown (backlash is not applied).
    """
    u = np.asarray(u, dtype=float)
    if history is not None and rows is None and len(history) != u.shape[0]:
        raise ValueError("run_pipeline: pass the rows of the history that u holds")
    ctx = Context(hand, u, direction, compliance, history, rows)
    # (stage, order, name): the result never depends on the order the effects were listed in
    items = sorted(items, key=lambda it: (STAGES.index(it[0].stage), it[0].order, it[0].name))
    stage_of = [it[0].stage for it in items]
    for eff, x in items:
        if eff.stage == "servo":
            eff.apply(ctx, x)
    for eff, x in items:
        if eff.stage == "reference":
            eff.apply(ctx, x)
    tension = [eff for eff, _ in items if eff.stage == "tension"]
    # a routed elasticity first in the tension stage puts its own reference angles in the context
    # without reading the cosine law's: they need not be computed
    if not (tension and isinstance(tension[0], (RoutedElasticity, RoutedElasticityPerFinger))):
        ctx.s = reference_angles(hand, ctx.u_eff, ctx.radius_scale)
    for eff, x in items:
        if eff.stage == "tension":
            eff.apply(ctx, x)
    ctx.q = couple(hand, ctx.s, ctx.compliance, ctx.routed)
    for stage in ("joint", MEASUREMENT):
        if stage in stage_of:
            for eff, x in items:
                if eff.stage == stage:
                    eff.apply(ctx, x)
    return ctx.q


def reference_angles(hand, u_eff: np.ndarray, radius_scale) -> np.ndarray:
    """Eq. (6)/(8) with the effective servo radius r * radius_scale; s6 = g u6 (the model's own
    cosine law, clipped to its domain)."""
    return hand.reference_angles(u_eff, hand.servo_radius * radius_scale)


def couple(hand, s: np.ndarray, compliance: np.ndarray, routed=None) -> np.ndarray:
    """q (N, 15) from s (N, 6) with the compliance each chain feels per sample (N, 5): eq. (13)/(14).
    ``routed``: the routed statics a routed elasticity put in the model (Context.routed), whose
    coupling then replaces the analytic one; what the paper's form adds with ``compliance`` (friction,
    a paper compliance fitted with it) is added to it."""
    q = hand.couple_compliant(s, compliance)
    if routed is not None:
        q += couple_routed(routed, s) - s @ hand.coupling_ideal
    return q


# ---------------------------------------------------------------------------
# effects read from a parameter file: the hook of Hand.forward / Hand.inverse
# ---------------------------------------------------------------------------

def effect_values(name: str, table: Mapping, hand=None, source: str | None = None) -> np.ndarray:
    """Check one ``[effects.<name>]`` table and return its parameter vector (missing keys are 0)."""
    base = f"effects.{name}"
    eff = get_effect(name, base, source)
    if not isinstance(table, Mapping):
        raise ParamError(base, table, "must be a table of parameter values", source)
    plist = eff.parameters(hand)
    keys = {p.key: k for k, p in enumerate(plist)}
    x = np.zeros(len(plist))
    for key, value in table.items():
        if key not in keys:
            raise ParamError(f"{base}.{key}", value,
                             f"unknown parameter of {name} (allowed: {', '.join(keys)})", source)
        p = plist[keys[key]]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ParamError(f"{base}.{key}", value, "must be a finite number", source)
        if not p.lower <= value <= p.upper:
            raise ParamError(f"{base}.{key}", value,
                             f"must lie in [{p.lower:g}, {p.upper:g}] (physical bounds: {p.doc})", source)
        x[keys[key]] = float(value)
    return x


def validate_effects(effects: Mapping, source: str | None = None) -> None:
    """Raise :class:`ParamError` naming the field if an ``[effects]`` table is not valid."""
    for name, table in effects.items():
        effect_values(name, table, None, source)


class EffectStack:
    """The fitted effects of a parameter file, applied by :class:`~phantom_cad.kinematics.model.Hand`.

    Semantics (docs/effects.md): every fitted effect applies to ``forward`` and ``inverse``; the
    ``compensated`` flag selects the spring/elasticity compensation, whose compliance is the fitted
    ``tendon_elasticity`` one when present (``fit`` always writes it, 0 when the data show none),
    else the [mechanics] k_s / EA; a fitted routed elasticity adds the routed statics at its scale
    (:attr:`compensation`). The direction of motion is unknown to ``Hand``: friction is left
    out (the control law aims at the middle of the hysteresis band). Measurement-stage effects (a
    camera's scale) describe the data, not the hand: ``forward`` applies them only with
    ``measured=True`` (to compare with measurements) and ``inverse`` never.
    """

    def __init__(self, params):
        self.params = params
        self.items: list[tuple[Effect, np.ndarray]] = []
        for name, table in params.effects.items():
            x = effect_values(name, table, None, params.source)
            self.items.append((get_effect(name), x))
        self.items.sort(key=lambda it: (STAGES.index(it[0].stage), it[0].order, it[0].name))
        self.names = tuple(e.name for e, _ in self.items)

    def __bool__(self) -> bool:
        return bool(self.items)

    @property
    def compensation(self) -> str:
        """"routed" when a fitted effect puts the routed statics in the model, else "paper"."""
        return "routed" if any(e.routed for e, _ in self.items) else "paper"

    def _items(self, compensated: bool, measured: bool = False):
        return [it for it in self.items if (compensated or not (it[0].name == "tendon_elasticity" or it[0].routed))
                and (measured or it[0].stage != MEASUREMENT)]

    def _base(self, hand, compensated: bool) -> float:
        m = hand.params.mechanics
        return m.spring_k / m.tendon_EA if compensated else 0.0

    def forward(self, hand, u, compensated: bool, direction=None, history: History | None = None,
                measured: bool = False) -> np.ndarray:
        """``direction`` and ``history`` (the recording ``u`` comes from, its rows in order) as in
        :func:`run_pipeline`; without them friction and backlash are left out. ``measured``: what
        the measurement reads (measurement-stage effects applied), not the hand's angles."""
        u = np.asarray(u, dtype=float)
        flat = u.reshape(-1, N_SERVOS)
        d = None if direction is None else np.broadcast_to(direction, u.shape).reshape(-1, N_SERVOS)
        q = run_pipeline(hand, self._items(compensated, measured), flat, d, self._base(hand, compensated), history)
        return q.reshape(u.shape[:-1] + (N_JOINTS,))

    def inverse(self, hand, q, compensated: bool) -> np.ndarray:
        """Control law with the effects: q (clipped) -> u. Joint- and servo-stage effects are inverted
        exactly, the radius and compliance enter the projection and the cosine law; friction is not
        applied (unknown direction)."""
        q = np.asarray(q, dtype=float)
        shape = q.shape
        q = q.reshape(-1, N_JOINTS)
        items = self._items(compensated)
        for eff, _ in items:
            if not has_invert(eff):
                raise ParamError(f"effects.{eff.name}", dict(self.params.effects.get(eff.name, {})),
                                 f"the {eff.stage}-stage effect '{eff.name}' has no invert(): the control law "
                                 "(Hand.inverse) cannot use it (docs/effects.md, 'The control law with effects')",
                                 self.params.source)
        for eff, x in reversed(items):
            if eff.stage == "joint":
                q = eff.invert(hand, q, x)
        # reference stage (effective radius), then the tension stage with unknown direction:
        # a constant compliance per chain, so each digit's reachable set is a line q = c s
        ctx = Context(hand, np.zeros((1, N_SERVOS)), None, self._base(hand, compensated))
        for eff, x in items:
            if eff.stage == "reference":
                eff.apply(ctx, x)
        radius = hand.servo_radius * ctx.radius_scale
        ctx.s = np.zeros((1, N_SERVOS))
        for eff, x in items:
            if eff.stage == "tension":
                eff.apply(ctx, x)
        # the travel's image in reference-angle space, with the effects of the servo and reference stages
        ends = Context(hand, np.vstack([hand.u_min, hand.u_max]), None, 0.0)
        for eff, x in items:
            if eff.stage == "servo":
                eff.apply(ends, x)
        if ctx.routed is None:
            s_ends = hand.reference_angles(ends.u_eff, radius)
            # project, clip, invert the cosine law with the effective radius, clip to the travel
            u = hand.control_law(q, hand.coupling_matrix(ctx.compliance[0]),
                                 (s_ends.min(axis=0), s_ends.max(axis=0)), radius)
        else:
            u = _routed_control_law(hand, ctx, q, routed_reference_angles(hand, ctx.routed, ends.u_eff,
                                                                          ctx.radius_scale))
        for eff, x in reversed(items):
            if eff.stage == "servo":
                u = eff.invert(hand, u, x)
        u = np.clip(u, hand.u_min, hand.u_max)
        return u.reshape(shape[:-1] + (N_SERVOS,))


def _routed_control_law(hand, ctx: Context, q: np.ndarray, s_ends: np.ndarray) -> np.ndarray:
    """u_eff (N, 6) for targets q (N, 15) on the routed statics a routed elasticity put in ``ctx``
    (forward: pipeline.couple): each digit's target projected onto its curve (the routed coupling
    plus what the paper's form adds with the context's compliance, constant per chain here), s
    clipped to the travel's image ``s_ends`` (2, 6), the routed servo law inverted with the
    effective radius, clipped to the travel."""
    ideal, extra = hand.coupling_vectors(0.0), hand.coupling_vectors(ctx.compliance[0])
    curves = [replace(c, c=c.c + (v - a)) for c, v, a in zip(ctx.routed, extra, ideal)]
    lo, hi = s_ends.min(axis=0), s_ends.max(axis=0)
    s = np.clip(project_routed(curves, q, lo, hi), lo, hi)
    u = np.empty(s.shape)
    for k, (chain, c) in enumerate(zip(hand.params.chains, ctx.routed)):
        u[:, k] = servo_angle(s[:, k], chain, c) / ctx.radius_scale[k]
    u[:, CMC_SERVO] = s[:, CMC_SERVO] / hand.params.thumb.cmc_gain
    return np.clip(u, hand.u_min, hand.u_max)


def build_effect_stack(params) -> EffectStack:
    """The stack ``phantom_cad.make_hand`` passes to the model when ``params.effects`` is non-empty.
    The plugins the file names are loaded first (parameters parsed without the effect library, as
    the export reads them, name effects only their plugins define)."""
    for i, path in enumerate(plugin_paths(params.plugins, params.source)):
        PARAMS_EFFECTS.load_plugin(path, f"plugins[{i}]", params.source)
    return EffectStack(params)


class ParamsEffects:
    """The effect library as the params layer is handed it (``params.schema.EffectLibrary``):
    ``phantom_cad.load_params``, ``load_hand`` and the CLI pass :data:`PARAMS_EFFECTS` to
    ``parse`` / ``load_params`` / ``dump_params``, so a file's plugins are loaded and its
    ``[effects.*]`` tables checked (the params layer never imports calibration)."""

    def load_plugin(self, path: str, field_name: str, source: str | None) -> None:
        load_plugin(path, f"{source}: {field_name}" if source else field_name)

    def check(self, effects: Mapping, source: str | None) -> None:
        validate_effects(effects, source)


PARAMS_EFFECTS = ParamsEffects()
