"""The ``phantom-cad build`` command (registered by phantom_cad/cli/__init__.py) over
:func:`phantom_cad.export.pipeline.build_hand`.

Importing this module does not import build123d/OCP: the build imports them in its
worker processes.
"""

from pathlib import Path
from typing import Optional

import typer

from ..params.io import DEFAULT_PARAMS


def build(
    params: Path = typer.Option(DEFAULT_PARAMS, "--params", "-p", help="Parameter file (TOML) of the hand.",
                                show_default="params/phantom.toml"),
    out: Optional[Path] = typer.Option(None, "--out", "-o",
                                       help="Export directory (default exports/<hand.name>, "
                                            "exports/<hand.name>_<side> with a --side that differs "
                                            "from the file). Replaced only when the whole build succeeded."),
    side: Optional[str] = typer.Option(None, "--side", help="Override hand.side: right or left (mirrored parts)."),
    jobs: Optional[int] = typer.Option(None, "--jobs", "-j", min=1,
                                       help="Worker processes building parts (default: os.cpu_count())."),
    slice_: bool = typer.Option(False, "--slice/--no-slice",
                                help="Slice every STL with PrusaSlicer (headless) and record print time and "
                                     "filament in the manifest; about 1-4 s per part the first time, cached after."),
    render: bool = typer.Option(True, "--render/--no-render", help="Write PNG renders (renders/)."),
    cache_dir: Optional[Path] = typer.Option(None, "--cache-dir",
                                             help="Part cache (default $PHANTOM_CAD_CACHE or .cache)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Print only errors."),
) -> None:
    """Build every printable part of the hand: STEP, STL, assembly STEP, BOM, renders, manifest.

    Parts are cached by their inputs: a rebuild with unchanged parameters takes about a second, changing one finger rebuilds only its parts. Every part is checked (one valid solid, STEP re-import, watertight manifold STL, no unplanned interference, slicing) before anything is written. See docs/exports.md.
    """
    from ..calibration.effects import PARAMS_EFFECTS
    from ..errors import UserError, one_line
    from ..export.pipeline import BuildError, build_hand
    from ..params import ParamError

    def log(msg: str) -> None:
        if not quiet:
            typer.echo(msg, err=True)

    try:
        result = build_hand(params, out, side=side, jobs=jobs, slice=slice_, render=render,
                            cache_dir=cache_dir, log=log, effects=PARAMS_EFFECTS)
    except (ParamError, UserError) as exc:
        typer.echo(f"error: {one_line(exc)}", err=True)
        raise typer.Exit(2)
    except BuildError as exc:
        typer.echo(f"error: {one_line(exc)}", err=True)
        raise typer.Exit(1)
    if not quiet:
        typer.echo(result.summary())
        totals = result.manifest.get("totals", {})
        if "print_time_s" in totals:
            h, rem = divmod(int(totals["print_time_s"]), 3600)
            typer.echo(f"estimated print: {h} h {rem // 60} min, {totals['filament_g']:.0f} g filament "
                       f"(PrusaSlicer defaults; layer height and infill from params)")
        coupon = result.manifest.get("coupon", {})
        if coupon:
            est = coupon.get("print")
            when = f" ({est['time_s'] / 60:.0f} min, {est['filament_g']:.1f} g)" if est else ""
            typer.echo(f"print first: {result.out_dir / coupon['stl']}{when}, the fit-test coupon: tune [print] "
                       f"with it ({result.out_dir / coupon['sheet']})")
        gauge = result.manifest.get("gauge", {})
        if gauge:
            typer.echo(f"before calibrating: {result.out_dir / gauge['stl']}, the angle gauge: measure the camera's "
                       f"scale on it ({result.out_dir / gauge['sheet']}; docs/calibration.md)")


def main() -> None:  # pragma: no cover - convenience entry point: python -m phantom_cad.cli.build
    typer.run(build)


if __name__ == "__main__":  # pragma: no cover
    main()
