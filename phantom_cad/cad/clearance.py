"""Do the tendons pass through material? Measured on the built solids, not on the routing model.

Points are sampled along every strand's path (``routing_paths.strand_path``) with the hand posed at
fractions of every joint's and servo's travel (``routing_paths.travel_poses``), carried into each
part's own frame (the frame the part is built in: right-handed, mm; a left hand's points are
mirrored back) and classified against the part's solid by OpenCascade
(``BRepClass3d_SolidClassifier``, after a fast pass on the tessellation). A point inside a solid is a tendon passing through material;
points inside the channels and grooves cut for the tendons are in no solid, by construction of
the solids, which is what is measured.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from ..kinematics import frames as F
from ..kinematics import routing
from ..kinematics import routing_paths
from ..kinematics.hand_params import HandParams


#: fractions of the travel the check poses the hand at
FRACTIONS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: spacing of the sample points along a strand (mm)
STEP_MM = 0.25


@dataclass(frozen=True)
class Hit:
    strand: str
    fraction: float
    part: str
    n_points: int                # how many samples of that strand lie in that part at that pose
    point_mm: tuple              # the first of them, in the part's frame


def _resample(pts: np.ndarray, step: float) -> np.ndarray:
    out = [pts[0]]
    for a, b in zip(pts[:-1], pts[1:]):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        out.extend(a + (b - a) * (k / n) for k in range(1, n + 1))
    return np.array(out)


#: chord tolerance of the tessellation the points are classified against (mm): the exported STL's
#: order, far below the 0.2 mm clearance around a tendon
TESSELLATION_MM = 0.01


def _mesh(shape):
    import trimesh
    verts, tris = shape.tessellate(TESSELLATION_MM, 0.1)
    return trimesh.Trimesh(np.array([[v.X, v.Y, v.Z] for v in verts]), np.array(tris), process=True)


def tendon_hits(params: HandParams, shapes: dict, fractions=FRACTIONS, step_mm: float = STEP_MM) -> list[Hit]:
    """Every (strand, pose, part) where sampled points of the strand lie inside the part's solid.
    ``shapes``: {part name (= its link's name): right-handed solid in its link frame, mm}. Points
    in a part's bounding box are classified against its tessellation (trimesh, ray parity) and
    every point found inside is confirmed on the B-rep (OpenCascade's solid classifier)."""
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN

    S = F.MIRROR[:3, :3] if params.side == "left" else np.eye(3)
    boxes, meshes, classifiers = {}, {}, {}
    for name, sh in shapes.items():
        bb = sh.bounding_box()
        boxes[name] = (np.array([bb.min.X, bb.min.Y, bb.min.Z]), np.array([bb.max.X, bb.max.Y, bb.max.Z]))
        meshes[name] = _mesh(sh)
        classifiers[name] = BRepClass3d_SolidClassifier(sh.wrapped)
    step = units.m(step_mm)
    hits = []
    for f, Ts in zip(fractions, routing_paths.travel_poses(params, fractions)):
        inv = {name: np.linalg.inv(Ts[name]) for name in shapes if name in Ts}
        for r in routing.routes(params):
            for st in r.strands:
                _, pts = routing_paths.strand_path(params, st, Ts)
                pts = _resample(pts, step)
                homo = np.c_[pts, np.ones(len(pts))]
                for name, Ti in inv.items():
                    local = units.mm((homo @ Ti.T)[:, :3]) @ S.T
                    lo, hi = boxes[name]
                    cand = local[np.all((local >= lo) & (local <= hi), axis=1)]
                    if not len(cand):
                        continue
                    cand = cand[meshes[name].contains(cand)]
                    found = []
                    cl = classifiers[name]
                    for p in cand:
                        cl.Perform(gp_Pnt(*map(float, p)), 1e-6)
                        if cl.State() == TopAbs_IN:
                            found.append(p)
                    if found:
                        hits.append(Hit(st.name, float(f), name, len(found),
                                        tuple(round(float(v), 3) for v in found[0])))
    return hits
