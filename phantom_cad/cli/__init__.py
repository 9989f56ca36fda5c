"""The `phantom-cad` command line: thin commands over the library.

Commands that need no geometry (params, model, and the calibration commands) never
import a CAD library; `build` imports it inside its body.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Optional

import typer

from ..errors import UserError, one_line
from .calibration import CSV_MARKER, check_output

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="The PHANTOM Hand from one parameter file: model, parts, calibration.")
params_app = typer.Typer(no_args_is_help=True, help="Show and validate parameter files.")
model_app = typer.Typer(no_args_is_help=True, help="The paper's kinematic model on measurement CSV files.")
app.add_typer(params_app, name="params")
app.add_typer(model_app, name="model")

ParamsOpt = typer.Option(None, "--params", "-p", help="Parameter file (default: params/phantom.toml).",
                         dir_okay=False)




StrictOpt = typer.Option(False, "--strict", help="Refuse input outside the travel / workspace instead of warning.")
RANGE_TOL = 1e-6  # rad: a value written at the end of the travel and read back is inside


def _outside(values, lo, hi, columns, lines, path, degrees: bool, strict: bool, what: str, consequence: str) -> None:
    """Warn on stderr (or, ``strict``, refuse) when cells of ``values`` (rows x columns, radians)
    lie outside [lo, hi]; the message names the file, the first such line and column, the value
    and the range, in the file's unit."""
    import numpy as np

    from ..units import deg

    bad = (values < lo - RANGE_TOL) | (values > hi + RANGE_TOL)
    if not bad.any():
        return
    r, c = map(int, np.argwhere(bad)[0])
    show = deg if degrees else (lambda x: x)
    unit = "deg" if degrees else "rad"
    message = (f"{path}, line {int(lines[r])}, column {columns[c]}: {show(values[r, c]):.6g} {unit} is outside "
               f"[{show(lo[c]):.6g}, {show(hi[c]):.6g}] {unit}; {int(bad.any(axis=1).sum())} of {len(values)} rows "
               f"have {what}")
    if strict:
        raise UserError(message)
    typer.echo(f"warning: {one_line(message)}; {consequence} (--strict refuses such input)", err=True)


# -- params --------------------------------------------------------------------

@params_app.command("validate")
def params_validate(files: list[Path] = typer.Argument(None, help="Parameter files (default: params/phantom.toml)."),
                    params: list[Path] = typer.Option(None, "--params", "-p", help="More parameter files.")):
    """Validate parameter files (every rule the build relies on); print OK or, as an error line, the first
    broken rule of each."""
    from .. import load_params
    from ..cad import preflight
    from ..params import ParamError

    failed = 0
    for f in [*(files or []), *(params or [])] or [None]:
        try:
            p = load_params(f)
            preflight.check(p)
            typer.echo(f"OK {p.source} (digest {p.digest[:12]})")
        except ParamError as exc:
            typer.echo(f"error: {one_line(exc)}", err=True)
            failed += 1
    if failed:
        raise typer.Exit(2)


@params_app.command("show")
def params_show(params: Optional[Path] = ParamsOpt):
    """Print the hand's derived quantities: L0, coupling vectors, workspace, servo travel."""
    from .. import load_hand

    typer.echo(describe(load_hand(params)))


def describe(hand) -> str:
    from ..kinematics.topology import JOINTS, SERVOS
    from ..units import deg, mm

    p = hand.params
    m = p.mechanics
    out = [f"hand {p.name} ({p.side}), {p.source}", f"digest {p.digest}",
           f"k_s = {m.spring_k:g} N/m, EA = {m.tendon_EA:g} N, loop preload = {m.loop_preload:g} N, "
           f"compensation: {hand.compensation}", ""]
    comp_label = "routed (at rest)" if hand.compensation == "routed" else "the paper's M^-1 A"
    out.append(f"{'chain':8s} {'L0 mm':>7s} {'r mm':>6s} {'travel deg':>14s}  ideal A / compensated, {comp_label}")
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
    out += ["", *opposition_lines(hand)]
    return "\n".join(out)


