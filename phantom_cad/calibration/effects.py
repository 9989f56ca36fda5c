"""The library of physical effects the paper's analytic model leaves out (docs/effects.md).

An effect is a small, documented unit: a formula, parameters with physical bounds, the
residual signature it leaves, and a reference. Effects plug into one pipeline that turns
servo angles ``u`` (N, 6) into joint angles ``q`` (N, 15), stage by stage:

    servo      u_eff = f(u)                 e.g. tendon slack (dead band)
    reference  r_eff = r * radius_scale     e.g. pulley radius error; then s = cosine law (eq. 6, 8)
    tension    kappa = k_s / EA felt by the chain's elastic tendon segments
               (tendon elasticity, eq. 11-14; friction along the tendon path)
    coupling   q_chain = s * M(kappa)^-1 A  (eq. 13-14, per sample, closed form)
    joint      q += delta                   e.g. joint zero offsets

The analytic model is the pipeline with no effect (kappa = 0). ``Hand.forward(u, compensated=True)``
is the pipeline with kappa = the parameter file's k_s / EA. Parameters are held in *file units*
(the unit is in the key, as everywhere in a parameter file: ``u2_deg``, ``compliance_per_m``).

Add your own effect with :func:`register_effect` (see docs/effects.md). numpy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ..kinematics.topology import (CHAINS, CMC_SERVO, DISTAL_JOINTS, JOINTS, N_JOINTS, N_SERVOS, SERVOS,
                                   TENDON_SERVOS, servo_joints)
from ..params.errors import ParamError
from ..params.schema import register_effect_check, register_plugin_loader
from ..units import DEG

STAGES = ("servo", "reference", "tension", "joint", "measurement")
#: the stage of effects that describe the measurement (a camera's scale), not the hand: fitted with
#: the others, never applied by Hand.forward / Hand.inverse (the control law aims at true angles)
MEASUREMENT = "measurement"

#: servo of every joint (0-based), the CMC's is the direct-drive servo
JOINT_SERVO = np.array([j.servo for j in JOINTS])
ALL_JOINTS = tuple(j.index for j in JOINTS)
#: the servos that pull a tendon chain (u1..u5)
CHAIN_SERVOS = tuple(s for s in SERVOS if s.drive == "tendon")


@dataclass(frozen=True)
class Param:
    """One parameter of an effect, in file units.

    ``key``: the key in ``[effects.<name>]`` (unit in the name). ``lower``/``upper``: physical
    bounds (a parameter file outside them is refused). ``typical``: the magnitude range a real
    hand shows (``simulate`` draws from it; with ``signed`` the sign is random too).
    ``joints``: q indices the parameter can move (for identifiability and the fit's sparsity).
    ``moving``: the parameter shows only when the servo of those joints moves.
    """

    key: str
    lower: float
    upper: float
    typical: tuple[float, float]
    signed: bool = False
    joints: tuple[int, ...] = ALL_JOINTS
    moving: bool = True
    doc: str = ""


#: the values of each feature of a :class:`Signature` ("any": the effect does not fix it)
SIGNATURE_FEATURES = {
    "direction": ("flips", "same", "any"),
    "at_rest": ("zero", "nonzero", "any"),
    "trend": ("grows", "flat", "any"),
    "joints": ("all", "distal", "mcp", "any"),
    "periodic": (True, False),
    "reversal": ("jump", "none", "any"),
    "digits": ("all", "some", "one", "any"),
}


@dataclass(frozen=True)
class Signature:
    """The residual an effect leaves when the model lacks it, feature by feature, in the words of
    the measured signature (calibration/residual.py, :func:`~.residual.measured_features`):

    ``direction``  "flips": the residual changes sign with the direction of motion (a band between
                   the flexing and the extending branch); "same": no direction dependence.
    ``at_rest``    "zero": the residual vanishes at the start of the travel; "nonzero": it is there.
    ``trend``      of the residual's main part (the band's width for a flipping effect, else the
                   residual itself) along the servo angle: "grows" (with servo angle and spring
                   tension: the upper half of the travel carries more than twice the lower half's)
                   or "flat".
    ``joints``     "all": MCP (thumb MP, CMC) and distal joints alike; "distal": PIP, DIP, thumb
                   IP and not the MCP; "mcp": the MCP alone.
    ``periodic``   a periodic pattern in the servo angle.
    ``reversal``   "jump": the residual steps within a few samples after each reversal of the
                   servo; "none": it passes through reversals continuously.
    ``digits``     the spread across the tendon-driven digits measured: "all" (on every one: an
                   effect of the whole hand), "some", "one" (a per-digit effect on some of them).
    Any feature may be "any" (the effect does not fix it)."""

    direction: str = "any"
    at_rest: str = "any"
    trend: str = "any"
    joints: str = "any"
    periodic: bool = False
    reversal: str = "any"
    digits: str = "any"

    def __post_init__(self):
        for key, allowed in SIGNATURE_FEATURES.items():
            if getattr(self, key) not in allowed:
                raise ValueError(f"Signature.{key} = {getattr(self, key)!r}: must be one of {allowed}")

    def to_json(self) -> dict:
        return {k: getattr(self, k) for k in SIGNATURE_FEATURES}


@dataclass(frozen=True)
class Runs:
    """One servo's runs of rows with one direction of motion within one sweep (a new run at every
    reversal and at every new sweep), over a :class:`History`: ``of_row`` (R,) the run of every
    row; per run, in row order: ``direction`` (+1/-1/0), ``first`` (the sweep's first run),
    ``u_start`` and ``u_end`` (the command at its first and last row), ``last`` (its last row).
    Within a run the command is monotone (flat steps hold the direction)."""

    of_row: np.ndarray
    direction: np.ndarray
    first: np.ndarray
    u_start: np.ndarray
    u_end: np.ndarray
    #: the history row of each run's last command
    last: np.ndarray


class History:
    """The whole recording in row order, for effects whose output depends on what came before
    (backlash after a reversal): the commanded servo angles ``u`` (R, 6) of every row of the file,
    the sweep code of every row ``sweep`` (R,) (rows of one sweep are one continuous motion, in row
    order; sweeps are independent) and the direction of motion ``direction`` (R, 6).

    The pipeline may run on any subset of the rows (a fold, a block of rows, every k-th row):
    ``Context.rows`` says which rows of the history the batch holds, so a history-dependent effect
    takes its state from the whole history (:meth:`runs`, computed once) and evaluates the batch's
    rows only. :meth:`cached` keeps a few small results per key."""

    def __init__(self, u, sweep, direction):
        self.u = np.asarray(u, dtype=float)
        self.sweep = np.asarray(sweep)
        self.direction = np.asarray(direction)
        self._runs: dict[int, Runs] = {}
        self._cache: dict = {}

    @classmethod
    def of(cls, m) -> "History":
        """The history of a :class:`~.data.Measurements`."""
        return cls(m.u, m.sweep, m.direction)

    def __len__(self) -> int:
        return len(self.u)

    def runs(self, servo: int) -> Runs:
        """The runs of one servo (0-based), computed once."""
        if servo not in self._runs:
            d = self.direction[:, servo]
            n = len(d)
            start = np.ones(n, dtype=bool)
            if n > 1:
                start[1:] = (d[1:] != d[:-1]) | (self.sweep[1:] != self.sweep[:-1])
            new_sweep = np.ones(n, dtype=bool)
            if n > 1:
                new_sweep[1:] = self.sweep[1:] != self.sweep[:-1]
            first_rows = np.flatnonzero(start)
            last_rows = np.append(first_rows[1:] - 1, n - 1)
            self._runs[servo] = Runs(np.cumsum(start) - 1, d[first_rows].astype(int), new_sweep[first_rows],
                                     self.u[first_rows, servo], self.u[last_rows, servo], last_rows)
        return self._runs[servo]

    def cached(self, key, compute):
        """compute(), kept under ``key``; the least recently used of 64 entries goes first."""
        if key in self._cache:
            self._cache[key] = self._cache.pop(key)
        else:
            if len(self._cache) >= 64:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = compute()
        return self._cache[key]


class Context:
    """What the pipeline carries from stage to stage (all arrays batch-first)."""

    def __init__(self, hand, u: np.ndarray, direction: np.ndarray | None, compliance: float,
                 history: History | None = None, rows: np.ndarray | None = None):
        n = u.shape[0]
        self.hand = hand
        self.params = hand.params
        self.u = u                                  # commanded servo angles (N, 6), rad
        #: +1 flexing, -1 extending, 0 unknown, per row and servo (N, 6); None = unknown everywhere
        self.direction = direction
        #: the whole recording (History) and which of its rows this batch holds (N,); None = unknown
        #: (Hand.forward, the control law): history-dependent effects then do nothing
        self.history = history
        self.rows = None if history is None else (np.arange(n) if rows is None else np.asarray(rows))
        #: the sweep code of every row of the batch (N,), or None
        self.sweep = None if history is None else history.sweep[self.rows]
        self.u_eff = u.copy()                       # servo stage output
        #: the plays on the drive applied so far ((key, half width function, servos), see apply_play)
        #: and what their one combined play adds to u_eff (N, 6)
        self.plays: list = []
        self.play_delta = np.zeros_like(self.u_eff)
        self.radius_scale = np.ones(len(CHAINS))    # reference stage: r_eff = r * radius_scale
        self.s: np.ndarray | None = None            # reference angles (N, 6), after the reference stage
        #: k_s / EA (1/m) felt by each chain's elastic segments (N, chains); 0 = analytic model
        self.compliance = np.full((n, len(CHAINS)), float(compliance))
        #: the base k_s / EA the pipeline started from (tendon_elasticity replaces it, and only it)
        self.compliance_base = float(compliance)
        #: the tendon's compliance k_s / EA (1/m) that converts a tension change into a deviation
        mech = hand.params.mechanics
        self.compliance_ref = mech.spring_k / mech.tendon_EA
        self.q: np.ndarray | None = None            # joint angles (N, 15), after the coupling

    @property
    def n(self) -> int:
        return self.u.shape[0]


class Effect:
    """Base class of an effect. Subclasses set the class attributes and implement :meth:`apply`.

    ``stage`` is one of ``STAGES``; ``order`` sorts effects within a stage. ``explanation`` is the
    one-line physical reading of the residual the effect explains (printed in reports).
    A ``measurement``-stage effect describes the sensor, not the hand (a camera's scale error): it
    is applied last, to what the measurement would read, and never by ``Hand.forward`` or the
    control law. For the control law (``Hand.inverse``), servo- and joint-stage effects implement
    :meth:`invert` (reference- and tension-stage effects are inverted by the pipeline itself,
    tension-stage ones as a compliance per chain that does not depend on the pose); ``fit``
    refuses an effect without it and ``Hand.inverse`` raises on one (ParamError).
    """

    name: str = ""
    stage: str = "joint"
    order: int = 50
    explanation: str = ""
    formula: str = ""
    signature: str = ""
    reference: str = ""
    #: the residual the effect leaves, feature by feature (:class:`Signature`); None: not declared
    leaves: Signature | None = None
    #: depends on the direction of motion (needs a sweep to be identified)
    directional: bool = False
    #: the effect this one is a variant of (more parameters, same physics): diagnose prefers it
    #: whenever the variant's extra parameters do not pay
    simpler: str | None = None

    def parameters(self, hand) -> list[Param]:
        raise NotImplementedError

    def apply(self, ctx: Context, x: np.ndarray) -> None:
        """Modify ``ctx`` in place with parameter values ``x`` (file units, order of parameters())."""
        raise NotImplementedError

    def invert(self, hand, value: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Servo stage: commanded u from u_eff; joint stage: model q from a target q."""
        return value

    invertible = False


REGISTRY: dict[str, Effect] = {}


def register_effect(cls):
    """Class decorator: add an :class:`Effect` subclass to the library under ``cls.name``."""
    eff = cls()
    if not eff.name or not eff.name.isidentifier():
        raise ValueError(f"effect name {eff.name!r} must be a Python identifier")
    if eff.stage not in STAGES:
        raise ValueError(f"effect {eff.name}: stage {eff.stage!r} is not one of {STAGES}")
    REGISTRY[eff.name] = eff
    return cls


def unregister_effect(name: str) -> None:
    REGISTRY.pop(name, None)


def get_effect(name: str, field_name: str | None = None, source: str | None = None) -> Effect:
    try:
        return REGISTRY[name]
    except KeyError:
        raise ParamError(field_name or "effects", name,
                         f"unknown effect (known: {', '.join(REGISTRY)})", source) from None


# ---------------------------------------------------------------------------
# the built-in effects
# ---------------------------------------------------------------------------

@register_effect
class TendonSlack(Effect):
    name = "tendon_slack"
    stage = "servo"
    order = 10
    explanation = ("joints lag by a constant servo angle from the start of travel, the same in both "
                   "directions, and stay at rest for the first degrees: slack in the tendon (a dead band "
                   "before it pulls)")
    formula = "u_eff = u_min + max(u - u_min - delta_j, 0) for the tendon servos u1..u5"
    signature = ("zero in a band at the start of travel, then a lag of about delta_j * dq/du on every joint "
                 "of the chain (MCP included); independent of the direction")
    reference = "dead-zone / backlash models of cable drives, e.g. Kaneko et al., IEEE T-RA 7(3), 1991"
    leaves = Signature(direction="same", at_rest="zero", trend="flat", joints="all", reversal="none")

    def parameters(self, hand):
        return [Param(f"{sv.label}_deg", 0.0, 15.0, (1.0, 4.0), False, servo_joints(sv.index), True,
                      f"dead band of servo {sv.label} before its tendon pulls, degrees")
                for sv in CHAIN_SERVOS]

    def apply(self, ctx, x):
        lo = ctx.hand.u_min[TENDON_SERVOS]
        d = x * DEG
        ctx.u_eff[:, TENDON_SERVOS] = lo + np.maximum(ctx.u_eff[:, TENDON_SERVOS] - lo - d, 0.0)

    invertible = True

    def invert(self, hand, u_eff, x):
        u = u_eff.copy()
        u[..., TENDON_SERVOS] = u_eff[..., TENDON_SERVOS] + x * DEG
        return u


@register_effect
class PulleyRadiusError(Effect):
    name = "pulley_radius_error"
    stage = "reference"
    order = 20
    explanation = ("every joint of the chain, MCP included, drifts in proportion to the servo angle, the same "
                   "in both directions: the servo pulley's effective radius differs from nominal")
    formula = "r_eff,j = r_j (1 + e_j) in eq. (5)-(6): L = L0 - r_eff u"
    signature = ("grows with u (about e_j * u * dq/du), on the MCP as much as on PIP/DIP; zero at rest; "
                 "independent of the direction")
    reference = "eq. (5)-(6) of the paper; effective radius = pulley radius + half the tendon diameter"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="all", reversal="none")

    def parameters(self, hand):
        return [Param(f"{sv.label}_relative", -0.2, 0.2, (0.015, 0.04), True, servo_joints(sv.index), True,
                      f"relative error of servo {sv.label}'s effective pulley radius")
                for sv in CHAIN_SERVOS]

    def apply(self, ctx, x):
        ctx.radius_scale = ctx.radius_scale * (1.0 + x)


@register_effect
class TendonElasticity(Effect):
    name = "tendon_elasticity"
    stage = "tension"
    order = 30
    explanation = ("distal joints (PIP, DIP, thumb IP) lag in proportion to flexion, the MCP does not, the same "
                   "in both directions: the return spring's tension stretches the tendon (eq. 11-14)")
    formula = ("T = k_s sum_i R_i q_i, b_j = T l_j / (EA R_j); M q = A q_MCP with C_j = (k_s/EA) l_j / R_j; "
               "fitted: the compliance ratio c = k_s / EA (1/m), one for the whole hand")
    signature = "negative on PIP/DIP/IP, growing with flexion, zero on MCP/MP/CMC; no direction dependence"
    reference = "the paper's mechanics-based compensation, eq. (11)-(14)"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="distal", reversal="none",
                       digits="all")

    def parameters(self, hand):
        return [Param("compliance_per_m", 0.0, 5.0, (0.07, 0.27), False, DISTAL_JOINTS, True,
                      "k_s / EA: spring rate over tendon axial stiffness, 1/m (only the ratio is identifiable)")]

    def apply(self, ctx, x):
        # replaces the base k_s / EA and only it: what other tension-stage effects added (before
        # or after this one) stays
        ctx.compliance += x[0] - ctx.compliance_base
        ctx.compliance_base = float(x[0])
        # `fit` writes compliance 0 when the data showed no elasticity: the base compensation is
        # then off, but the tendon's stiffness that friction stretches stays the [mechanics] one,
        # as it was when friction was fitted without this effect
        if x[0] > 0.0:
            ctx.compliance_ref = float(x[0])


