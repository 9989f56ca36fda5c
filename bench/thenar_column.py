"""Where can the thumb's CMC sit if the palm holds it on a column and servo 6 turns it from the
forearm module? (docs/opposition.md, "A thenar without servo 6": a design study, nothing of it is
built yet.)

The design this prices (issue 12: servo 6 no longer coaxial under the CMC, so nothing of the palm
hangs below its palmar face):

* the CMC base (a thumb part, below the palm's palmar face) carries a column along the CMC axis up
  into the palm, which holds it in a journal (radius ``COLUMN_RADIUS`` with a hole clearance) from
  its palmar face;
* on the column, inside the palm, a pulley of radius ``LOOP_RADIUS``: a closed cable loop of equal
  pulley radii turns it from servo 6 in the forearm module's row (q15 = u6, eq. 9, unchanged);
* its cavity lies above the finger drives' plane (``frames.tendon_height``), below the palm's
  dorsal face less a wall and the room the thumb drive needs to turn onto the CMC axis above the
  column (``TURN_ROOM``): the thumb drive still reaches the CMC along its axis, so turning the CMC
  leaves its length alone;
* the loop's strands leave the pulley toward the forearm (-y) within ``LOOP_TILT`` of its plane.

For each case the placement search (``opposition.solve``) runs with these requirements as its
``constraint`` (metres of violation, priced like the thumb's reach into the palm) and the palm no
broader than the 95th-percentile envelope (95 mm at hand length 189 mm): the journal's and the
cavity's walls inside the line that far radial of the pinky's ulnar edge. Cases: the palm's
thickness (24 mm, the file's; 30 mm, a human palm; 35 mm, issue 12's limit), and whether the
journal and cavity must stay ahead of the wrist crease or may reach behind it (the palm's thenar
then reaches back past the crease and the forearm module starts behind it).

About a minute a case on the project's machine.
Run: .venv/bin/python bench/thenar_column.py [PARAMS.toml] [SEED]
"""

from __future__ import annotations

import copy
import math
import sys
import time

import numpy as np

from phantom_cad import make_hand
from phantom_cad.kinematics import frames as F
from phantom_cad.kinematics import opposition as O
from phantom_cad.params import parse
from phantom_cad.params.io import DEFAULT_PARAMS, load_document

#: the design's dimensions (m) [choice]: a printed journal round a 1 mm tendon bore, a loop pulley
#: like a finger servo's (6 mm: 38 N of loop tension at the servo's stall torque), the drive's turn
COLUMN_RADIUS = 4e-3
LOOP_RADIUS = 6e-3
TURN_ROOM = 3e-3
LOOP_TILT = math.radians(10.0)


def column_violation(params, behind_wrist: bool, beside: bool = False):
    """The design's requirements of a placement T0 (T_palm_cmc_base at rest), as metres of
    violation (<= 0: met), for ``opposition.solve``'s ``constraint``. ``beside``: the pulley's
    cavity lies radial of the index drive's channel (at any height in the palm) instead of above
    the finger drives' plane."""
    c, w = params.print.hole_clearance, params.palm.wall
    Tp, Tth = params.palm.thickness, params.thumb.thickness
    r_base = params.thumb.width / 2.0
    hd = params.hardware.tendon_diameter
    R = LOOP_RADIUS + 2.0 * hd + hd + c                 # the pulley's cavity: flanges, running room
    h = params.cad.servo_pulley_width / 2.0 + c
    _, hi = O.palm_envelope(params)
    x_lo = hi[0] - 0.095 * params.hand_length / 0.189   # the 95 mm palm's radial edge
    wrist = F.wrist_y(params)
    z_plane = F.tendon_height(params) + hd / 2.0 + c + w   # above the finger drives' channels
    if beside:
        z_plane = -Tp / 2.0 + w
    x_index = F.socket_tendon_point(params, "index")[0] - hd / 2.0 - c - w   # radial of its channel

    def violation(T0):
        a, C = T0[:3, 2], T0[:3, 3]
        if a[2] < 0.3:                                   # the column must climb into the palm
            return 0.05 * (0.3 - a[2]) + 0.05
        s = math.sqrt(max(1.0 - a[2] ** 2, 0.0))
        v = []
        # the CMC base (a disc of the thumb's half width, the thumb's thickness) under the palm face
        v.append(C[2] + Tth / 2.0 * a[2] + r_base * s + c + Tp / 2.0)
        # the journal where the column enters the palmar face, with a wall, inside the envelope
        P = C + (-Tp / 2.0 - C[2]) / a[2] * a
        foot = (COLUMN_RADIUS + c + w) / a[2]
        v.append(x_lo - (P[0] - foot))
        if not behind_wrist:
            v.append(wrist - (P[1] - foot))
        # the pulley's cavity: above the drives' plane, below the dorsal face less a wall and the turn
        ez = R * s + h * a[2]
        z_bot, z_top = z_plane + ez, Tp / 2.0 - w - TURN_ROOM - ez
        v.append(z_bot - z_top)
        Q = C + (z_bot - C[2]) / a[2] * a
        ex = R * math.sqrt(max(1.0 - a[0] ** 2, 0.0)) + h * abs(a[0])
        ey = R * math.sqrt(max(1.0 - a[1] ** 2, 0.0)) + h * abs(a[1])
        v.append(x_lo - (Q[0] - ex - w))
        if beside:
            v.append(Q[0] + ex - x_index)
        if not behind_wrist:
            v.append(wrist - (Q[1] - ey - w))
        # the loop's strands leave toward the forearm near the pulley's plane
        v.append(R * (abs(a[1]) - math.sin(LOOP_TILT)))
        return sum(max(x, 0.0) for x in v)

    return violation


def cases(path, seed: int):
    doc = load_document(path)
    for thickness in (24.0, 30.0, 35.0):
        d = copy.deepcopy(doc)
        d["palm"]["thickness_mm"] = thickness
        params = parse(d, str(path))
        hand = make_hand(params)
        b = O.default_bounds(params)
        bounds = O.Bounds(offset=(b.offset[0], b.offset[1], (-45e-3 * params.hand_length / 0.189, b.offset[2][1])),
                          axis=b.axis)
        for behind in (False, True):
            t = time.perf_counter()
            s = O.solve(hand, bounds, seed=seed, population=16, generations=150,
                        constraint=column_violation(params, behind))
            yield thickness, behind, s, time.perf_counter() - t


def main(argv):
    path = argv[1] if len(argv) > 1 else DEFAULT_PARAMS
    seed = int(argv[2]) if len(argv) > 2 else 1
    print(f"seed {seed}")
    print("| palm (mm) | journal and cavity | CMC centre (mm) | axis (deg) | margin (deg) | "
          "pads meet (index / middle / ring) | violation (mm) | s |")
    print("|---:|---|---|---|---:|---|---:|---:|")
    for thickness, behind, s, dt in cases(path, seed):
        c = ", ".join(f"{v * 1e3:.1f}" for v in s.offset)
        a = ", ".join(f"{math.degrees(v):.1f}" for v in s.axis)
        meet = " / ".join(("yes" if s.reach[f].reaches else "no") for f in O.OPPOSED)
        where = "may reach behind the wrist crease" if behind else "ahead of the wrist crease"
        print(f"| {thickness:g} | {where} | {c} | {a} | {math.degrees(s.margin):+.1f} | {meet} | "
              f"{s.violation * 1e3:.2f} | {dt:.0f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv)
