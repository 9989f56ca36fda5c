"""The words of the calibration commands, as lines: the text ``compare`` and ``diagnose`` print (and
put in their report.md) from the metrics and the diagnosis, the outliers' line, and the header
``fit`` writes atop the calibrated file (and prints). The pictures and the report.md around the
text are report.py's; the CLI prints and writes what these return.
"""

from __future__ import annotations

from ..errors import one_line
from ..kinematics.topology import JOINT_NAMES, Q_COLUMNS
from .diagnose import OUTLIER_SIGMAS, ROBUST_SCALE, mae
from .framework import MEASUREMENT, get_effect
from .identify import combinations


def compare_text(m, mb, ma, label, fitted) -> list[str]:
    """The table ``compare`` prints: MAE / RMS / max per joint of the analytic model (``mb``, report.metrics)
    and, with ``ma``, of the model ``label``; the fitted values of ``fitted`` (a FitResult) if any."""
    out = [f"{len(m)} rows, {mb['overall']['n']} measured angles; residual = measured - model, degrees",
           f"{'joint':18s} {'analytic MAE':>12s} {'RMS':>7s} {'max':>7s}" +
           (f"   {'after MAE':>10s} {'RMS':>7s} {'max':>7s}" if ma else "")]
    for c, v in mb["per_joint"].items():
        name = f"{c} {JOINT_NAMES[Q_COLUMNS.index(c)]}"
        row = f"{name:18s} {v['mae']:12.3f} {v['rms']:7.3f} {v['max']:7.3f}"
        if ma:
            a = ma["per_joint"][c]
            row += f"   {a['mae']:10.3f} {a['rms']:7.3f} {a['max']:7.3f}"
        out.append(row)
    o = mb["overall"]
    row = f"{'overall':18s} {o['mae']:12.3f} {o['rms']:7.3f} {o['max']:7.3f}"
    if ma:
        a = ma["overall"]
        row += f"   {a['mae']:10.3f} {a['rms']:7.3f} {a['max']:7.3f}"
    out.append(row)
    if ma:
        out.append(f"after = {label}")
    if fitted is not None:
        vals, errs = fitted.values(), fitted.uncertainties()
        for n in vals:
            for k, v in vals[n].items():
                out.append(f"  {n}.{k} = {v:.5g} {plus_minus(errs[n][k])}")
    return out


def plus_minus(std: float) -> str:
    """``+- 0.012``, or what a NaN standard deviation means (calibration/identify.py)."""
    return f"+- {std:.2g}" if std == std else "(not identifiable alone: see the combination below)"


def diagnosis_text(d, result) -> list[str]:
    """What ``diagnose`` prints of the diagnosis ``d`` and its JSON ``result`` (``d.to_json()``)."""
    out = [f"{result['rows']} rows, {result['measured_cells']} measured angles",
           f"MAE of the analytic model: {result['mae_deg_before']:.3f} deg; with the selected effects: "
           f"{result['mae_deg_after']:.3f} deg", ""]
    out.append("candidates, first round (dIC < 0 and held-out ratio < 0.99 pass):")
    out.append(f"  {'effect':22s} {'dIC':>10s} {'RSS ratio':>10s} {'held-out':>9s} {'n_eff':>8s} {'pass':>5s}")
    for c in d.ranking:
        held = f"{c.heldout_ratio:9.4f}" if c.heldout_ratio == c.heldout_ratio else f"{'-':>9s}"
        out.append(f"  {c.effect:22s} {c.delta_ic:10.1f} {c.rss_ratio:10.4f} {held} "
                   f"{c.n_eff:8.0f} {'yes' if c.passes else 'no':>5s}")
    out.append("")
    if not d.selected:
        out.append("selected: nothing (no library effect passes)")
    for name in d.selected:
        eff = get_effect(name)
        side = result["effects"][name]["side"]
        out.append(f"selected: {name}" + (" (measurement side: an error of the data, not of the hand; the "
                                          "control law never uses it)" if side == "measurement" else ""))
        out.append(f"  why: {eff.explanation}")
        for k, v in result["effects"][name]["parameters"].items():
            out.append(f"  {name}.{k} = {v['value']:.5g} " + (f"+- {v['std']:.2g}" if v["identifiable"]
                                                             else "(not identifiable alone: see below)"))
    for a in result["ambiguities"]:
        if a.get("kind") == "hand_or_measurement":
            out.append(hand_or_measurement_text(a))
            continue
        out.append(f"ambiguous (round {a['round']}): {a['effects'][0]} and {a['effects'][1]} explain the residual "
                   f"equally well (dIC {a['delta_ic'][0]:.1f} vs {a['delta_ic'][1]:.1f}); kept {a['effects'][0]}. "
                   f"To separate them: {a['experiment']}")
    for c in result["identifiability"]:
        out.append(c["text"])
    for n in d.notes:
        out.append(f"note: {n}")
    out.append("")
    out.append(f"{'joint':18s} {'MAE before':>10s} {'after':>8s} {'noise floor':>11s} {'tolerance':>9s}  (deg)")
    verdict = result["verdict"]["per_joint"]
    for c, v in result["per_joint"].items():
        row = f"{c + ' ' + JOINT_NAMES[Q_COLUMNS.index(c)]:18s} {v['before']:10.3f} {v['after']:8.3f}"
        if c in verdict:
            row += (f" {result['noise_floor_per_joint_deg'][c]:11.3f} {verdict[c]['tolerance_deg']:9.3f}"
                    f"{'' if verdict[c]['consistent'] else '  structure left'}")
        if c in result["made_worse"]:
            row += "  made worse"
        out.append(row)
    out.append("")
    out.extend(verdict_lines(result))
    if result["outliers_count"]:
        out.append(outlier_text(result["outliers"], result["robust"], result["outliers_count"]))
    return out