@register_effect
class TendonElasticityPerFinger(Effect):
    name = "tendon_elasticity_per_finger"
    stage = "tension"
    order = 31
    simpler = "tendon_elasticity"
    explanation = ("distal joints lag in proportion to flexion, the MCP does not, by a different amount on each "
                   "finger: each tendon (or its return spring) has its own compliance (eq. 11-14 per finger)")
    formula = "C_j = c_k l_j / R_j for chain k: the compliance ratio k_s / EA fitted per finger (5 values)"
    signature = ("negative on PIP/DIP/IP, growing with flexion, zero on MCP/MP/CMC, its size different from "
                 "finger to finger; no direction dependence")
    reference = "the paper's mechanics-based compensation, eq. (11)-(14), one compliance per tendon"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="distal", reversal="none")

    def parameters(self, hand):
        return [Param(f"{c.digit}_per_m", 0.0, 5.0, (0.07, 0.27), False, c.q_index[1:], True,
                      f"k_s / EA of the {c.digit} tendon, 1/m") for c in CHAINS]

    def apply(self, ctx, x):
        # replaces the base k_s / EA (or tendon_elasticity's, which runs before) chain by chain
        ctx.compliance += x - ctx.compliance_base
        ctx.compliance_base = 0.0
        ctx.compliance_ref = np.where(x > 0.0, x, ctx.compliance_ref)