def opposition_lines(hand, reach=None, oppose=None) -> list[str]:
    """The thumb pad's closest approach to each fingertip pad over the servo travel, and how squarely
    they meet (kinematics/opposition.py; docs/opposition.md); with ``oppose`` (rad), the pads'
    normals held within it of facing each other too."""
    import math

    from ..kinematics import opposition
    from ..kinematics.topology import CMC_SERVO, SERVOS, THUMB_CHAIN
    from ..units import deg, mm

    reach = opposition.reach(hand, oppose=oppose) if reach is None else reach
    # the thumb's two servos, in the order of reach()'s u_thumb
    u1, u6 = SERVOS[THUMB_CHAIN.servo].label, SERVOS[CMC_SERVO].label
    out = ["opposition (thumb pad to fingertip pad over the travel; pads <= 0 mm: they meet; margin: how far "
           f"inside the {deg(opposition.PAD_CONE):g} deg pad cone the contact direction stays"
           + ("" if oppose is None else f", the pads' normals within {deg(oppose):g} deg of facing each other")
           + "):"]
    for f, r in reach.items():
        pad = (f"pads {mm(r.gap):+.1f} mm at {u1} {deg(r.u_thumb[0]):.1f}, {u6} {deg(r.u_thumb[1]):.1f}, "
               f"{f} {deg(r.u_finger):.1f} deg" if math.isfinite(r.gap) else "the pads never face each other")
        squarely = (f"; margin {deg(r.margin):+.1f} deg at {u1} {deg(r.u_contact[0]):.1f}, "
                    f"{u6} {deg(r.u_contact[1]):.1f}, "
                    f"{f} {deg(r.u_contact[2]):.1f} deg" if math.isfinite(r.margin) else "")
        need = "" if f in opposition.OPPOSED else " (not required)"
        out.append(f"  {f:7s} {pad}{squarely}; tips on any side {mm(r.surface_gap):+.1f} mm{need}")
    return out