def hand_or_measurement_text(a: dict) -> str:
    """The sentence of a hand effect kept over a measurement effect that explains the data as well."""
    kept, gone, mae = a["kept"], a["withdrawn"], a["mae_deg"]
    joints = ", ".join(a["outside"]["joints"]) or "none measured"
    sig = a.get("signature")
    matched = (f"; the analytic model's residual has {kept}'s signature" if sig and not sig["mismatches"] else
               f"; the analytic model's residual differs from {kept}'s signature in: {', '.join(sig['mismatches'])}"
               if sig else "")
    return (f"both explain the data (round {a['round']}): {kept} (the hand; MAE {mae['with_hand_effect']:.3f} deg) "
            f"and {gone} (the measurement; MAE {mae['with_measurement_instead']:.3f} deg in its place). {gone} shows "
            f"nothing of its own on the joints {kept} cannot move ({joints}), so {kept} is kept: the control law "
            f"needs it{matched}. To separate them: {a['experiment']}")


def verdict_lines(result) -> list[str]:
    """The measured verdict and the residual's signature in plain sentences."""
    noise = result["noise"]
    model = " + ".join(result["selected"]) or "the analytic model"
    out = [f"noise floor estimated from the data (neighbouring samples, sample spacing "
           f"{noise['sample_spacing_deg']:.2f} deg of servo angle): {result['noise_floor_deg']:.3f} deg MAE"]
    if result["explained"]:
        out.append(f"explained: yes - the residual of {model} ({result['verdict']['overall']['mae_deg']:.3f} deg MAE"
                   f"{' without the outliers' if result['robust'] else ''}) is consistent "
                   f"with that noise overall and on every joint")
    else:
        left = result["left"]
        worst = sorted(left, key=lambda c: -left[c]["structured_rms_deg"])
        joints = ", ".join(f"{c} {left[c]['structured_rms_deg']:.2f}" for c in worst)
        overall = result["verdict"]["overall"]
        white = ("" if overall["white"] else
                 f"; neighbouring residuals are correlated: lag-1 autocorrelation {overall['autocorrelation']:.2f}, "
                 f"{overall['whiteness_z']:.1f} standard errors above white noise's 0")
        out.append(f"explained: no - {model} leaves structure beyond the noise "
                   f"(overall {overall['mae_deg']:.3f} deg MAE, consistent up to {overall['tolerance_deg']:.3f}{white}); "
                   f"RMS beyond the noise, deg: {joints or 'none per joint'}")
    for when, key in (("the analytic model's residual", "before"), ("what is left", "after")):
        sentences = result["signature"][key]["sentences"]
        if sentences and (key == "before" or (result["selected"] and not result["explained"])):
            out.append(f"signature of {when}: " + "; ".join(sentences))
        match = result["signature_match"].get(key)
        if match and (key == "before" or not result["explained"]):
            best = match.get("best_candidate")
            out.append(f"{when} against the signatures the effects declare"
                       f"{f' (best candidate: {best})' if best else ''}:")
            out.extend(f"  {t}" for t in match["sentences"])
    return out


def outlier_text(found: list[dict], robust: bool, count: int | None = None, shown: int = 10,
                 robust_note: str = "left out of the verdict") -> str:
    """One line naming the outliers (sweep, row, file line, joint, residual); ``count``: how many
    there are when ``found`` lists only the first ones; ``robust_note``: what a robust fit did with them."""
    count = len(found) if count is None else count
    items = ", ".join(f"sweep {o['sweep']} row {o['row']} (line {o['line']}) {o['joint']} {o['residual_deg']:+.2f}"
                      for o in found[:shown])
    more = f" and {count - min(shown, len(found))} more" if count > min(shown, len(found)) else ""
    return (f"outliers ({count} cells beyond {OUTLIER_SIGMAS:g} noise sd"
            f"{', ' + robust_note if robust else '; --robust keeps them from bending the fit'}): "
            f"{items}{more}")


def fit_header(first: str, params, rows: int, before, res, names: list[str], robust: bool,
               found: list[dict]) -> list[str]:
    """The comment lines ``fit`` writes atop the calibrated file (``first``: the marker line with the
    command): the source file, the MAE of the analytic model (``before``) and of the fit ``res``,
    each fitted value with its uncertainty, the measurement-side effects, the combinations that are
    identifiable only together, and the outliers ``found``."""
    vals, errs = res.values(), res.uncertainties()
    header = [first,
              f"# from {one_line(params.source)} (digest {params.digest[:12]}), {rows} rows.",
              f"# MAE {mae(before):.4f} deg (analytic) -> {mae(res):.4f} deg (with the effects).",
              "# Fitted on the analytic model; [effects.tendon_elasticity] compliance_per_m replaces k_s/EA",
              "# in the compensated model (0 when not fitted). Uncertainties (1 sd):"]
    for n in names:
        for k, v in vals[n].items():
            header.append(f"#   {n}.{k} = {v:.6g} {plus_minus(errs[n][k])}")
    for n in names:
        if get_effect(n).stage == MEASUREMENT:
            header.append(f"# {n} describes the measurement, not the hand: Hand.forward and the control law "
                          "never apply it (compare -p does).")
    for c in combinations(res):
        header.append(f"# {c.text()}")
    if robust or found:
        header.append(f"# {'Robust fit (soft_l1, scale ' + format(ROBUST_SCALE, 'g') + ' noise sd); ' if robust else ''}"
                      f"{len(found)} cells beyond the outlier limit ({OUTLIER_SIGMAS:g} noise sd).")
    return header