@register_effect
class FrictionHysteresis(Effect):
    name = "friction_hysteresis"
    stage = "tension"
    #: after both elasticity effects: the capstan term stretches the tendon whose compliance they set
    order = 35
    directional = True
    explanation = ("residual flips sign with the direction of motion and grows with tension: friction in the "
                   "tendon path (capstan)")
    formula = ("capstan: the elastic segments carry T exp(d mu Theta), Theta = sum of the chain's joint angles "
               "(the tendon's wrap on the joint pulleys), d = +1 flexing / -1 extending; the extra stretch "
               "T (exp(d mu Theta) - 1) l_j / (EA R_j) enters eq. (13) as a compliance k_s/EA (exp(d mu Theta) - 1)")
    signature = ("PIP/DIP/IP lag when flexing and lead when extending (a hysteresis loop), the gap grows with "
                 "flexion; MCP untouched; zero when the direction is unknown")
    reference = "capstan equation T2 = T1 exp(mu theta) (Euler-Eytelwein); Kaneko et al., IEEE T-RA 7(3), 1991"
    leaves = Signature(direction="flips", at_rest="zero", trend="grows", joints="distal", reversal="jump",
                       digits="all")

    def parameters(self, hand):
        return [Param("mu", 0.0, 1.0, (0.08, 0.25), False, DISTAL_JOINTS, True,
                      "friction coefficient of the tendon on its pulleys and guides")]

    def apply(self, ctx, x):
        if ctx.direction is None or x[0] == 0.0:
            return
        if ctx.s is None:
            raise RuntimeError("friction_hysteresis needs the reference angles")
        # Theta = s * sum(A): the sum of the chain's joint angles, the tendon's wrap on its pulleys
        theta = ctx.s[:, TENDON_SERVOS] * ctx.hand.coupling_ideal.sum(axis=1)[TENDON_SERVOS]
        f = np.exp(ctx.direction[:, TENDON_SERVOS] * x[0] * theta)
        ctx.compliance += ctx.compliance_ref * (f - 1.0)


