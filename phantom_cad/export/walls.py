"""Wall thickness of a printed part, measured on its mesh by ray casting (the requirement: every
wall at least two perimeters of the nozzle, 0.8 mm by default).

Points are sampled over the surface (area-weighted, seeded: the same mesh gives the same
numbers). From each, rays go into the solid along the inward normal and six directions
:data:`CONE_DEG` around it; the point's wall is the median of the distances at which they leave
the solid, each taken along the normal (the shape diameter function, with a median: one ray
that grazes a face or slips past an edge does not decide it; a flat wall measures its thickness
on every ray). Points within :data:`EDGE_MM` of a sharp edge (faces meeting at more
than :data:`SHARP_DEG`) are not measured: there the wall is the edge's own angle, not a wall
(a box's corner is not thin). Units: those of the mesh (mm).

A wall is two faces within :data:`WALL_DEG` of parallel; where the median ray leaves through a
face further off parallel the point is on an **edge** (a wedge of that apex angle, e.g. a hole
that leaves a face obliquely): :func:`thin_walls` reports both, the walls apart.

Limits: near the corner of a narrow strip (the 2 mm side of a plate) two edges cut the cone and
the side reads down to 0.8 of the strip's width (1.6 mm for 2 mm, within 0.4 mm of the corner);
a wall is found where points are sampled: at :data:`SAMPLES` points about every 0.5 mm on a
finger part, 1.2 mm on the palm (tests/cad/test_walls.py checks a plate, a tube and a roof over a channel).
"""

from __future__ import annotations

import numpy as np

from .. import units
from ..kinematics.hand_params import HandParams
from ..kinematics.vectors import clipped_acos
from ..params.rules import MIN_WALL

#: half-angle of the cone of rays around the inward normal (degrees)
CONE_DEG = 15.0
#: rays per point besides the normal
CONE_RAYS = 6
#: faces meeting at more than this angle make a sharp edge (degrees)
SHARP_DEG = 20.0
#: points nearer a sharp edge than this are not measured (mm)
EDGE_MM = 0.1
#: surface samples per part
SAMPLES = 20000
#: a wall: the face a point lies on and the face its median ray leaves through are within this
#: angle of parallel (degrees); thinner points between faces further apart are edges (wedges)
WALL_DEG = 30.0


