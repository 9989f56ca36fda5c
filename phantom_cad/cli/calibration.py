"""Command functions of the calibration workflow: simulate, compare, diagnose, fit.

Registered in phantom_cad/cli/__init__.py. None imports a CAD library. Bad input raises DataError,
ParamError or errors.UserError (printed as ``error: ...``, exit code 2).
"""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

ParamsOpt = typer.Option(None, "--params", "-p", help="Parameter file (default: params/phantom.toml).",
                         dir_okay=False)
DegreesOpt = typer.Option(False, "--degrees", help="Angles in the CSV are degrees.")
RobustOpt = typer.Option(False, "--robust", help="Robust fits (soft_l1 loss, scale 3 noise sd from the data); "
                         "cells beyond 5 noise sd are listed as outliers.")
PluginOpt = typer.Option(None, "--plugin", help="Python file that registers effects (@register_effect), "
                         "repeatable; see docs/effects.md.", dir_okay=False)


def _load_plugins(plugins: Optional[List[Path]]) -> list[str]:
    """Load every --plugin file (PluginError, exit 2, naming the file and line, on failure); return
    their absolute paths."""
    import os

    from ..calibration.effects import load_plugin

    out = []
    for p in plugins or []:
        load_plugin(p, "--plugin")
        out.append(os.path.abspath(p))
    return out


def _user_error(msg: str):
    from ..errors import UserError

    return UserError(msg)


def _effect_names(text: Optional[str], option: str = "--effects") -> list[str]:
    from ..calibration.effects import REGISTRY

    if text is None or text.strip().lower() in ("", "none"):
        return []
    names = [t.strip() for t in text.split(",") if t.strip()]
    for n in names:
        if n not in REGISTRY:
            raise _user_error(f"{option} {text}: unknown effect '{n}' (known: {', '.join(REGISTRY)}, or none)")
    if len(set(names)) != len(names):
        raise _user_error(f"{option} {text}: an effect is listed twice")
    return names


CSV_MARKER = "# phantom-cad "               # the first line of every CSV the commands write
JSON_MARKER = '{\n  "generator": "phantom-cad diagnose"'
FIT_MARKER = "# Calibrated by `phantom-cad fit"


def check_output(path: Optional[Path], marker: str, what: str) -> None:
    """Before any work: ``path`` is writable and new, or an earlier output of the same kind."""
    from ..atomic import check_file_replaceable

    if path is not None:
        check_file_replaceable(path, marker, what)


def _write_json(path: Path, obj) -> None:
    from ..atomic import write_json_atomic

    write_json_atomic(path, obj)


# -- simulate ---------------------------------------------------------------------

def simulate(
    out: Path = typer.Option(..., "--out", help="Measurement CSV to write.", dir_okay=False),
    params: Optional[Path] = ParamsOpt,
    effects: str = typer.Option("none", "--effects", help="Hidden effects, comma separated, or none."),
    noise_deg: float = typer.Option(0.1, "--noise-deg", help="Gaussian noise on every measured angle, degrees (sd)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the hidden magnitudes and of the noise."),
    points: int = typer.Option(50, "--points", help="Samples per direction per servo."),
    effect_param: Optional[List[str]] = typer.Option(
        None, "--effect-param", help="Explicit hidden value EFFECT.PARAM=VALUE (file units), repeatable; the "
                                     "effect's other parameters are then 0."),
    travel: float = typer.Option(1.0, "--travel", help="Fraction of each servo's travel to sweep."),
    measure: str = typer.Option("chain", "--measure", help="chain: record the swept servo's joints only; all: every joint."),
    joints: Optional[str] = typer.Option(None, "--joints", help="q columns to record, e.g. q3,q4,q5 (default all)."),
    degrees: bool = typer.Option(False, "--degrees", help="Write degrees instead of radians."),
    plugin: Optional[List[Path]] = PluginOpt,
):
    """Sweep every servo (flex, then extend, others at 0) and write what a hand with hidden effects would measure."""
    from .. import load_hand
    from ..calibration.data import write_measurements
    from ..calibration.labels import Labels
    from ..calibration.simulate import SimulationError, parse_effect_params, simulate as run

    check_output(out, CSV_MARKER, "a CSV written by phantom-cad")
    _load_plugins(plugin)
    hand = load_hand(params)
    names = _effect_names(effects)
    cols = None if joints is None else [c.strip() for c in joints.split(",") if c.strip()]
    try:
        sim = run(hand, names, noise_deg=noise_deg, seed=seed, points=points,
                  explicit=parse_effect_params(effect_param), travel=travel, measure=measure, joints=cols)
    except SimulationError as exc:
        raise _user_error(str(exc)) from None
    m = sim.measurements
    hidden = "; ".join(f"{n}: " + ", ".join(f"{k}={v:.6g}" for k, v in kv.items()) for n, kv in sim.hidden.items())
    write_measurements(out, m.u, m.q, sweep=Labels(m.sweep_ids, m.sweep),
                       q_columns=m.q_columns, degrees=degrees,
                       comments=[f"phantom-cad simulate --effects {','.join(names) or 'none'} --noise-deg {noise_deg:g} "
                                 f"--seed {seed} --points {points}, params digest {hand.params.digest[:12]}, "
                                 f"{'degrees' if degrees else 'radians'}",
                                 f"hidden: {hidden or 'nothing (the analytic model)'}",
                                 f"noise floor (MAE of the noise alone): {sim.noise_mae_deg:.4f} deg"])
    typer.echo(f"wrote {len(m)} rows ({len(m.sweep_ids)} sweeps) to {out}")
    typer.echo(f"hidden: {hidden or 'nothing'}; noise floor {sim.noise_mae_deg:.4f} deg MAE")