@register_effect
class JointOffset(Effect):
    name = "joint_offset"
    stage = "joint"
    order = 90
    explanation = ("a constant per joint, present at rest and in both directions: a zero offset "
                   "(assembly or the measurement's reference)")
    formula = "q_i = q_model,i + o_i"
    signature = "constant per joint over the whole sweep, nonzero at rest, independent of direction and servo"
    reference = "standard zero-offset calibration of joint encoders (e.g. Hollerbach & Wampler 1996)"
    leaves = Signature(direction="same", at_rest="nonzero", trend="flat", joints="any", reversal="none")

    def parameters(self, hand):
        return [Param(f"{j.label}_deg", -10.0, 10.0, (0.5, 2.0), True, (j.index,), False,
                      f"zero offset of joint {j.label}, degrees") for j in JOINTS]

    def apply(self, ctx, x):
        ctx.q += x * DEG

    invertible = True

    def invert(self, hand, q, x):
        return q - x * DEG


def play_start(runs: Runs, half) -> np.ndarray:
    """The output of the play (backlash) operator of half width ``half`` when each run starts: a
    sweep starts with the output at the command; a run flexing ends at max(y0, u_end - half), one
    extending at min(y0, u_end + half) (the command is monotone within a run). ``half``: one value,
    or one per run (the half width at the run's last command, for a play whose width follows the
    command: drive_friction)."""
    y0 = np.empty(runs.direction.size)
    halves = np.broadcast_to(np.asarray(half, dtype=float), runs.direction.shape)
    y = 0.0
    for i, (d, first, us, ue, h) in enumerate(zip(runs.direction, runs.first, runs.u_start, runs.u_end, halves)):
        y = us if first else y
        y0[i] = y
        if d > 0:
            y = max(y, ue - h)
        elif d < 0:
            y = min(y, ue + h)
    return y0


