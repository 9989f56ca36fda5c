"""The CMC placement the default hand's file carries (docs/opposition.md, "Within the palm's
thenar"): the placement search (``kinematics.thumb_placement.solve``) with the palm's thenar as its
constraint (``thumb_placement.thenar_constraint``: the CMC axis within 60 deg of the palm's normal, the
CMC base below the palm, the thumb drive's turn above the CMC pulley under the dorsal face, the
journal's and the turn's walls within a palm of human breadth), a larger population and more
generations than `params opposition --solve`, for several seeds (the landscape has several optima:
each row is a placement the search reaches, a lower bound of the best). Four decimals, as
`--solve` prints: the margin can sit on an edge that rounding to 0.01 crosses (docs/opposition.md).

About 10 s a seed on the project's machine.
Run: .venv/bin/python bench/opposition_thenar.py [PARAMS.toml] [SEEDS, e.g. 1,2,3]
"""

from __future__ import annotations

import math
import sys
import time

from phantom_cad import load_params, make_hand
from phantom_cad.cad.preflight import cmc_base_floor
from phantom_cad.kinematics import opposition as O, thumb_placement as TP
from phantom_cad.params.io import DEFAULT_PARAMS


def main(argv):
    params = load_params(argv[1] if len(argv) > 1 else DEFAULT_PARAMS)
    seeds = [int(s) for s in (argv[2] if len(argv) > 2 else "1,2,3").split(",")]
    hand = make_hand(params)
    print("| seed | CMC centre (mm) | axis (deg) | margin (deg) | pads meet (index / middle / ring) | "
          "thumb outside the palm (mm) | s |")
    print("|---:|---|---|---:|---|---:|---:|")
    for seed in seeds:
        t = time.perf_counter()
        s = TP.solve(hand, seed=seed, population=16, generations=150, constraint=TP.thenar_constraint(params, floor=cmc_base_floor(params)))
        c = ", ".join(f"{v * 1e3:.4f}" for v in s.offset)
        a = ", ".join(f"{math.degrees(v):.4f}" for v in s.axis)
        meet = " / ".join(("yes" if s.reach[f].reaches else "no") for f in O.OPPOSED)
        held = "" if s.violation <= 0.0 else f" (the thenar misses it by {s.violation * 1e3:.1f} mm)"
        print(f"| {seed} | {c} | {a} | {math.degrees(s.margin):+.1f}{held} | {meet} | {-s.intrusion * 1e3:.1f} | "
              f"{time.perf_counter() - t:.0f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv)