# -- compare ----------------------------------------------------------------------

def compare(
    data: Path = typer.Argument(..., help="Measurement CSV.", dir_okay=False),
    params: Optional[Path] = ParamsOpt,
    effects: Optional[str] = typer.Option(
        None, "--effects", help="Effects to fit and add to the analytic model (comma separated); none: the analytic "
                                "model alone. Default: the parameter file's fitted effects, or else the compensated "
                                "model (the printed routing's statics)."),
    report: Optional[Path] = typer.Option(None, "--report", help="Folder for report.md, metrics.json and PNGs (a new "
                                          "folder, or an earlier report, which is replaced)."),
    compensation: Optional[str] = typer.Option(
        None, "--compensation", help="The compensated model without --effects: routed (the printed routing's "
                                     "statics, the default) or paper (eq. 11-14, as the paper's story)."),
    degrees: bool = DegreesOpt,
    plugin: Optional[List[Path]] = PluginOpt,
):
    """Residual = measured - model per joint: MAE / RMS / max before (analytic) and after (with the effects)."""
    from .. import load_hand
    from ..errors import UserError
    from ..calibration.data import read_measurements
    from ..calibration.effects import History, run_pipeline
    from ..calibration.diagnosis_text import compare_text
    from ..calibration.fitting import fit_effects
    from ..calibration.report import metrics

    _load_plugins(plugin)
    if compensation not in (None, "routed", "paper"):
        raise UserError(f"--compensation {compensation}: must be routed or paper")
    hand = load_hand(params)
    if compensation is not None and compensation != hand.compensation:
        if hand.effects:
            raise UserError(f"--compensation {compensation}: a calibrated file's effects build on the "
                            f"{hand.compensation} compensation")
        hand = load_hand(params, compensation=compensation)
    m = read_measurements(data, degrees=degrees).require_joints()
    q_before = run_pipeline(hand, [], m.u, None, 0.0)
    fitted = None
    if effects is not None:
        names = _effect_names(effects)
        if names:
            fitted = fit_effects(hand, m, names)
            q_after = fitted.model.predict_measurements(fitted.theta, m)
            label = "fitted " + " + ".join(names)
        else:
            q_after, label = None, None
    elif hand.effects:
        q_after = hand.effects.forward(hand, m.u, True, m.direction, History.of(m), measured=True)
        label = "calibrated (" + " + ".join(hand.effects.names) + ")"
    else:
        q_after = hand.forward(m.u, compensated=True)
        label = "compensated (the routed statics)" if hand.compensation == "routed" else "compensated (eq. 11-14)"
    mb = metrics(m, q_before)
    ma = metrics(m, q_after) if q_after is not None else None
    lines = compare_text(m, mb, ma, label, fitted)
    typer.echo("\n".join(lines))
    if report:
        from ..calibration.report import ReportDir, compare_markdown, plot_hysteresis, plot_mae, plot_residuals
        from ..calibration.residual import made_worse, noise_floor

        with ReportDir(report) as tmp:
            plot_residuals(tmp / "residual_before.png", m, q_before, "residual of the analytic model")
            bm = {c: v["mae"] for c, v in mb["per_joint"].items()}
            am = {c: v["mae"] for c, v in ma["per_joint"].items()} if ma else None
            noise = noise_floor(m)
            worse = made_worse(bm, am, noise.floor_deg, noise.cells) if am else []
            plot_mae(tmp / "mae.png", bm, am, ("analytic", label or ""), "MAE per joint", noise.floor_deg,
                     noise.overall_deg, worse)
            if q_after is not None:
                plot_residuals(tmp / "residual_after.png", m, q_after, f"residual, {label}")
                plot_hysteresis(tmp / "hysteresis.png", m, q_after, q_before, f"deviation from the analytic model: measured, {label}")
            else:
                plot_hysteresis(tmp / "hysteresis.png", m, q_before, q_before, "deviation from the analytic model")
            _write_json(tmp / "metrics.json", {"before": mb, "after": ma, "after_model": label})
            (tmp / "report.md").write_text(compare_markdown(m, hand.params.digest, lines, bm, am, label),
                                           encoding="utf-8")
        typer.echo(f"report in {report}")