def play(u: np.ndarray, rows: np.ndarray, runs: Runs, half, y0: np.ndarray) -> np.ndarray:
    """The play operator's output at ``rows`` of the history (their commands ``u``): within a run
    flexing max(y0, u - half), extending min(y0, u + half), at rest y0. ``half``: one value or one
    per row (u - half must not fall as u grows: a width that grows by less than the command)."""
    r = runs.of_row[rows]
    d, start = runs.direction[r], y0[r]
    return np.where(d > 0, np.maximum(start, u - half),
                    np.where(d < 0, np.minimum(start, u + half), np.clip(start, u - half, u + half)))


def apply_play(ctx: Context, key, half_width, servos) -> None:
    """Add a play (a dead band at each reversal) to the drive of ``servos`` (0-based indices or a
    slice): its half width in rad ``half_width(rows)`` (len(rows), 6) at rows of the history (one
    value per servo, from the command there; 0 on the other servos). ``key`` names the play and its
    parameters (the cache of the run starts). Plays in series (the servo gear's backlash, then the
    drive tendon's friction band) act as one play of the summed width: after a reversal the output stands still until the
    command has crossed both bands, then trails it by both halves. So the servo stage keeps one play,
    of every width added so far: its contribution to u_eff (``ctx.play_delta``) is replaced, what
    other servo-stage effects did stays (exact for constant widths; a width that follows the
    command is taken at the command). The output at the start of each run comes from the whole
    history (play_start), computed once per set of plays."""
    h = ctx.history
    ctx.plays.append((key, half_width, frozenset(int(j) for j in np.arange(N_SERVOS)[servos])))
    keys = tuple(k for k, _, _ in ctx.plays)

    def total(rows):
        return sum(f(rows) for _, f, _ in ctx.plays)

    half_rows = total(ctx.rows)
    delta = np.zeros_like(ctx.u_eff)
    for j in sorted(set().union(*(sv for _, _, sv in ctx.plays))):
        runs = h.runs(j)
        y0 = h.cached(("play", keys, j), lambda runs=runs, j=j: play_start(runs, total(runs.last)[:, j]))
        delta[:, j] = play(ctx.u[:, j], ctx.rows, runs, half_rows[:, j], y0) - ctx.u[:, j]
    ctx.u_eff = ctx.u_eff - ctx.play_delta + delta
    ctx.play_delta = delta


