"""The ``phantom-cad size`` command (registered by phantom_cad/cli/__init__.py): a validated
parameter file for a person (``phantom_cad.sizing``) and what a designer acts on. Builds no
geometry: imports no CAD library (the pre-build rules of ``cad.preflight`` are numpy)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

#: the first line of every file ``size`` writes: it replaces only files that start with it
MARKER = "# phantom-cad size:"


def size(
    hand_length: float = typer.Option(..., "--hand-length", help="Hand length (mm): wrist crease to the tip of the "
                                      "middle finger."),
    hand_breadth: float = typer.Option(..., "--hand-breadth", help="Hand breadth (mm): across the heads of "
                                       "metacarpals 2-5."),
    out: Path = typer.Option(..., "--out", "-o", help="Parameter file to write (params/NAME.toml).", dir_okay=False),
    side: str = typer.Option("right", "--side", help="right or left."),
    segments: Optional[Path] = typer.Option(None, "--segments", help="TOML file of measured segment lengths and "
                                            "widths (mm; docs/sizing.md).", dir_okay=False),
    name: Optional[str] = typer.Option(None, "--name", help="The hand's name (default: the output file's stem)."),
    search: bool = typer.Option(True, "--search/--no-search", help="Where the reference's CMC placement, scaled, "
                                "does not oppose, search one (about 15 s each); --no-search keeps the reference's."),
) -> None:
    """Write a complete, validated parameter file for a person's hand: every size-dependent choice
    re-solved for the hand length, breadth and measured segments (docs/sizing.md), and print the
    reach, opposition, grasp and palm of the result. An impossible request writes nothing."""
    from ..atomic import check_file_replaceable
    from ..cad import preflight
    from ..errors import UserError
    from ..params.io import dump_params
    from ..sizing import Person, read_segments
    from ..sizing import size as solve

    if side not in ("right", "left"):
        raise UserError(f"--side {side}: must be right or left")
    check_file_replaceable(out, MARKER, "a parameter file written by phantom-cad size")
    name = name if name is not None else out.stem
    if not name or not all(c.isascii() and (c.isalnum() or c in "-_") for c in name):
        raise UserError(f"--name {name!r}: must be a non-empty name of ASCII letters, digits, '-' and '_' "
                        "(it names the export folder; the default is the output file's stem)")
    measured = read_segments(segments) if segments is not None else {}
    person = Person(hand_length, hand_breadth, side, name, measured)
    result = solve(person, check=preflight.check, search=search, floor=preflight.cmc_base_floor)
    given = ", ".join(f"{d}.{k} {v:g}" for d, t in measured.items() for k, v in t.items())
    header = (f"{MARKER} hand length {hand_length:g} mm, hand breadth {hand_breadth:g} mm, {side} hand"
              f"{f', measured: {given}' if given else ''}\n"
              "# Every size-dependent value is solved for this hand from params/phantom.toml's choices and the\n"
              "# rules `phantom-cad params validate` checks; unmeasured lengths are Buchholz, Armstrong &\n"
              "# Goldstein 1992's fractions of the hand length (docs/sizing.md).\n\n")
    dump_params(result.document, out, header)
    typer.echo(f"wrote {out}: {name} ({side}), digest {result.params.digest[:12]}")
    typer.echo("\n".join(report(result.params, result.searched)))


def printed_pinch_lines(hand) -> list[str]:
    """Where the thumb's pad meets each opposed pad on the printed tips (``kinematics.printed_tips``:
    the model's contacts, the finger closed onto the still thumb as ``phantom-cad check`` closes
    the solids)."""
    from ..kinematics import opposition
    from ..kinematics.printed_tips import printed_pinch
    from ..kinematics.topology import CMC_SERVO, SERVOS, THUMB_CHAIN, chain
    from ..units import deg

    u1, u6 = THUMB_CHAIN.servo, CMC_SERVO
    parts = []
    for f in opposition.OPPOSED:
        c = printed_pinch(hand, f)
        parts.append(f"{f} no pad-to-pad contact" if c is None else
                     f"{f} {c.distance_mm:.2f} mm at {SERVOS[u1].label} {deg(c.u[u1]):.1f}, {SERVOS[u6].label} "
                     f"{deg(c.u[u6]):.1f}, {f} {deg(c.u[chain(f).servo]):.1f} deg")
    return ["  on the printed tips (the finger closed onto the still thumb, as check closes the solids): "
            + "; ".join(parts)]


def report(p, searched: bool) -> list[str]:
    """What a designer acts on: each digit's section, travel and reach against Table I; the
    opposition; the power grasp's cylinder; the palm against its envelope; the forearm module's
    breadth; the thinnest designed wall."""
    from ..kinematics import forearm_layout as FL
    from ..kinematics import frames as F
    from ..kinematics import servo_geometry as SG
    from ..kinematics import thenar as TH
    from ..kinematics.model import Hand
    from ..kinematics.power_grasp import power_grasp_diameter_mm
    from ..params.rules import MIN_WALL
    from ..sizing import solvers as S
    from ..units import deg, mm
    from . import opposition_lines

    hand = Hand(p)
    k = p.hand_length / 0.189
    lo, hi = hand.workspace(compensated=False)
    out = ["", f"{'digit':7s} {'width':>6s} {'thick':>6s} {'travel deg':>11s}  reach at full travel / Table I (deg)"]
    for c in p.chains:
        spec = c.spec
        d = p.digit(spec.digit)
        reach = ", ".join(f"{j.upper()} {deg(hi[i]):.1f}/{deg(lim[1]):.1f}"
                          for j, i, lim in zip(c.joints, spec.q_index, c.limits))
        out.append(f"{spec.digit:7s} {mm(d.width):6.1f} {mm(d.thickness):6.1f} {deg(c.travel[1]):11.1f}  {reach}")
    out += ["", *opposition_lines(hand), *printed_pinch_lines(hand)]
    out.append(f"  (CMC placement: {'searched' if searched else 'the reference hand scaled'}; "
               f"offset {[round(mm(v), 2) for v in p.palm.thumb_cmc_offset]} mm)")
    out.append("")
    out.append(f"power grasp: a cylinder of {power_grasp_diameter_mm(p):.1f} mm (35 mm at hand length 189 mm), across "
               "the palm (closed on and held by phantom-cad check)")
    x0, x1 = (mm(v) for v in FL.metacarpal_x(p))
    pts = TH.thenar_points(p, F.T_palm_thumb_cmc_base(p))
    # only the journal and the turn set how far radial the thenar block reaches (the pulley's cavity
    # opens where it reaches past them: kinematics.thenar.thenar_points)
    xt = mm(min(float(pts[k][:, 0].min()) for k in ("journal", "turn")))
    breadth = max(x1, xt) - min(x0, xt)
    thick = mm(p.palm.thickness + p.palm.heel_height)
    env_b, env_t = (v * k for v in S.PALM_ENVELOPE)
    out.append(f"palm: {breadth:.1f} mm broad (metacarpal block and thenar), {thick:.1f} mm thick with the heel; "
               f"the 95th-percentile envelope at this hand length: {env_b:.1f} x {env_t:.1f} mm"
               f"{'' if breadth <= env_b + 1e-9 and thick <= env_t + 1e-9 else ' (outside it)'}")
    fa, limit = mm(FL.forearm_width(p)), mm(SG.forearm_width_limit(p))
    wide = " (wider: docs/sizing.md, limitations)" if fa > limit + 1e-9 else ""
    out.append(f"forearm module: {fa:.1f} mm wide; the target within a human forearm is "
               f"{limit:.1f} mm at this hand length (80 mm at 189 mm){wide}")
    walls = {"palm.wall_mm": p.palm.wall, "cad.cheek_mm": p.cad.cheek}
    thinnest = min(walls, key=walls.get)
    out.append(f"thinnest designed wall: {thinnest} = {mm(walls[thinnest]):g} mm (the rules' minimum "
               f"{mm(MIN_WALL):g} mm, two perimeters; the built parts' walls are measured by phantom-cad build)")
    from ..kinematics.force import fingertip_forces
    from .force import default_commands

    forces = fingertip_forces(p, hand.forward(default_commands(hand), compensated=True))
    out.append("fingertip force at half travel, servos stalled (N; phantom-cad force, docs/force.md): "
               + ", ".join(f"{f.digit} {f.force:.2f}" for f in forces))
    return out
