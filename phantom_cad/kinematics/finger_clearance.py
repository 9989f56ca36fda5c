"""How close neighbouring fingers come as they flex: each finger link as boxes that hold its
part (numpy only, right-hand palm frame, metres), posed by the model over a grid of servo
commands, and the least distance between the boxes of two neighbouring fingers.

A link's boxes (link frame: x along the joint axes, y along the link, z dorsal; the parts in
``cad/parts/phalanx.py`` and ``finger_base.py``): a phalanx is ``width`` x ``thickness`` from its
joint axis to the clevis boss round its far axis (radius thickness / 2), or to the fingertip; its
tongue reaches a clevis slot's back (``dimensions.slot_back``) behind the axis, a cheek narrower
each side. A finger base is ``width`` x ``thickness`` from its magnet face
(``cad.finger_base_length``) to the MCP clevis boss. The boxes hold the parts' rounded ends by their
corners, so a clearance between boxes is at most the parts' clearance.
"""

from __future__ import annotations

import itertools

import numpy as np

from .dimensions import slot_back
from .frames import fingertip
from .hand_params import HandParams
from .link_frames import link_transforms
from .opposition import segment_distance
from .topology import FINGERS, SERVOS, digit_links

#: fractions of each finger servo's travel the clearance is measured at: every 5 %, which holds the
#: collision check's command grid (``export.interference.SWEEP_FRACTIONS``)
GRID = tuple(k / 20.0 for k in range(21))

# the 8 corners (as signs) and 12 edges (corner index pairs) of a box
_SIGNS = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))
BOX_EDGES = np.array([(i, j) for i in range(8) for j in range(i + 1, 8)
                      if np.count_nonzero(_SIGNS[i] != _SIGNS[j]) == 1])


def rounded_ends(params: HandParams, finger: str) -> dict[str, tuple[float, float]]:
    """{phalanx link: (y, r)} of each phalanx's rounded far end in its link frame (m): a half
    cylinder about the link's x at y of radius r, across the finger: the clevis boss round its far
    joint's axis (y its length, r half its thickness) or the fingertip (``frames.fingertip``)."""
    d = params.fingers[finger]
    out = {}
    for ln in digit_links(finger)[1:]:
        if ln.segment == "distal":
            L, r, _ = fingertip(params, finger)
            out[ln.name] = (L - r, r)
        else:
            out[ln.name] = (getattr(d, ln.segment), d.thickness / 2.0)
    return out


def link_boxes(params: HandParams, finger: str, rounded: bool = False) -> dict[str, list[tuple[np.ndarray, np.ndarray]]]:
    """{link name: [(centre, half extents)]} of a finger's link boxes in their link frames (m).
    ``rounded``: each phalanx's main box stops at its rounded end's axis (:func:`rounded_ends`),
    and the axis follows as a box of no thickness (half extents (W / 2, 0, 0)), round which the
    caller takes the end's radius; else the main box reaches over the end."""
    d = params.fingers[finger]
    W, T = d.width, d.thickness
    back = slot_back(T, params.print.hole_clearance)
    tongue = W / 2.0 - params.cad.cheek
    ends = rounded_ends(params, finger)

    def box(x0, x1, y0, y1):
        lo, hi = np.array([x0, y0, -T / 2.0]), np.array([x1, y1, T / 2.0])
        return (lo + hi) / 2.0, (hi - lo) / 2.0

    out = {}
    for ln in digit_links(finger):
        if ln.parent_joint is None:           # the finger base: magnet face to the MCP clevis boss
            out[ln.name] = [box(-W / 2.0, W / 2.0, -params.cad.finger_base_length, T / 2.0)]
            continue
        y, r = ends[ln.name]
        out[ln.name] = [box(-W / 2.0, W / 2.0, 0.0, y if rounded else y + r), box(-tongue, tongue, -back, 0.0)]
        if rounded:
            out[ln.name].append((np.array([0.0, y, 0.0]), np.array([W / 2.0, 0.0, 0.0])))
    return out


def posed_boxes(params: HandParams, hand, fractions=GRID, compensated: bool = False,
                rounded: bool = False) -> dict[str, tuple]:
    """{finger: (fixed, moving)} of every finger's boxes over its servo's travel, each a tuple
    (centres (n, 3), axes (n, 3, 3), half extents (n, 3)) in the palm frame (right hand, m):
    ``fixed`` the finger base's (n = 1), ``moving`` the phalanges' at each fraction (n =
    len(fractions) x boxes, the fraction slowest). ``hand``: the model (``Hand``) whose ``forward``
    poses the fingers (ideal coupling, as the collision check poses them, or ``compensated``); each
    finger hangs on its own servo, so one pose per fraction holds all four."""
    servos = [s.index for s in SERVOS if s.digit in FINGERS]
    boxes = {f: link_boxes(params, f, rounded) for f in FINGERS}
    out = {f: ([], []) for f in FINGERS}
    for k, frac in enumerate(fractions):
        u = np.array(hand.u_min, float)
        u[servos] += frac * (hand.u_max[servos] - hand.u_min[servos])
        T = link_transforms(params, hand.forward(u, compensated=compensated), mirrored=False)
        for f in FINGERS:
            fixed, moving = out[f]
            for ln in digit_links(f):
                if ln.parent_joint is None and k:
                    continue
                R, t = T[ln.name][:3, :3], T[ln.name][:3, 3]
                for c, h in boxes[f][ln.name]:
                    (fixed if ln.parent_joint is None else moving).append((R @ c + t, R, h))

    def pack(items):
        return tuple(np.array([it[i] for it in items]) for i in range(3))
    return {f: (pack(fixed), pack(moving)) for f, (fixed, moving) in out.items()}


