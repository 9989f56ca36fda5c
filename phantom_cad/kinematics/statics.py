"""The printed hand's statics: the routed compensation (docs/transmission.md).

Per tendon chain (joints 0..n-1, reference joint 0, pulley radii R_i, s = q_0), gravity and
contact loads aside:

* the return cord pulls with T = k_s sum R_i q_i (eq. 11);
* loop k (between joints k and k + 1) holds every joint beyond it: F_k = (n - 1 - k) T. Its give
  R_k q_k - R_{k+1} q_{k+1} is the stretch of its strands over their whole rest lengths, wraps
  included: unpreloaded only the taut strand a pulls, give = F_k L_a / EA; with a preload P both
  pull while F_k < P (1 + L_b / L_a), give = F_k / (EA (1/L_a + 1/L_b)), and beyond only a,
  give = (F_k - P) L_a / EA;
* the drive pulls with F_d = n T R_0 / arm, arm = d1 d2 sin(alpha - s) / L(s) its moment arm
  about the reference joint, and stretches by F_d L_d / EA: L(s) = L0 - r u + F_d L_d / EA.

The loops are linear in T within each regime (which loops have gone one-sided), so the joints
are piecewise affine in s, q = c s + d, with c the Sherman-Morrison form of
``closed_form.coupling_vector`` on the routed lever v_j = sum_{k<j} (n - 1 - k) L_k / R_j. The
servo angle of a reference angle is closed form (:func:`servo_angle`); the reference angle of a
servo angle is the root of a scalar equation, found by Newton steps from the cosine law
(:func:`reference_angle`, to convergence). :class:`RoutedLaw` is the same pair for all five
chains at once, at the speed a control loop needs: its forward starts each Newton solve from a
polynomial fit of the solution made when the hand is built, so one or two steps reach it
(checked then against :func:`reference_angle` on a fine grid of the travel). numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from types import SimpleNamespace

import numpy as np

from ..errors import ParamError
from . import closed_form as cf
from .hand_params import ChainParams, HandParams
from .memo import memoised
from .routing import routes
from .routing_paths import lengths
from .topology import CHAINS, N_JOINTS, joint

#: Newton's stopping step (rad) in :func:`reference_angle`: the error left after it is of the
#: order of its square, far below the 0.1 degree the twin is held to
TOLERANCE = 1e-12
#: Newton steps at most (from the cosine law the solve takes 3 to 4 over the travel)
MAX_STEPS = 20
#: degree of :class:`RoutedLaw`'s start: a Chebyshev fit of the solution's cosine-law argument
#: over the travel (about 1e-5 rad from the solution on the default hand)
START_DEGREE = 6
#: largest error (rad) :class:`RoutedLaw`'s forward may leave against :func:`reference_angle`
FAST_TOLERANCE = 1e-10


@dataclass(frozen=True)
class ChainStrands:
    """The rest lengths (m) of one chain's strands, from the routing model (q = 0, u = 0)."""

    drive: float
    #: per loop (reference side first): (the strand that pulls when the distal joint lags, its partner)
    loops: tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class ChainStatics:
    """One chain's routed statics, piecewise affine in the reference angle s: from ``s_from[m]``
    on, the joints are q = c[m] s + d[m] and the return cord pulls with T = t[m] s + t0[m]."""

    s_from: np.ndarray   # (M,), s_from[0] = -inf, ascending
    c: np.ndarray        # (M, n)
    d: np.ndarray        # (M, n), rad
    t: np.ndarray        # (M,), N/rad
    t0: np.ndarray       # (M,), N
    #: the drive's stretch per unit T L / sin(alpha - s): n R_0 L_d / (EA d1 d2) (1/N)
    gamma: float

    @cached_property
    def linear(self) -> bool:
        """One regime over s >= 0 through the origin (no preload): q = c s, T = t s (worked out
        once: every solve and coupling asks)."""
        return bool(np.all(self.s_from[1:] <= 0.0) and not self.d[-1].any() and self.t0[-1] == 0.0)

    def regime(self, s) -> np.ndarray:
        """The regime index of each reference angle."""
        return np.searchsorted(self.s_from, s, side="right") - 1

    def joints(self, s) -> np.ndarray:
        """q (..., n) of reference angles s (...): c s + d in each one's regime."""
        s = np.asarray(s, dtype=float)
        if self.linear:
            return s[..., None] * self.c[-1]
        m = self.regime(s)
        return s[..., None] * self.c[m] + self.d[m]


_STRANDS: dict = {}