# -- diagnose ---------------------------------------------------------------------

def diagnose(
    data: Path = typer.Argument(..., help="Measurement CSV.", dir_okay=False),
    params: Optional[Path] = ParamsOpt,
    report: Optional[Path] = typer.Option(None, "--report", help="Folder for report.md and PNGs (a new folder, or an "
                                          "earlier report, which is replaced)."),
    json_out: Optional[Path] = typer.Option(None, "--json", help="Write the result as JSON.", dir_okay=False),
    candidates: Optional[str] = typer.Option(None, "--candidates", help="Restrict the candidate effects (comma separated)."),
    robust: bool = RobustOpt,
    degrees: bool = DegreesOpt,
    plugin: Optional[List[Path]] = PluginOpt,
    jobs: Optional[int] = typer.Option(None, "--jobs", "-j", min=1,
                                       help="Worker processes for the candidate fits (default: the CPUs available; "
                                            "the result does not depend on it)."),
):
    """Which effect is missing? Score every effect of the library, add the ones the held-out data confirm."""
    from .. import load_hand
    from ..calibration.data import read_measurements
    from ..calibration.diagnose import diagnose as run
    from ..calibration.diagnosis_text import diagnosis_text

    check_output(json_out, JSON_MARKER, "a JSON written by phantom-cad diagnose")
    _load_plugins(plugin)
    hand = load_hand(params)
    m = read_measurements(data, degrees=degrees).require_joints()
    names = _effect_names(candidates, "--candidates") if candidates else None
    d = run(hand, m, names, robust=robust, jobs=jobs)
    result = d.to_json()
    text = diagnosis_text(d, result)
    typer.echo("\n".join(text))
    if json_out:
        _write_json(json_out, result)
        typer.echo(f"wrote {json_out}")
    if report:
        from ..calibration.report import ReportDir, diagnose_markdown, plot_hysteresis, plot_mae, plot_residuals

        before = {c: v["before"] for c, v in result["per_joint"].items()}
        after = {c: v["after"] for c, v in result["per_joint"].items()}
        q_before = d.before.model.predict_measurements(d.before.theta, m)
        q_after = d.after.model.predict_measurements(d.after.theta, m)
        label = " + ".join(d.selected) or "analytic"
        with ReportDir(report) as tmp:
            plot_residuals(tmp / "residual_before.png", m, q_before, "residual of the analytic model")
            plot_residuals(tmp / "residual_after.png", m, q_after, f"residual with {label}")
            plot_mae(tmp / "mae.png", before, after, ("analytic", f"with {label}"), "MAE per joint",
                     result["noise_floor_per_joint_deg"], result["noise_floor_deg"], result["made_worse"])
            plot_hysteresis(tmp / "hysteresis.png", m, q_after, q_before,
                            f"deviation from the analytic model: measured, and modelled with {label}")
            _write_json(tmp / "diagnosis.json", result)
            (tmp / "report.md").write_text(diagnose_markdown(m, hand.params.digest, text, before, after, label),
                                           encoding="utf-8")
        typer.echo(f"report in {report}")


# -- fit --------------------------------------------------------------------------

