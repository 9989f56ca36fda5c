"""The `phantom-cad` command line: thin commands over the library.

Commands that need no geometry (params, model, and the calibration commands) never
import a CAD library; `build` imports it inside its body.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Optional

import typer

from ..errors import UserError

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="The PHANTOM Hand from one parameter file: model, parts, calibration.")
params_app = typer.Typer(no_args_is_help=True, help="Show and validate parameter files.")
model_app = typer.Typer(no_args_is_help=True, help="The paper's kinematic model on measurement CSV files.")
app.add_typer(params_app, name="params")
app.add_typer(model_app, name="model")

ParamsOpt = typer.Option(None, "--params", "-p", help="Parameter file (default: params/phantom.toml).",
                         dir_okay=False)




# -- params --------------------------------------------------------------------

@params_app.command("validate")
def params_validate(files: list[Path] = typer.Argument(None, help="Parameter files (default: params/phantom.toml)."),
                    params: list[Path] = typer.Option(None, "--params", "-p", help="More parameter files.")):
    """Validate parameter files (every rule the build relies on); print OK or the first broken rule of each."""
    from ..cad import preflight
    from ..params import ParamError, load_params

    failed = 0
    for f in [*(files or []), *(params or [])] or [None]:
        try:
            p = load_params(f)
            preflight.check(p)
            typer.echo(f"OK {p.source} (digest {p.digest[:12]})")
        except ParamError as exc:
            typer.echo(f"FAIL {exc}", err=True)
            failed += 1
    if failed:
        raise typer.Exit(2)


@params_app.command("show")
def params_show(params: Optional[Path] = ParamsOpt):
    """Print the hand's derived quantities: L0, coupling vectors, workspace, servo travel."""
    from .. import load_hand

    typer.echo(describe(load_hand(params)))


def describe(hand) -> str:
    import numpy as np

    from ..kinematics.topology import JOINTS, SERVOS
    from ..units import deg, mm

    p = hand.params
    out = [f"hand {p.name} ({p.side}), {p.source}", f"digest {p.digest}",
           f"k_s = {p.mechanics.spring_k:g} N/m, EA = {p.mechanics.tendon_EA:g} N", ""]
    out.append(f"{'chain':8s} {'L0 mm':>7s} {'r mm':>6s} {'travel deg':>14s}  ideal A / compensated M^-1 A")
    for chain in p.chains:
        spec = chain.spec
        ideal = hand.coupling_ideal[spec.servo, list(spec.q_index)]
        comp = hand.coupling_compensated[spec.servo, list(spec.q_index)]
        pair = ", ".join(f"{j}: {a:.4f} / {c:.4f}" for j, a, c in zip(chain.joints, ideal, comp))
        travel = "[" + ", ".join(f"{deg(v):.1f}" for v in chain.travel) + "]"
        out.append(f"{spec.digit:8s} {mm(chain.guide.L0):7.3f} {mm(chain.servo_radius):6.2f} {travel:>14s}  {pair}")
    out.append("")
    lo, hi = hand.workspace(compensated=True)
    out.append(f"{'q':4s} {'joint':12s} {'limits rad':>16s} {'travel image (compensated) rad':>32s}")
    for j in JOINTS:
        i = j.index
        out.append(f"{j.label:4s} {j.name:12s} [{hand.q_min[i]:6.3f}, {hand.q_max[i]:6.3f}] "
                   f"{'':10s}[{lo[i]:6.3f}, {hi[i]:6.3f}]")
    out.append("")
    out.append("servos: " + ", ".join(f"{sv.label} {sv.name} [{deg(hand.u_min[sv.index]):.1f}, "
                                      f"{deg(hand.u_max[sv.index]):.1f}] deg" for sv in SERVOS))
    return "\n".join(out)


# -- model ---------------------------------------------------------------------

@model_app.command("forward")
def model_forward(
    inp: Path = typer.Option(..., "--in", help="CSV with columns u1..u6 (radians).", dir_okay=False),
    out: Path = typer.Option(..., "--out", help="CSV to write: u1..u6 and the model's q1..q15.", dir_okay=False),
    compensated: bool = typer.Option(False, "--compensated", help="Spring + tendon-elasticity compensation (eq. 11-14)."),
    degrees: bool = typer.Option(False, "--degrees", help="Angles in the input and output are degrees."),
    params: Optional[Path] = ParamsOpt,
):
    """Joint angles the model predicts for the servo angles of a measurement CSV."""
    from .. import load_hand
    from ..calibration.data import read_measurements, write_measurements

    hand = load_hand(params)
    m = read_measurements(inp, degrees=degrees, sweeps=False)
    q = hand.forward(m.u, compensated=compensated)
    sweep = [m.sweep_ids[k] for k in m.sweep] if m.has_sweep_column else None
    write_measurements(out, m.u, q, sweep=sweep, t=m.t, degrees=degrees,
                       comments=[f"phantom-cad model forward{' --compensated' if compensated else ''}, "
                                 f"params digest {hand.params.digest[:12]}, {'degrees' if degrees else 'radians'}"])
    typer.echo(f"wrote {len(m)} rows to {out}")


