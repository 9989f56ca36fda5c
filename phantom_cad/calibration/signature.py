"""The residual's signature: what shape the structure a model leaves has, and which effect it
looks like.

Signature (per joint, of a residual)
    the part that flips with the direction of motion and the part that does not (bins of the
    servo angle, the mean when flexing and when extending: half their difference / half their
    sum); the value at rest; the linear trend against the servo angle; a least-squares
    periodogram against the servo angle (periods PERIODS_DEG); MCP (and thumb MP, CMC) vs the
    distal joints; the mean at the very start of the travel; how much the upper half of the
    travel carries over the lower half (of the residual, and of the flipping band); the jump of
    the residual across each reversal.

Features and the library's declarations
    :func:`measured_features` reads those numbers, over the joints with structure beyond the
    noise, as the features an effect declares (effects.Signature: direction, at_rest, trend,
    joints, periodic, reversal); :func:`signature_report` compares them with the best
    candidate's declaration and with every registered effect's, in sentences.
"""

from __future__ import annotations

import math

import numpy as np

from ..kinematics.topology import CMC_SERVO, DISTAL_JOINTS, JOINT_SERVO, Q_COLUMNS, SERVOS
from ..units import DEG_PER_RAD
from .residual import NoiseFloor, fit_cells

#: candidate periods of the periodogram, degrees of servo angle
PERIODS_DEG = tuple(float(p) for p in range(10, 121, 2))
#: a period is reported when its sinusoid removes at least this share of the detrended variance ...
PERIOD_SHARE = 0.5
#: ... and at least this many times the median share over the candidate periods
PERIOD_CONTRAST = 3.0
#: servo angles within this fraction of the travel from its start count as "at rest"
REST_FRACTION = 0.05
#: number of servo-angle bins for the direction split
DIRECTION_BINS = 12
#: "at the start": the samples within this fraction of the swept range from its lowest servo angle
START_FRACTION = 0.02
#: samples on each side of a reversal whose means are compared (the reversal jump)
REVERSAL_SAMPLES = 3
#: a part "grows" when the upper half of the travel carries more than this multiple of the lower half's
GROWTH = 2.0
#: a feature is read only when it stands this many noise standard errors above the noise
FEATURE_SIGMAS = 4.0
#: the signature of a joint is computed on at most about this many of its samples (every k-th)
SIGNATURE_SAMPLES = 5_000


def _sinusoid_shares(t: np.ndarray, e: np.ndarray, var: float, Q: np.ndarray, periods) -> np.ndarray:
    """For each period p: the share of the detrended variance ``var`` that a line plus one
    sinusoid of period p removes beyond the line, i.e. 1 - RSS([1, t, cos, sin]) / var, for all
    periods at once: cos and sin with the line projected out (``Q``, an orthonormal basis of
    [1, t]), then the 2 x 2 normal equations of each period."""
    w = 2 * math.pi * t[:, None] / np.asarray(periods, dtype=float)[None, :]
    C, S = np.cos(w), np.sin(w)
    C -= Q @ (Q.T @ C)
    S -= Q @ (Q.T @ S)
    cc, ss, cs = np.einsum("ij,ij->j", C, C), np.einsum("ij,ij->j", S, S), np.einsum("ij,ij->j", C, S)
    ce, se = e @ C, e @ S
    det = cc * ss - cs * cs
    ok = det > 1e-12 * np.maximum(cc * ss, 1e-300)
    a = np.where(ok, (ss * ce - cs * se) / np.where(ok, det, 1.0), 0.0)
    b = np.where(ok, (cc * se - cs * ce) / np.where(ok, det, 1.0), 0.0)
    return (a * ce + b * se) / var


