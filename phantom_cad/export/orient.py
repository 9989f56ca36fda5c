"""The print orientation of a part, chosen by a measured overhang criterion, so that the
part prints with as little support as it can.

Of the 24 rotations that lay a part's link-frame axes along the printer's axes, the one whose
mesh has the least overhang: the area of the faces that look down more steeply than
:data:`OVERHANG_DEG` from the vertical (a slicer's support threshold) and do not lie on the bed.
Only rotations that rest the part on a flat face are candidates: faces on the bed cover at least
:data:`MIN_BED` of the footprint (the bounding box's). Ties (within :data:`TIE_MM2`) go to the
part's declared ``print_rotation``, then to the order of :func:`axis_rotations`, so the choice is
deterministic. numpy only.
"""

from __future__ import annotations

import itertools

import numpy as np

from .. import units

#: a face looking down more steeply than this from the vertical needs support (degrees)
OVERHANG_DEG = 45.0
#: faces within this of the bed rest on it (mm)
BED_MM = 1e-3
#: the faces on the bed cover at least this share of the footprint
MIN_BED = 0.25
#: overhang areas closer than this are a tie (mm^2)
TIE_MM2 = 1.0


def axis_rotations() -> list[np.ndarray]:
    """The 24 proper rotations that map the axes onto the axes, in a fixed order."""
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            R = np.zeros((3, 3))
            R[np.arange(3), perm] = signs
            if np.linalg.det(R) > 0.0:
                out.append(R)
    return out


def _faces(vertices: np.ndarray, faces: np.ndarray):
    """(vertices, unit normals, areas, face vertex indices) of the mesh, once per mesh."""
    v = np.asarray(vertices, float)
    f = np.asarray(faces)
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(n, axis=1) / 2.0
    return v, n / np.maximum(2.0 * area, 1e-300)[:, None], area, f


def _overhang(mesh, R: np.ndarray) -> tuple[float, float, float]:
    """(overhang area, area on the bed, footprint) in mm^2 of the mesh (:func:`_faces`) rotated by
    ``R`` and resting on z = 0."""
    v, n, area, f = mesh
    z = v @ R[2]
    z -= z.min()
    on_bed = z[f].max(axis=1) <= BED_MM
    down = n @ R[2] < -np.cos(units.rad(OVERHANG_DEG))
    x, y = v @ R[0], v @ R[1]
    return (float(area[down & ~on_bed].sum()), float(area[down & on_bed].sum()),
            float(np.ptp(x) * np.ptp(y)))


def print_rotation(vertices: np.ndarray, faces: np.ndarray, declared: np.ndarray) -> tuple[np.ndarray, float]:
    """(rotation, its overhang area in mm^2): the candidate of least overhang (module doc)."""
    declared = np.asarray(declared, float)
    mesh = _faces(vertices, faces)
    best, best_area = None, np.inf
    for R in [declared] + axis_rotations():
        area, bed, footprint = _overhang(mesh, R)
        if bed < MIN_BED * footprint:
            continue
        if area < best_area - TIE_MM2:
            best, best_area = R, area
    if best is None:            # no flat face: the declared one
        return declared, _overhang(mesh, declared)[0]
    return best, best_area