@model_app.command("inverse")
def model_inverse(
    inp: Path = typer.Option(..., "--in", help="CSV with columns q1..q15 (radians).", dir_okay=False),
    out: Path = typer.Option(..., "--out", help="CSV to write: u1..u6.", dir_okay=False),
    ideal: bool = typer.Option(False, "--ideal", help="Use the analytic model without compensation."),
    degrees: bool = typer.Option(False, "--degrees", help="Angles in the input and output are degrees."),
    params: Optional[Path] = ParamsOpt,
):
    """Servo angles of the control law (eq. 15) for target joint angles: clipped, projected, in travel."""
    import numpy as np

    from .. import load_hand
    from ..calibration.data import read_table, write_table
    from ..kinematics.topology import Q_COLUMNS, U_COLUMNS

    hand = load_hand(params)
    table = read_table(inp, required=Q_COLUMNS, optional=U_COLUMNS + ("t",), text_columns=("sweep",),
                       degrees=degrees)
    q = np.column_stack([table.values[c] for c in Q_COLUMNS])
    u = hand.inverse(q, compensated=not ideal)
    cols = {}
    if "sweep" in table.text:
        cols["sweep"] = table.text["sweep"]
    if "t" in table.values:
        cols["t"] = table.values["t"]
    cols.update({c: u[:, i] for i, c in enumerate(U_COLUMNS)})
    write_table(out, cols, degrees=degrees,
                comments=[f"phantom-cad model inverse{' --ideal' if ideal else ''}, "
                          f"params digest {hand.params.digest[:12]}, {'degrees' if degrees else 'radians'}"])
    typer.echo(f"wrote {len(table)} rows to {out}")


# -- demo ----------------------------------------------------------------------

@app.command("demo")
def demo(params: Optional[Path] = ParamsOpt,
         out: Optional[Path] = typer.Option(None, "--out", help="Export folder for the parts (default exports/<hand>)."),
         slice_: Optional[bool] = typer.Option(None, "--slice/--no-slice", show_default="slice when installed",
                                               help="Slice the parts with PrusaSlicer for print estimates "
                                                    "(cached). Default: when prusa-slicer is installed."),
         cache_dir: Optional[Path] = typer.Option(None, "--cache-dir",
                                                  help="Part cache (default $PHANTOM_CAD_CACHE or .cache).")):
    """The main job on the default hand: workspace, a forward/inverse round trip, and every printable part."""
    import numpy as np

    from .. import load_hand
    from ..export.slicer import find_slicer
    from ..params import DEFAULT_PARAMS

    hand = load_hand(params)
    typer.echo(describe(hand))
    u = np.linspace(hand.u_min, hand.u_max, 101)
    for compensated in (False, True):
        q = hand.forward(u, compensated=compensated)
        err = np.abs(hand.inverse(q, compensated=compensated) - u).max()
        typer.echo(f"round trip inverse(forward(u)) over the whole travel, "
                   f"{'compensated' if compensated else 'analytic'}: max |du| = {err:.2e} rad")
    typer.echo("")
    build(params=params or DEFAULT_PARAMS, out=out, side=None, jobs=None, slice_=slice_, render=True,
          cache_dir=cache_dir, quiet=False)
    if slice_ is None and find_slicer() is None:
        typer.echo("slicing skipped: prusa-slicer is not installed (as root: bash .ci/sysdeps, or apt-get install "
                   "prusa-slicer; then phantom-cad build --slice)")


# -- parts (phantom_cad/cad/cli.py; CAD is imported inside the command) -------------
from .build import build  # noqa: E402

app.command("build")(build)


# -- calibration (phantom_cad/calibration/cli.py) -------------------------------
from . import calibration as _calibration_cli  # noqa: E402  (numpy-free at import; no CAD)

app.command("simulate")(_calibration_cli.simulate)
app.command("compare")(_calibration_cli.compare)
app.command("diagnose")(_calibration_cli.diagnose)
app.command("fit")(_calibration_cli.fit)


def main() -> None:
    """Entry point: click handles usage errors and exit codes; our errors print one line, exit 2."""
    from ..calibration.data import DataError
    from ..params import ParamError

    try:
        app()
    except (ParamError, DataError, UserError) as exc:
        typer.echo(f"error: {exc}", err=True)
        sys.exit(2)


if __name__ == "__main__":
    main()