def box_distance(a, b) -> np.ndarray:
    """The distance between boxes a[i] and b[i] (each (centres (n, 3), axes (n, 3, 3) as columns,
    half extents (n, 3))); where two overlap, minus the least translation that parts them (the
    separating-axis theorem's depth). Separated: the least of every corner of one to the other box
    and every edge of one to every edge of the other (the nearest points of two convex polyhedra lie
    on such a pair)."""
    depth = separating_gap(a, b)
    out = depth.copy()
    apart = depth > 0.0
    if apart.any():
        out[apart] = _separated_distance(_take(a, apart), _take(b, apart))
    return out


def least_box_distance(a, b) -> float:
    """``box_distance(a, b).min()``, measuring exactly only the pairs that may hold it: the
    separating gap is a lower bound on each pair's distance (a projection shortens every distance)."""
    gap = separating_gap(a, b)
    if gap.min() <= 0.0:
        return float(gap.min())
    first = np.array([int(gap.argmin())])
    bound = float(_separated_distance(_take(a, first), _take(b, first))[0])
    near = gap < bound
    if not near.any():
        return bound
    return min(bound, float(_separated_distance(_take(a, near), _take(b, near)).min()))


def _take(box, which):
    return tuple(v[which] for v in box)


def separating_gap(a, b) -> np.ndarray:
    """The largest gap between the projections of boxes a[i] and b[i] onto their separating axes
    (3 + 3 face normals, 9 edge cross products): positive where they are apart (a lower bound on
    their distance), else minus the depth of their overlap. In a's frame (Gottschalk's form: b's
    axes are the columns of C = Ra^T Rb)."""
    ca, Ra, ha = a
    cb, Rb, hb = b
    t = np.einsum("nji,nj->ni", Ra, cb - ca)                       # b's centre in a's frame
    C = np.einsum("nki,nkj->nij", Ra, Rb)
    A = np.abs(C)
    gaps = [np.abs(t) - ha - np.einsum("nij,nj->ni", A, hb),                        # a's faces
            np.abs(np.einsum("ni,nij->nj", t, C)) - hb - np.einsum("nij,ni->nj", A, ha)]  # b's faces
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            # the axis a_i x b_j, of length sin(a_i, b_j): none where the two edges are parallel
            length = np.sqrt(np.maximum(1.0 - C[:, i, j] ** 2, 0.0))
            ra = ha[:, i1] * A[:, i2, j] + ha[:, i2] * A[:, i1, j]
            rb = hb[:, j1] * A[:, i, j2] + hb[:, j2] * A[:, i, j1]
            dist = np.abs(t[:, i2] * C[:, i1, j] - t[:, i1] * C[:, i2, j])
            ok = length > 1e-9
            gaps.append(np.where(ok, (dist - ra - rb) / np.where(ok, length, 1.0), -np.inf)[:, None])
    return np.concatenate(gaps, axis=1).max(axis=1)


def box_corners(box) -> np.ndarray:
    """The 8 corners (n, 8, 3) of boxes (centres, axes, half extents), in :data:`BOX_EDGES`' order."""
    c, R, h = box
    return c[:, None, :] + np.einsum("nij,nkj->nki", R, _SIGNS * h[:, None, :])


def _point_box(p: np.ndarray, box) -> np.ndarray:
    """Distance of points p (n, k, 3) to box[n] (outside; 0 inside)."""
    c, R, h = box
    local = np.einsum("nji,nkj->nki", R, p - c[:, None, :])
    return np.linalg.norm(np.maximum(np.abs(local) - h[:, None, :], 0.0), axis=2).min(axis=1)


def _separated_distance(a, b) -> np.ndarray:
    pa, pb = box_corners(a), box_corners(b)
    best = np.minimum(_point_box(pa, b), _point_box(pb, a))
    # every edge of a against every edge of b
    p0, p1 = pa[:, BOX_EDGES[:, 0]], pa[:, BOX_EDGES[:, 1]]               # (n, 12, 3)
    q0, q1 = pb[:, BOX_EDGES[:, 0]], pb[:, BOX_EDGES[:, 1]]
    d = segment_distance(p0[:, :, None], p1[:, :, None], q0[:, None], q1[:, None])[0]
    return np.minimum(best, d.reshape(len(d), -1).min(axis=1))


def neighbour_clearance(params: HandParams, hand, fractions=GRID) -> tuple[float, tuple[str, str]]:
    """The least distance (m) between the boxes of two neighbouring fingers over the grid of both
    servos' commands (every pair of fractions), each finger's phalanges against the other's
    phalanges and finger base; and the pair where it is least (negative: the boxes overlap)."""
    posed = posed_boxes(params, hand, fractions)
    best, where = np.inf, ("", "")
    for a, b in zip(FINGERS, FINGERS[1:]):
        (fa, ma), (fb, mb) = posed[a], posed[b]
        na, nb = len(ma[0]), len(mb[0])
        pairs = [
            (tuple(np.repeat(v, nb, axis=0) for v in ma), tuple(np.tile(v, (na,) + (1,) * (v.ndim - 1)) for v in mb)),
            (ma, tuple(np.repeat(v, na, axis=0) for v in fb)),
            (mb, tuple(np.repeat(v, nb, axis=0) for v in fa)),
        ]
        d = min(least_box_distance(x, y) for x, y in pairs)
        if d < best:
            best, where = d, (a, b)
    return best, where
