"""How far the CMC base stands from a box of the palm or the forearm module at rest (the palm's
heel, the module's block), measured on the solids its part is made of: the hub (a cylinder of
thumb.width_mm about the CMC axis), the column up the axis into the palm, and the metacarpal's
arm (a box as wide out to the MP axis). ``forearm_layout.heel_gap`` and ``forearm_layout.forearm_gap``
read it; the pre-build check and the placement search keep to both.

The box and each of the base's solids are convex, so the distance between them is found on
features: along every edge of the box to the solid (the distance from a point to a convex solid is
convex along a line: least by shrinking brackets), and along every straight line on the solid's
boundary (the arm's twelve edges, the cylinders' generators every 360 / :data:`GENERATORS` deg
round) to the box; the least over the solids. Exact for the box
pairs; for a cylinder within its generators' sagitta (under 0.01 mm at 12 mm radius).
Signed: negative where they overlap. numpy only; palm frame, right hand, m."""

from __future__ import annotations

import math

import numpy as np

from .frames import T_palm_thumb_cmc_base
from .hand_params import HandParams
from .thenar import thenar, thenar_layout

#: the cylinders' straight lines measured round their side
GENERATORS = 96


def box_distance(P: np.ndarray, lo, hi) -> np.ndarray:
    """Signed distance (n,) from points P (n, 3) to the box [lo, hi]: Euclidean outside, minus the
    depth to the nearest face inside."""
    q = np.maximum(np.asarray(lo) - P, P - np.asarray(hi))
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)


def cylinder_distance(Q: np.ndarray, r: float, z0: float, z1: float) -> np.ndarray:
    """Signed distance (n,) from points Q (n, 3) to the solid cylinder of radius r about the z axis
    from z0 to z1."""
    d = np.c_[np.hypot(Q[:, 0], Q[:, 1]) - r, np.maximum(z0 - Q[:, 2], Q[:, 2] - z1)]
    return np.linalg.norm(np.maximum(d, 0.0), axis=1) + np.minimum(d.max(axis=1), 0.0)


def least_along(f, a: np.ndarray, b: np.ndarray, rounds: int = 5, n: int = 17) -> float:
    """The least over segments a_k -> b_k (k, 3) of a convex function f of points (m, 3) -> (m,)
    that changes by at most the distance moved (a distance): per segment n samples, then n again
    between the least one's neighbours, ``rounds`` times (the bracket shrinks to 1 / 8 of itself
    each time: to 3e-5 of the segment, a micrometre or two on the CMC base's and the module's
    edges). A segment whose samples all lie more than half a step above the least found is dropped:
    nowhere between them can it come lower."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    lo, hi = np.zeros(len(a)), np.ones(len(a))
    length = np.linalg.norm(b - a, axis=1)
    u = np.linspace(0.0, 1.0, n)
    best = math.inf
    for _ in range(rounds):
        t = lo[:, None] + (hi - lo)[:, None] * u[None, :]                       # (k, n)
        v = f((a[:, None, :] + t[..., None] * (b - a)[:, None, :]).reshape(-1, 3)).reshape(len(a), n)
        i = np.argmin(v, axis=1)
        rows = np.arange(len(a))
        least = v[rows, i]
        best = min(best, float(least.min()))
        keep = least - length * (hi - lo) / (2.0 * (n - 1)) <= best
        lo, hi = t[rows, np.maximum(i - 1, 0)][keep], t[rows, np.minimum(i + 1, n - 1)][keep]
        a, b, length = a[keep], b[keep], length[keep]
    return best


def box_edges(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """The twelve edges (a, b) (12, 3) each of the box [lo, hi]."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    pairs = [(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1]
    return c[[i for i, _ in pairs]], c[[j for _, j in pairs]]


def cmc_base_solids(params: HandParams, T0: np.ndarray | None = None, floor: float | None = None) -> list:
    """The CMC base at rest as solids in its own frame (the CMC axis z, the metacarpal along y):
    ("cylinder", r, z0, z1) the hub (thumb.width_mm across, from ``floor`` to thumb.thickness_mm / 2)
    and the column (up the axis to the palm's palmar face, ``thenar.thenar``); ("box", lo, hi) the arm
    (as wide, from ``floor`` to the dorsal face, out to the MP axis). ``T0``: another CMC placement
    than the file's; ``floor`` (m, default -thumb.thickness_mm / 2): the part reaches lower where
    the MP guide's boss hangs below the palmar face (``cad.parts.thumb.ThumbCMCBase.palmar_floor``,
    which the pre-build check passes)."""
    th = params.thumb
    t = thenar(params) if T0 is None else thenar_layout(params, T0)
    W, T, L = th.width, th.thickness, th.metacarpal
    z0 = -T / 2.0 if floor is None else min(floor, -T / 2.0)
    out = [("cylinder", W / 2.0, z0, T / 2.0), ("box", np.array([-W / 2.0, 0.0, z0]), np.array([W / 2.0, L, T / 2.0]))]
    if t["face"] > T / 2.0:
        out.append(("cylinder", t["column_r"], T / 2.0, t["face"]))
    return out


def cmc_base_gap(params: HandParams, lo, hi, T0: np.ndarray | None = None, floor: float | None = None) -> float:
    """The signed distance (m) from the CMC base at rest (:func:`cmc_base_solids`; ``T0`` and
    ``floor`` as there) to the box [lo, hi] (palm frame): negative where they overlap."""
    T0 = T_palm_thumb_cmc_base(params) if T0 is None else T0
    R, o = T0[:3, :3], T0[:3, 3]
    ea, eb = box_edges(lo, hi)
    ea, eb = (ea - o) @ R, (eb - o) @ R             # the box's edges in the base's frame
    a = np.linspace(0.0, 2.0 * math.pi, GENERATORS, endpoint=False)
    best = math.inf
    lines = []                                      # the base's straight lines, its frame
    for solid in cmc_base_solids(params, T0, floor):
        if solid[0] == "cylinder":
            _, r, z0, z1 = solid
            inside = lambda q, r=r, z0=z0, z1=z1: cylinder_distance(q, r, z0, z1)    # noqa: E731
            ring = np.c_[r * np.cos(a), r * np.sin(a)]
            lines.append((np.c_[ring, np.full(len(a), z0)], np.c_[ring, np.full(len(a), z1)]))
        else:
            _, blo, bhi = solid
            inside = lambda q, blo=blo, bhi=bhi: box_distance(q, blo, bhi)            # noqa: E731
            lines.append(box_edges(blo, bhi))
        best = min(best, least_along(inside, ea, eb))
    sa, sb = np.vstack([x for x, _ in lines]), np.vstack([y for _, y in lines])
    return min(best, least_along(lambda p: box_distance(p, lo, hi), sa @ R.T + o, sb @ R.T + o))
