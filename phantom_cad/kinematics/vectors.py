"""Vector helpers that the kinematics and every layer above share: the angle a cosine gives
(clipped, as rounding puts two unit vectors' dot product just past +-1), the cross product of
two 3-vectors and a frame across an axis. numpy only."""

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