@register_effect
class CameraScale(Effect):
    name = "camera_scale"
    stage = MEASUREMENT
    order = 10
    explanation = ("one joint's measured angle is a fixed multiple of the model's, in both directions and "
                   "zero at rest: a scale error of the measurement (camera calibration, marker placement), "
                   "not of the hand; never used by the control law")
    formula = "q_measured,i = (1 + k_i) q_i"
    signature = "proportional to the joint angle on one joint, zero at rest, independent of direction"
    reference = "scale calibration of vision-based joint measurement (e.g. Hollerbach & Wampler 1996)"
    leaves = Signature(direction="same", at_rest="zero", trend="grows", joints="any", reversal="none")

    def parameters(self, hand):
        return [Param(f"{j.label}_relative", -0.2, 0.2, (0.01, 0.04), True, (j.index,), True,
                      f"scale error of the measurement of joint {j.label}, relative") for j in JOINTS]

    def apply(self, ctx, x):
        ctx.q *= 1.0 + x


@register_effect
class Backlash(Effect):
    name = "backlash"
    stage = "servo"
    #: first: the play is in the servo's drive, ahead of the tendon's slack (slack(play(u)))
    order = 5
    directional = True
    explanation = ("after each reversal the joints stay still while the servo turns through a dead band, then "
                   "follow it lagging by half the band, on every joint of the chain: backlash (play) in the drive")
    formula = ("play operator per servo within each sweep, full width b_j: u_eff,k = min(max(u_eff,k-1, u_k - b/2), "
               "u_k + b/2), u_eff = u at the start of a sweep")
    signature = ("a band of about b_j * dq/du between the flexing and the extending branch, the same width over "
                 "the travel, on every joint of the chain (MCP included); after each reversal the residual ramps "
                 "across the band within b_j of servo travel; zero when the history is unknown")
    reference = "play / backlash operator (Krasnosel'skii & Pokrovskii 1989; Tao & Kokotovic, Automatica 1993)"
    leaves = Signature(direction="flips", at_rest="any", trend="flat", joints="all", reversal="jump")

    def parameters(self, hand):
        return [Param(f"{sv.label}_deg", 0.0, 10.0, (1.0, 3.5), False, servo_joints(sv.index), True,
                      f"full width of the play of servo {sv.label}'s drive, degrees") for sv in SERVOS]

    def apply(self, ctx, x):
        if ctx.history is None or not np.any(x):
            return
        half = 0.5 * np.asarray(x, dtype=float) * DEG
        apply_play(ctx, ("backlash", tuple(half)), lambda rows: np.broadcast_to(half, (len(rows), N_SERVOS)),
                   np.flatnonzero(half > 0))

    #: the control law does not know the direction of the next move: it aims at the middle of the
    #: play (u = u_eff), as it aims at the middle of the friction band
    invertible = True


