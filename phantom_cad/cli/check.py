"""The ``phantom-cad check`` command (registered by phantom_cad/cli/__init__.py) over
:func:`phantom_cad.export.check.check_export`. Imports the CAD and simulation stack inside the
command (it measures the exported solids)."""

from pathlib import Path
from typing import Optional

import typer

from ..params.io import DEFAULT_PARAMS


def check(
    params: Path = typer.Option(DEFAULT_PARAMS, "--params", "-p", help="Parameter file (TOML) of the hand.",
                                show_default="params/phantom.toml"),
    out: Optional[Path] = typer.Option(None, "--out", "-o",
                                       help="Export folder to check (default that of phantom-cad build); built "
                                            "first when missing or built from other parameters or by other code."),
    side: Optional[str] = typer.Option(None, "--side", help="Override hand.side: right or left."),
    samples: int = typer.Option(8, "--samples", min=1, help="Random servo commands for the pose checks."),
    settle: int = typer.Option(3, "--settle", min=0,
                               help="Of those, commands at which the MJCF is simulated to equilibrium (2 s each)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the random servo commands."),
    cache_dir: Optional[Path] = typer.Option(None, "--cache-dir",
                                             help="Part cache for a build (default $PHANTOM_CAD_CACHE or .cache)."),
    sweep: bool = typer.Option(True, "--sweep/--no-sweep",
                               help="Pose the parts over a grid of servo commands and measure that no two "
                                    "collide (about 15 s)."),
    slice_: Optional[bool] = typer.Option(None, "--slice/--no-slice",
                                          help="When the export is built first: slice it with PrusaSlicer, whose "
                                               "filament estimate gives the parts' masses the MuJoCo hold depends "
                                               "on (default: when prusa-slicer is installed)."),
    functional: bool = typer.Option(True, "--functional/--no-functional",
                                    help="The functional rows: opposition and the power grasp on the solids, the "
                                         "grasp held in MuJoCo, walls, tendon paths (docs/descriptions.md)."),
) -> None:
    """Check that the export's parts, URDF, MJCF and the kinematic model describe one mechanism.

    Prints one table (check, worst item, expected, measured, tolerance, ok): URDF and MJCF poses
    against the posed CAD assembly at random servo commands, joint angles against hand.forward,
    joint axes against the bearing bores measured in the STEP solids, inertials against the
    solids, meshes, URIs, check_urdf, MuJoCo's model test, and no two parts colliding over a grid of
    servo commands (the pinch contacts of the thumb with a finger are listed with where they begin);
    then what the hand must do: the thumb's pad reaching the index, middle and ring pads on the
    solids, a cylinder scaled with the hand (35 mm at 189 mm) enclosed on the solids and held palm
    down in MuJoCo, every wall two perimeters thick, every tendon path outside material. One row
    reports each fingertip's distance to the palm at full travel and never fails. Exit 0 when every
    row is ok, 1 on any failing row, 2 on an error. See docs/descriptions.md.
    """
    from ..calibration.effects import PARAMS_EFFECTS
    from ..errors import one_line
    from ..export.check import check_export, table
    from ..export.pipeline import BuildError, ensure_export

    def log(msg: str) -> None:
        typer.echo(msg, err=True)

    try:
        folder, hand_params = ensure_export(params, out, side, log, effects=PARAMS_EFFECTS, cache_dir=cache_dir,
                                            slice=slice_)
    except BuildError as exc:
        typer.echo(f"error: {one_line(exc)}", err=True)
        raise typer.Exit(1)
    rows = check_export(folder, hand_params, samples=samples, settle=settle, seed=seed, log=log, sweep=sweep,
                        functional=functional)
    typer.echo(f"{hand_params.name} ({hand_params.side}), params digest {hand_params.digest[:12]}, {folder}")
    typer.echo(table(rows))
    failed = [r for r in rows if r.ok is False]
    skipped = [r for r in rows if r.ok is None]
    typer.echo(f"{len(rows) - len(failed) - len(skipped)} ok, {len(failed)} failed, {len(skipped)} not run")
    if failed:
        raise typer.Exit(1)
