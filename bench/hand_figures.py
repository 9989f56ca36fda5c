"""Pictures of the assembled hand (docs/parts.md, README): the default hand's built solids placed by
``assembly.pose_transforms`` at rest (two views) and at 60 % of every joint limit. Run from the repository's
root: .venv/bin/python bench/hand_figures.py [OUT_DIR]   (default docs/img; about 40 s)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from phantom_cad.cad import assembly, registry
from phantom_cad.export import render, step_stl
from phantom_cad.kinematics import frames
from phantom_cad.kinematics.topology import JOINTS
from phantom_cad.params.io import DEFAULT_PARAMS, load_params


def main(out: Path) -> None:
    p = load_params(DEFAULT_PARAMS)
    meshes = {}
    for name in assembly.part_names(p):
        part = registry.part(p, name)
        v, f = step_stl.tessellate(part.build(), 0.05)
        meshes[name] = (v, f, part.color, part.digit)
    limits = {j["name"]: j["limits"] for j in frames.joints(p)}
    q60 = np.array([0.6 * limits[j.name][1] for j in JOINTS])
    out.mkdir(parents=True, exist_ok=True)
    shots = (("hand_rest.png", None, "rest pose", (28.0, -62.0)),
             ("hand_top.png", None, "rest pose, seen from the dorsal side", (90.0, -90.0)),
             ("hand_flexed.png", q60, "60 % of every joint limit, seen from the palm side", (-25.0, -125.0)))
    for fname, q, what, (elev, azim) in shots:
        T = assembly.pose_transforms(p, q)
        items, labelled = [], set()
        for name, (v, f, color, digit) in meshes.items():
            key = digit or name
            label = key if key not in labelled and (digit is not None or name in ("palm", "forearm")) else None
            labelled.add(key)
            items.append(render.MeshItem(name, v @ T[name][:3, :3].T + T[name][:3, 3], f, tuple(color), label))
        render.render_png(items, out / fname, title=f"{p.name} hand ({p.side}), {what}",
                          subtitle="tendon servos in the forearm module; stepped metacarpal heads; default parameters", elev=elev, azim=azim,
                          size_px=1000, max_faces=150000)
        print(f"wrote {out / fname}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "img")
