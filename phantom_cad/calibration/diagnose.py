"""Which physical effect is missing? Forward selection with held-out evidence (``phantom-cad diagnose``).

Start from the analytic model. Each round, every effect of the library not yet in the model is
added in turn and all parameters are refitted; a candidate is scored by an information criterion
computed with an effective sample size,

    dIC = n_eff ln(RSS_with / RSS_without) + (p_with - p_without) ln(n_eff),

(BIC with n replaced by n_eff, because residuals within a sweep are correlated; n_eff from the
lag-1 autocorrelation of the residuals of the round's best-fitting candidate, one value per round
so that candidates are compared on one scale), and must also lower the *held-out* error:
the sweeps are cut into contiguous blocks assigned alternately to two folds, the model is fitted
on one fold and evaluated on the other, both ways; the candidate passes only if the held-out sum
of squares falls below HELDOUT_RATIO times the model's without it (checked only for candidates
with dIC < 0: the others fail already; their held-out ratio is None). The best passing candidate
(lowest dIC) is added; the loop stops when none passes. The measurement's own errors
(measurement-stage effects: ``camera_scale``) are a separate family, scored only when no effect of
the hand passes any more, on what the hand's effects leave (then the backward step may drop hand
effects they make redundant): a 15-parameter per-joint scale would otherwise absorb the hand's
elasticity and radius errors, and the control law, which never applies it, would lose them.
For the same reason a measurement effect replaces a hand effect only on evidence of its own: when
the backward step after it drops a hand effect it duplicates exactly (calibration/identify.py), its
parameters on the joints none of those hand effects can move (a scale on the MCPs, which no tendon
stretch produces) must pass the forward step's rule on their own; if they do not, both explain the
data, the hand effects stay (the control law needs them), the measurement effect is withdrawn, and
the report names the pair and the experiment that separates them (the angle gauge under the camera).
Candidates whose dIC is within
AMBIGUITY_IC of the winner's are reported as indistinguishable on these data, with the experiment
that separates them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..kinematics.topology import Q_COLUMNS
from .data import Measurements
from .framework import MEASUREMENT, REGISTRY, get_effect
from .identify import combinations, experiment_text, near_duplicate
from .residual import MAE_PER_SIGMA, NoiseFloor, made_worse, noise_floor, verdict
from .signature import measured_features, signature, signature_report
from .parallel import FitPool
from .fitting import (FitResult, Model, Problem, fit, fit_streamed, folds, robust_active, robust_loss,
                      single_threaded_blas)

#: a candidate must bring the held-out sum of squares below this fraction of the model's without it
HELDOUT_RATIO = 0.99
#: |dIC| differences below this are "equally well" (Kass & Raftery 1995: > 10 is very strong evidence)
AMBIGUITY_IC = 10.0
MAX_ROUNDS = 8
#: the selection (fits of every candidate, held-out checks, pruning) runs on at most this many
#: measured cells, every k-th row of the file; the selected effects are then refitted on every row.
#: Cells, not rows: a fit's cost is its residual cells (scipy's trust region takes the SVD of the
#: cells x parameters Jacobian at every step), and a file that records every joint on every row
#: has six times the cells of one that records the swept finger's (2,004 such rows, 30,060 cells:
#: 7.3 s with every row, 3.1 s on every third, the same effects selected and the same final MAE)
SELECTION_CELLS = 15_000
#: robust fits: soft_l1 scale, in noise standard deviations (residuals beyond it weigh about linearly)
ROBUST_SCALE = 3.0
#: a measured cell whose final residual is beyond this many of its joint's noise sd is an outlier
OUTLIER_SIGMAS = 5.0
#: an outlier stands out from the median of this many neighbouring samples on each side (an isolated glitch)
OUTLIER_NEIGHBOURS = 2
#: outliers listed at most (the count is always given)
MAX_OUTLIERS = 100

#: the measurement that separates two effects that explain a residual equally well
SEPARATING_EXPERIMENTS = {
    frozenset({"tendon_elasticity", "pulley_radius_error"}):
        "measure the MCP of the same finger (a pulley radius error moves the MCP, elasticity leaves it at "
        "the model), or the PIP and DIP together (a radius error keeps the 4:5:4 joint ratio, elasticity bends it)",
    frozenset({"routed_elasticity", "tendon_elasticity"}):
        "measure the MCP of the same finger over the whole travel (the routed stretch lowers it through the "
        "drive's stretch, the paper's eq. 13 leaves it at the model), with the PIP and DIP",
    frozenset({"routed_elasticity", "pulley_radius_error"}):
        "measure the PIP and DIP with the MCP of the same finger (a radius error keeps the joints' ratios, "
        "the strands' stretch bends them, the distal joints most)",
    frozenset({"tendon_elasticity", "friction_hysteresis"}):
        "sweep in both directions: friction flips sign with the direction of motion, elasticity does not",
    frozenset({"tendon_slack", "joint_offset"}):
        "record the rest pose and the first degrees of travel in fine steps: slack is a dead band that starts "
        "at q = 0, an offset is already there at rest",
    frozenset({"tendon_slack", "pulley_radius_error"}):
        "sweep from the very start of the travel in fine steps: slack is a dead band near u = 0, a radius "
        "error grows in proportion to u",
    frozenset({"joint_offset", "pulley_radius_error"}):
        "record the rest pose: an offset is there at u = 0, a radius error is not",
    frozenset({"friction_hysteresis", "tendon_slack"}):
        "reverse the direction in the middle of the travel: friction opens a loop at every reversal, slack "
        "only near the start",
}
#: what separates a hand effect from a measurement error that duplicates it on the recorded sweeps
GAUGE_EXPERIMENT = ("photograph the printed angle gauge (phantom-cad build writes it beside the parts, gauge/) in "
                    "the finger's plane with the same camera and fit the camera's scale on its known angles first "
                    "(docs/calibration.md): a scale the gauge shows is the camera's, what is left after it is the hand's")
SEPARATING_EXPERIMENTS.update({
    frozenset({name, "camera_scale"}): GAUGE_EXPERIMENT + "; or sweep again with a weight on the fingertip: a tendon's "
    "stretch grows with its tension, a camera's scale does not"
    for name in ("tendon_elasticity", "tendon_elasticity_per_finger")})
DEFAULT_EXPERIMENT = ("sweep the whole travel in both directions in fine steps and measure every joint of the "
                      "chain (MCP included)")


def separating_experiment(a: str, b: str) -> str:
    if frozenset({a, b}) in SEPARATING_EXPERIMENTS:
        return SEPARATING_EXPERIMENTS[frozenset({a, b})]
    if MEASUREMENT in {get_effect(a).stage, get_effect(b).stage}:
        return GAUGE_EXPERIMENT
    return DEFAULT_EXPERIMENT


@dataclass
class Candidate:
    effect: str
    delta_ic: float
    rss_ratio: float
    heldout_ratio: float
    passes: bool
    n_eff: float
    n_params: int
    mae_deg: float
    result: FitResult = field(repr=False, default=None)

    def to_json(self):
        return {"effect": self.effect, "delta_ic": round(self.delta_ic, 3), "rss_ratio": round(self.rss_ratio, 6),
                "heldout_ratio": round(self.heldout_ratio, 6) if np.isfinite(self.heldout_ratio) else None,
                "passes": self.passes,
                "n_eff": round(self.n_eff, 1), "n_params": self.n_params, "mae_deg": round(self.mae_deg, 5)}


@dataclass
class Diagnosis:
    measurements: Measurements
    before: FitResult
    after: FitResult
    selected: list[str]
    rounds: list[list[Candidate]]
    ambiguities: list[dict]
    notes: list[str]
    noise: NoiseFloor = None
    hand: object = field(repr=False, default=None)
    robust: bool = False

    def outlier_cells(self) -> np.ndarray:
        """Boolean over the final fit's cells: |residual| > OUTLIER_SIGMAS x the joint's noise sd
        (computed once: the verdict and the outlier list both read it)."""
        if getattr(self, "_outlier_cells", None) is None:
            self._outlier_cells = outlier_cells(self.after, self.noise)
        return self._outlier_cells

    def outliers(self) -> list[dict]:
        return outliers(self.after, self.measurements, self.noise, self.outlier_cells())

    def verdict(self) -> dict:
        """The verdict; with robust fits, over the cells that are not outliers."""
        return verdict(self.after, self.noise, ~self.outlier_cells() if self.robust else None)

    def signatures(self) -> dict:
        """Signature of the analytic model's residual (before) and of what is left (after)."""
        return {"before": signature(self.before, self.measurements, self.hand),
                "after": signature(self.after, self.measurements, self.hand)}

    def signature_match(self, sig: dict | None = None, v: dict | None = None) -> dict:
        """The measured signature's features (over the joints with structure beyond the noise)
        against the declared signature (Effect.leaves) of the best candidate: of the first round
        for the analytic model's residual (``before``), of the last round, which nothing passed,
        for what is left (``after``, only when not explained)."""
        sig = sig or self.signatures()
        v = v or self.verdict()
        out = {}
        vb = verdict(self.before, self.noise)
        left_before = [c for c, pj in vb["per_joint"].items() if not pj["consistent"]]
        best = self.ranking[0].effect if self.ranking else None
        out["before"] = signature_report(measured_features(sig["before"], left_before, self.noise), best, REGISTRY)
        if not v["explained"]:
            left = [c for c, pj in v["per_joint"].items() if not pj["consistent"]]
            # the last round that scored anything (a family with nothing left to score ends empty)
            last = next((r for r in reversed(self.rounds) if r), None)
            best_after = last[0].effect if last and not last[0].passes else None
            out["after"] = signature_report(measured_features(sig["after"], left, self.noise), best_after, REGISTRY)
        return out

    def ambiguities_json(self, sig: dict | None = None) -> list[dict]:
        """The ambiguities; a hand effect kept over a measurement effect carries whether the analytic
        model's residual has its declared signature (``signature``: matching and mismatching features)."""
        out = []
        for a in self.ambiguities:
            a = dict(a)
            if a.get("kind") == "hand_or_measurement":
                sig = sig or self.signatures()
                vb = verdict(self.before, self.noise)
                left = [c for c, pj in vb["per_joint"].items() if not pj["consistent"]]
                rep = signature_report(measured_features(sig["before"], left, self.noise), a["kept"], REGISTRY)
                a["signature"] = None if rep is None else {k: rep.get(k) for k in ("matches", "mismatches")}
            out.append(a)
        return out

    @property
    def ranking(self) -> list[Candidate]:
        return self.rounds[0] if self.rounds else []

    def per_joint(self) -> dict[str, dict[str, float]]:
        b = mae_per_joint(self.before)
        a = mae_per_joint(self.after)
        return {c: {"before": round(b[c], 5), "after": round(a[c], 5)} for c in b}

    def made_worse(self) -> list[str]:
        """Joints whose MAE the selected effects raised beyond noise (residual.made_worse)."""
        b, a = mae_per_joint(self.before), mae_per_joint(self.after)
        return made_worse(b, a, self.noise.floor_deg, self.noise.cells)

    def to_json(self) -> dict:
        vals, errs = self.after.values(), self.after.uncertainties()
        effects = {}
        for name in self.selected:
            eff = get_effect(name)
            effects[name] = {
                "explanation": eff.explanation,
                # the measurement's own error (never in the control law) or the hand's physics
                "side": "measurement" if eff.stage == MEASUREMENT else "hand",
                "parameters": {k: _value_json(v, errs[name][k]) for k, v in vals[name].items()},
            }
        v = self.verdict()
        sig = self.signatures()
        left = {}
        if not v["explained"]:
            for c, pj in v["per_joint"].items():
                if not pj["consistent"]:
                    left[c] = {"mae_deg": pj["mae_deg"], "tolerance_deg": pj["tolerance_deg"],
                               "structured_rms_deg": pj["structured_rms_deg"],
                               "structured_mae_deg": pj["structured_mae_deg"],
                               "signature": sig["after"]["per_joint"].get(c)}
        return {
            "generator": "phantom-cad diagnose",
            "source": self.measurements.source,
            "rows": len(self.measurements),
            "measured_cells": int(self.before.m),
            "mae_deg_before": round(mae(self.before), 5),
            "mae_deg_after": round(mae(self.after), 5),
            "noise_floor_deg": round(self.noise.overall_deg, 5),
            "noise_floor_per_joint_deg": {c: round(x, 5) for c, x in self.noise.floor_deg.items()},
            "noise": self.noise.to_json(),
            "explained": v["explained"],
            "verdict": v,
            "left": left,
            "signature": sig,
            "signature_match": self.signature_match(sig, v),
            "robust": self.robust,
            "outliers_count": len(outl := self.outliers()),
            "outliers": outl[:MAX_OUTLIERS],
            "selected": list(self.selected),
            "effects": effects,
            "ranking": [c.to_json() for c in self.ranking],
            "rounds": [[c.to_json() for c in r] for r in self.rounds],
            "ambiguities": self.ambiguities_json(sig),
            "identifiability": [c.to_json() for c in combinations(self.after)],
            "per_joint": self.per_joint(),
            "made_worse": self.made_worse(),
            "notes": self.notes,
        }