def fit(
    data: Path = typer.Argument(..., help="Measurement CSV.", dir_okay=False),
    effects: str = typer.Option(..., "--effects", help="Effects to fit, comma separated."),
    out: Path = typer.Option(..., "--out", help="Parameter file to write (e.g. params/calibrated.toml).", dir_okay=False),
    params: Optional[Path] = ParamsOpt,
    degrees: bool = DegreesOpt,
    plugin: Optional[List[Path]] = PluginOpt,
    robust: bool = RobustOpt,
):
    """Fit effect parameters and write a parameter file whose model (forward / inverse) uses them.

    The fit starts from the analytic model; the written file is the input file with its `effects` tables
    replaced by the fitted ones (tendon_elasticity written as 0 when not fitted: it replaces the
    k_s/EA (mechanics) of the compensated model and nothing else) and its ``plugins`` extended by
    the --plugin files (relative to the written file). Refused: an effect the control law cannot
    invert. The written file is loaded back and must reproduce the fit's prediction."""
    import os

    import numpy as np

    from .. import load_hand
    from ..params import dump_params
    from ..params.schema import plugin_paths
    from ..canon import plain
    from ..calibration.data import read_measurements
    from ..calibration.diagnosis_text import fit_header, outlier_text
    from ..calibration.effects import PARAMS_EFFECTS, History, get_effect, has_invert, validate_effects
    from ..errors import one_line
    from ..calibration.fitting import Model, Problem, fit as run_fit

    check_output(out, FIT_MARKER, "a parameter file written by phantom-cad fit")
    plugin_files = _load_plugins(plugin)
    hand = load_hand(params)
    names = _effect_names(effects)
    if not names:
        raise _user_error("--effects: name at least one effect to fit")
    for n in names:
        eff = get_effect(n)
        if not has_invert(eff):
            raise _user_error(f"--effects {effects}: effect '{n}' ({eff.stage} stage) has no invert(), so the control "
                              f"law (Hand.inverse) could not use the calibrated file; add invert(self, hand, value, x) "
                              f"to it (docs/effects.md), or use it with compare/diagnose only")
    m = read_measurements(data, degrees=degrees).require_joints()
    problem = Problem(hand, m)
    before = run_fit(Model(hand, [], problem), problem)
    from ..calibration.diagnose import ROBUST_SCALE, outliers
    from ..calibration.residual import MAE_PER_SIGMA, noise_floor

    noise = noise_floor(m)
    if robust:
        from ..calibration.fitting import robust_loss

        with robust_loss(ROBUST_SCALE * noise.overall_deg / MAE_PER_SIGMA):
            res = run_fit(Model(hand, names, problem), problem)
    else:
        res = run_fit(Model(hand, names, problem), problem)
    found = outliers(res, m, noise)
    vals = res.values()
    table = {n: {k: round(v, 9) for k, v in vals[n].items()} for n in names}
    if "tendon_elasticity" not in table:
        # the fit starts from the analytic model: a zero compliance keeps compensated=True consistent
        # with it (it replaces the base k_s/EA only; other tension-stage effects keep what they add)
        table["tendon_elasticity"] = {"compliance_per_m": 0.0}
    validate_effects(table, str(out))
    doc = plain(hand.params.document)
    doc["effects"] = table
    here = os.path.dirname(os.path.abspath(out))
    files = list(dict.fromkeys([*plugin_paths(hand.params.plugins, hand.params.source), *plugin_files]))
    if files:
        doc["plugins"] = [os.path.relpath(f, here) for f in files]
    else:
        doc.pop("plugins", None)
    command = (f"{one_line(data)} --effects {','.join(names)}" + (" --robust" if robust else "")
               + "".join(f" --plugin {one_line(p)}" for p in plugin or []))
    header = fit_header(f"{FIT_MARKER} {command}`", hand.params, len(m), before, res, names, robust, found)
    dump_params(doc, out, header="\n".join(header) + "\n\n", effects=PARAMS_EFFECTS)
    # the written file must load and reproduce the fit: no written effect may override another
    written = load_hand(out)
    q_fit = res.model.predict_measurements(res.theta, m)
    q_file = written.effects.forward(written, m.u, True, m.direction, History.of(m), measured=True)
    gap = float(np.nanmax(np.abs(q_file - q_fit)[np.isfinite(m.q)]))
    if gap > 1e-6:
        os.replace(out, str(out) + ".rejected")
        raise _user_error(f"{out}: the written effects ({', '.join(written.effects.names)}) do not reproduce the fit "
                          f"(up to {np.degrees(gap):.4f} deg apart): one of them overrides another; the file was "
                          f"moved to {out}.rejected")
    typer.echo("\n".join(h[2:] for h in header))
    if found:
        typer.echo(outlier_text(found, robust, robust_note="weighed about linearly"))
    typer.echo(f"wrote {out}")
