"""Pictures of where PrusaSlicer puts support in a phalanx (docs/parts.md, "Teardrop channels"): the
index proximal phalanx as exported (dorsal face down), cut in the plane of its return channel, with
PrusaSlicer's automatic support (its extrusion paths within 0.3 mm of the plane) in red; once with
the channels round (``up=None``: the parts before the teardrops) and once as built (teardrops).
Run: .venv/bin/python bench/support_figures.py [OUT_DIR] (needs prusa-slicer on the PATH)
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402

from phantom_cad.cad import assembly  # noqa: E402
from phantom_cad.cad.parts import tendons  # noqa: E402
from phantom_cad.export import slicer, step_stl, supports  # noqa: E402
from phantom_cad.params.io import load_params  # noqa: E402

PART = "index_proximal"


def sliced(p, round_channels: bool):
    """(mesh in the link frame, support points in the link frame, {feature: mm}) of PART."""
    from phantom_cad.cad.parts import common
    keep = common.teardrop
    if round_channels:
        common.teardrop = lambda p0, p1, r, up=None, roof=None: keep(p0, p1, r)
    try:
        part = assembly.build_part(p, PART)
    finally:
        common.teardrop = keep
    v, f = step_stl.tessellate(part.shape, p.print.stl_tolerance * 1e3)
    R = np.asarray(part.print_rotation, float)
    vp, T = step_stl.to_print_pose(v, R)
    with tempfile.TemporaryDirectory() as tmp:
        stl = Path(tmp) / f"{PART}.stl"
        trimesh.Trimesh(vp, f, process=False).export(stl)
        link = supports.link_points(stl, T, slicer.config_ini(p.print))
    return trimesh.Trimesh(v, f, process=False), link, supports.in_features(p, PART, link)


def main(out_dir: Path) -> None:
    p = load_params()
    lt = tendons.link_tendons(p, PART)
    x = next(p0[0] for p0, p1, d in lt.channels if d > 1.5)        # the return channel's plane
    fig, axes = plt.subplots(2, 1, figsize=(11, 6.4))
    for ax, round_channels in zip(axes, (True, False)):
        mesh, pts, feats = sliced(p, round_channels)
        sec = mesh.section(plane_origin=[x, 0, 0], plane_normal=[1, 0, 0])
        for e in sec.discrete:
            ax.plot(e[:, 1], -e[:, 2], "k-", lw=0.8)
        near = np.abs(pts[:, 0] - x) < 0.3
        ax.plot(pts[near, 1], -pts[near, 2], ".", color="#d62728", ms=1.5)
        grooves = sum(v for k, v in feats.items() if k.startswith("groove"))
        channels = sum(v for k, v in feats.items() if k.startswith("channel"))
        kind = "round channels (before)" if round_channels else "teardrop channels (as built)"
        ax.set_title(f"{PART}, {kind}: support in its channels {channels:.0f} mm, in its grooves "
                     f"{grooves:.0f} mm (PrusaSlicer, {p.print.layer_height * 1e3:g} mm layers)", fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("y (mm, along the phalanx)")
        ax.set_ylabel("up as printed (mm)")
    fig.tight_layout()
    out_dir.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_dir / "support_channels.png", dpi=110)
    print(out_dir / "support_channels.png")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/img"))