def _value_json(value: float, std: float) -> dict:
    """A fitted parameter for JSON: its standard deviation, or null and ``identifiable: false`` when
    it is part of a combination the data cannot separate (calibration/identify.py)."""
    if np.isfinite(std):
        return {"value": round(value, 6), "std": round(std, 6), "identifiable": True}
    return {"value": round(value, 6), "std": None, "identifiable": False}


def outlier_cells(fr: FitResult, noise: NoiseFloor) -> np.ndarray:
    """Boolean over a fit's cells: an isolated glitch, |residual| > OUTLIER_SIGMAS x the joint's
    noise sd **and** as far from the residual's local level (the median of the same joint's
    residual on the OUTLIER_NEIGHBOURS rows either side in the same sweep). A residual the model
    leaves over a stretch of the sweep (structure: an effect that is missing) is not an outlier: it
    is what the verdict and the signature are about, and a robust verdict must not drop it."""
    p, r = fr.problem, fr.residual
    sig = np.array([noise.sigma_deg.get(c, np.nan) for c in Q_COLUMNS])[p.j_idx]
    limit = OUTLIER_SIGMAS * np.nan_to_num(sig, nan=np.inf)
    return (np.abs(r) > limit) & (np.abs(r - _local_level(p, r)) > limit)


def _local_level(p: Problem, r: np.ndarray, k: int = OUTLIER_NEIGHBOURS) -> np.ndarray:
    """Per cell: the median of its joint's residuals on the k measured rows before and after it in
    its sweep (itself left out); the cell's own residual where it has no neighbour."""
    level = r.copy()
    for j in np.unique(p.j_idx):
        cells = np.flatnonzero(p.j_idx == j)            # row order (cells are row-major)
        e, sw = r[cells], p.sweep[p.r_idx[cells]]
        n = cells.size
        window = np.full((n, 2 * k), np.nan)
        for col, shift in enumerate([*range(-k, 0), *range(1, k + 1)]):
            src = np.arange(n) + shift
            ok = (src >= 0) & (src < n)
            ok[ok] &= sw[src[ok]] == sw[ok]
            window[ok, col] = e[src[ok]]
        has = np.isfinite(window).any(axis=1)
        level[cells[has]] = np.nanmedian(window[has], axis=1)
    return level


