"""Joint-angle vectors for tests, written by joint name."""

from __future__ import annotations

import math

import numpy as np

from phantom_cad.kinematics.topology import JOINTS, joint


def q_deg(**deg) -> np.ndarray:
    """Joint angles (15,) rad from degrees by joint name (``topology.JOINTS``), the rest 0."""
    q = np.zeros(len(JOINTS))
    for name, v in deg.items():
        q[joint(name).index] = math.radians(v)
    return q
