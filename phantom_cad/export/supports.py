"""Where PrusaSlicer puts support under the exported parts, by tendon feature (the requirement: the
tendon grooves and channels must print without support in the exported orientation).

PrusaSlicer slices a part's STL as exported (its automatic supports, :func:`slicer.slice_supports`);
the support's extrusion paths, sampled every 0.25 mm, are moved back into the part's link frame
(the manifest's ``print_transform``) and counted against the routing model's features on that
link (``cad.parts.tendons.LinkTendons``):

* a **groove**: within its width of its plane, from its floor out to one width past the cord's
  centreline (the groove's mouth, where support under its roof would stand);
* a **channel**: within its radius of its axis, between its ends, where the part surrounds it
  (given the part's mesh: at least 6 of 8 points half a flank outside its wall are in the solid; a
  run that starts in the space of the parent's hub, beside a tongue, is no channel there).

The result is millimetres of support path (samples x 0.25 mm): a measure of how much support a
feature takes, not a volume.
"""

from __future__ import annotations

import numpy as np

from .. import units
from ..kinematics.hand_params import HandParams
from . import slicer


#: where a channel counts as in the part: this share of the points around it are in the solid
SURROUNDED = 6 / 8


def in_features(params: HandParams, link: str, points: np.ndarray, solid=None) -> dict[str, float]:
    """mm of support path inside each tendon groove and channel of ``link`` (``points``: link
    frame, mm, right hand): {"groove <role> <joint>": mm, "channel <k>": mm}. ``solid``: the part
    (a ``trimesh.Trimesh``, link frame), for where a channel lies in it."""
    from ..cad.parts.tendons import link_tendons
    from ..kinematics.dimensions import FLANK
    from ..kinematics.vectors import perpendicular_frame

    lt = link_tendons(params, link)
    P = np.asarray(points, float).reshape(-1, 3)
    out: dict[str, float] = {}
    for g in lt.grooves:
        r = np.hypot(P[:, 1] - g.y, P[:, 2] - g.z)
        inside = (np.abs(P[:, 0] - g.x) <= g.width / 2.0) & (r >= g.floor) & (r <= g.radius + g.width)
        key = f"groove {g.role} {g.joint}"
        out[key] = out.get(key, 0.0) + float(inside.sum()) * slicer.SUPPORT_SPACING
    for k, (p0, p1, d) in enumerate(lt.channels):
        p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
        L = float(np.linalg.norm(p1 - p0))
        u = (p1 - p0) / L
        t = (P - p0) @ u
        dist = np.linalg.norm(P - (p0 + np.clip(t, 0.0, L)[:, None] * u), axis=1)
        inside = (t >= 0.0) & (t <= L) & (dist <= d / 2.0)
        if solid is not None and inside.any():
            e1, e2 = perpendicular_frame(u)
            ang = np.arange(8) * (np.pi / 4.0)
            ring = (d / 2.0 + units.mm(FLANK) / 2.0) * (np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2)
            idx = np.flatnonzero(inside)
            around = (p0 + t[idx, None] * u)[:, None, :] + ring[None]
            share = solid.contains(around.reshape(-1, 3)).reshape(len(idx), 8).mean(axis=1)
            inside[idx[share < SURROUNDED]] = False
        out[f"channel {k}"] = float(inside.sum()) * slicer.SUPPORT_SPACING
    return out


def link_points(stl_path, print_transform, ini_text: str, project=None) -> np.ndarray:
    """PrusaSlicer's support under an exported part (:func:`slicer.slice_supports`; ``project``:
    its PrusaSlicer project, blockers and all), moved into its link frame (``print_transform``:
    the manifest's 4x4 from link to print frame), mm."""
    pts = slicer.slice_supports(stl_path, ini_text, project=project)
    T = np.linalg.inv(np.asarray(print_transform, float))
    return pts @ T[:3, :3].T + T[:3, 3] if len(pts) else pts


def part_support(params: HandParams, stl_path, print_transform, link: str, ini_text: str, project=None,
                 side: str = "right") -> dict:
    """Slice an exported part with automatic supports (as an STL, or its ``project``): {"total_mm":
    the support path, "features": :func:`in_features`, the part's STL as its solid}
    (``print_transform`` as for :func:`link_points`). ``side``: the export's; a left hand's support
    and solid are mirrored back into the right hand's link frame, where :func:`in_features`
    finds the routing model's features."""
    import trimesh

    from ..cad.assembly import MIRROR
    from .step_stl import read_stl

    pts = link_points(stl_path, print_transform, ini_text, project)
    v, f = read_stl(open(stl_path, "rb").read())
    T = np.linalg.inv(np.asarray(print_transform, float))
    v = v @ T[:3, :3].T + T[:3, 3]
    if side == "left":
        pts, v, f = pts * MIRROR, v * MIRROR, f[:, ::-1]
    solid = trimesh.Trimesh(v, f, process=False)
    return {"total_mm": float(len(pts)) * slicer.SUPPORT_SPACING, "features": in_features(params, link, pts, solid)}
