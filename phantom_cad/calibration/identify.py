"""Which parameter combinations the data cannot separate, and the recording that would.

From the fit's normal matrix J^T J at the solution (J: residual cells x free parameters, degrees
per file unit). Each column is scaled to unit norm, D_k = ||J_:k|| (so a parameter's unit does not
matter), and the scaled matrix C = D^-1 J^T J D^-1 is decomposed, C = V diag(s^2) V^T. A unit
vector v of V whose singular value s_i is below ``1 / KAPPA`` of the largest is a combination the
data cannot see: moving the parameters by

    delta theta = eps v / D

changes the prediction over the recorded cells by only s_i eps (RMS s_i eps / sqrt(m)), against
about eps for any single parameter. Such parameters get no standard deviation (the covariance
along v is not bounded by these data: a standard deviation from it, e.g. +-0.0001 for an exactly
collinear pair, would mean nothing): they are reported as not identifiable, with the combination.

The separating recording is computed from the model, not looked up: for every servo whose joints
a parameter of the combination moves, in each direction (flexing, extending) and over each third
of its travel, the model predicts the recording (21 rows, the other servos at rest) at theta +- h
delta theta, and the RMS change per unit eps of each joint of that servo's chain is compared with
the recorded data's s_i / sqrt(m). The recording with the largest gain is proposed, with the
joint that shows it most. A combination that no such recording moves (gain < MIN_GAIN) is the
same function of the commands for every recording of one servo: the report says so and that
one of the parameters must come from another measurement.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.topology import JOINTS, Q_COLUMNS, SERVOS
from .data import motion_direction
from .framework import JOINT_SERVO, History

#: a combination is not identifiable when its scaled singular value is below 1 / KAPPA of the largest
KAPPA = 1e4
#: weights below this (of a unit combination) are left out of its description
MIN_WEIGHT = 0.05
#: a proposed recording must show the combination this many times better than the data did
MIN_GAIN = 10.0
#: rows of a proposed recording
ROWS = 21
#: a parameter whose variance grows this many times when another effect's parameters join the fit
#: is nearly duplicated by them (its uncertainty tenfold): separable in principle, not on these data
NEAR_DUPLICATE = 100.0
#: the thirds of a servo's travel a recording may cover
RANGES = ((0.0, 1.0 / 3.0), (1.0 / 3.0, 2.0 / 3.0), (2.0 / 3.0, 1.0))


@dataclass
class Combination:
    """A direction in parameter space the data do not constrain."""

    weights: dict[str, float]        # "effect.key" -> weight of the unit combination (scaled units)
    ratio: float                     # s_i / s_max
    rms_data: float                  # RMS change (deg) over the recorded cells per unit eps
    experiment: dict | None          # the best recording, or None when none separates them
    vector: np.ndarray               # delta theta per unit eps (file units, free parameters)

    def text(self) -> str:
        names = " and ".join(self.weights)
        out = (f"not identifiable from these data: {names} (the combination "
               + " ".join(f"{w:+.2f} {n}" for n, w in self.weights.items())
               + f" moves the prediction {self.ratio:.1e} times as much as a single parameter)")
        if self.experiment is None:
            return (out + "; no recording of one servo separates them (the model predicts the same for "
                    "every command): fix one of them from another measurement")
        return out + "; " + experiment_text(self.experiment)

    def to_json(self) -> dict:
        return {"parameters": {k: round(v, 4) for k, v in self.weights.items()},
                "singular_ratio": float(f"{self.ratio:.3e}"), "rms_data_deg": float(f"{self.rms_data:.3e}"),
                "experiment": self.experiment, "text": self.text()}


def experiment_text(e: dict) -> str:
    """The sentence that proposes a recording (:func:`_experiment`'s dict)."""
    if e["gain"] is None:
        more = f"by {e['rms_deg_per_unit']:.3g} deg per unit, where these data do not move at all"
    elif e["gain"] >= 1000:
        more = "more than 1000 times more per unit than in these data"
    else:
        more = f"{e['gain']:.0f} times more per unit than in these data"
    return (f"to separate them, record servo {e['servo']} {e['direction']} over {e['from_deg']:.0f}-"
            f"{e['to_deg']:.0f} deg and measure {e['joint']} ({e['joint_name']}): there the combination moves "
            f"the prediction {more}")


@dataclass
class NearDuplicate:
    """A parameter another effect's parameters nearly duplicate on the fitted data."""

    parameter: str                   # "effect.key"
    inflation: float                 # its variance with the other effect / without it
    experiment: dict | None          # the recording that separates them best (:func:`_experiment`)


def near_duplicate(fr, effect: str, other: str) -> NearDuplicate | None:
    """The parameter of ``effect`` whose variance grows most when ``other``'s parameters join the
    fit, if it grows at least :data:`NEAR_DUPLICATE`-fold: the ratio of its variance inflation
    factors, the diagonal of the inverse scaled normal matrix C (module docstring) with all of
    ``fr``'s free parameters and with ``other``'s left out. A combination the singular values call
    not identifiable (:func:`combinations`) inflates without bound; this one is separable in
    principle but not at these data's noise. The proposed recording moves the prediction most
    along the direction the data confuse: C^-1 e_k, the parameter's error ellipsoid's axis."""
    JTJ = getattr(fr, "jtj", None)
    if JTJ is None:
        return None
    owner = [fr.model.names[k] for k, _, _ in fr.model.free]
    d = np.sqrt(np.clip(np.diag(JTJ), 0.0, None))
    live = np.flatnonzero(d > 0)
    mine = [i for i in live if owner[i] == effect]
    rest = [i for i in live if owner[i] != other]
    if not mine or not any(owner[i] == other for i in live):
        return None
    C = JTJ / np.outer(np.where(d > 0, d, 1.0), np.where(d > 0, d, 1.0))
    with_all = np.linalg.pinv(C[np.ix_(live, live)])
    without = np.linalg.pinv(C[np.ix_(rest, rest)])
    pos_all = {i: n for n, i in enumerate(live)}
    pos_rest = {i: n for n, i in enumerate(rest)}
    ratios = {i: with_all[pos_all[i], pos_all[i]] / without[pos_rest[i], pos_rest[i]] for i in mine}
    worst = max(ratios, key=ratios.get)
    if not ratios[worst] >= NEAR_DUPLICATE:
        return None
    v = np.zeros(fr.model.p)
    v[live] = with_all[:, pos_all[worst]]
    v /= np.linalg.norm(v)
    s2 = float(v[live] @ C[np.ix_(live, live)] @ v[live])
    delta = np.where(d > 0, v / np.where(d > 0, d, 1.0), 0.0)
    experiment = _experiment(fr, delta, np.sqrt(max(s2, 0.0)) / np.sqrt(max(fr.m, 1)))
    _, _, prm = fr.model.free[worst]
    return NearDuplicate(f"{effect}.{prm.key}", float(ratios[worst]), experiment)


def _null_directions(fr) -> list[tuple[np.ndarray, float, float]]:
    """(unit combination v over the free parameters, s_i / s_max, s_i) of every direction the data
    cannot see; cheap (no prediction): run for every fit's uncertainties."""
    JTJ = getattr(fr, "jtj", None)
    if JTJ is None or fr.model.p < 2:
        return []
    d = np.sqrt(np.clip(np.diag(JTJ), 0.0, None))
    live = np.flatnonzero(d > 0)
    if live.size < 2:
        return []
    Dl = d[live]
    lam, V = np.linalg.eigh(JTJ[np.ix_(live, live)] / np.outer(Dl, Dl))
    s = np.sqrt(np.clip(lam, 0.0, None))
    smax = float(s.max())
    out = []
    for i in (np.flatnonzero(s < smax / KAPPA) if smax > 0 else ()):
        v = np.zeros(fr.model.p)
        v[live] = V[:, i] * np.sign(V[np.argmax(np.abs(V[:, i])), i])
        out.append((v, float(s[i]) / smax, float(s[i])))
    return out


def not_identifiable(fr) -> np.ndarray:
    """Boolean over ``fr``'s free parameters: part of a combination the data cannot separate."""
    mask = np.zeros(fr.model.p, dtype=bool)
    for v, _, _ in _null_directions(fr):
        mask |= np.abs(v) >= MIN_WEIGHT
    return mask


def combinations(fr) -> list[Combination]:
    """The combinations of ``fr``'s free parameters its data cannot separate (module docstring),
    each with the recording that would separate them."""
    names = [f"{fr.model.names[k]}.{prm.key}" for k, _, prm in fr.model.free]
    out = []
    nulls = _null_directions(fr)
    if not nulls:
        return out
    d = np.sqrt(np.clip(np.diag(fr.jtj), 0.0, None))
    for v, ratio, s in nulls:
        weights = {names[k]: float(v[k]) for k in np.argsort(-np.abs(v)) if abs(v[k]) >= MIN_WEIGHT}
        delta = np.where(d > 0, v / np.where(d > 0, d, 1.0), 0.0)
        rms_data = s / np.sqrt(max(fr.m, 1))
        out.append(Combination(weights, ratio, rms_data, _experiment(fr, delta, rms_data), delta))
    return out


def _experiment(fr, delta: np.ndarray, rms_data: float) -> dict | None:
    """The one-servo recording that moves the prediction most along ``delta`` (module docstring)."""
    model, hand = fr.model, fr.model.hand
    joints = {j for (k, i, prm), dv in zip(model.free, delta) if dv != 0 for j in prm.joints}
    servos = sorted({int(JOINT_SERVO[j]) for j in joints})
    # a step small against every parameter's range, inside the bounds
    width = np.where(np.isfinite(model.upper - model.lower), model.upper - model.lower, 1.0)
    h = 1e-4 * float(np.min(width[delta != 0] / np.abs(delta[delta != 0]))) if np.any(delta) else 0.0
    if h <= 0:
        return None
    lo_t = np.clip(fr.theta - h * delta, model.lower, model.upper)
    hi_t = np.clip(fr.theta + h * delta, model.lower, model.upper)
    step = float(np.max(np.abs(hi_t - lo_t) / np.where(delta != 0, np.abs(delta), np.inf)))
    if step <= 0:
        return None
    best = None
    for sv in servos:
        cols = [j.index for j in JOINTS if j.servo == sv]
        umax = float(hand.u_max[sv])
        for direction, word in ((1.0, "flexing"), (-1.0, "extending")):
            for a, b in RANGES:
                u = np.zeros((ROWS, len(SERVOS)))
                path = np.linspace(a * umax, b * umax, ROWS)
                u[:, sv] = path if direction > 0 else path[::-1]
                dirs = motion_direction(u)
                hist = History(u, np.zeros(ROWS, dtype=int), dirs)
                dq = (model.predict(hi_t, u, dirs, hist) - model.predict(lo_t, u, dirs, hist)) / step
                dq = np.degrees(dq[:, cols])
                per_joint = np.sqrt(np.mean(dq ** 2, axis=0))
                rms = float(np.sqrt(np.mean(dq ** 2)))
                if best is None or rms > best[0]:
                    jb = cols[int(np.argmax(per_joint))]
                    best = (rms, sv, word, a * umax, b * umax, jb)
    if best is None or best[0] <= 0:
        return None
    gain = best[0] / rms_data if rms_data > 0 else float("inf")
    if not gain >= MIN_GAIN:
        return None
    rms, sv, word, a, b, jb = best
    return {"servo": SERVOS[sv].label, "direction": word, "from_deg": round(float(np.degrees(a)), 1),
            "to_deg": round(float(np.degrees(b)), 1), "joint": Q_COLUMNS[jb], "joint_name": JOINTS[jb].name,
            "rms_deg_per_unit": round(float(rms), 6), "gain": round(float(gain), 1) if np.isfinite(gain) else None}