def chain_strands(params: HandParams) -> tuple[ChainStrands, ...]:
    """Per tendon chain (servo order), its drive's and loops' rest lengths and which strand of
    each loop is taut under the return cord's load: the one that lengthens when the loop's
    proximal joint flexes alone. Memoised by the parameters' digest (read-only)."""
    return memoised(_STRANDS, (params.digest,), lambda: _chain_strands(params), cap=16)


def _chain_strands(params: HandParams) -> tuple[ChainStrands, ...]:
    used = [r for r in routes(params) if r.tendon.kind in ("drive", "coupling")]
    rest = lengths(params, which=used)
    out = []
    for spec in CHAINS:
        mine = [r for r in used if r.tendon.digit == spec.digit]
        drive = next(r for r in mine if r.tendon.kind == "drive")
        loops = sorted((r for r in mine if r.tendon.kind == "coupling"),
                       key=lambda r: spec.q_index.index(joint(r.tendon.joints[0]).index))
        pairs = []
        for r in loops:
            q = np.zeros(N_JOINTS)
            q[joint(r.tendon.joints[0]).index] = 0.1
            bent = lengths(params, q, which=[r])
            a, b = sorted(r.strands, key=lambda st: bent[st.name] - rest[st.name], reverse=True)
            pairs.append((rest[a.name], rest[b.name]))
        out.append(ChainStrands(rest[drive.strands[0].name], tuple(pairs)))
    return tuple(out)


def chain_statics(radii, strands: ChainStrands, d1: float, d2: float, spring_k: float, EA: float,
                  preload: float = 0.0) -> ChainStatics:
    """The regimes of one chain (:class:`ChainStatics`), worked out from the loops' break tensions."""
    R = np.asarray(radii, dtype=float)
    n = len(R)
    A = cf.ideal_coupling(R)
    gamma = n * R[0] * strands.drive / (EA * d1 * d2)
    if spring_k == 0.0 or n == 1:
        # no return load: the strands carry nothing
        return ChainStatics(np.array([-np.inf]), A[None], np.zeros((1, n)), np.zeros(1), np.zeros(1), gamma)
    La = np.array([a for a, _ in strands.loops])
    Lb = np.array([b for _, b in strands.loops])
    share = n - 1 - np.arange(n - 1)                  # loop k carries (n - 1 - k) T
    both = La * Lb / (La + Lb)                        # both strands pull: in parallel
    t_break = preload * (1.0 + Lb / La) / share      # T at which loop k's slack strand goes slack
    order = np.argsort(t_break, kind="stable")
    kappa = spring_k / EA
    RA = float(R @ A)
    s_from, cs, ds, ts, t0s = [-np.inf], [], [], [], []
    for m in range(n):
        broken = np.zeros(n - 1, bool)
        broken[order[:m]] = True
        lever_lengths = share * np.where(broken, La, both)
        v = cf.elastic_lever(R, lever_lengths)
        Rv = float(R @ v)
        # the broken loops' preload offset, P L_a / EA, carried along the chain as the lever is
        pv = cf.elastic_lever(R, np.where(broken, preload * La, 0.0))
        c = cf.coupling_vector(R, lever_lengths, kappa, constants=(A, v, RA, Rv))
        d = cf.coupling_vector(R, lever_lengths, kappa, constants=(pv, v, float(R @ pv), Rv)) / EA
        if m > 0:
            s_from.append((t_break[order[m - 1]] - t0s[-1]) / ts[-1])
        cs.append(c)
        ds.append(d)
        ts.append(spring_k * float(R @ c))
        t0s.append(spring_k * float(R @ d))
    return ChainStatics(np.array(s_from), np.array(cs), np.array(ds), np.array(ts), np.array(t0s), gamma)


def hand_statics(params: HandParams, scale=None, check: bool = True) -> tuple[ChainStatics, ...]:
    """:func:`chain_statics` of every tendon chain (servo order) with the file's k_s, EA and loop
    preload. ``scale``: per chain (5,), or one for all, the strands' compliance k_s / EA as a
    multiple of the file's (the strands of chain k have EA / scale[k]; 0: rigid strands), as a
    calibration fits it. ``check``: a ParamError naming EA when the strands' stretch takes back
    all of a coupled joint's motion in some regime (it would stand still or extend while its
    reference joint flexes)."""
    m = params.mechanics
    scales = np.broadcast_to(np.asarray(1.0 if scale is None else scale, dtype=float), (len(params.chains),))
    # a scale of 0 is rigid strands: EA infinite (every stretch term is then 0), as is one so
    # small that EA / scale overflows
    with np.errstate(over="ignore", divide="ignore"):
        ea = m.tendon_EA / scales
    out = tuple(chain_statics(c.radii, st, c.guide.d1, c.guide.d2, m.spring_k, e, m.loop_preload)
                for c, st, e in zip(params.chains, chain_strands(params), ea))
    if not check:
        return out
    # the smallest coupling of any coupled joint in any regime: the joint that goes first
    value, chain, k = min(((float(c.c[:, k].min()), chain, k) for chain, c in zip(params.chains, out)
                           for k in range(1, len(chain.radii))), key=lambda item: item[0])
    if not value > 0.0:
        raise ParamError("mechanics.tendon_EA_N", m.tendon_EA,
                         f"with spring_k_N_per_m = {m.spring_k:g} the strands' stretch (the routed statics) "
                         f"leaves {chain.digit} {chain.joints[k].upper()} a coupling of {value:.4g}: "
                         f"a coupled joint must flex with its {chain.joints[0].upper()}, so EA must be larger",
                         params.source)
    return out


