"""Vector helpers that the kinematics and every layer above share: the angle a cosine gives
(clipped, as rounding puts two unit vectors' dot product just past +-1), the cross product of
two 3-vectors, a frame across an axis, and the nearest points of a box, a cylinder and a convex
solid swept along a line to many points. numpy only."""

from __future__ import annotations

import math

import numpy as np


def clipped_acos(c):
    """The angle (rad, in [0, pi]) whose cosine is ``c``, clipped to [-1, 1] first: the angle
    between two unit vectors from their dot product. A number gives a float (math.acos), an
    array an array (np.arccos)."""
    if np.ndim(c) == 0:
        return math.acos(max(-1.0, min(1.0, float(c))))
    return np.arccos(np.clip(c, -1.0, 1.0))


def cross3(a, b) -> np.ndarray:
    """``np.cross(a, b)`` of two 3-vectors, to the bit (the same products and differences, in the
    same order), at a tenth of its cost on one pair: the routing model takes thousands per pose."""
    a0, a1, a2 = float(a[0]), float(a[1]), float(a[2])
    b0, b1, b2 = float(b[0]), float(b[1]), float(b[2])
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def perpendicular_frame(u) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (v, w) that make (u, v, w) a right-handed orthonormal frame with the unit
    vector ``u`` (v across u and the axis least along it)."""
    u = np.asarray(u, float)
    v = np.cross(u, np.eye(3)[int(np.argmin(np.abs(u)))])
    v /= np.linalg.norm(v)
    return v, np.cross(u, v)


def nearest_on_box(q: np.ndarray, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """(distance, nearest point) from each of the points ``q`` (n, 3) to the solid axis-aligned box
    [lo, hi] (a bound may be infinite: a box open that way); 0 and the point itself inside."""
    n = np.clip(q, lo, hi)
    return np.linalg.norm(q - n, axis=1), n


def nearest_on_cylinder(q: np.ndarray, z0: float, z1: float, r: float) -> tuple[np.ndarray, np.ndarray]:
    """(distance, nearest point) from each of the points ``q`` (n, 3) to the solid cylinder of
    radius ``r`` about the z axis from z0 to z1 (z1 may be infinite: open up); 0 and the point
    itself inside."""
    rho = np.hypot(q[:, 0], q[:, 1])
    k = np.minimum(rho, r) / np.maximum(rho, 1e-300)
    n = np.c_[q[:, 0] * k, q[:, 1] * k, np.clip(q[:, 2], z0, z1)]
    return np.linalg.norm(q - n, axis=1), n


#: golden-section steps of :func:`nearest_on_swept`: the bracket shrinks by 0.618 a step, to 1e-9
#: of the sweep's length
_SWEEP_STEPS = 44


def nearest_on_swept(q: np.ndarray, nearest, e, length: float) -> tuple[np.ndarray, np.ndarray]:
    """(distance, nearest point) from each of the points ``q`` (n, 3) to a convex solid swept along
    the unit vector ``e`` from 0 to ``length``: ``nearest`` gives (distance, nearest point) of the
    solid itself (:func:`nearest_on_box`, :func:`nearest_on_cylinder`). The distance to the solid
    moved by t e is convex in t (a convex set's distance, along a line), so a golden-section search
    per point finds the least."""
    q, e = np.asarray(q, float), np.asarray(e, float)
    g = (math.sqrt(5.0) - 1.0) / 2.0
    lo, hi = np.zeros(len(q)), np.full(len(q), float(length))
    a, b = hi - g * (hi - lo), lo + g * (hi - lo)
    fa, fb = nearest(q - a[:, None] * e)[0], nearest(q - b[:, None] * e)[0]
    for _ in range(_SWEEP_STEPS):
        left = fa <= fb                     # the least lies in [lo, b]; else in [a, hi]
        hi, lo = np.where(left, b, hi), np.where(left, lo, a)
        a2, b2 = hi - g * (hi - lo), lo + g * (hi - lo)
        new = np.where(left, a2, b2)
        fn = nearest(q - new[:, None] * e)[0]
        # left: the old a is the new b and a2 the new a; else the old b is the new a and b2 the new b
        a, b, fa, fb = (np.where(left, a2, b), np.where(left, a, b2),
                        np.where(left, fn, fb), np.where(left, fa, fn))
    t = (lo + hi) / 2.0
    d, n = nearest(q - t[:, None] * e)
    return d, n + t[:, None] * e
