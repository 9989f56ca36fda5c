"""PNG renders of tessellated parts and of the assembly (matplotlib Agg, no display).

Flat shading: each triangle's colour is its part colour scaled by a Lambert term for a
fixed light; orthographic projection, equal axes, millimetre ticks. Matplotlib's
painter's algorithm sorts triangles by depth, which is good enough for reading the shape.
The PNG carries no timestamp, so the same mesh gives the same file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: light direction (unit vector towards the light) in the view's world frame
_LIGHT = np.array([0.35, -0.45, 0.82])
_AMBIENT = 0.35


@dataclass
class MeshItem:
    name: str
    vertices: np.ndarray    # (n, 3) mm, already placed in the render frame
    faces: np.ndarray       # (m, 3)
    color: tuple[float, float, float]
    label: str | None = None  # text drawn at the item's centroid (None = no label)


def _decimate_for_view(vertices, faces, max_faces):
    """Keep a deterministic, evenly spaced subset of triangles beyond ``max_faces``.
    (Only for pictures: with flat shading at PNG resolution missing slivers are invisible
    on dense fillet strips; ``max_faces`` bounds the render time.)"""
    if len(faces) <= max_faces:
        return faces
    idx = np.linspace(0, len(faces) - 1, max_faces).astype(int)
    return faces[idx]


def _shade(tri: np.ndarray, color) -> np.ndarray:
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    light = _LIGHT / np.linalg.norm(_LIGHT)
    lam = np.abs(n @ light)  # two-sided
    k = _AMBIENT + (1 - _AMBIENT) * lam
    rgb = np.clip(np.asarray(color)[None, :] * k[:, None], 0, 1)
    return np.concatenate([rgb, np.ones((len(rgb), 1))], axis=1)


def render_png(items: list[MeshItem], path: str | os.PathLike, title: str, *,
               elev: float = 22.0, azim: float = -58.0, size_px: int = 900,
               max_faces: int = 60000, subtitle: str | None = None, bed: bool = False) -> None:
    """Render ``items`` into a PNG at ``path``. ``bed``: the items rest on z = 0 (print
    orientation); the view starts at z = 0 and a grey bed square is drawn there."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    dpi = 100
    fig = Figure(figsize=(size_px / dpi, size_px / dpi), dpi=dpi)
    ax = fig.add_subplot(111, projection="3d", proj_type="ortho")
    total = sum(len(it.faces) for it in items) or 1
    polys, colors = [], []
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for it in items:
        budget = max(200, int(max_faces * len(it.faces) / total))
        faces = _decimate_for_view(it.vertices, it.faces, budget)
        tri = it.vertices[faces]
        polys.append(tri)
        colors.append(_shade(tri, it.color))
        lo = np.minimum(lo, it.vertices.min(axis=0))
        hi = np.maximum(hi, it.vertices.max(axis=0))
    tri = np.concatenate(polys)
    fc = np.concatenate(colors)
    # edges in the face colour hide the anti-aliasing seams between triangles
    coll = Poly3DCollection(tri, facecolors=fc, edgecolors=fc, linewidths=0.25)
    ax.add_collection3d(coll)
    centre, half = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-3) * 1.05
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    if bed:
        # seen from above (elev > 0) the bed is always behind the part: draw it first
        ax.computed_zorder = False
        coll.set_zorder(2)
        ax.set_zlim(0.0, 2 * half)
        sq = np.array([[centre[0] - half, centre[1] - half, 0], [centre[0] + half, centre[1] - half, 0],
                       [centre[0] + half, centre[1] + half, 0], [centre[0] - half, centre[1] + half, 0]])
        ax.add_collection3d(Poly3DCollection([sq], facecolors=[(0.85, 0.85, 0.85, 0.6)], edgecolors="0.6",
                                             linewidths=0.5, zorder=1))
    else:
        ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    ax.tick_params(labelsize=7)
    # four or five ticks an axis: every 3D tick is an artist of its own (half a picture's time
    # went into the default's dozen ticks an axis)
    from matplotlib.ticker import MaxNLocator
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(4))
    for it in items:
        if it.label:
            c = it.vertices.mean(axis=0)
            ax.text(c[0], c[1], hi[2] + 0.04 * half if len(items) > 1 else c[2], it.label,
                    fontsize=8, ha="center", color="black", zorder=10)
    fig.suptitle(title, fontsize=12)
    if subtitle:
        fig.text(0.5, 0.915, subtitle, ha="center", fontsize=8, color="0.3")
    fig.subplots_adjust(left=0, right=1, bottom=0.02, top=0.92)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi, metadata={"Software": None})