@params_app.command("opposition")
def params_opposition(params: Optional[Path] = ParamsOpt,
                      solve: bool = typer.Option(False, "--solve", help="Search the thumb's CMC placement that "
                                                 "maximizes the opposition margin (seconds) and print it as "
                                                 "parameter-file lines."),
                      pads_face: bool = typer.Option(False, "--pads-face", help="Count a contact only where the "
                                                     "pads' normals are within 30 deg of facing each other "
                                                     "too (docs/opposition.md, 'Pad to pad').")):
    """The thumb's reach to the fingertip pads; with --solve, the CMC placement that opposes index,
    middle and ring best (docs/opposition.md). Nothing is written: paste the printed lines."""
    import math

    from .. import load_hand
    from ..kinematics import opposition, thumb_placement
    from ..units import deg, mm

    hand = load_hand(params)
    p = hand.params
    typer.echo(f"{p.source}: CMC at {[round(mm(v), 2) for v in p.palm.thumb_cmc_offset]} mm, axis "
               f"{[round(deg(v), 2) for v in p.palm.thumb_cmc_axis]} deg")
    oppose = opposition.PAD_OPPOSE if pads_face else None
    typer.echo("\n".join(opposition_lines(hand, oppose=oppose)))
    if not solve:
        return
    from ..cad import preflight

    sol = thumb_placement.solve(hand, constraint=thumb_placement.thenar_constraint(p, floor=preflight.cmc_base_floor(p)),
                                oppose=oppose)
    b = thumb_placement.default_bounds(p)
    typer.echo("")
    typer.echo(f"solved ({sol.evaluations} evaluations; bounds: CMC "
               + ", ".join(f"{a} [{mm(lo):.1f}, {mm(hi):.1f}] mm" for a, (lo, hi) in zip("xyz", b.offset)) + "; "
               + ", ".join(f"{a} [{deg(lo):.0f}, {deg(hi):.0f}] deg"
                           for a, (lo, hi) in zip(("roll", "pitch", "yaw"), b.axis))
               + "):")
    typer.echo("\n".join(opposition_lines(hand, sol.reach, oppose)))
    verdict = ("the pads of index, middle and ring all meet" if math.isfinite(sol.margin) and sol.margin >= 0.0
               else "index, middle and ring are not all met pad to pad")
    palm = (f"stay {mm(-sol.intrusion):.1f} mm outside" if sol.intrusion <= 0.0
            else f"reach {mm(sol.intrusion):.1f} mm into")
    thenar = ("the palm's thenar holds it within a palm of human breadth" if sol.violation <= 0.0
              else f"the palm's thenar misses it by {mm(sol.violation):.1f} mm")
    typer.echo(f"margin {deg(sol.margin):+.1f} deg ({verdict}); the thumb's links {palm} the palm envelope; "
               f"{thenar}")
    typer.echo("")
    typer.echo("[palm]")
    # four decimals: the margin of a solved placement can sit on the edge of the command grid's
    # contact band, where a change of 0.01 mm or deg moves it by degrees (docs/opposition.md)
    typer.echo(f"thumb_cmc_offset_mm = [{', '.join(f'{mm(v):.4f}' for v in sol.offset)}]"
               f"  # solved: opposition margin {deg(sol.margin):+.1f} deg (phantom-cad params opposition --solve)")
    typer.echo(f"thumb_cmc_axis_deg = [{', '.join(f'{deg(v):.4f}' for v in sol.axis)}]")
    # the placement moves the palm's back face and the servos behind it, toward which the finger
    # drives' coupler bores run below the magnet pockets: lift them as `phantom-cad size` does
    from ..params import DEFAULT_PARAMS, load_document
    from ..sizing import magnet_lift

    doc = load_document(p.source or DEFAULT_PARAMS)
    doc["palm"]["thumb_cmc_offset_mm"] = [round(mm(v), 4) for v in sol.offset]
    doc["palm"]["thumb_cmc_axis_deg"] = [round(deg(v), 4) for v in sol.axis]
    magnet_lift(doc)
    typer.echo(f"magnet_lift_mm = {doc['palm'].get('magnet_lift_mm', 0.0):g}"
               "  # the pockets' lift this placement needs (as phantom-cad size solves it)")


# -- model ---------------------------------------------------------------------

@model_app.command("forward")
def model_forward(
    inp: Path = typer.Option(..., "--in", help="CSV with columns u1..u6 (radians).", dir_okay=False),
    out: Path = typer.Option(..., "--out", help="CSV to write: u1..u6 and the model's q1..q15.", dir_okay=False),
    compensated: bool = typer.Option(False, "--compensated", help="Compensated: the printed routing's statics (return-cord tension, the loops' and the drive's stretch; docs/transmission.md); with fitted effects in the file, the paper's eq. 11-14 and the effects."),
    degrees: bool = typer.Option(False, "--degrees", help="Angles in the input and output are degrees."),
    strict: bool = StrictOpt,
    params: Optional[Path] = ParamsOpt,
):
    """Joint angles the model predicts for the servo angles of a measurement CSV.

    Servo angles outside the travel in the parameter file are extrapolated with a warning
    (refused with --strict)."""
    from .. import load_hand
    from ..calibration.data import read_measurements, write_measurements
    from ..calibration.labels import Labels
    from ..kinematics.topology import U_COLUMNS

    check_output(out, CSV_MARKER, "a CSV written by phantom-cad")
    hand = load_hand(params)
    m = read_measurements(inp, degrees=degrees, sweeps=False)
    _outside(m.u, hand.u_min, hand.u_max, U_COLUMNS, m.lines, inp, degrees, strict,
             "servo angles outside the travel", "the model extrapolates there")
    q = hand.forward(m.u, compensated=compensated)
    sweep = Labels(m.sweep_ids, m.sweep) if m.has_sweep_column else None
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
    strict: bool = StrictOpt,
    params: Optional[Path] = ParamsOpt,
):
    """Servo angles of the control law (eq. 15) for target joint angles: clipped, projected, in travel.

    Targets outside the workspace (what the travel reaches) are clipped with a warning (refused
    with --strict)."""
    import numpy as np

    from .. import load_hand
    from ..calibration.data import read_table, write_table
    from ..kinematics.topology import Q_COLUMNS, U_COLUMNS

    check_output(out, CSV_MARKER, "a CSV written by phantom-cad")
    hand = load_hand(params)
    table = read_table(inp, required=Q_COLUMNS, optional=U_COLUMNS + ("t",), text_columns=("sweep",),
                       degrees=degrees)
    q = np.column_stack([table.values[c] for c in Q_COLUMNS])
    lo, hi = hand.workspace(compensated=not ideal)
    _outside(q, lo, hi, Q_COLUMNS, table.lines, inp, degrees, strict,
             "joint targets outside the workspace", "the control law clips them to the travel")
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
from .view import view  # noqa: E402
app.command("view")(view)
from .check import check  # noqa: E402

