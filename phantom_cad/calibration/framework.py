"""The effect framework: what an effect is and where the library keeps it (docs/effects.md).

An effect is a small, documented unit: a formula, parameters with physical bounds (:class:`Param`),
the residual signature it leaves (:class:`Signature`), and a reference. It acts on a
:class:`Context` at one of the pipeline's ``STAGES`` and may read the whole recording
(:class:`History`, its :class:`Runs`). :func:`register_effect` adds an :class:`Effect` subclass
to ``REGISTRY`` (the library's own effects in calibration/library.py, a user's in a plugin);
:func:`get_effect` looks one up by name. numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.topology import CHAINS, JOINTS, SERVOS
from ..params.errors import ParamError

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
    the measured signature (calibration/signature.py, :func:`~.signature.measured_features`):

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
        #: the routed statics per tendon chain (kinematics.statics.ChainStatics, servo order) a routed
        #: elasticity put in the model, and their compliance scale (5,); None: the paper's coupling
        self.routed = None
        self.routed_scale = None
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
    #: the effect puts the routed statics (kinematics/statics.py) in the model: it is part of the
    #: compensation (``Hand.forward(u, compensated=False)`` leaves it out), and a hand with it uses
    #: the routed servo law and coupling in its control law
    routed: bool = False
    #: the form of the tendon's stretch the effect models ("paper": eq. 13; "routed": the routing's
    #: statics), or None: diagnose keeps one form in a model (a candidate of the other form is
    #: scored in place of the selected one)
    stretch: str | None = None

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


def has_invert(eff: Effect) -> bool:
    """Whether the control law can undo the effect: servo- and joint-stage effects must override
    :meth:`Effect.invert` (or declare ``invertible``); reference and tension stages are inverted by
    the pipeline itself; a measurement-stage effect is never in the control law."""
    if eff.stage in ("reference", "tension", MEASUREMENT):
        return True
    return bool(eff.invertible) or type(eff).invert is not Effect.invert
