"""The fingertip force table of docs/force.md: each digit's force on a plate at its pad from the
force model (``kinematics.force.fingertip_forces`` at the posture where the pads met the plates)
and from the MJCF twin (``export.twin.press``), every servo at a fraction of its travel (half,
``phantom-cad force``'s default, unless ``--fraction`` says otherwise), as
tests/export/test_twin_force.py measures them; the twin's difference from the model in
parentheses, and the paper's Table II in the last column.

    python bench/force_table.py                                 # default, sized_160, hand_length_170
    python bench/force_table.py default left --fraction 0.25
    python bench/force_table.py default=exports/phantom sized_160=/tmp/sized_160.toml:exports/sized

A name is one of tests.support.hands.HANDS (or "slender"), or ``sized_160``: the file
``phantom-cad size --hand-length 160 --hand-breadth 72 --name sized_160`` writes (tests/conftest.py's
``sized_file``). ``name=folder`` takes an export already built (for ``sized_160``,
``sized_160=file.toml:folder``); a bare name is built here, unsliced and without renders, into
/tmp/phantom_force_table/<name> with the part cache /tmp/phantom_force_table/part-cache (a few
minutes a hand when the cache is cold). Prints the markdown table, then for each hand its tendon
servos' angles past contact and their torques, whether its twin came to rest, and how far the pads
met the plates from where the model puts them.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

WORK = Path("/tmp/phantom_force_table")
LABELS = {"default": "default", "left": "left", "sized_160": "160 x 72 mm", "hand_length_170": "170 mm example",
          "slender": "slender"}


def sized_file() -> Path:
    """The file ``phantom-cad size`` writes for the tests' sized hand (tests/conftest.py)."""
    from tests.conftest import SIZED_HAND

    length, breadth, name = SIZED_HAND
    path = WORK / f"{name}.toml"
    if not path.exists():
        WORK.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-m", "phantom_cad", "size", "--hand-length", str(length),
                        "--hand-breadth", str(breadth), "--name", name, "--out", str(path)], check=True)
    return path


def source(name: str, spec: str | None):
    """(parameters, export folder) of one hand, building the export when no folder is given."""
    from phantom_cad.export.pipeline import build_hand
    from phantom_cad.params import parse
    from phantom_cad.params.io import load_params
    from tests.support import hands

    if name == "sized_160":
        if spec is not None:
            path, folder = spec.split(":", 1)
            return load_params(path), Path(folder)
        path, side = sized_file(), None
        params = load_params(path)
    else:
        if spec is not None:
            return parse(hands.hand_document(name)), Path(spec)
        path, side = hands.hand_source(name)
        params = parse(hands.hand_document(name))
    folder = WORK / name
    if not (folder / "manifest.json").exists():
        (WORK / "part-cache").mkdir(parents=True, exist_ok=True)
        build_hand(path, folder, side=side, jobs=2, slice=False, render=False, cache_dir=WORK / "part-cache")
    return params, folder


def measure(params, folder: Path, fraction: float) -> dict:
    """The model's and the twin's force per digit, as tests/export/test_twin_force.py takes them."""
    import mujoco

    from phantom_cad.export import twin
    from phantom_cad.kinematics.force import fingertip_forces
    from phantom_cad.kinematics.model import Hand

    hand = Hand(params)
    u = hand.u_min + fraction * (hand.u_max - hand.u_min)
    got = twin.press(mujoco, folder / "description" / "mjcf" / "scene.xml", u)
    contact = hand.forward(got["u0"], compensated=True)
    model = {f.digit: f.force for f in fingertip_forces(params, contact)}
    return {"model": model, "twin": got["force"], "rested": got["rested"],
            "past": np.degrees(got["u"][:5] - got["u0"][:5]), "torque": got["torque"][:5], "stall": got["stall"][:5],
            "q_off": math.degrees(float(np.abs(got["q0"] - contact).max()))}


def main(argv: list[str]) -> None:
    from phantom_cad.cli.force import TABLE_II

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("hands", nargs="*", default=["default", "sized_160", "hand_length_170"])
    ap.add_argument("--fraction", type=float, default=0.5, help="every servo at this fraction of its travel")
    args = ap.parse_args(argv)
    rows = {}
    for arg in args.hands:
        name, _, spec = arg.partition("=")
        params, folder = source(name, spec or None)
        rows[name] = measure(params, folder, args.fraction)
    head = "| digit | " + " | ".join(f"model, {LABELS.get(n, n)} | twin, {LABELS.get(n, n)}" for n in rows)
    print(head + " | Table II |")
    print("|---|" + "---|---|" * len(rows) + "---|")
    for digit, paper in TABLE_II.items():
        cells = []
        for r in rows.values():
            model, tw = r["model"][digit], r["twin"][digit]
            cells += [f"{model:.2f}", f"{tw:.2f} ({100 * (tw / model - 1.0):+.1f} %)"]
        print(f"| {digit} | " + " | ".join(cells) + f" | {paper:.2f} |")
    print()
    for name, r in rows.items():
        past = ", ".join(f"{p:.1f}" for p in r["past"])
        torque = ", ".join(f"{t:.3f}" for t in r["torque"])
        print(f"{name}: tendon servos (1-5) past contact {past} deg, torque {torque} N m "
              f"(stall {r['stall'][0]:.3f}); rested {r['rested']}; pads off the model {r['q_off']:.3f} deg")


if __name__ == "__main__":
    main(sys.argv[1:])