def outliers(fr: FitResult, m: Measurements, noise: NoiseFloor, cells: np.ndarray | None = None) -> list[dict]:
    """The outlier cells of a fit: sweep, row (0-based), file line, joint, residual (deg).
    ``cells``: :func:`outlier_cells` when already computed."""
    p, r = fr.problem, fr.residual
    out = []
    for k in np.flatnonzero(outlier_cells(fr, noise) if cells is None else cells):
        row = int(p.rows[p.r_idx[k]])
        out.append({"sweep": m.sweep_ids[int(m.sweep[row])], "row": row, "line": int(m.lines[row]),
                    "joint": Q_COLUMNS[int(p.j_idx[k])], "residual_deg": round(float(r[k]), 4)})
    return out


def mae(fr: FitResult) -> float:
    return float(np.mean(np.abs(fr.residual))) if fr.m else float("nan")


def mae_per_joint(fr: FitResult, keep: np.ndarray | None = None) -> dict[str, float]:
    """{joint: MAE (deg)} over the fit's cells (those of ``keep``, a boolean over them, if given)."""
    p = fr.problem
    out = {}
    for j, c in enumerate(Q_COLUMNS):
        sel = p.j_idx == j if keep is None else (p.j_idx == j) & keep
        if sel.any():
            out[c] = float(np.mean(np.abs(fr.residual[sel])))
    return out


