"""Can any CMC placement make the thumb's pad face the index, middle and ring pads (docs/opposition.md,
"Pad to pad")? The placement search (``kinematics.thumb_placement.solve``) with ``oppose =
PAD_OPPOSE``: a contact counts only where, besides the contact direction lying in both pads'
45 deg cones, the pads' normals are within 30 deg of facing each other. Run under the rules the
default file's placement was found with (the palm's thenar and a human palm, the default
bounds), then with each rule taken away and wider bounds, to see which rule stands in the way.
Each row is a placement the search reaches (a lower bound of the best); the margin is
min(45 deg less the contact direction's angle, 30 deg less the normals' angle) at the squarest
contact, the smallest of the three fingers.

With ``--twist DEGREES,...``: the same search under the file's rules (thenar, human palm, default
bounds) with the file's ``thumb.twist`` set to each angle: the MP and IP axes turned about the
thumb metacarpal's length (a pronation of the thumb, fixed in its metacarpal), which turns its
pad's cone about the CMC axis open (docs/opposition.md, "Pad to pad").

About 30 s a row on the project's machine.
Run: .venv/bin/python bench/opposition_facing.py [PARAMS.toml] [SEED] [--twist 45,70,90]
"""

from __future__ import annotations

import math
import sys
import time


from phantom_cad import load_params, make_hand
from phantom_cad.cad.preflight import cmc_base_floor
from phantom_cad.kinematics import frames as F
from phantom_cad.kinematics import opposition as O
from phantom_cad.kinematics import thumb_placement as TP
from phantom_cad.kinematics import thenar as TH
from phantom_cad.params import parse
from phantom_cad.params.io import DEFAULT_PARAMS, load_document


def wide_bounds(params) -> TP.Bounds:
    """The default bounds opened: the CMC centre 20 mm further radial, from the MCPs' line back to
    110 mm behind it, 60 mm palmar to 20 mm dorsal; every axis angle free (scaled as the default's)."""
    b = TP.default_bounds(params)
    k = params.hand_length / 0.189
    r = math.radians
    return TP.Bounds(offset=((b.offset[0][0] - 0.020 * k, b.offset[0][1]), (-0.110 * k, 0.0), (-0.060 * k, 0.020 * k)),
                    axis=((r(-180), r(180)), (r(-90), r(90)), (r(-180), r(180))))


def row(label, params, T0, reach, seconds):
    z = T0[:3, 2]
    c = ", ".join(f"{v * 1e3:.1f}" for v in T0[:3, 3])
    held = TH.thenar_margins(params, T0)
    viol = TP.thenar_constraint(params, floor=cmc_base_floor(params))(T0)
    margin = min(reach[f].margin for f in O.OPPOSED)
    meet = " / ".join(("yes" if reach[f].reaches else "no") for f in O.OPPOSED)
    print(f"| {label} | {c} | {math.degrees(math.acos(z[2])):.0f} | {math.degrees(margin):+.1f} | {meet} | "
          f"{'yes' if viol <= 0.0 else f'no ({viol * 1e3:.0f} mm)'} | {math.degrees(held['tilt']):+.0f} | {seconds:.0f} |",
          flush=True)


def twisted(path, psi: float):
    """The file with its thumb twisted by psi (deg): ``thumb.twist_deg``, the MP turned about the
    metacarpal's length (through the document, so that the memoised routes are keyed on it)."""
    doc = load_document(path)
    doc["thumb"]["twist_deg"] = psi
    return parse(doc, str(path))


def main(argv):
    twist = None
    if "--twist" in argv:
        k = argv.index("--twist")
        twist = [float(v) for v in argv[k + 1].split(",")]
        argv = argv[:k] + argv[k + 2:]
    path = argv[1] if len(argv) > 1 else DEFAULT_PARAMS
    params = load_params(path)
    seed = int(argv[2]) if len(argv) > 2 else 1
    hand = make_hand(params)
    if twist is not None:
        return main_twist(params, path, seed, twist)
    print("| rules | CMC centre (mm) | CMC axis from the palm's normal (deg) | margin (deg) | pads meet "
          "(index / middle / ring) | the thenar holds it | tilt margin (deg) | s |")
    print("|---|---|---:|---:|---|---|---:|---:|")
    T0 = F.thumb_cmc_placement(params.palm.thumb_cmc_offset, params.palm.thumb_cmc_axis)
    t = time.perf_counter()
    row("the file's placement", params, T0, O.reach(hand, oppose=O.PAD_OPPOSE, fingers=O.OPPOSED), time.perf_counter() - t)
    cases = [("thenar and human palm, default bounds (as `--solve`)", None, TP.thenar_constraint(params, floor=cmc_base_floor(params))),
             ("thenar and human palm, wide bounds", wide_bounds(params), TP.thenar_constraint(params, floor=cmc_base_floor(params))),
             ("thenar only (no human palm), wide bounds", wide_bounds(params), TP.thenar_constraint(params, human=False, floor=cmc_base_floor(params))),
             ("palm envelope only, wide bounds", wide_bounds(params), None)]
    for label, bounds, constraint in cases:
        t = time.perf_counter()
        s = TP.solve(hand, bounds=bounds, seed=seed, population=16, generations=150, constraint=constraint,
                     oppose=O.PAD_OPPOSE)
        T0 = F.thumb_cmc_placement(s.offset, s.axis)
        row(label, params, T0, s.reach, time.perf_counter() - t)


def main_twist(params, path, seed, twist):
    print("| twist (deg) | CMC centre (mm) | axis (deg) | margin (deg) | pads meet (index / middle / ring) | "
          "margin without oppose (index / middle / ring, deg) | s |")
    print("|---:|---|---|---:|---|---|---:|")
    for psi in twist:
        hand = make_hand(twisted(path, psi))
        t = time.perf_counter()
        s = TP.solve(hand, seed=seed, population=16, generations=150, constraint=TP.thenar_constraint(params, floor=cmc_base_floor(params)),
                     oppose=O.PAD_OPPOSE)
        T0 = F.thumb_cmc_placement(s.offset, s.axis)
        loose = O.reach(hand, T0=T0, fingers=O.OPPOSED)
        c = ", ".join(f"{v * 1e3:.1f}" for v in s.offset)
        a = ", ".join(f"{math.degrees(v):.1f}" for v in s.axis)
        meet = " / ".join(("yes" if s.reach[f].reaches else "no") for f in O.OPPOSED)
        held = "" if s.violation <= 0.0 else f" (the thenar misses it by {s.violation * 1e3:.1f} mm)"
        print(f"| {psi:g} | {c} | {a} | {math.degrees(s.margin):+.1f}{held} | {meet} | "
              f"{' / '.join(f'{math.degrees(loose[f].margin):+.1f}' for f in O.OPPOSED)} | {time.perf_counter() - t:.0f} |",
              flush=True)


if __name__ == "__main__":
    main(sys.argv)