def servo_angle(s, chain: ChainParams, statics: ChainStatics, T=None):
    """u of reference angle s: (L0 - L(s) + F_d(s) L_d / EA) / r, in closed form. ``T`` the
    return cord's tension at s, when known."""
    g = chain.guide
    if T is None:
        m = statics.regime(s)
        T = statics.t[m] * s + statics.t0[m]
    return cf.stretched_servo_angle(s, g.alpha, chain.servo_radius, statics.gamma * T,
                                    cf.chord_constants(g.d1, g.d2, g.alpha))


def reference_angle(u, chain: ChainParams, statics: ChainStatics, rate: bool = False):
    """s of servo angle u: the root of servo_angle(s) = u, by Newton steps from the cosine law
    (the uncompensated s, which the stretch only lowers) until a step is below :data:`TOLERANCE`.
    With ``rate`` also ds/du. Broadcasts over u."""
    u = np.asarray(u, dtype=float)
    s, dg = _solve([u.ravel()], [chain], [statics])
    s, dg = s.reshape(u.shape), dg.reshape(u.shape)
    if rate:
        return s[()], (chain.servo_radius / dg)[()]
    return s[()]


def reference_angles(us, chains, statics) -> list[np.ndarray]:
    """:func:`reference_angle` of several chains at once: ``us`` one 1-D array of servo angles per
    chain. The same Newton steps on every element, each chain stopping on its own steps (so each
    result is the one :func:`reference_angle` gives), run as one set of array operations: the
    per-call cost of numpy, not the arithmetic, is what a few hundred angles per chain cost."""
    keep = [k for k, u in enumerate(us) if len(u)]
    out = [np.zeros(0) for _ in us]
    if keep:
        s, _ = _solve([np.asarray(us[k], dtype=float) for k in keep], [chains[k] for k in keep],
                      [statics[k] for k in keep])
        bounds = np.cumsum([0] + [len(us[k]) for k in keep])
        for k, a, b in zip(keep, bounds[:-1], bounds[1:]):
            out[k] = s[a:b]
    return out


def _solve(us, chains, statics) -> tuple[np.ndarray, np.ndarray]:
    """(s, g') of the flat servo angles ``us`` (one 1-D array per chain) concatenated: Newton
    steps on g(s) = (L0 - r u) - L(s) + gamma T(s) L(s) / sin(alpha - s), each chain's constants
    spread over its elements, a chain's elements frozen once its largest step is below
    :data:`TOLERANCE`. g' is the one of each chain's last step."""
    sizes = [len(u) for u in us]
    starts = np.cumsum([0] + sizes[:-1])
    chain_of = np.repeat(np.arange(len(us)), sizes)
    u = np.concatenate(us) if len(us) > 1 else us[0]

    def spread(values):
        return np.asarray(values, dtype=float)[chain_of]

    g = [c.guide for c in chains]
    chord = [cf.chord_constants(x.d1, x.d2, x.alpha) for x in g]
    # each chain's constants are worked out on its scalars, as for one chain alone, then spread
    cosine = [cf.cosine_coefficients(x.d1, x.d2, x.alpha, c.servo_radius) for x, c in zip(g, chains)]
    alpha, d1d2 = spread([x.alpha for x in g]), spread([x.d1 * x.d2 for x in g])
    sumsq, two, L0 = (spread([c[i] for c in chord]) for i in range(3))
    r, gamma = spread([c.servo_radius for c in chains]), spread([c.gamma for c in statics])
    s = cf.reference_angle(u, spread([x.d1 for x in g]), spread([x.d2 for x in g]), alpha, r,
                           coefficients=tuple(spread([c[i] for c in cosine]) for i in range(3)))
    s = np.array(s, dtype=float, ndmin=1)
    target = L0 - r * u
    linear = [c.linear for c in statics]
    if all(linear):
        a, b = spread([c.t[-1] for c in statics]), 0.0
    else:
        a, b = np.empty(u.shape), np.empty(u.shape)
    active = np.ones(len(us), bool)
    moving = np.ones(u.shape, bool)
    dg_last = np.empty(u.shape)
    for _ in range(MAX_STEPS):
        if not all(linear):
            for k, (c, lin) in enumerate(zip(statics, linear)):
                part = slice(starts[k], starts[k] + sizes[k])
                if lin:
                    a[part], b[part] = c.t[-1], 0.0
                else:
                    m = c.regime(s[part])
                    a[part], b[part] = c.t[m], c.t0[m]
        phi = alpha - s
        x, S = np.cos(phi), np.sin(phi)
        L = np.sqrt(sumsq - two * x)
        T = a * s + b
        h = T * L / S
        dL = -d1d2 * S / L
        dg = -dL + gamma * ((a * L + T * dL) / S + h * x / S)
        step = (L - target - gamma * h) / dg
        np.add(s, step, out=s, where=moving)
        np.copyto(dg_last, dg, where=moving)
        largest = np.maximum.reduceat(np.abs(step), starts) if u.size else np.zeros(len(us))
        active &= largest > TOLERANCE
        if not active.any():
            break
        moving = active[chain_of]
    return s, dg_last