app.command("check")(check)
from .size import size as _size  # noqa: E402

app.command("size")(_size)
from .pose import pose as _pose  # noqa: E402

app.command("pose")(_pose)

from .force import force as _force  # noqa: E402

app.command("force")(_force)
from .drive import drive_app as _drive_app  # noqa: E402

app.add_typer(_drive_app, name="drive")

from .retarget import retarget as _retarget  # noqa: E402

app.command("retarget")(_retarget)
from .grasp import grasp as _grasp  # noqa: E402

app.command("grasp")(_grasp)


def main(argv: Optional[list[str]] = None) -> None:
    """Entry point. Every failure is one line on stderr and nothing else:

    - our errors (a bad parameter file, CSV, option value or output path) and click's usage errors
      (unknown option, value of the wrong type): ``error: ...``, exit 2;
    - an operating-system error nothing else caught (disk full, a file vanishing under us):
      ``error: <path>: <reason>``, exit 2;
    - a defect of phantom-cad itself: ``error: internal error ...``, exit 1; ``PHANTOM_CAD_DEBUG=1``
      shows its traceback.
    """
    import os

    from ..calibration.data import DataError
    from ..params import ParamError

    def fail(message: str, code: int = 2) -> None:
        typer.echo(f"error: {one_line(message)}", err=True)
        sys.exit(code)

    try:
        code = app(args=argv, standalone_mode=False)
    except (ParamError, DataError, UserError) as exc:
        fail(str(exc))
    except typer.Abort:
        fail("interrupted", 130)
    except typer.TyperException as exc:  # click's usage errors: unknown option, bad value, missing argument
        ctx = getattr(exc, "ctx", None)
        if type(exc).__name__ == "NoArgsIsHelpError":  # a command group alone: its help, as click prints it
            typer.echo(exc.format_message())
            sys.exit(2)
        where = f"{ctx.command_path}: " if ctx is not None else ""
        hint = f" (see '{ctx.command_path} --help')" if ctx is not None else ""
        fail(f"{where}{exc.format_message()}{hint}")
    except KeyboardInterrupt:
        fail("interrupted", 130)
    except OSError as exc:
        if os.environ.get("PHANTOM_CAD_DEBUG"):
            raise
        where = f"{exc.filename}: " if exc.filename else ""
        fail(f"{where}{exc.strerror or exc}")
    except Exception as exc:
        if os.environ.get("PHANTOM_CAD_DEBUG"):
            raise
        fail(f"internal error ({type(exc).__name__}: {exc}); please report it with the command that caused it "
             "(PHANTOM_CAD_DEBUG=1 shows the traceback)", 1)
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":
    main()
