"""Fit effect parameters to measurements (scipy.optimize.least_squares) and predict with them.

A :class:`Model` is the analytic model plus a list of effects; only the parameters the data
can identify are free (a joint that was never measured, a servo that never moved: fixed at 0).
Residuals are measured - model in degrees over every measured cell. Parameter uncertainties come
from the Jacobian at the solution, cov = (J^T J)^-1 * RSS / (m - p), inflated by m / n_eff because
the residuals within a sweep are correlated (see :func:`effective_size`); a parameter in a
combination the data cannot separate (:mod:`.identify`) has none (NaN: not identifiable).
"""

from __future__ import annotations

import contextlib
import functools

from dataclasses import dataclass, field

import numpy as np

from scipy.optimize import least_squares

from ..units import DEG_PER_RAD
from .data import Measurements
from .framework import JOINT_SERVO, Effect, History, Param, get_effect
from .pipeline import run_pipeline
from .identify import not_identifiable


#: the loss of every fit: "linear" (least squares) unless inside robust_loss()
_LOSS = {"loss": "linear", "f_scale": 1.0}


@contextlib.contextmanager
def robust_loss(f_scale_deg: float):
    """Context: fits use scipy's soft_l1 loss with scale ``f_scale_deg`` (residuals well beyond it
    count about linearly, not squared), and the sums of squares that score models (RSS, held-out)
    are the same robust cost, f^2 sum 2 (sqrt(1 + (r/f)^2) - 1) (= r^2 for small r)."""
    old = dict(_LOSS)
    _LOSS.update(loss="soft_l1", f_scale=float(f_scale_deg))
    try:
        yield
    finally:
        _LOSS.clear()
        _LOSS.update(old)


def robust_active() -> bool:
    """True inside robust_loss()."""
    return _LOSS["loss"] != "linear"


def cost(r: np.ndarray) -> float:
    """Sum of squares, or the robust cost inside robust_loss()."""
    if _LOSS["loss"] == "linear":
        return float(r @ r)
    f = _LOSS["f_scale"]
    return float(f * f * np.sum(2.0 * (np.sqrt(1.0 + (r / f) ** 2) - 1.0)))