@register_effect
class DriveFriction(Effect):
    name = "drive_friction"
    stage = "servo"
    #: after the drive's play (5), before the tendon's slack (10): the friction acts along the
    #: drive tendon between the servo pulley and the finger
    order = 7
    directional = True
    explanation = ("every joint of the chain, MCP included, lags when flexing and leads when extending by a "
                   "band already there at rest and wider as the spring's tension grows, and stands still for "
                   "the band's width after each reversal: friction along the drive tendon's path (guides, "
                   "palm channels), loaded by the return spring's pre-tension and tension")
    formula = ("a play of full width w(u) on each tendon servo's command, within each sweep: flexing "
               "u_eff = max(u_eff,prev, u - w/2), extending min(u_eff,prev, u + w/2), u_eff = u at the start "
               "of a sweep; w(u) = w_rest + w_growth (s - s_min) / (s_max - s_min), s = eq. (6)'s MCP "
               "reference angle, to which the spring's tension (eq. 11, T = k_s sum R_i q_i) is proportional; "
               "in series with backlash the two plays act as one of the summed width")
    signature = ("a band between the flexing and the extending branch on every joint of the chain (MCP "
                 "included), present where the travel starts back (at rest) and widening with flexion; after "
                 "each reversal the joints stand still through the band; the same width law on every digit")
    reference = ("Coulomb friction in series with an elastic tendon is a play (Prandtl's elastic-plastic "
                 "element; Krasnosel'skii & Pokrovskii 1989); tension-proportional friction in tendon-sheath "
                 "and guide paths: Kaneko et al., IEEE T-RA 7(3), 1991")
    leaves = Signature(direction="flips", at_rest="any", trend="any", joints="all", reversal="jump",
                       digits="all")

    def parameters(self, hand):
        servos = tuple(j for sv in CHAIN_SERVOS for j in servo_joints(sv.index))
        return [Param("width_at_rest_deg", 0.0, 10.0, (0.8, 2.0), False, servos, True,
                      "full width of the friction band at rest (the spring's pre-tension), servo degrees"),
                Param("width_growth_deg", 0.0, 10.0, (0.8, 2.0), False, servos, True,
                      "what the band's full width gains from rest to full flexion (the spring's tension), "
                      "servo degrees")]

    @staticmethod
    def tension(hand, u) -> np.ndarray:
        """(s - s_min) / (s_max - s_min) at commands u (..., 6): the spring's tension from rest (0) to
        full flexion (1), s = eq. (6)'s reference angle (0 on the CMC's direct drive)."""
        s = hand.reference_angles(np.asarray(u, dtype=float), hand.servo_radius)
        out = np.zeros(np.shape(u))
        span = hand.s_max - hand.s_min
        out[..., TENDON_SERVOS] = ((s - hand.s_min) / np.where(span > 0, span, 1.0))[..., TENDON_SERVOS]
        return out

    @staticmethod
    def band(tension, x) -> np.ndarray:
        """w / 2 in rad, per servo (0 on the CMC's direct drive), at the tensions of :meth:`tension`."""
        out = 0.5 * (x[0] + x[1] * tension) * DEG
        out[..., CMC_SERVO] = 0.0
        return out

    def apply(self, ctx, x):
        if ctx.history is None or not np.any(x):
            return
        h, hand, x = ctx.history, ctx.hand, np.asarray(x, dtype=float)
        # the tension at every row of the recording does not depend on x: computed once
        t = h.cached(("drive_friction tension",), lambda: self.tension(hand, h.u))
        apply_play(ctx, ("drive_friction", tuple(x)), lambda rows: self.band(t[rows], x), TENDON_SERVOS)

    #: the control law aims at the middle of the band (u = u_eff), as for backlash and friction
    invertible = True


# ---------------------------------------------------------------------------
# the pipeline
# ---------------------------------------------------------------------------

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
    ctx.s = reference_angles(hand, ctx.u_eff, ctx.radius_scale)
    for eff, x in items:
        if eff.stage == "tension":
            eff.apply(ctx, x)
    ctx.q = couple(hand, ctx.s, ctx.compliance)
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


