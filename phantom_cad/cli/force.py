"""The ``phantom-cad force`` command (registered by phantom_cad/cli/__init__.py): each digit's
fingertip force against a plate at its pad, its servo stalled (``kinematics.force``,
docs/force.md). Builds no geometry: imports no CAD library."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

#: the paper's Table II: mean fingertip force (N) of five trials per digit, measured with a force gauge
TABLE_II = {"thumb": 3.35, "index": 2.87, "middle": 2.51, "ring": 2.73, "pinky": 2.33}


def _angles(text: str, n: int, option: str) -> list[float]:
    from ..errors import UserError

    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != n or not all(v == v and abs(v) < 1e6 for v in values):
        raise UserError(f"{option} {text!r}: must be {n} comma-separated angles in degrees")
    return values


def default_commands(hand):
    """The posture ``force`` reports without --u or --q: every servo at half its travel."""
    return (hand.u_min + hand.u_max) / 2.0


def force(
    u: Optional[str] = typer.Option(None, "--u", help="The six servo commands u1..u6 (degrees, comma-separated), "
                                    "where each pad meets its plate (default: every servo at half its travel)."),
    q: Optional[str] = typer.Option(None, "--q", help="Or the 15 joint angles q1..q15 (degrees, Table I order) "
                                    "at which the pads meet their plates."),
    servo: Optional[str] = typer.Option(None, "--servo", help="A catalogue servo's stall torque instead of the "
                                        "file's (scs0009, mg90s, xl330-m288; docs/force.md)."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
    params: Optional[Path] = typer.Option(None, "--params", "-p", help="Parameter file (default: "
                                          "params/phantom.toml).", dir_okay=False),
) -> None:
    """Each fingertip's force (N) on a plate at its pad, its servo at its stall torque: the drive's
    tension through the routed tendons to the joints, less the return cord's pull, balanced by the
    plate through the pad's levers (docs/force.md). Compare the paper's Table II."""
    import numpy as np

    from .. import load_hand
    from ..errors import UserError
    from ..kinematics.force import drive_give, fingertip_forces
    from ..kinematics.topology import N_JOINTS, N_SERVOS, Q_COLUMNS, U_COLUMNS
    from ..params import servos as catalogue
    from ..units import DEG

    if u is not None and q is not None:
        raise UserError("--u and --q: give the posture one way, servo commands or joint angles")
    hand = load_hand(params)
    p = hand.params
    torque = None
    if servo is not None:
        if servo not in catalogue.CATALOGUE:
            raise UserError(f"--servo {servo!r}: not in the catalogue ({', '.join(catalogue.names())})")
        torque = catalogue.CATALOGUE[servo].stall_torque_Nm
    if q is not None:
        joints = np.array(_angles(q, N_JOINTS, "--q")) * DEG
        lo, hi = hand.q_min, hand.q_max
        bad = np.flatnonzero((joints < lo - 1e-9) | (joints > hi + 1e-9))
        if bad.size:
            k = int(bad[0])
            raise UserError(f"--q: {Q_COLUMNS[k]} = {joints[k] / DEG:g} deg is outside Table I's "
                            f"[{lo[k] / DEG:g}, {hi[k] / DEG:g}] deg")
        commands, posture = None, "the joint angles given"
    else:
        commands = default_commands(hand) if u is None else np.array(_angles(u, N_SERVOS, "--u")) * DEG
        bad = np.flatnonzero((commands < hand.u_min - 1e-9) | (commands > hand.u_max + 1e-9))
        if bad.size:
            k = int(bad[0])
            raise UserError(f"--u: {U_COLUMNS[k]} = {commands[k] / DEG:g} deg is outside its travel "
                            f"[{hand.u_min[k] / DEG:g}, {hand.u_max[k] / DEG:g}] deg")
        joints = hand.forward(commands, compensated=True)
        posture = "every servo at half its travel" if u is None else "the servo commands given"
    forces = fingertip_forces(p, joints, torque)
    tau = p.servo.stall_torque if torque is None else torque
    # the servo turns on past contact by the drive's give (and the loops', a few degrees more: the
    # twin, docs/force.md) before it stalls; with less travel left it stops short of its stall torque
    need = {f.digit: drive_give(p, f.digit, f.drive_tension) + p.servo.stall_error for f in forces}
    left = ({} if commands is None else
            {c.digit: float(hand.u_max[c.spec.servo] - commands[c.spec.servo]) for c in p.chains})
    short = [d for d in left if left[d] < need[d]]
    source = servo or catalogue.named(p.servo) or "the file's [servo]"
    if as_json:
        typer.echo(json.dumps({
            "hand": p.name, "side": p.side, "servo": source, "stall_torque_Nm": tau, "posture": posture,
            "u_deg": None if commands is None else [round(float(v) / DEG, 6) for v in commands],
            "q_deg": [round(float(v) / DEG, 6) for v in joints],
            "digits": {f.digit: {"force_N": round(f.force, 6), "drive_tension_N": round(f.drive_tension, 6),
                                 "return_tension_N": round(f.return_tension, 6),
                                 "loop_tensions_N": [round(v, 6) for v in f.loop_tensions],
                                 "joint_torques_Nm": [round(v, 6) for v in f.joint_torques],
                                 **({"cmc_torque_Nm": round(f.cmc_torque, 6)} if f.cmc_torque is not None else {}),
                                 "travel_needed_deg": round(need[f.digit] / DEG, 6),
                                 **({"travel_left_deg": round(left[f.digit] / DEG, 6)} if left else {}),
                                 "table_ii_N": TABLE_II[f.digit]} for f in forces}}, indent=1))
        return
    typer.echo(f"{p.name} ({p.side}): {source}, stall torque {tau:g} N m; posture: {posture}")
    typer.echo(f"{'digit':7s} {'force N':>8s} {'drive N':>8s} {'return N':>9s}  {'Table II N':>10s}")
    for f in forces:
        typer.echo(f"{f.digit:7s} {f.force:8.2f} {f.drive_tension:8.2f} {f.return_tension:9.2f}  "
                   f"{TABLE_II[f.digit]:10.2f}{'  *' if f.digit in short else ''}")
    for d in short:
        typer.echo(f"* {d}: its servo needs more than {need[d] / DEG:.1f} deg of travel past contact to stall (the "
                   f"drive's stretch and the stall error), and has {left[d] / DEG:.1f}: it presses with less",
                   err=True)
    thumb = forces[0]
    if thumb.cmc_torque is not None and abs(thumb.cmc_torque) > p.servo.stall_torque * p.thumb.cmc_gain:
        typer.echo(f"warning: the thumb's plate turns the CMC with {abs(thumb.cmc_torque):.3f} N m, more than "
                   "servo 6 holds: the thumb swings off its plate", err=True)
    if any(f.force <= 0.0 for f in forces):
        typer.echo("a force <= 0: the return cord pulls that pad off its plate", err=True)
