"""Pictures of where PrusaSlicer puts support in a phalanx (docs/parts.md): the index proximal
phalanx as exported (dorsal face down), with PrusaSlicer's automatic support (its extrusion paths
within 0.3 mm of the plane) in red,

* ``support_channels.png`` ("Teardrop channels"): cut in the plane of its return channel, once with
  the channels round (``up=None``: the parts before the teardrops) and once as built (teardrops);
* ``support_blockers.png`` ("Support in the tendon grooves and channels"): cut in the plane of its
  return groove, sliced as the bare STL and as its project (``export.project3mf``), whose support
  blockers are outlined in blue.

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
from phantom_cad.export import orient, project3mf, slicer, step_stl, supports  # noqa: E402
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
    blockers_figure(p, out_dir)


def blockers_figure(p, out_dir: Path) -> None:
    """``support_blockers.png``: PART as the build exports it (orientation, blockers), sliced as
    its STL and as its project, cut in its return groove's plane."""
    import trimesh

    part = assembly.build_part(p, PART)
    v, f = step_stl.tessellate(part.shape, p.print.stl_tolerance * 1e3)
    R, _ = orient.print_rotation(v, f, part.print_rotation)
    vp, T = step_stl.to_print_pose(v, R)
    held = [b for b in part.blockers if b.holds(R[2])]
    g = next(g for g in tendons.link_tendons(p, PART).grooves if g.role == "return")
    ini = slicer.config_ini(p.print)
    mesh = trimesh.Trimesh(v, f, process=False)
    fig, axes = plt.subplots(2, 1, figsize=(11, 5.6))
    with tempfile.TemporaryDirectory() as tmp:
        stl = Path(tmp) / f"{PART}.stl"
        trimesh.Trimesh(vp, f, process=False).export(stl)
        proj = Path(tmp) / f"{PART}.3mf"
        proj.write_bytes(project3mf.project_bytes(PART, vp, f, [
            (b.label, b.vertices @ T[:3, :3].T + T[:3, 3], b.faces) for b in held]))
        for ax, project in zip(axes, (None, proj)):
            res = supports.part_support(p, stl, T, PART, ini, project=project)
            pts = supports.link_points(stl, T, ini, project)
            for e in mesh.section(plane_origin=[g.x, 0, 0], plane_normal=[1, 0, 0]).discrete:
                ax.plot(e[:, 1], -e[:, 2], "k-", lw=0.8)
            if project is not None:
                for b in held:
                    sec = trimesh.Trimesh(b.vertices, b.faces).section(plane_origin=[g.x, 0, 0], plane_normal=[1, 0, 0])
                    for e in ([] if sec is None else sec.discrete):
                        ax.plot(e[:, 1], -e[:, 2], "-", color="#1f77b4", lw=0.8)
            near = np.abs(pts[:, 0] - g.x) < 0.3
            ax.plot(pts[near, 1], -pts[near, 2], ".", color="#d62728", ms=1.5)
            feats = res["features"]
            grooves = sum(x for k, x in feats.items() if k.startswith("groove"))
            channels = sum(x for k, x in feats.items() if k.startswith("channel"))
            kind = ("its STL" if project is None else
                    f"its project (print/{PART}.3mf), its {len(held)} support blockers outlined in blue")
            ax.set_title(f"{PART} sliced as {kind} (PrusaSlicer, {p.print.layer_height * 1e3:g} mm layers, "
                         f"automatic supports):\nsupport path in its grooves {grooves:.0f} mm, in its channels "
                         f"{channels:.0f} mm, all of it {res['total_mm']:.0f} mm", fontsize=9)
            ax.set_aspect("equal")
            lo, hi = mesh.bounds
            ax.set_xlim(lo[1] - 3.0, hi[1] + 3.0)
            ax.set_ylim(-hi[2] - 1.5, -lo[2] + 1.5)
            ax.set_xlabel(f"y (mm, along the phalanx), the return groove's plane x = {g.x:.2f} mm")
            ax.set_ylabel("up as printed (mm)")
    fig.tight_layout()
    out_dir.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_dir / "support_blockers.png", dpi=110)
    print(out_dir / "support_blockers.png")


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/img")
    if "--blockers" in sys.argv:       # the second picture only
        out = Path(next((a for a in sys.argv[1:] if not a.startswith("--")), "docs/img"))
        blockers_figure(load_params(), out)
    else:
        main(out)
