"""The grasp pictures and table of docs/grasps.md: every grasp of the library
(phantom_cad/export/grasps.toml) simulated on an export's MJCF scene as ``phantom-cad grasp`` does,
one 480 x 360 picture each drawn by MuJoCo's offscreen renderer (EGL) when the hand has closed on
the presented object (before it is let go); the markdown table on stdout. Run from the repository's root on an export of
the default hand (``phantom-cad build``, or bench/compare_exports.py's):
MUJOCO_GL=egl .venv/bin/python bench/grasp_figures.py EXPORT_DIR [OUT_DIR]   (default docs/img)
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

from phantom_cad import load_hand, postures  # noqa: E402
from phantom_cad.export import grasps as G  # noqa: E402

WIDTH, HEIGHT = 480, 360
#: the view: across the palm from the little finger's side, a little below the palm (the fingers'
#: flexion and the thumb in profile)
AZIMUTH, ELEVATION = 180.0, 20.0
#: the camera's distance (m) at the paper's 189 mm hand
DISTANCE_M = 0.30


def picture(path: Path, scale: float):
    import mujoco
    from PIL import Image

    def draw(t) -> None:
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.lookat[:] = t.T_start[:3, 3] / 1000.0        # where the object was put (mm -> m)
        cam.distance, cam.azimuth, cam.elevation = DISTANCE_M * scale, AZIMUTH, ELEVATION
        opt = mujoco.MjvOption()
        opt.geomgroup[:] = 0
        opt.geomgroup[0] = opt.geomgroup[2] = 1          # the object (group 0) and the parts' visual meshes
        with mujoco.Renderer(t.m, HEIGHT, WIDTH) as r:
            r.update_scene(t.d, camera=cam, scene_option=opt)
            Image.fromarray(r.render()).save(path)
    return draw


def table(results) -> list[str]:
    """The markdown table of docs/grasps.md (its columns: ``grasps.COLUMNS``)."""
    out = ["| " + " | ".join(G.COLUMNS) + " |", "|" + "---|" * len(G.COLUMNS)]
    for r in results:
        cells = list(G.row(r))
        cells[0] = f"`{cells[0]}`"
        out.append("| " + " | ".join(cells) + " |")
    return out


def main(export: str, out_dir: str = "docs/img") -> None:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    hand = load_hand()
    library = postures.load(hand)
    scene = Path(export) / "description" / "mjcf" / "scene.xml"
    results = []
    t0 = time.process_time()
    for g in G.load().values():
        results.append(G.run(scene, hand, g, library, closed=picture(out / f"grasp_{g.name}.png", G.scale(hand.params))))
        r = results[-1]
        print(f"{g.name}: {'held' if r.held else 'dropped'}, approach (deg) {np.degrees(r.u_approach).round(1).tolist()}"
              f"{'' if r.cleared else ', no thumb command clears the object'}", file=sys.stderr)
    print(f"{len(results)} grasps, {time.process_time() - t0:.1f} s CPU (with the pictures)", file=sys.stderr)
    print("\n".join(table(results)))


if __name__ == "__main__":
    main(*sys.argv[1:])