def _periodogram(t: np.ndarray, x: np.ndarray):
    """(best period, its share of the detrended variance, median share) or None."""
    if x.size < 12 or np.ptp(t) <= 0:
        return None
    Q, _ = np.linalg.qr(np.column_stack([np.ones_like(t), t]))
    e = x - Q @ (Q.T @ x)
    var = float(e @ e)
    if var <= 0:
        return None
    periods = [p for p in PERIODS_DEG if p <= np.ptp(t)]
    if len(periods) < 3:
        return None
    shares = _sinusoid_shares(t, e, var, Q, periods)
    k = int(np.argmax(shares))
    # refine the peak on a 0.25 deg grid around the best candidate
    best_p, best_s = periods[k], float(shares[k])
    fine = np.arange(max(periods[0], best_p - 2.0), best_p + 2.0 + 1e-9, 0.25)
    fine_shares = _sinusoid_shares(t, e, var, Q, fine)
    j = int(np.argmax(fine_shares))
    if fine_shares[j] > best_s:
        best_p, best_s = float(fine[j]), float(fine_shares[j])
    return float(best_p), float(best_s), float(np.median(shares))


def _growth(u_deg: np.ndarray, x: np.ndarray) -> float | None:
    """Mean |x| over the upper half of the swept range over that of the lower half."""
    if x.size < 4 or np.ptp(u_deg) <= 0:
        return None
    mid = u_deg.min() + 0.5 * np.ptp(u_deg)
    low, high = np.abs(x[u_deg < mid]), np.abs(x[u_deg >= mid])
    if not low.size or not high.size:
        return None
    return float(high.mean() / max(low.mean(), 1e-12))


def _reversal_jumps(u_deg: np.ndarray, d: np.ndarray, x: np.ndarray, sweep: np.ndarray | None) -> list[float]:
    """At each reversal of the servo within a sweep: the mean residual of the REVERSAL_SAMPLES
    samples after it minus that of the REVERSAL_SAMPLES before (nearly the same servo angles, so a
    residual continuous in u gives about 0)."""
    k = REVERSAL_SAMPLES
    same = np.ones(x.size - 1, dtype=bool) if sweep is None else sweep[1:] == sweep[:-1]
    turns = np.flatnonzero(same & (d[1:] * d[:-1] < 0)) + 1
    out = []
    for t in turns:
        if t - k < 0 or t + k > x.size or (sweep is not None and
                                           (sweep[t - k] != sweep[t] or sweep[t + k - 1] != sweep[t])):
            continue
        out.append(float(x[t:t + k].mean() - x[t - k:t].mean()))
    return out


def joint_signature(u_deg: np.ndarray, d: np.ndarray, x: np.ndarray, travel_deg: tuple[float, float],
                    sweep: np.ndarray | None = None) -> dict:
    """Signature of one joint's residual x (deg) against its servo angle u (deg), direction d,
    samples in row order (``sweep``: their sweep codes, for the reversals)."""
    out: dict = {"rms_deg": round(float(np.sqrt(np.mean(x * x))), 5), "n": int(x.size)}
    lo, hi = travel_deg
    rest = u_deg <= lo + REST_FRACTION * (hi - lo)
    out["at_rest_deg"] = round(float(np.mean(x[rest])), 5) if rest.any() else None
    # the samples at the very start of the travel (within START_FRACTION of the swept range)
    start = u_deg <= u_deg.min() + START_FRACTION * max(float(np.ptp(u_deg)), 1e-12)
    out["at_start_deg"] = round(float(np.mean(x[start])), 5)
    out["at_start_n"] = int(start.sum())
    g = _growth(u_deg, x)
    out["growth"] = round(g, 4) if g is not None else None
    jumps = _reversal_jumps(u_deg, d, x, sweep)
    if jumps:
        out["reversal_jump_deg"] = round(float(np.sqrt(np.mean(np.square(jumps)))), 5)
        out["reversals"] = len(jumps)
    if np.ptp(u_deg) > 0 and x.size >= 3:
        slope, icpt = np.polyfit(u_deg, x, 1)
        fit = slope * u_deg + icpt
        ss = float(np.sum((x - x.mean()) ** 2))
        out["trend_deg_per_10deg"] = round(float(slope) * 10.0, 5)
        out["trend_share"] = round(1.0 - float(np.sum((x - fit) ** 2)) / ss, 4) if ss > 0 else 0.0
    both = (d > 0).any() and (d < 0).any()
    if both:
        edges = np.linspace(u_deg.min(), u_deg.max() + 1e-9, DIRECTION_BINS + 1)
        b = np.clip(np.digitize(u_deg, edges) - 1, 0, DIRECTION_BINS - 1)
        odd, even, centre = [], [], []
        for k in range(DIRECTION_BINS):
            f, e = x[(b == k) & (d > 0)], x[(b == k) & (d < 0)]
            if f.size and e.size:
                odd.append((f.mean() - e.mean()) / 2)
                even.append((f.mean() + e.mean()) / 2)
                centre.append(0.5 * (edges[k] + edges[k + 1]))
        if odd:
            out["direction_flipping_rms_deg"] = round(float(np.sqrt(np.mean(np.square(odd)))), 5)
            out["direction_independent_rms_deg"] = round(float(np.sqrt(np.mean(np.square(even)))), 5)
            fg = _growth(np.array(centre), np.array(odd))
            out["flip_growth"] = round(fg, 4) if fg is not None else None
    out["both_directions"] = bool(both)
    per = _periodogram(u_deg, x)
    if per is not None:
        p, share, med = per
        clear = share >= PERIOD_SHARE and share >= PERIOD_CONTRAST * max(med, 1e-12)
        out["period"] = {"best_deg": round(p, 2), "share": round(share, 4), "median_share": round(med, 4),
                         "clear": bool(clear)}
    return out