class RoutedLaw:
    """The routed servo laws of the five tendon chains at once (servo order): ``servo_angles``
    (s -> u, closed form) and ``reference_angles`` (u -> s). Arrays broadcast over leading
    batch axes, chain last ``(..., 5)``, or chain first ``(5, ...)`` with ``columns=True`` (the
    batched forward's layout).

    Without a loop preload (every chain :attr:`ChainStatics.linear`) both run vectorised over the
    chains: the forward evaluates the start's polynomial, one arccos and ``steps`` Newton steps
    (the fewest that stay within :data:`FAST_TOLERANCE` of :func:`reference_angle` over the
    travel); a servo angle outside the travel, where the fit does not hold, is solved by
    :func:`reference_angle`. With a preload, chain by chain with :func:`reference_angle`.
    """

    def __init__(self, chains, statics):
        self.chains, self.statics = tuple(chains), tuple(statics)
        self.linear = all(c.linear for c in self.statics)
        g = [c.guide for c in self.chains]
        d1, d2, alpha = (np.array([getattr(x, k) for x in g]) for k in ("d1", "d2", "alpha"))
        r = np.array([c.servo_radius for c in self.chains])
        lo = np.array([c.travel[0] for c in self.chains])
        hi = np.array([c.travel[1] for c in self.chains])
        sumsq, two, L0 = cf.chord_constants(d1, d2, alpha)
        gamma_t = np.array([c.gamma * c.t[-1] for c in self.statics])
        # the fit holds on the travel (a hair beyond: rounding of the ends)
        self._lo, self._hi = lo - 1e-12, hi + 1e-12
        self._row = SimpleNamespace(d1d2=d1 * d2, alpha=alpha, r=r, sumsq=sumsq, two=two, L0=L0, gamma_t=gamma_t,
                                    mid=(lo + hi) / 2.0, scale=2.0 / np.maximum(hi - lo, 1e-300),
                                    lo=self._lo, hi=self._hi)
        self.steps = 0
        if not self.linear:
            return
        # the start: x(u) = cos(alpha - s(u)) fitted over the travel at Chebyshev nodes, a
        # polynomial in u whose constant is cos(alpha): at u = 0 the solve gives s = 0 exactly
        nodes = np.cos(np.pi * (np.arange(64) + 0.5) / 64)
        coef = np.empty((START_DEGREE + 1, len(self.chains)))
        coef[0] = np.cos(alpha)
        for k, (chain, c) in enumerate(zip(self.chains, self.statics)):
            u = self._row.mid[k] + nodes / self._row.scale[k]
            x = np.cos(alpha[k] - reference_angle(u, chain, c))
            basis = u[:, None] ** np.arange(1, START_DEGREE + 1)
            coef[1:, k] = np.linalg.lstsq(basis, x - coef[0, k], rcond=None)[0]
        self._row.coef = coef
        self._col = SimpleNamespace(**{k: (v[..., None] if isinstance(v, np.ndarray) else v)
                                       for k, v in vars(self._row).items()})
        grid = lo + np.linspace(0.0, 1.0, 1025)[:, None] * (hi - lo)
        exact = np.stack([reference_angle(grid[:, k], chain, c)
                          for k, (chain, c) in enumerate(zip(self.chains, self.statics))], axis=-1)
        start = sum(c * grid ** i for i, c in enumerate(coef))
        if not np.all(np.abs(start) < 1.0):
            return                      # no fast path (the start leaves the arccos's domain)
        for steps in range(1, 5):
            self.steps = steps
            if np.abs(self._fast(grid, self._row)[0] - exact).max() <= FAST_TOLERANCE:
                return
        self.steps = 0                  # no fast path: every solve to convergence

    def servo_angles(self, s: np.ndarray, columns: bool = False) -> np.ndarray:
        """u (..., 5) of reference angles s (..., 5): (L0 - L(s) + F_d(s) L_d / EA) / r."""
        if not self.linear:
            return self._per_chain(servo_angle, s, columns)
        k = self._col if columns else self._row
        return cf.stretched_servo_angle(s, k.alpha, k.r, k.gamma_t * s, (k.sumsq, k.two, k.L0))

    def reference_angles(self, u: np.ndarray, columns: bool = False, out: np.ndarray | None = None,
                         work=None) -> np.ndarray:
        """s (..., 5) of servo angles u (..., 5) (see the class; ``work``: eight arrays of u's
        shape the solve may use)."""
        if not self.steps:
            s = self._per_chain(reference_angle, u, columns)
        else:
            k = self._col if columns else self._row
            s, beyond = self._fast(u, k, out, work, columns)
            if beyond:
                outside = (u < k.lo) | (u > k.hi)
                s[outside] = self._per_chain(reference_angle, u, columns)[outside]
        if out is not None and s is not out:
            out[...] = s
            return out
        return s

    def _per_chain(self, fn, x, columns):
        out = np.empty(np.shape(x))
        for k, (chain, c) in enumerate(zip(self.chains, self.statics)):
            if columns:
                out[k] = fn(x[k], chain, c)
            else:
                out[..., k] = fn(x[..., k], chain, c)
        return out

    def _fast(self, u, k, out=None, work=None, columns=False):
        """(s, whether some u lies beyond its travel, where the fit does not hold): Newton steps
        from the fitted start (no preload: T = t s), in place on ``out`` and the eight arrays of
        ``work`` (each of u's shape; allocated when not given): a batched forward passes the same
        ones for every block, which then stay in the CPU cache (a fresh array costs more in page
        faults than the arithmetic on it)."""
        L, target, x, S, a, b, c, w2 = (np.empty(u.shape) for _ in range(8)) if work is None else work
        s = np.empty(u.shape) if out is None else out
        np.copyto(w2, u)                 # contiguous (a batched forward's u is a transposed view)
        u = w2
        axes = tuple(range(1, u.ndim)) if columns else tuple(range(u.ndim - 1))
        beyond = bool(u.size) and bool(np.any(u.min(axis=axes) < self._lo) or np.any(u.max(axis=axes) > self._hi))
        np.multiply(k.r, u, out=target)
        np.subtract(k.L0, target, out=target)                # L0 - r u
        np.multiply(u, k.coef[-1], out=x)
        for coef in k.coef[-2:0:-1]:
            x += coef
            x *= u
        x += k.coef[0]
        # within the travel the fit stays inside the cosine law's domain (checked when built)
        np.arccos(x, out=s)
        np.subtract(k.alpha, s, out=s)
        np.multiply(x, x, out=S)
        np.subtract(1.0, S, out=S)
        np.sqrt(S, out=S)                                    # sin(alpha - s)
        for i in range(self.steps):
            if i:   # (x, S) = (cos, sin)(alpha - s) after s moved by -c: second order is exact here
                np.multiply(c, c, out=a)
                a *= -0.5
                a += 1.0                                     # cos(c)
                np.multiply(S, c, out=b)
                S *= a
                np.multiply(x, c, out=L)
                S += L
                x *= a
                x -= b
            np.multiply(k.two, x, out=L)
            np.subtract(k.sumsq, L, out=L)
            np.sqrt(L, out=L)                                # the chord L
            # g = (L0 - r u) - L + h, h = gamma t s L / S (the drive's stretch); with
            # dL/ds = -d1 d2 S / L: g' = gamma t L / S + h x / S + d1 d2 (S - gamma t s) / L
            np.divide(L, S, out=a)
            np.multiply(k.gamma_t, s, out=w2)                # gamma t s
            np.multiply(w2, a, out=b)                        # h
            a *= k.gamma_t
            np.multiply(b, x, out=c)
            c /= S
            a += c
            np.subtract(S, w2, out=c)
            c *= k.d1d2
            c /= L
            a += c                                           # g'
            np.subtract(target, L, out=c)
            c += b                                           # g
            c /= a
            s -= c
        return s, beyond