def _cone(n: np.ndarray) -> np.ndarray:
    """(m, 1 + CONE_RAYS, 3) unit directions: n and CONE_RAYS around it at CONE_DEG."""
    a = np.where(np.abs(n[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    u = np.cross(n, a)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w = np.cross(n, u)
    c, s = np.cos(units.rad(CONE_DEG)), np.sin(units.rad(CONE_DEG))
    dirs = [n] + [c * n + s * (np.cos(phi) * u + np.sin(phi) * w)
                  for phi in 2.0 * np.pi * np.arange(CONE_RAYS) / CONE_RAYS]
    return np.stack(dirs, axis=1)


def _edge_distance(mesh, points: np.ndarray) -> np.ndarray:
    """Distance of each point to the nearest sharp edge of the mesh (inf without one)."""
    from scipy.spatial import cKDTree

    sharp = mesh.face_adjacency_angles > units.rad(SHARP_DEG)
    if not sharp.any():
        return np.full(len(points), np.inf)
    seg = mesh.vertices[mesh.face_adjacency_edges[sharp]]                    # (k, 2, 3)
    length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
    step = EDGE_MM / 4.0
    n = np.maximum(np.ceil(length / step).astype(int), 1)
    t = np.concatenate([np.linspace(0.0, 1.0, k + 1) for k in n])
    idx = np.repeat(np.arange(len(seg)), n + 1)
    dense = seg[idx, 0] + t[:, None] * (seg[idx, 1] - seg[idx, 0])
    d, _ = cKDTree(dense).query(points)
    return d


def wall_samples(vertices: np.ndarray, faces: np.ndarray, samples: int = SAMPLES, seed: int = 0
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points, walls, off_parallel): surface points away from sharp edges, the wall measured at
    each (the median of the cone's exit distances; inf where no ray leaves, which a closed mesh
    does not allow) and the angle (degrees) between the face the point lies on and the face its
    median ray (the one whose distance is the wall) leaves through (0: two parallel faces; a
    wedge of apex angle a: a)."""
    import trimesh

    mesh = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces, np.int64), process=False)
    points, face = trimesh.sample.sample_surface(mesh, samples, seed=seed)
    keep = _edge_distance(mesh, points) >= EDGE_MM
    points, normals = points[keep], mesh.face_normals[face[keep]]
    dirs = -_cone(normals)
    m, k, _ = dirs.shape
    eps = 1e-4
    origins = np.repeat(points, k, axis=0) + dirs.reshape(-1, 3) * eps
    hit, ray, tri = mesh.ray.intersects_location(origins, dirs.reshape(-1, 3), multiple_hits=False)
    dist = np.full(m * k, np.inf)
    dist[ray] = np.linalg.norm(hit - origins[ray], axis=1) + eps
    # each exit distance along the normal: a flat wall measures its thickness on every ray
    along = dist.reshape(m, k) * np.r_[1.0, np.full(k - 1, np.cos(units.rad(CONE_DEG)))]
    exit_normal = np.full((m * k, 3), np.nan)
    exit_normal[ray] = mesh.face_normals[tri]
    # the wall is the median ray's (k is odd): the face it leaves through says wall or edge (near
    # a corner the normal's own ray can leave through a far parallel face while the median one
    # leaves through the corner's side)
    median = np.argsort(along, axis=1, kind="stable")[:, k // 2]
    leaves = exit_normal.reshape(m, k, 3)[np.arange(m), median]
    cos = -np.einsum("ij,ij->i", normals, leaves)
    off = units.deg(clipped_acos(np.nan_to_num(cos, nan=-1.0)))
    return points, along[np.arange(m), median], off


def wall_thickness(vertices: np.ndarray, faces: np.ndarray, samples: int = SAMPLES, seed: int = 0
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(points, walls) of :func:`wall_samples`."""
    points, walls, _ = wall_samples(vertices, faces, samples, seed)
    return points, walls


def thin_walls(vertices: np.ndarray, faces: np.ndarray, minimum: float, samples: int = SAMPLES,
               seed: int = 0) -> dict:
    """What is thinner than ``minimum``: {"thinnest": the least thickness measured, "at": its
    point, "fraction": the share of measured points below ``minimum``, "points": how many were
    measured}, and the same of the **walls** alone ("wall_thinnest", "wall_at", "wall_fraction":
    points whose median ray leaves through a face within :data:`WALL_DEG` of parallel to theirs;
    inf / None / 0 without one). The rest are edges: two faces meeting at an angle (a
    wedge, whose tip a slicer rounds by a perimeter), not a wall between two faces."""
    points, walls, off = wall_samples(vertices, faces, samples, seed)
    i = int(np.argmin(walls))
    wall = off <= WALL_DEG
    thin = walls < minimum
    out = {"thinnest": float(walls[i]), "at": [round(float(v), 3) for v in points[i]],
           "fraction": float(np.mean(thin)), "points": int(len(walls)),
           "wall_thinnest": float("inf"), "wall_at": None, "wall_fraction": float(np.mean(thin & wall))}
    if wall.any():
        j = int(np.argmin(np.where(wall, walls, np.inf)))
        out["wall_thinnest"] = float(walls[j])
        out["wall_at"] = [round(float(v), 3) for v in points[j]]
    return out


def wall_bar_mm(params: HandParams) -> float:
    """The thinnest wall (mm) a part's exported mesh may read: two perimeters of the nozzle
    (``params.rules.MIN_WALL``) less twice the STL tolerance, as a mesh lies within that tolerance of
    each face (a wall of exactly two perimeters can read that much thinner)."""
    return units.mm(MIN_WALL) - 2.0 * units.mm(params.print.stl_tolerance)


def part_walls(meshes: dict[str, tuple[np.ndarray, np.ndarray]], params: HandParams,
               samples: int = SAMPLES) -> dict[str, dict]:
    """{part: :func:`thin_walls` of its mesh (vertices, faces; mm) against :func:`wall_bar_mm`}."""
    bar = wall_bar_mm(params)
    return {n: thin_walls(v, f, bar, samples) for n, (v, f) in sorted(meshes.items())}
