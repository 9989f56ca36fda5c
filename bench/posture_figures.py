"""The posture gallery of docs/postures.md: each library posture (phantom_cad/postures/library.toml)
through ``phantom-cad pose`` on the default hand, its built solids placed at the model's joint angles at
the posture's commands (``hand.forward(u, compensated=True)``), one 400 px picture each, seen from the
palm's side; and the table of docs/postures.md printed on stdout (markdown). Run once from the
repository's root (about a minute: the parts are built once):
.venv/bin/python bench/posture_figures.py [OUT_DIR]   (default docs/img)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from phantom_cad import load_hand, postures
from phantom_cad.cad import assembly, registry
from phantom_cad.export import render, step_stl
from phantom_cad.kinematics.topology import JOINT_NAMES

#: the view: from the palm's side, low over the thumb's side (each finger's flexion shows in profile)
ELEV, AZIM = -70.0, -150.0
SIZE_PX = 400


def table(results) -> list[str]:
    """The markdown table of docs/postures.md."""
    head = "| # | posture | description | servo commands u1..u6 (deg) | max error (deg) | reached |"
    out = [head, "|---|---|---|---|---|---|"]
    for name, r in results.items():
        p = r.posture
        cmds = ", ".join(f"{v:.1f}" for v in np.degrees(r.u))
        verdict = "yes" if r.reached else "no"
        if r.contact is not None and not r.refused:
            verdict += f", stopped at the thumb's contact with the {r.contact.finger}"
        out.append(f"| {p.figure or ''} | `{name}` | {p.description} | {cmds} | "
                   f"{np.degrees(r.max_error):.2f} ({JOINT_NAMES[r.worst]}) | {verdict} |")
    return out


def main(out: Path) -> None:
    hand = load_hand()
    p = hand.params
    library = postures.load(hand)
    results = {n: postures.pose(hand, post) for n, post in library.items()}
    # the hand without its forearm module and servo pulleys (as hand_figures.py's close views)
    meshes = {}
    for name in assembly.part_names(p):
        if name == "forearm" or name.startswith("servo_pulley_"):
            continue
        part = registry.part(p, name)
        v, f = step_stl.tessellate(part.build(), 0.2)
        meshes[name] = (v, f, part.color)
    out.mkdir(parents=True, exist_ok=True)
    for name, r in results.items():
        T = assembly.pose_transforms(p, r.q)
        items = [render.MeshItem(n, v @ T[n][:3, :3].T + T[n][:3, 3], f, tuple(c), None)
                 for n, (v, f, c) in meshes.items()]
        fig = f"Fig. 4 ({r.posture.figure}): " if r.posture.figure else ""
        path = out / f"posture_{name}.png"
        render.render_png(items, path, title=f"{fig}{name}",
                          subtitle="u1..u6 " + ", ".join(f"{v:.0f}" for v in np.degrees(r.u)) + " deg",
                          elev=ELEV, azim=AZIM, size_px=SIZE_PX)
        print(f"wrote {path}", file=sys.stderr)
    print("\n".join(table(results)))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "img")