def delta_ic(base: FitResult, cand: FitResult, n_eff: float) -> float:
    """n_eff ln(RSS_cand / RSS_base) + (p_cand - p_base) ln(n_eff); < 0 favours the candidate."""
    ratio = cand.rss / base.rss if base.rss > 0 else 1.0
    return float(n_eff * np.log(max(ratio, 1e-300)) + (cand.model.p - base.model.p) * np.log(n_eff))


def diagnose(hand, m: Measurements, candidates=None, start=(), robust: bool = False,
             jobs: int | None = None) -> Diagnosis:
    """Forward selection of effects (module docstring). ``candidates`` default: the whole library.
    ``jobs``: worker processes for the fits (default: the CPUs available; 1: all in this process;
    the result is the same, calibration/parallel.py).
    ``robust``: every fit uses the soft_l1 loss with scale ROBUST_SCALE x the data's noise sd, and
    the scores use the same robust cost (so a few glitches neither bend a fit nor pass a candidate)."""
    with single_threaded_blas():
        if not robust:
            return _diagnose(hand, m, candidates, start, jobs)
        sigma = noise_floor(m).overall_deg / MAE_PER_SIGMA
        with robust_loss(ROBUST_SCALE * sigma):
            d = _diagnose(hand, m, candidates, start, jobs)
        d.robust = True
        d.notes.append(f"robust fits: soft_l1 loss with scale {ROBUST_SCALE * sigma:.3f} deg ({ROBUST_SCALE:g} x the "
                       f"noise sd); outliers (beyond {OUTLIER_SIGMAS:g} noise sd) are left out of the verdict")
        return d


