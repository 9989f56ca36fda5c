"""The ``phantom-cad pose`` command (registered by phantom_cad/cli/__init__.py): a named posture
through the control law (``phantom_cad.postures``; docs/postures.md). Builds no geometry: imports no
CAD library.

Exit codes: 0 the posture is reached (every joint within its tolerance, no refused contact); 3 it
is not (out of reach of the coupling, or refused at a contact: the output says which and by how
much); 2 bad input (one ``error:`` line)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

#: the exit code of a posture the hand does not make (1 is an internal error, 2 bad input)
NOT_REACHED = 3


def pose(
    name: Optional[str] = typer.Argument(None, help="The posture's name (--list shows them)."),
    params: Optional[Path] = typer.Option(None, "--params", "-p", help="Parameter file (default: "
                                          "params/phantom.toml).", dir_okay=False),
    postures: Optional[Path] = typer.Option(None, "--postures", help="A TOML file of more postures (a name "
                                            "in the library replaces the library's; docs/postures.md).",
                                            dir_okay=False),
    json_: bool = typer.Option(False, "--json", help="Print the result as JSON."),
    list_: bool = typer.Option(False, "--list", help="List the postures and exit."),
) -> None:
    """Servo commands for a named posture: the target clipped into the workspace, the control law,
    the joint angles the model gives and the error per joint; a posture that drives the thumb into
    a finger stops at the first contact or is refused, as it says. Exit 0 reached, 3 not."""
    from .. import load_hand
    from .. import postures as P
    from ..errors import UserError

    hand = load_hand(params)
    library = P.load(hand, postures)
    if list_:
        if json_:
            typer.echo(_json({n: {"description": p.description, "figure": p.figure, "source": p.source}
                              for n, p in library.items()}))
        else:
            width = max(map(len, library))
            for n, p in library.items():
                typer.echo(f"{n:{width}s}  {p.description}")
        return
    if name is None:
        raise UserError("pose: give a posture's name, or --list")
    if name not in library:
        raise UserError(f"pose: unknown posture {name!r} (known: {', '.join(library)})")
    result = P.pose(hand, library[name])
    typer.echo(_json(as_dict(result)) if json_ else "\n".join(lines(result)))
    if not result.reached:
        raise typer.Exit(NOT_REACHED)


def _json(obj) -> str:
    import json

    return json.dumps(obj, indent=2)


def verdict(r) -> str:
    """One line: reached, or why not and by how much."""
    from ..kinematics.topology import JOINT_NAMES
    from ..units import deg

    p = r.posture
    if r.refused:
        return (f"refused: on the way to these commands the thumb's tip meets the {r.contact.finger} fingertip "
                f"at {100 * r.contact.fraction:.1f} % from rest (the posture refuses contact)")
    if r.wrong_finger:
        return (f"not reached: the thumb's tip meets the {r.contact.finger} fingertip first "
                f"(at {100 * r.contact.fraction:.1f} % from rest), not the {p.finger} it is for")
    worst = JOINT_NAMES[r.worst]
    if r.reached:
        return f"reached: max error {deg(r.max_error):.2f} deg ({worst}) within the tolerance {deg(p.tolerance):g} deg"
    n = int((~r.within).sum())
    return (f"not reachable: max error {deg(r.max_error):.2f} deg ({worst}), {deg(r.max_error - p.tolerance):.2f} deg "
            f"beyond the tolerance {deg(p.tolerance):g} deg; {n} of 15 joints outside it")


def lines(r) -> list[str]:
    from ..kinematics.topology import JOINTS, SERVOS
    from ..units import deg

    p = r.posture
    fig = f" (the paper's Fig. 4, {p.figure})" if p.figure else ""
    out = [f"posture {p.name}{fig}: {p.description}", f"from {p.source}", ""]
    refused = "  (refused: not to be sent)" if r.refused else ""
    out.append(f"{'servo':22s} {'deg':>8s} {'rad':>9s}{refused}")
    for s in SERVOS:
        out.append(f"{s.label + ' ' + s.name:22s} {deg(r.u[s.index]):8.2f} {r.u[s.index]:9.4f}")
    out.append("")
    out.append(f"{'joint':12s} {'target':>7s} {'model':>7s} {'error':>7s}  (deg; model: hand.forward(u, compensated=True))")
    for j in JOINTS:
        i = j.index
        clip = "  clipped to the workspace" if abs(r.clipped[i] - p.target[i]) > 1e-12 else ""
        flag = "" if r.within[i] else "  outside the tolerance"
        out.append(f"{j.name:12s} {deg(p.target[i]):7.2f} {deg(r.q[i]):7.2f} {deg(r.error[i]):+7.2f}{flag}{clip}")
    out.append("")
    if r.contact is not None and not r.refused:
        out.append(f"contact: the thumb's tip meets the {r.contact.finger} fingertip at "
                   f"{100 * r.contact.fraction:.1f} % of the way from rest: the commands are stopped there")
    out.append(verdict(r))
    return out


def as_dict(r) -> dict:
    from ..kinematics.topology import JOINTS, SERVOS
    from ..units import deg

    p = r.posture
    return {
        "posture": p.name, "description": p.description, "figure": p.figure, "source": p.source,
        "tolerance_deg": deg(p.tolerance), "on_contact": p.on_contact, "finger": p.finger,
        "servos": {s.label: {"name": s.name, "deg": deg(float(r.u[s.index])), "rad": float(r.u[s.index])}
                   for s in SERVOS},
        "joints": {j.name: {"target_deg": deg(float(p.target[j.index])), "clipped_deg": deg(float(r.clipped[j.index])),
                            "model_deg": deg(float(r.q[j.index])), "error_deg": deg(float(r.error[j.index])),
                            "within": bool(r.within[j.index])} for j in JOINTS},
        "max_error_deg": deg(r.max_error),
        "contact": None if r.contact is None else {"finger": r.contact.finger, "fraction": r.contact.fraction,
                                                   "stopped": not r.refused},
        "refused": r.refused, "reached": r.reached, "verdict": verdict(r),
    }