def couple(hand, s: np.ndarray, compliance: np.ndarray) -> np.ndarray:
    """q (N, 15) from s (N, 6) with the compliance each chain feels per sample (N, 5): eq. (13)/(14)."""
    return hand.couple(s, hand.coupling_vectors(compliance))


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
    else the [mechanics] k_s / EA. The direction of motion is unknown to ``Hand``: friction is left
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

    def _items(self, compensated: bool, measured: bool = False):
        return [it for it in self.items if (compensated or it[0].name != "tendon_elasticity")
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
        s_ends = hand.reference_angles(ends.u_eff, radius)
        # project, clip, invert the cosine law with the effective radius, clip to the travel
        u = hand.control_law(q, hand.coupling_matrix(ctx.compliance[0]),
                             (s_ends.min(axis=0), s_ends.max(axis=0)), radius)
        for eff, x in reversed(items):
            if eff.stage == "servo":
                u = eff.invert(hand, u, x)
        u = np.clip(u, hand.u_min, hand.u_max)
        return u.reshape(shape[:-1] + (N_SERVOS,))


def build_effect_stack(params) -> EffectStack:
    """The stack ``phantom_cad.load_hand`` passes to the model when ``params.effects`` is non-empty."""
    return EffectStack(params)


register_effect_check(validate_effects)


# ---------------------------------------------------------------------------
# a user's effects in a plugin file (--plugin FILE.py, or `plugins = [...]` in a parameter file)
# ---------------------------------------------------------------------------

#: resolved plugin path -> the effect names it registered (a file is executed once per process)
PLUGINS: dict[str, tuple[str, ...]] = {}


class PluginError(ParamError):
    """A plugin file that cannot be loaded: names the file, the line and the rule."""

    def __init__(self, path: str, rule: str, where: str | None = None):
        self.field, self.value, self.rule, self.source = where or "--plugin", path, rule, None
        ValueError.__init__(self, f"{where + ': ' if where else ''}plugin {path}: {rule}")


def load_plugin(path, where: str | None = None) -> tuple[str, ...]:
    """Execute the Python file ``path`` once; return the names of the effects it registered.

    Refused (PluginError, naming the file and the line): a missing file, a syntax error, an
    exception while it runs (an import error included), no effect registered, or an effect whose
    name is already taken by the library or another plugin."""
    import hashlib
    import importlib.util
    import os
    import sys
    import traceback

    path = os.path.abspath(os.fspath(path))
    if path in PLUGINS:
        return PLUGINS[path]

    def fail(rule: str):
        return PluginError(path, rule, where)

    if not os.path.isfile(path):
        raise fail("no such file" if not os.path.exists(path) else "is not a file")
    if not path.endswith(".py"):
        raise fail("a plugin must be a Python file (.py)")
    module_name = "phantom_cad_plugin_" + hashlib.sha256(path.encode()).hexdigest()[:12]
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    before = dict(REGISTRY)
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        _restore(before)
        raise fail(f"line {exc.lineno}: syntax error: {exc.msg}") from None
    except Exception as exc:
        _restore(before)
        frames = [f for f in traceback.extract_tb(exc.__traceback__) if os.path.abspath(f.filename) == path]
        line = f"line {frames[-1].lineno}: " if frames else ""
        raise fail(f"{line}{type(exc).__name__}: {exc}") from None
    new = tuple(n for n, e in REGISTRY.items() if before.get(n) is not e)
    taken = [n for n in new if n in before]
    if taken:
        _restore(before)
        raise fail(f"effect '{taken[0]}' is already defined (by the library or another plugin); give yours "
                   "another name")
    if not new:
        raise fail("registers no effect (decorate an Effect subclass with @register_effect)")
    sys.modules[module_name] = module
    PLUGINS[path] = new
    return new


def _restore(before: dict) -> None:
    REGISTRY.clear()
    REGISTRY.update(before)


def unload_plugin(path) -> None:
    """Forget a plugin and unregister its effects (tests)."""
    import os

    for name in PLUGINS.pop(os.path.abspath(os.fspath(path)), ()):
        unregister_effect(name)


def has_invert(eff: Effect) -> bool:
    """Whether the control law can undo the effect: servo- and joint-stage effects must override
    :meth:`Effect.invert` (or declare ``invertible``); reference and tension stages are inverted by
    the pipeline itself; a measurement-stage effect is never in the control law."""
    if eff.stage in ("reference", "tension", MEASUREMENT):
        return True
    return bool(eff.invertible) or type(eff).invert is not Effect.invert


def _load_listed_plugin(path: str, field_name: str, source: str | None) -> None:
    load_plugin(path, f"{source}: {field_name}" if source else field_name)


register_plugin_loader(_load_listed_plugin)
