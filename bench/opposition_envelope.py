"""How much opposition a human-scale thenar leaves (docs/opposition.md, "Within the human-scale
palm"): the CMC placement search (kinematics.opposition.solve) run again with its centre held
to what issue 12's palm allows.

1. the search's own bounds (the thumb may sit up to 35 mm radial of the palm's edge);
2. the palm no broader than the 95th-percentile envelope (95 mm at hand length 189 mm, scaled):
   the CMC centre at least a support's radius (a 683 bearing seat and a wall) inside the line
   that far radial of the pinky's ulnar edge;
3. and the CMC base's dorsal face no lower than the palm's palmar face (whatever holds the CMC
   then stays within the palm's thickness): the centre at most half the thumb's thickness below it.

Larger population and more generations than `params opposition --solve` (the constrained
problems are narrower). About a minute per row on the project's machine.
Run: .venv/bin/python bench/opposition_envelope.py [PARAMS.toml]
"""

from __future__ import annotations

import math
import sys
import time

from phantom_cad import load_params, make_hand
from phantom_cad.kinematics import opposition as O
from phantom_cad.params.io import DEFAULT_PARAMS


def rows(params):
    hand = make_hand(params)
    b = O.default_bounds(params)
    _, hi = O.palm_envelope(params)
    limit = 0.095 * params.hand_length / 0.189
    support = params.hardware.bearing_outer / 2.0 + params.palm.wall
    x_min = hi[0] - limit + support
    z_min = -params.palm.thickness / 2.0 - params.thumb.thickness / 2.0
    broad = O.Bounds(offset=((x_min, b.offset[0][1]), b.offset[1], b.offset[2]), axis=b.axis)
    thick = O.Bounds(offset=((x_min, b.offset[0][1]), b.offset[1], (z_min, b.offset[2][1])), axis=b.axis)
    cases = (("the search's bounds", b),
             (f"palm <= {limit * 1e3:.1f} mm broad (CMC x >= {x_min * 1e3:.1f} mm)", broad),
             (f"and the CMC base within the palm's face (CMC z >= {z_min * 1e3:.1f} mm)", thick))
    for label, bounds in cases:
        t = time.perf_counter()
        s = O.solve(hand, bounds, seed=1, population=16, generations=150)
        yield label, s, time.perf_counter() - t


def main(argv):
    params = load_params(argv[1] if len(argv) > 1 else DEFAULT_PARAMS)
    print("| bounds | CMC centre (mm) | axis (deg) | margin (deg) | pads meet (index / middle / ring) | s |")
    print("|---|---|---|---:|---|---:|")
    for label, s, dt in rows(params):
        c = ", ".join(f"{v * 1e3:.1f}" for v in s.offset)
        a = ", ".join(f"{math.degrees(v):.1f}" for v in s.axis)
        meet = " / ".join(("yes" if s.reach[f].reaches else "no") for f in O.OPPOSED)
        print(f"| {label} | {c} | {a} | {math.degrees(s.margin):+.1f} | {meet} | {dt:.0f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv)
