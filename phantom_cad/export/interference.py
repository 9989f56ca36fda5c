"""The interference check of the assembly: pairwise intersection volumes of the placed part
meshes (manifold3d booleans)."""

from __future__ import annotations

from typing import Any

import numpy as np

#: overlap volume (mm^3) above which two placed parts count as intersecting; it absorbs
#: the tessellation error (params.print.stl_tolerance) of parts that merely touch
INTERFERENCE_TOL_MM3 = 1.0


def interference(meshes: dict[str, tuple[np.ndarray, np.ndarray]], poses: dict[str, np.ndarray],
                 allowed: set[frozenset], tol_mm3: float = INTERFERENCE_TOL_MM3) -> dict:
    """Pairwise intersection volumes of the placed meshes (manifold3d booleans).

    ``meshes`` are in link frames (mm), ``poses`` the 4x4 placements. Pairs whose boxes
    do not overlap are skipped. Returns {"checked_pairs", "collisions": [...],
    "designed_contacts": [...]} where a collision is a non-designed pair overlapping by more
    than ``tol_mm3``."""
    import manifold3d

    names = sorted(meshes)
    placed, boxes = {}, {}
    for n in names:
        v, f = meshes[n]
        T = np.asarray(poses[n], dtype=float)
        w = v @ T[:3, :3].T + T[:3, 3]
        boxes[n] = (w.min(axis=0), w.max(axis=0))
        placed[n] = (w, f)
    solids: dict[str, Any] = {}

    def solid(n):
        if n not in solids:
            w, f = placed[n]
            solids[n] = manifold3d.Manifold(manifold3d.Mesh(
                vert_properties=w.astype(np.float32), tri_verts=f.astype(np.uint32)))
        return solids[n]

    checked, collisions, contacts, largest = 0, [], [], None
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            (alo, ahi), (blo, bhi) = boxes[a], boxes[b]
            if np.any(alo > bhi) or np.any(blo > ahi):
                continue
            checked += 1
            vol = float((solid(a) ^ solid(b)).volume())
            designed = frozenset((a, b)) in allowed
            entry = {"parts": [a, b], "volume_mm3": round(max(vol, 0.0), 4) + 0.0}
            if designed:
                contacts.append(entry)
            else:
                if largest is None or vol > largest["volume_mm3"]:
                    largest = entry
                if vol > tol_mm3:
                    collisions.append(entry)
    return {"checked_pairs": checked, "tolerance_mm3": tol_mm3,
            "collisions": collisions, "designed_contacts": contacts,
            "largest_other_overlap": largest}