def signature(fr, m, hand, joints=None) -> dict:
    """Per-joint signature of a fit's residual and a plain summary (module docstring).
    ``joints``: q columns to describe (default: every measured one)."""
    rows, jj, r = fit_cells(fr)
    d_all = m.direction
    per = {}
    for j, c in enumerate(Q_COLUMNS):
        if joints is not None and c not in joints:
            continue
        sel = jj == j
        if not sel.any():
            continue
        s = JOINT_SERVO[j]
        # the rows where the joint's own servo moves (other sweeps hold it still)
        rr = rows[sel]
        moving = np.flatnonzero(d_all[rr, s] != 0)
        if moving.size < 3:
            continue
        # a long recording: every k-th sample in row order (the features are averages over the
        # travel; a million samples add nothing but time)
        every = -(-moving.size // SIGNATURE_SAMPLES)
        moving = moving[::every]
        u = m.u[rr, s][moving] * DEG_PER_RAD
        per[c] = joint_signature(u, d_all[rr, s][moving], r[sel][moving],
                                 (float(hand.u_min[s] * DEG_PER_RAD), float(hand.u_max[s] * DEG_PER_RAD)),
                                 m.sweep[rr][moving])
        if every > 1:
            per[c]["every_kth_sample"] = int(every)
    summary = _summary(per)
    return {"per_joint": per, **summary}


def _group_rms(per: dict, distal: bool) -> float | None:
    vals = [v["rms_deg"] for c, v in per.items() if (Q_COLUMNS.index(c) in DISTAL_JOINTS) == distal]
    return round(float(np.sqrt(np.mean(np.square(vals)))), 5) if vals else None


def _summary(per: dict) -> dict:
    """Whole-residual features and one or two plain sentences."""
    out: dict = {"mcp_rms_deg": _group_rms(per, False), "distal_rms_deg": _group_rms(per, True)}
    sentences = []
    if per and not any(v["both_directions"] for v in per.values()):
        out["direction"] = "one direction only"
        sentences.append("the data move in one direction only: direction-dependent physics (friction, backlash) "
                         "cannot be seen; record the return sweep too")
    periodic = {c: v["period"]["best_deg"] for c, v in per.items() if v.get("period", {}).get("clear")}
    if periodic:
        ps = np.array(list(periodic.values()))
        out["periodic"] = {"period_deg": round(float(np.median(ps)), 2), "joints": sorted(periodic, key=Q_COLUMNS.index)}
        # whether an effect predicts it is the match's to say (signature_report knows the registry)
        sentences.append(f"the residual is periodic in u with period {np.median(ps):.0f} deg on "
                         f"{', '.join(out['periodic']['joints'])}: look at the servo horn / pulley eccentricity")
    flip = {c: v for c, v in per.items() if "direction_flipping_rms_deg" in v}
    if flip:
        odd = float(np.sqrt(np.mean([v["direction_flipping_rms_deg"] ** 2 for v in flip.values()])))
        even = float(np.sqrt(np.mean([v["direction_independent_rms_deg"] ** 2 for v in flip.values()])))
        out["direction_flipping_rms_deg"], out["direction_independent_rms_deg"] = round(odd, 5), round(even, 5)
        if odd > even:
            sentences.append(f"the residual flips with the direction of motion (RMS {odd:.2f} deg flipping vs "
                             f"{even:.2f} deg not): hysteresis, friction or backlash")
    mcp, dist = out["mcp_rms_deg"], out["distal_rms_deg"]
    if mcp is not None and dist is not None and not periodic:
        if dist > 2 * mcp:
            sentences.append(f"it sits on the distal joints (RMS {dist:.2f} deg) more than on the MCP/MP/CMC "
                             f"({mcp:.2f} deg): the coupling (tendon stretch) rather than the drive")
        elif mcp > 2 * dist:
            sentences.append(f"it sits on the MCP/MP/CMC (RMS {mcp:.2f} deg) more than on the distal joints "
                             f"({dist:.2f} deg): the drive (servo, pulley, guide) rather than the coupling")
    rests = [abs(v["at_rest_deg"]) for v in per.values() if v.get("at_rest_deg") is not None]
    trends = [v.get("trend_share", 0.0) for v in per.values()]
    if not periodic and trends and np.median(trends) > 0.5:
        sentences.append("it grows in proportion to the servo angle (a gain or radius error, or a stretch)")
    elif not periodic and rests and np.median(rests) > 0.5 * np.median([v["rms_deg"] for v in per.values()]):
        sentences.append("it is present at rest (an offset)")
    out["sentences"] = sentences
    return out


# ---------------------------------------------------------------------------
# the measured signature against the one an effect declares (effects.Signature)
# ---------------------------------------------------------------------------

#: how each feature value reads in a sentence
FEATURE_WORDS = {
    ("direction", "flips"): "it flips with the direction of motion",
    ("direction", "same"): "it is the same in both directions",
    ("at_rest", "zero"): "it vanishes at rest (the start of the travel)",
    ("at_rest", "nonzero"): "it is present at rest",
    ("trend", "grows"): "it grows with the servo angle (tension)",
    ("trend", "flat"): "it is flat over the travel",
    ("joints", "all"): "it is on the MCP and the distal joints alike",
    ("joints", "distal"): "it is on the distal joints (PIP, DIP, IP), not the MCP",
    ("joints", "mcp"): "it is on the MCP/MP/CMC, not the distal joints",
    ("periodic", False): "it is not periodic in u",
    ("reversal", "jump"): "it jumps after each reversal",
    ("reversal", "none"): "it passes through reversals without a jump",
    ("digits", "all"): "it is on every digit measured",
}
#: what to look at when a measured feature is one no library effect declares
FEATURE_HINTS = {
    "periodic": "look at the servo horn / pulley eccentricity",
    "joints": "a measurement-side error (camera scale or offset on those joints) or the guide geometry (d1, d2, alpha)",
    "reversal": "history after a reversal: backlash / a dead band in the drive",
    "direction": "friction or backlash (direction-dependent physics)",
    "digits": "a per-digit effect (one tendon's slack, pulley radius or compliance)",
}


def _word(key, value, measured: dict | None = None) -> str:
    if key == "digits" and value in ("one", "some"):
        which = ", ".join((measured or {}).get("digits_with_structure", []))
        return f"it is on {'one digit' if value == 'one' else 'some digits'} only" + (f" ({which})" if which else "")
    if key == "periodic" and value is True:
        period = (measured or {}).get("period_deg")
        return f"the residual is periodic in u with period {period:.0f} deg" if period else "the residual is periodic in u"
    return FEATURE_WORDS.get((key, value), f"{key}: {value}")


def measured_features(sig: dict, joints, noise: NoiseFloor) -> dict | None:
    """The features of a residual's signature (``sig`` = :func:`signature`'s output) over the
    structured ``joints`` (q columns beyond the noise), in the vocabulary of effects.Signature.
    A feature the data cannot show is "unknown" (one-direction data: direction and reversal). None
    when no joint has structure."""
    per = sig["per_joint"]
    J = [c for c in joints if c in per]
    if not J:
        return None
    sd = {c: noise.sigma_deg.get(c, float("nan")) for c in per}
    out: dict = {"joints_used": J}
    # direction: the flipping part against the part that does not flip, pooled over J
    both = [c for c in J if "direction_flipping_rms_deg" in per[c]]
    if both:
        odd = math.sqrt(np.mean([per[c]["direction_flipping_rms_deg"] ** 2 for c in both]))
        even = math.sqrt(np.mean([per[c]["direction_independent_rms_deg"] ** 2 for c in both]))
        # noise on a bin's half difference: sigma / sqrt(2 x samples per bin and direction)
        floor = np.mean([sd[c] / math.sqrt(max(per[c]["n"] / (2 * DIRECTION_BINS), 1.0)) / math.sqrt(2) for c in both])
        flips = odd > even and odd > FEATURE_SIGMAS * floor
        out["direction"] = "flips" if flips else "same"
    else:
        out["direction"] = "unknown"
    # at rest
    votes = []
    for c in J:
        v = per[c]
        thr = max(0.5 * v["rms_deg"], FEATURE_SIGMAS * sd[c] / math.sqrt(max(v["at_start_n"], 1)))
        votes.append(abs(v["at_start_deg"]) > thr)
    out["at_rest"] = "nonzero" if 2 * sum(votes) > len(votes) else "zero"
    # trend of the main part: the band's width when it flips, else the residual itself
    key = "flip_growth" if out["direction"] == "flips" else "growth"
    g = [per[c][key] for c in J if per[c].get(key) is not None]
    out["trend"] = ("grows" if float(np.median(g)) > GROWTH else "flat") if g else "unknown"
    out["growth"] = round(float(np.median(g)), 3) if g else None
    # MCP vs distal, over the chains with structure, less the noise
    servos = {int(JOINT_SERVO[Q_COLUMNS.index(c)]) for c in J}
    groups = {True: [], False: []}
    for c, v in per.items():
        j = Q_COLUMNS.index(c)
        if int(JOINT_SERVO[j]) in servos:
            groups[j in DISTAL_JOINTS].append(max(0.0, v["rms_deg"] ** 2 - sd[c] ** 2))
    if groups[True] and groups[False]:
        dist, mcp = math.sqrt(np.mean(groups[True])), math.sqrt(np.mean(groups[False]))
        out["joints"] = "distal" if dist > 2 * mcp else "mcp" if mcp > 2 * dist else "all"
        out["distal_structured_rms_deg"], out["mcp_structured_rms_deg"] = round(dist, 5), round(mcp, 5)
    else:
        out["joints"] = "unknown"
    # periodic
    periodic = [per[c]["period"]["best_deg"] for c in J if per[c].get("period", {}).get("clear")]
    out["periodic"] = 2 * len(periodic) > len(J)
    if out["periodic"]:
        out["period_deg"] = round(float(np.median(periodic)), 2)
    # a jump after the reversals
    rev = [c for c in J if "reversal_jump_deg" in per[c]]
    if rev:
        jumps = [per[c]["reversal_jump_deg"] > FEATURE_SIGMAS * sd[c] * math.sqrt(2.0 / REVERSAL_SAMPLES) for c in rev]
        out["reversal"] = "jump" if 2 * sum(jumps) > len(jumps) else "none"
    else:
        out["reversal"] = "unknown"
    # spread across the tendon-driven digits that were measured: on every one, on some, on one
    measured = {int(JOINT_SERVO[Q_COLUMNS.index(c)]) for c in per} - {CMC_SERVO}
    structured = sorted({int(JOINT_SERVO[Q_COLUMNS.index(c)]) for c in J} - {CMC_SERVO})
    if len(measured) < 2 or not structured:
        out["digits"] = "unknown"
    else:
        out["digits"] = ("all" if set(structured) == measured else "one" if len(structured) == 1 else "some")
        out["digits_with_structure"] = [SERVOS[k].digit for k in structured]
    return out


FEATURE_KEYS = ("direction", "at_rest", "trend", "joints", "periodic", "reversal", "digits")


def _predicts(leaves, key: str, value) -> bool:
    """Whether a declared signature (or None) predicts a measured feature value. A per-digit effect
    declares digits "any" (its parameters sit on any subset of the digits): it predicts "one" and
    "some" as well; for the other features "any" only does not contradict."""
    if leaves is None:
        return False
    declared = getattr(leaves, key)
    return declared == value or (key == "digits" and declared == "any" and value != "unknown")


def compare_features(measured: dict, declared) -> dict:
    """Which measured features the declared signature (effects.Signature, or None) matches."""
    match, mismatch, unknown = [], [], []
    if declared is None:
        return {"declared": None, "matches": [], "mismatches": [], "unknown": list(FEATURE_KEYS)}
    for k in FEATURE_KEYS:
        mv, dv = measured.get(k, "unknown"), getattr(declared, k)
        if mv == "unknown":
            unknown.append(k)
        elif dv == "any" or mv == dv:
            match.append(k)
        else:
            mismatch.append(k)
    return {"declared": declared.to_json(), "matches": match, "mismatches": mismatch, "unknown": unknown}


def signature_report(measured: dict | None, best: str | None, registry: dict) -> dict | None:
    """The measured features against the best candidate's declared signature and against the
    whole library: which features match, which do not, which effects leave this signature, and the
    sentences to print."""
    if measured is None:
        return None
    out: dict = {"measured": {k: measured.get(k, "unknown") for k in FEATURE_KEYS},
                 "details": {k: v for k, v in measured.items() if k not in FEATURE_KEYS}}
    fits = [n for n, e in registry.items()
            if getattr(e, "leaves", None) is not None and not compare_features(measured, e.leaves)["mismatches"]]
    out["effects_with_this_signature"] = fits
    sentences = []
    if best is not None:
        cmp = compare_features(measured, getattr(registry.get(best), "leaves", None))
        out["best_candidate"] = best
        out.update(cmp)
        if cmp["declared"] is None:
            sentences.append(f"{best} declares no signature (Effect.leaves): its features cannot be compared")
        else:
            # the features no library effect predicts first: they say most about what is missing
            def predicted(k):
                return any(_predicts(getattr(e, "leaves", None), k, measured[k]) for e in registry.values())
            for k in sorted(cmp["mismatches"], key=predicted):
                said = _word(k, measured[k], measured)
                decl = _word(k, getattr(registry[best].leaves, k))
                others = [n for n, e in registry.items() if _predicts(getattr(e, "leaves", None), k, measured[k])]
                if others:
                    sentences.append(f"does not match {best}, whose residual {decl[3:] if decl.startswith('it ') else decl}: "
                                     f"{said}; {', '.join(others)} predict{'s' if len(others) == 1 else ''} that")
                else:
                    sentences.append(f"does not match {best}: {said}: no library effect predicts that; "
                                     f"{FEATURE_HINTS.get(k, 'consider your own effect (docs/effects.md)')}")
            if cmp["matches"]:
                sentences.append(f"matches {best}: " + "; ".join(_word(k, measured[k], measured) for k in cmp["matches"]))
            if cmp["unknown"]:
                sentences.append("cannot be seen in these data: " + ", ".join(cmp["unknown"]))
    if not fits:
        sentences.append("no single library effect leaves this signature (two effects at once, or one outside the library)")
    elif best is not None and best not in fits:
        sentences.append(f"the library effects whose declared signature matches: {', '.join(fits)}")
    elif best is None:
        sentences.append(f"the library effects whose declared signature matches: {', '.join(fits)}")
    out["sentences"] = sentences
    return out


__all__ = ["joint_signature", "signature", "measured_features", "compare_features", "signature_report"]
