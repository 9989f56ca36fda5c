"""The ``phantom-cad grasp`` command (registered by phantom_cad/cli/__init__.py): the grasp library
simulated by MuJoCo on an export's MJCF (``phantom_cad.export.grasps``; docs/grasps.md). Imports the
CAD stack only when it has to build the export.

Exit codes: 0 it ran (a dropped object is a result, not an error); 2 bad input (one ``error:``
line); 1 a build that failed."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer


def grasp(
    name: Optional[str] = typer.Argument(None, help="The grasp's name (--list shows them)."),
    all_: bool = typer.Option(False, "--all", help="Every grasp of the library."),
    params: Optional[Path] = typer.Option(None, "--params", "-p", help="Parameter file (default: params/phantom.toml); "
                                          "its export is built first when missing (cached parts are reused).",
                                          dir_okay=False),
    export: Optional[Path] = typer.Option(None, "--export", help="An existing export folder to use (built from "
                                          "--params, on the side it records) instead of building one.",
                                          file_okay=False),
    grasps: Optional[Path] = typer.Option(None, "--grasps", help="A TOML file of more grasps (a name in the library "
                                          "replaces the library's; docs/grasps.md).", dir_okay=False),
    json_: bool = typer.Option(False, "--json", help="Print the results as JSON."),
    list_: bool = typer.Option(False, "--list", help="List the grasps and exit."),
) -> None:
    """Simulate grasps of the paper's Fig. 4 (14-29) in the MuJoCo twin: the object presented, the hand
    closing by its posture's servo commands, then gravity in six directions for 2 s each. Prints per
    grasp held or dropped per direction, the largest slip (mm) and the servo torques against their
    stall torque. Exit 0 when it ran."""
    import json

    from ..errors import UserError
    from ..export import grasps as G

    library = G.load(grasps)
    if list_:
        if json_:
            typer.echo(json.dumps({n: {"figure": g.figure, "category": g.category, "description": g.description,
                                       "source": g.source} for n, g in library.items()}, indent=2))
        else:
            width = max(map(len, library))
            for n, g in library.items():
                typer.echo(f"{n:{width}s}  {g.figure:2d}  {g.description}")
        return
    if (name is None) == (not all_):
        raise UserError("grasp: give a grasp's name or --all (--list shows them)")
    if name is not None and name not in library:
        raise UserError(f"grasp: unknown grasp {name!r} (known: {', '.join(library)})")
    hand, scene = _hand_and_scene(params, export)
    from .. import postures

    postures_ = postures.load(hand)
    chosen = list(library.values()) if all_ else [library[name]]
    results = []
    for g in chosen:
        G.commands(hand, g, postures_)      # a posture the library lacks: one error line before any simulation
    for g in chosen:
        results.append(G.run(scene, hand, g, postures_))
    if json_:
        typer.echo(json.dumps([G.as_dict(r) for r in results], indent=2))
        return
    typer.echo(f"{hand.params.name} ({hand.params.side}), {scene}")
    typer.echo(table([G.COLUMNS] + [G.row(r) for r in results]))
    typer.echo("")
    typer.echo(table([G.TORQUE_COLUMNS] + [G.torque_row(r) for r in results]))
    typer.echo(f"{sum(r.held for r in results)} of {len(results)} held in every direction "
               f"(held: touching the hand and within {G.HELD_MM:g} mm of where it was let go after "
               f"{G.HOLD_S:g} s)")


def table(rows) -> str:
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows)


def _hand_and_scene(params, export):
    """(the hand's model, its MJCF scene): ``export``'s, which must have been built from ``params``
    (the default file; the side the export records), or the export of ``params``, built first when
    missing (as ``phantom-cad check`` does)."""
    from .. import make_hand
    from ..calibration.effects import PARAMS_EFFECTS
    from ..errors import UserError, one_line
    from ..export.pipeline import BuildError, ensure_export, export_problem, load_build_params

    if export is not None:
        import json

        try:
            side = json.loads((export / "manifest.json").read_text(encoding="utf-8"))["hand"]["side"]
        except FileNotFoundError:
            raise UserError(f"--export {export}: no export there (no manifest.json)") from None
        except (OSError, ValueError, KeyError, TypeError):
            raise UserError(f"--export {export}: manifest.json is unreadable or records no hand side") from None
        path, _, hp, _ = load_build_params(params, side, PARAMS_EFFECTS)
        reason = export_problem(export, hp.digest, hp.side)
        if reason is not None:
            raise UserError(f"--export {export}: {reason}; give the parameter file it was built from with --params")
        return make_hand(hp), export / "description" / "mjcf" / "scene.xml"
    try:
        folder, hp = ensure_export(params, None, None, lambda m: typer.echo(m, err=True), effects=PARAMS_EFFECTS)
    except BuildError as exc:
        typer.echo(f"error: {one_line(exc)}", err=True)
        raise typer.Exit(1)
    return make_hand(hp), folder / "description" / "mjcf" / "scene.xml"