def single_threaded_blas():
    """Context: BLAS on one thread. The fits multiply small matrices thousands of times; a
    multithreaded BLAS spends more in waking and (on a loaded 2-core machine) fighting for cores
    than in arithmetic: measured 18 s instead of 2 s for bench_diagnose's largest case under load."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # optional at run time: only slower
        return contextlib.nullcontext()
    return threadpool_limits(limits=1, user_api="blas")


class Problem:
    """Data prepared for fitting: rows, measured cells, directions."""

    def __init__(self, hand, m: Measurements, rows: np.ndarray | None = None, all_directions=None,
                 history: History | None = None):
        self.hand = hand
        self.data = m
        # the direction of motion of every row of the file, computed once (subsets share it)
        self.all_directions = m.direction if all_directions is None else all_directions
        #: the whole recording in row order (history-dependent effects), shared by subsets
        self.history = History(m.u, m.sweep, self.all_directions) if history is None else history
        if rows is None:            # every row: views, no copies (a 1,000,000-row file is 200 MB)
            self.rows = np.arange(len(m))
            self.u, self.direction, self.q, self.sweep = m.u, self.all_directions, m.q, m.sweep
        else:
            self.rows = rows = np.asarray(rows)
            self.u, self.direction, self.q = m.u[rows], self.all_directions[rows], m.q[rows]
            self.sweep = m.sweep[rows]
        self.mask = np.isfinite(self.q)
        self.r_idx, self.j_idx = np.nonzero(self.mask)
        self.meas = self.q[self.mask]

    @functools.cached_property
    def lag_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """(a, b): the cells (indices into a residual of this problem) of every pair of one joint on
        consecutive rows of one sweep, b the later one; computed once (every fit's n_eff and the
        verdict's whiteness read them)."""
        order = np.lexsort((self.r_idx, self.j_idx))
        r, j = self.r_idx[order], self.j_idx[order]
        pair = (j[1:] == j[:-1]) & (r[1:] == r[:-1] + 1) & (self.sweep[r[1:]] == self.sweep[r[:-1]])
        return order[:-1][pair], order[1:][pair]

    def subset(self, rows) -> "Problem":
        return Problem(self.hand, self.data, self.rows[np.asarray(rows)], self.all_directions, self.history)

    @property
    def m(self) -> int:
        return self.meas.size


class Model:
    """The analytic model plus effects, with the data-identifiable parameters free.

    ``only``: {effect name: joint indices}: that effect's parameters are free only where one of
    their joints is among them (the rest held at 0), e.g. a camera's scales on the joints a hand
    effect cannot move. ``key`` names the model (its effects, and the restriction if any)."""

    def __init__(self, hand, names, problem: Problem, only: dict | None = None):
        self.hand = hand
        self.names = tuple(names)
        self.only = tuple(sorted((n, tuple(sorted(int(j) for j in js))) for n, js in (only or {}).items()))
        self.key = (self.names, self.only) if self.only else self.names
        self.effects: list[Effect] = [get_effect(n) for n in self.names]
        self.plists: list[list[Param]] = [e.parameters(hand) for e in self.effects]
        allowed = dict(self.only)
        self.active = [np.array([identifiable(p, problem) and (n not in allowed or bool(set(p.joints) & set(allowed[n])))
                                 for p in pl], dtype=bool) for n, pl in zip(self.names, self.plists)]
        self.free: list[tuple[int, int, Param]] = [
            (k, i, p) for k, pl in enumerate(self.plists) for i, p in enumerate(pl) if self.active[k][i]]
        self.lower = np.array([p.lower for _, _, p in self.free])
        self.upper = np.array([p.upper for _, _, p in self.free])

    @property
    def p(self) -> int:
        return len(self.free)

    def items(self, theta):
        xs = [np.zeros(len(pl)) for pl in self.plists]
        for (k, i, _), v in zip(self.free, theta):
            xs[k][i] = v
        return list(zip(self.effects, xs))

    def predict(self, theta, u, direction, history: History | None = None, rows=None) -> np.ndarray:
        """q for commands ``u`` (N, 6); ``history`` and ``rows`` as in run_pipeline."""
        return run_pipeline(self.hand, self.items(theta), u, direction, 0.0, history, rows)

    def predict_measurements(self, theta, m: Measurements) -> np.ndarray:
        """q for every row of ``m``, with its directions and history."""
        return self.predict(theta, m.u, m.direction, History.of(m))

    def values(self, theta) -> dict[str, dict[str, float]]:
        """{effect: {key: value}} of the free parameters (file units)."""
        out: dict[str, dict[str, float]] = {n: {} for n in self.names}
        for (k, _, p), v in zip(self.free, theta):
            out[self.names[k]][p.key] = float(v)
        return out

    def start(self, previous: "FitResult | None" = None) -> np.ndarray:
        x0 = np.clip(np.zeros(self.p), self.lower, self.upper)
        if previous is not None:
            old = {(previous.model.names[k], p.key): v for (k, _, p), v in zip(previous.model.free, previous.theta)}
            for n, (k, _, p) in enumerate(self.free):
                x0[n] = old.get((self.names[k], p.key), x0[n])
        return x0


def identifiable(p: Param, problem: Problem) -> bool:
    """A parameter is free when one of its joints was measured (while its servo moved, if it needs motion)."""
    for j in p.joints:
        rows = problem.mask[:, j]
        if not rows.any():
            continue
        if not p.moving:
            return True
        uj = problem.u[rows, JOINT_SERVO[j]]
        if np.ptp(uj) > 1e-9:
            return True
    return False


@dataclass
class FitResult:
    model: Model
    theta: np.ndarray
    std: np.ndarray
    residual: np.ndarray          # degrees, over the problem's measured cells
    problem: Problem
    rss: float = field(init=False)
    n_eff: float = field(init=False)
    #: J^T J at the solution (free parameters, degrees^2 per file unit^2), when computed
    jtj: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        self.rss = cost(self.residual)
        self.n_eff = effective_size(self.problem, self.residual)

    @property
    def m(self) -> int:
        return self.residual.size

    def values(self):
        return self.model.values(self.theta)

    def uncertainties(self):
        return self.model.values(self.std)


def effective_size(problem: Problem, residual: np.ndarray) -> float:
    """Effective number of independent residuals, n_eff = m (1 - rho) / (1 + rho).

    rho is the lag-1 autocorrelation of the residuals along the rows of each sweep, pooled over
    sweeps and joints (an AR(1) reading of the correlation a smooth unmodelled error leaves),
    clipped to [0, 0.95].
    """
    m = residual.size
    if m < 3:
        return float(m)
    a, b = problem.lag_pairs
    den = float(residual @ residual)
    if den <= 0 or not a.size:
        return float(m)
    rho = float(np.sum(residual[a] * residual[b])) / den
    rho = min(max(rho, 0.0), 0.95)
    return m * (1.0 - rho) / (1.0 + rho)


#: rows predicted at once: the effects' intermediates stay small on a 1,000,000-row file
PREDICT_ROWS = 65536


def _chunks(problem: Problem):
    """(rows a:b, their measured cells ca:cb in the residual) in blocks of PREDICT_ROWS rows."""
    n = len(problem.rows)
    bounds = list(range(0, n, PREDICT_ROWS)) + [n]
    # where each chunk's measured cells start in the residual (cells are in row-major order)
    cells = np.concatenate([[0], np.cumsum(problem.mask.sum(axis=1))])[bounds]
    return list(zip(bounds[:-1], bounds[1:], cells[:-1], cells[1:]))


def _chunk_residual(model: Model, problem: Problem, theta, a, b, ca, cb) -> np.ndarray:
    q = model.predict(theta, problem.u[a:b], problem.direction[a:b], problem.history, problem.rows[a:b])
    return (problem.meas[ca:cb] - q[problem.mask[a:b]]) * DEG_PER_RAD


def _residual_fn(model: Model, problem: Problem):
    chunks = _chunks(problem)

    def fun(theta):
        out = np.empty(problem.m)
        for a, b, ca, cb in chunks:
            out[ca:cb] = _chunk_residual(model, problem, theta, a, b, ca, cb)
        return out
    return fun


def _groups(model: Model) -> list[list[int]]:
    """Free parameters in structurally orthogonal groups: no two in a group move a common joint,
    so one forward difference gives every column of a group (Curtis-Powell-Reid)."""
    groups: list[tuple[list[int], set[int]]] = []
    for k, (_, _, par) in enumerate(model.free):
        joints = set(par.joints)
        for members, used in groups:
            if not used & joints:
                members.append(k)
                used |= joints
                break
        else:
            groups.append(([k], set(joints)))
    return [members for members, _ in groups]


def _forward_step(x, lo, hi) -> np.ndarray:
    """scipy's "2-point" step: sqrt(eps) max(1, |x|) with the sign of x (+ at 0), turned back
    where it would leave the bounds."""
    h = np.sqrt(np.finfo(float).eps) * np.where(x >= 0, 1.0, -1.0) * np.maximum(1.0, np.abs(x))
    return np.where((x + h > hi) | (x + h < lo), -h, h)


def _parameter_cells(model: Model, j_idx) -> list[np.ndarray]:
    """Per free parameter: the indices of the cells (of joints ``j_idx``) it moves (indices, not a
    mask: each Jacobian fills its columns with them)."""
    return [np.flatnonzero(np.isin(j_idx, par.joints)) for _, _, par in model.free]


def _forward_difference(model: Model, groups, x, r0, evaluate, cells) -> np.ndarray:
    """The (r0.size, p) forward-difference Jacobian at ``x`` of ``evaluate`` (theta -> the residual
    r0 is at x): one evaluation per group of :func:`_groups`, each parameter's column filled on its
    ``cells`` (:func:`_parameter_cells`)."""
    h = _forward_step(x, model.lower, model.upper)
    J = np.zeros((r0.size, model.p))
    for members in groups:
        step = np.zeros(model.p)
        step[members] = h[members]
        diff = evaluate(x + step) - r0
        for k in members:
            J[cells[k], k] = diff[cells[k]] / h[k]
    return J


def _grouped_jacobian(model: Model, problem: Problem, fun):
    """(fun, jac) for least_squares: a dense forward-difference Jacobian, one evaluation per group
    of :func:`_groups` (a dozen groups for forty parameters); the residual at x is the one
    least_squares has just evaluated there, remembered, not computed again."""
    groups = _groups(model)
    cells = _parameter_cells(model, problem.j_idx)
    last: dict = {}

    def f(x):
        r = fun(x)
        last["x"], last["r"] = x.copy(), r
        return r

    def jac(x):
        r0 = last["r"] if "x" in last and np.array_equal(last["x"], x) else fun(x)
        return _forward_difference(model, groups, x, r0, fun, cells)
    return f, jac


def fit(model: Model, problem: Problem, x0=None, uncertainty: bool = True) -> FitResult:
    """Least-squares fit of the model's free parameters (trust region reflective, physical bounds).

    The Jacobian is scipy's forward difference taken for a group of parameters that share no
    joint at a time (:func:`_grouped_jacobian`) and kept dense, so the trust-region steps are
    exact (an SVD of the m x p Jacobian, p <= ~40). scipy's own sparse path (jac_sparsity, lsmr)
    spent more in building sparse matrices than in the model (docs/performance.md)."""
    fun = _residual_fn(model, problem)
    if model.p == 0:
        r = fun(np.zeros(0))
        return FitResult(model, np.zeros(0), np.zeros(0), r, problem)
    x0 = model.start() if x0 is None else np.clip(x0, model.lower, model.upper)
    width = model.upper - model.lower
    eps = 1e-9 * width
    x0 = np.minimum(np.maximum(x0, model.lower + eps), model.upper - eps)
    f, jac = _grouped_jacobian(model, problem, fun)
    kw = dict(jac=jac, bounds=(model.lower, model.upper), method="trf", x_scale="jac", tr_solver="exact",
              xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200)
    if _LOSS["loss"] != "linear":
        kw.update(loss=_LOSS["loss"], f_scale=_LOSS["f_scale"])
    res = least_squares(f, x0, **kw)
    r = res.fun
    if uncertainty:
        J = np.asarray(res.jac)
        return _result(model, problem, res.x, r, J.T @ J)
    return FitResult(model, res.x, np.full(model.p, np.nan), r, problem)


def _result(model: Model, problem: Problem, theta, r, JTJ) -> FitResult:
    """The fit at ``theta`` with the uncertainties of the module docstring."""
    dof = max(r.size - model.p, 1)
    s2 = float(r @ r) / dof
    out = FitResult(model, theta, np.full(model.p, np.nan), r, problem, jtj=JTJ)
    inflate = r.size / max(out.n_eff, 1.0)
    cov = np.linalg.pinv(JTJ) * s2 * inflate
    out.std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    # a parameter in a combination the data cannot see has no finite uncertainty (calibration/identify.py)
    out.std[not_identifiable(out)] = np.nan
    return out


def fit_streamed(model: Model, problem: Problem, x0=None, max_iter: int = 50) -> FitResult:
    """:func:`fit` in bounded memory, for problems of millions of cells: Levenberg-Marquardt on
    the normal equations, J^T J and J^T r summed over blocks of PREDICT_ROWS rows, so that no
    m x p Jacobian is ever held (scipy's least_squares holds several: about 600 MB for 2.5 M cells).

    The Jacobian is the forward difference of :func:`fit` (:func:`_forward_step`, one evaluation
    per group of :func:`_groups`). A step that leaves the bounds is clipped to them; the fit stops
    when the linearized model promises a decrease of the sum of squares below 1e-10 of it."""
    if model.p == 0:
        return fit(model, problem, x0)
    lo, hi = model.lower, model.upper
    theta = model.start() if x0 is None else np.clip(x0, lo, hi)
    chunks = _chunks(problem)
    groups = _groups(model)

    def sse(x) -> float:
        return float(sum(np.sum(_chunk_residual(model, problem, x, *c) ** 2) for c in chunks))

    def normal_equations(x):
        """J^T J, J^T r and r at x."""
        JTJ, g, r = np.zeros((model.p, model.p)), np.zeros(model.p), np.empty(problem.m)
        for a, b, ca, cb in chunks:
            r0 = r[ca:cb] = _chunk_residual(model, problem, x, a, b, ca, cb)
            J = _forward_difference(model, groups, x, r0,
                                    lambda t: _chunk_residual(model, problem, t, a, b, ca, cb),
                                    _parameter_cells(model, problem.j_idx[ca:cb]))
            JTJ += J.T @ J
            g += J.T @ r0
        return JTJ, g, r

    JTJ, g, r = normal_equations(theta)
    rss = float(r @ r)
    lam = 1e-3
    for _ in range(max_iter):
        d = np.diag(JTJ).copy()
        d[d <= 0] = 1.0
        try:
            delta = np.linalg.solve(JTJ + lam * np.diag(d), -g)
        except np.linalg.LinAlgError:
            delta = -np.linalg.pinv(JTJ + lam * np.diag(d)) @ g
        delta = np.clip(theta + delta, lo, hi) - theta
        # the decrease the linearized model promises: |r + J delta|^2 = rss + 2 g.delta + delta' J'J delta
        promised = -(2.0 * g @ delta + delta @ JTJ @ delta)
        if promised <= 1e-10 * rss:
            break
        new = sse(theta + delta)
        if new < rss:
            theta, lam = theta + delta, max(lam / 10.0, 1e-12)
            JTJ, g, r = normal_equations(theta)
            rss = float(r @ r)
        else:
            lam *= 10.0
            if lam > 1e12:
                break
    return _result(model, problem, theta, r, JTJ)


def fit_effects(hand, m: Measurements, names) -> FitResult:
    problem = Problem(hand, m)
    with single_threaded_blas():
        return fit(Model(hand, names, problem), problem)


def predict(hand, m: Measurements, effects: dict | None = None) -> np.ndarray:
    """q (N, 15) the analytic model + ``effects`` ({name: {key: value}}, file units) predicts for the
    rows of ``m``, with the direction of motion derived from the sweeps."""
    from .pipeline import effect_values

    items = [(get_effect(n), effect_values(n, v, hand)) for n, v in (effects or {}).items()]
    return run_pipeline(hand, items, m.u, m.direction, 0.0, History.of(m))


def folds(problem: Problem, blocks: int = 6) -> list[np.ndarray]:
    """Two folds of contiguous blocks: each sweep is cut into ``blocks`` runs of rows, alternately
    assigned; each fold holds both directions and both ends of the travel. Returns row positions
    (into the problem) of fold 0 and fold 1."""
    fold = np.zeros(len(problem.rows), dtype=int)
    for k in np.unique(problem.sweep):
        idx = np.flatnonzero(problem.sweep == k)
        pos = np.arange(idx.size) * blocks // idx.size
        fold[idx] = pos % 2
    return [np.flatnonzero(fold == 0), np.flatnonzero(fold == 1)]


def heldout_fold(model: Model, train: Problem, test: Problem, x0) -> float:
    """Sum of squared residuals (deg^2, or the robust cost) on ``test`` of ``model`` fitted on
    ``train`` from ``x0``."""
    fr = fit(model, train, x0, uncertainty=False)
    return cost(_residual_fn(model, test)(fr.theta))