def _diagnose(hand, m: Measurements, candidates, start, jobs: int | None) -> Diagnosis:
    names = list(REGISTRY) if candidates is None else list(candidates)
    for n in names:
        get_effect(n, "--effects")
    full = Problem(hand, m.require_joints())
    step = max(1, -(-full.m // SELECTION_CELLS))
    problem = full if step == 1 else full.subset(np.arange(0, len(m), step))
    parts = folds(problem)
    with FitPool(hand, problem, parts, jobs) as pool:
        return _select(hand, m, names, start, full, step, problem, pool)


def _select(hand, m: Measurements, names, start, full: Problem, step: int, problem: Problem,
            pool: FitPool) -> Diagnosis:
    notes: list[str] = []
    current = list(start)
    base = pool.fit(Model(hand, current, problem))
    heldout_cache: dict[tuple, float] = {}

    def evidence(prev: FitResult, effect: str, hand_effects: list[str], n_eff: float) -> dict:
        """Whether the measurement effect ``effect`` shows where none of ``hand_effects`` reaches: its
        parameters on the joints none of theirs moves, added to ``prev`` (the model before it), must
        pass the forward step's rule (dIC < 0 and held-out ratio < HELDOUT_RATIO)."""
        reach = {j for n in hand_effects for p in get_effect(n).parameters(hand) for j in p.joints}
        own = {j for p in get_effect(effect).parameters(hand) for j in p.joints}
        model = Model(hand, [*prev.model.names, effect], problem, {effect: own - reach})
        joints = [Q_COLUMNS[j] for j in sorted({j for k, _, p in model.free if model.names[k] == effect
                                                for j in p.joints} - reach)]
        out = {"outside": {"joints": joints, "delta_ic": None, "heldout_ratio": None}, "passes": False, "text": ""}
        if model.p == prev.model.p:
            return out
        res = pool.fit(model, model.start(prev))
        dic = delta_ic(prev, res, n_eff)
        out["outside"]["delta_ic"] = round(dic, 3)
        if dic < 0:
            held([(prev.model, prev), (model, res)])
            base_held = heldout_cache[prev.model.key]
            ratio = heldout_cache[model.key] / base_held if base_held > 0 else 1.0
            out["outside"]["heldout_ratio"] = round(ratio, 6)
            out["passes"] = bool(ratio < HELDOUT_RATIO)
            out["text"] = (f"; {effect} replaced it on evidence of its own: on the joints {', '.join(hand_effects)} "
                           f"cannot move ({', '.join(joints)}) it passes alone (dIC {dic:+.1f}, held-out ratio "
                           f"{ratio:.3f})")
        return out

    def held(jobs: list[tuple[Model, FitResult]]) -> None:
        """The held-out sums of squares of (model, the fit to start from), into heldout_cache."""
        todo = {model.key: (model, model.start(start_from)) for model, start_from in jobs
                if model.key not in heldout_cache}
        for key, sse in zip(todo, pool.heldout(list(todo.values()))):
            heldout_cache[key] = sse

    rounds: list[list[Candidate]] = []
    ambiguities: list[dict] = []
    saturated: FitResult | None = None           # the whole hand family at once (n_eff's floor)
    n_floor = 0.0                                # the floor, once a round has used it
    seen: set[frozenset] = set()                 # the models the rounds ended with
    withheld: set[str] = set()                   # measurement effects withdrawn for lack of evidence
    directions_seen = {int(v) for v in np.unique(m.direction)}
    if not ({1, -1} <= directions_seen):
        notes.append("the data move in one direction only: direction-dependent effects (friction) cannot be "
                     "told from direction-independent ones")
    # the hand's physics first; the measurement's own errors (camera_scale) only on what it leaves
    measurement = {n for n in names if get_effect(n).stage == MEASUREMENT}
    hand_names = [n for n in names if n not in measurement]
    family = "hand" if set(names) - measurement else "measurement"
    for _ in range(MAX_ROUNDS):
        candidates = [n for n in names if n not in current and n not in withheld
                      and (n in measurement) == (family == "measurement")]
        models = []
        for n in candidates:
            model = Model(hand, _with(current, n, len(start)), problem)
            if not any(model.names[k] == n for k, _, _ in model.free):
                if not rounds:
                    notes.append(f"{n}: no parameter is identifiable from these data (not scored)")
                continue
            models.append((n, model))
        results = pool.fits([(model, model.start(base)) for _, model in models])
        fits = [(n, model, res) for (n, model), res in zip(models, results)]
        if not fits:
            if family == "hand" and measurement:
                family = "measurement"
                continue
            rounds.append([])
            break

        def score(n_eff: float) -> list[Candidate]:
            dics = [delta_ic(base, res, n_eff) for _, _, res in fits]
            # the held-out check only where it can decide: a candidate with dIC >= 0 fails already
            # (each candidate starts from its own fit to all rows; the base from itself)
            passing_ic = [(model, res) for (_, model, res), d in zip(fits, dics) if d < 0]
            if passing_ic:
                held([(base.model, base)] + passing_ic)
            base_held = heldout_cache.get(base.model.key)
            out = []
            for (n, model, res), dic in zip(fits, dics):
                if dic < 0:
                    ratio_h = heldout_cache[model.key] / base_held if base_held > 0 else 1.0
                else:
                    ratio_h = float("nan")      # not run
                passes = bool(dic < 0 and ratio_h < HELDOUT_RATIO)
                out.append(Candidate(n, float(dic), res.rss / base.rss if base.rss > 0 else 1.0, float(ratio_h),
                                     passes, float(n_eff), model.p - base.model.p, mae(res), res))
            return sorted(out, key=lambda c: c.delta_ic)

        # one effective sample size for the whole round: that of the best-fitting candidate's residuals
        n_eff = max(min(fits, key=lambda f: f[2].rss)[2].n_eff, 2.0)
        scored = score(n_eff)
        if not any(c.passes for c in scored) and family == "hand" and len(hand_names) > 1 and n_eff < 0.5 * problem.m:
            # nothing passes, on strongly correlated residuals: another hidden effect may keep the best
            # candidate's residual as correlated as an unmodelled one. Floor: the residual of the whole
            # hand family fitted at once, what the library can reach (fitted once, when first needed)
            if saturated is None:
                whole = Model(hand, list(dict.fromkeys([*start, *hand_names])), problem)
                saturated = pool.fit(whole, whole.start(base))
            if saturated.n_eff > n_eff:
                scored = score(saturated.n_eff)
                # from here on the backward step scores on the same scale (else it undoes the round)
                n_floor = max(n_floor, saturated.n_eff)
        rounds.append(scored)
        passing = [c for c in scored if c.passes]
        if not passing:
            if family == "hand" and measurement:
                family = "measurement"
                continue
            break
        best = passing[0]
        for other in passing[1:]:
            if other.delta_ic - best.delta_ic < AMBIGUITY_IC:
                ambiguities.append({
                    "round": len(rounds), "effects": [best.effect, other.effect],
                    "delta_ic": [round(best.delta_ic, 3), round(other.delta_ic, 3)],
                    "experiment": separating_experiment(best.effect, other.effect),
                })
        before_best = (list(current), base)
        replaced = [c for c in current if c not in _with(current, best.effect, len(start))]
        current[:] = _with(current, best.effect, len(start))
        for name in replaced:
            notes.append(f"{best.effect} replaced {name}: a model holds one form of the tendon's stretch")
        base = best.result
        if family == "measurement":
            # the measurement's own error is now modelled: the hand's physics it masked may show
            # (measured: a 6-parameter backlash, beaten under 15 camera scales by a 2-parameter
            # friction band, is found only on the residual the scales leave)
            family = "hand"
        base, dropped = _prune(hand, problem, current, base, len(start), pool, n_floor)
        duplicates, exact = _duplicated(best, dropped)
        if exact:
            ev = evidence(before_best[1], best.effect, exact, best.n_eff)
            if not ev["passes"]:
                # no evidence of its own: the hand effects it duplicates stay, the control law needs them
                for name in exact:
                    ambiguities.append({
                        "round": len(rounds), "effects": [name, best.effect], "kind": "hand_or_measurement",
                        "kept": name, "withdrawn": best.effect,
                        "mae_deg": {"with_hand_effect": round(mae(before_best[1]), 5),
                                    "with_measurement_instead": round(mae(base), 5)},
                        "outside": ev["outside"],
                        "experiment": separating_experiment(name, best.effect),
                    })
                current[:], base = before_best
                withheld.add(best.effect)
                family = "measurement"
                continue
            for name in exact:
                duplicates[name] += ev["text"]
        for name, dic in dropped:
            notes.append(f"{name} was dropped after {best.effect} was added: the model without it scores "
                         f"better (dIC {dic:+.1f}); what it explained is explained by the others"
                         + duplicates.get(name, ""))
        base, simpler = _simplify(hand, problem, current, base, len(start), pool, n_floor)
        for variant, parent, dic in simpler:
            notes.append(f"{variant} was replaced by its simpler form {parent} after {best.effect} was added: "
                         f"with the others in the model the extra parameters no longer pay (dIC {dic:+.1f})")
        # keep only the fits the made-worse check may read (models within the current one): on a
        # 20,000-row selection with every joint recorded each fit holds 2.4 MB of residuals
        pool.fitted = {k: v for k, v in pool.fitted.items() if set(k) <= set(current)}
        if frozenset(current) in seen:
            notes.append(f"the selection returned to a model it had already reached ({', '.join(current) or 'analytic'}): "
                         f"stopped there (forward and backward steps would cycle)")
            break
        seen.add(frozenset(current))
    noise = noise_floor(m)
    base, worse = _made_worse(hand, problem, current, base, len(start), pool, noise)
    for name, joints in worse:
        notes.append(f"{name} was dropped at the end: with it, {joints} fit worse than without it, beyond what "
                     f"noise explains; a selected effect must not make any joint worse")
    before = fit(Model(hand, [], full), full)
    if problem is not full:
        model = Model(hand, current, full)
        base = fit_streamed(model, full, model.start(base))
        notes.append(f"the effects were selected on every {step}th row ({problem.rows.size:,} of {len(m):,} rows; "
                     f"the ranking above is theirs); the selected effects were then fitted on all rows, and the "
                     f"MAE and parameters below are of that fit")
    return Diagnosis(m, before, base, current[len(start):], rounds, ambiguities, [n for n in notes if n],
                     noise, hand)


def _with(current: list[str], name: str, keep: int) -> list[str]:
    """``current`` with ``name`` added and, when it models the tendon's stretch (Effect.stretch), the
    selected effects of the other form taken out (not the first ``keep``, the user's start): the
    routed and the paper's form describe the same strands, and both at once would fit any spread
    of the stretch over the joints by mixing them."""
    form = get_effect(name).stretch
    return [c for i, c in enumerate(current)
            if i < keep or not form or get_effect(c).stretch in (None, form)] + [name]


def _duplicated(best: Candidate, dropped) -> tuple[dict[str, str], list[str]]:
    """{hand effect dropped: the sentence that says so} for the hand effects a measurement effect
    just added duplicates on these data: exactly (their parameters and the measurement's form a
    combination the fit with both cannot separate, calibration/identify.py) or nearly (with the
    measurement's parameters in the fit, one of the effect's parameters' variance grows
    identify.NEAR_DUPLICATE-fold or more: a drive pulley's radius error scales its chain's angles
    almost as a camera's per-joint scales do, the cosine law's curvature alone tells them apart).
    The backward step keeps the simpler model, the measurement side; said so, because if the hand
    has the effect the calibrated control law lacks it (a uniform tendon compliance scales each
    distal joint by a constant: on a sweep it is a per-joint scale of the camera).
    Also returns the names duplicated exactly."""
    if not dropped or get_effect(best.effect).stage != MEASUREMENT:
        return {}, []
    out, exact = {}, []
    combos = combinations(best.result)
    lacks = ("the measurement side is kept as the simpler model, so a calibrated control law lacks {name}; "
             "if the hand has it, calibrate the camera on the angle gauge first (docs/calibration.md) and fit "
             "with --effects {name}")
    for name, _ in dropped:
        for c in combos:
            keys = list(c.weights)
            if any(k.startswith(f"{name}.") for k in keys) and any(k.startswith(f"{best.effect}.") for k in keys):
                shown = " ".join(f"{w:+.2f} {k}" for k, w in list(c.weights.items())[:4])
                exact.append(name)
                out[name] = (f"; but the data cannot tell {name} from {best.effect} (not identifiable together: "
                             f"{shown}{' ...' if len(keys) > 4 else ''}): " + lacks.format(name=name))
                break
        else:
            near = near_duplicate(best.result, name, best.effect)
            if near is not None:
                out[name] = (f"; but the data barely tell {name} from {best.effect} (nearly duplicated: with "
                             f"{best.effect} in the fit the variance of {near.parameter} grows {near.inflation:,.0f}-fold, "
                             f"its uncertainty {near.inflation ** 0.5:.0f}-fold): " + lacks.format(name=name)
                             + ("; " + experiment_text(near.experiment) if near.experiment else
                                "; no recording of one servo separates them better than these data do"))
    return out, exact


def _simplify(hand, problem, current: list[str], base: FitResult, keep: int, pool: FitPool, n_floor: float = 0.0):
    """A selected variant (an effect with ``simpler``: the per-finger elasticity) is replaced by its
    simpler form when that scores no worse with the model as it now is: a variant picked in an
    early round may have been absorbing what an effect added later explains."""
    done = []
    for name in list(current[keep:]):
        parent = getattr(get_effect(name), "simpler", None)
        if not parent or parent in current:
            continue
        names = [parent if n == name else n for n in current]
        model = Model(hand, names, problem)
        res = pool.fit(model, model.start(base))
        dic = delta_ic(base, res, max(base.n_eff, n_floor, 2.0))      # IC(simpler) - IC(variant)
        if dic <= 0:
            current[current.index(name)] = parent
            base = res
            done.append((name, parent, float(dic)))
    return base, done


def _made_worse(hand, problem: Problem, current: list[str], base: FitResult, keep: int, pool: FitPool,
                noise: NoiseFloor):
    """The last check of the selection: every selected effect must explain its share without making
    a joint worse beyond noise (residual.made_worse: the joint's MAE with it exceeds that without it
    by more than SMALL_SAMPLE x its noise floor / sqrt(cells)) on a joint that one of its parameters
    moves together with others (a trade between joints). The model without each selected
    effect is, for all but the last added, a fit the selection already made (FitPool.fitted); with
    robust fits the cells either fit finds to be outliers are left out of the comparison; an
    effect that fails is dropped (the worst first, by its largest rise in noise floors) and the
    check runs again on what is left. Returns the final fit and [(effect, "q3 (0.081 -> 0.094 deg),
    ...")]."""
    dropped = []
    cells = {Q_COLUMNS[j]: int(n) for j, n in zip(*np.unique(problem.j_idx, return_counts=True))}

    def shared(name) -> set[str]:
        """The joints one of the effect's parameters moves together with another joint: only there
        can it trade one joint's fit for another's. A parameter of one joint alone (an offset, a
        camera scale) fits that joint by least squares; a rise of its MAE there is the pull of
        outliers (listed, and what --robust is for), not a trade."""
        return {Q_COLUMNS[j] for p in get_effect(name).parameters(hand) if len(p.joints) > 1 for j in p.joints}
    while len(current) > keep:
        names = current[keep:]
        models = [Model(hand, [n for n in current if n != name], problem) for name in names]
        todo = [m for m in models if m.names not in pool.fitted]
        pool.fits([(m, m.start(base)) for m in todo])
        failing = []
        for name, model in zip(names, models):
            res = pool.fitted[model.names]
            # robust fits: judged without the glitches of either fit, as the verdict is
            judged = ~(outlier_cells(base, noise) | outlier_cells(res, noise)) if robust_active() else None
            with_it, without = mae_per_joint(base, judged), mae_per_joint(res, judged)
            traded = shared(name)
            bad = [c for c in made_worse(without, with_it, noise.floor_deg, cells) if c in traded]
            if bad:
                floor = {c: noise.floor_deg.get(c) or 1.0 for c in bad}
                rise = max((with_it[c] - without[c]) / floor[c] for c in bad)
                text = ", ".join(f"{c} ({without[c]:.3f} -> {with_it[c]:.3f} deg)" for c in bad)
                failing.append((rise, name, res, text))
        if not failing:
            break
        _, name, res, text = max(failing, key=lambda f: f[0])
        current.remove(name)
        base = res
        dropped.append((name, text))
    return base, dropped


def _prune(hand, problem, current: list[str], base: FitResult, keep: int, pool: FitPool, n_floor: float = 0.0):
    """Backward step: drop a selected effect whose removal lowers the information criterion."""
    dropped = []
    while len(current) - keep > 1:
        trials = []
        removable = current[keep:-1]           # the effect just added stays
        models = [Model(hand, [n for n in current if n != name], problem) for name in removable]
        n_eff = max(base.n_eff, n_floor, 2.0)
        for name, res in zip(removable, pool.fits([(model, model.start(base)) for model in models])):
            dic = -delta_ic(res, base, n_eff)   # IC(without) - IC(with)
            trials.append((dic, name, res))
        dic, name, res = min(trials, key=lambda t: t[0])
        if dic >= 0:
            break
        current.remove(name)
        base = res
        dropped.append((name, float(dic)))
    return base, dropped
