"""Where PrusaSlicer puts support under the exported parts, by tendon feature (issue 12: the tendon
grooves and channels must print without support in the exported orientation).

PrusaSlicer slices a part's STL as exported (its automatic supports, :func:`slicer.slice_supports`);
the support's extrusion paths, sampled every 0.25 mm, are moved back into the part's link frame
(the manifest's ``print_transform``) and counted against the routing model's features on that
link (``cad.parts.tendons.LinkTendons``):

* a **groove**: within its width of its plane, from its floor out to one width past the cord's
  centreline (the groove's mouth, where support under its roof would stand);
* a **channel**: within its radius of its axis, between its ends.

The result is millimetres of support path (samples x 0.25 mm): a measure of how much support a
feature takes, not a volume.
"""

from __future__ import annotations

import numpy as np

from . import slicer


def in_features(params, link: str, points: np.ndarray) -> dict[str, float]:
    """mm of support path inside each tendon groove and channel of ``link`` (``points``: link
    frame, mm, right hand): {"groove <role> <joint>": mm, "channel <k>": mm}."""
    from ..cad.parts.tendons import link_tendons

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
        out[f"channel {k}"] = float(((t >= 0.0) & (t <= L) & (dist <= d / 2.0)).sum()) * slicer.SUPPORT_SPACING
    return out


def link_points(stl_path, print_transform, ini_text: str) -> np.ndarray:
    """PrusaSlicer's support under an exported part (:func:`slicer.slice_supports`), moved into
    its link frame (``print_transform``: the manifest's 4x4 from link to print frame), mm."""
    pts = slicer.slice_supports(stl_path, ini_text)
    T = np.linalg.inv(np.asarray(print_transform, float))
    return pts @ T[:3, :3].T + T[:3, 3] if len(pts) else pts


def part_support(params, stl_path, print_transform, link: str, ini_text: str) -> dict:
    """Slice an exported part with automatic supports: {"total_mm": the support path, "features":
    :func:`in_features`} (``print_transform`` as for :func:`link_points`)."""
    pts = link_points(stl_path, print_transform, ini_text)
    return {"total_mm": float(len(pts)) * slicer.SUPPORT_SPACING, "features": in_features(params, link, pts)}
