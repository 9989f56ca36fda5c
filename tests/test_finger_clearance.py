"""kinematics.finger_clearance: the distance between two boxes against closed forms, and its grid of
commands holding the collision check's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.kinematics import finger_clearance as FC
from phantom_cad.kinematics.opposition import segment_distance


def rot(axis: str, deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def cube(centre, R=np.eye(3), half=0.5):
    return np.array([centre], float), np.array([R]), np.full((1, 3), half)


@pytest.mark.parametrize("a, b, want", [
    (cube((0, 0, 0)), cube((3, 0, 0)), 2.0),                                  # face to face
    (cube((0, 0, 0)), cube((3, 0, 0), rot("z", 45)), 2.5 - math.sqrt(0.5)),   # an edge to a face
    (cube((0, 0, 0), rot("z", 45)), cube((3, 0, 0), rot("y", 45)), 3.0 - math.sqrt(2.0)),   # crossed edges
    (cube((0, 0, 0)), cube((2, 2, 2)), math.sqrt(3.0)),                        # corner to corner
    (cube((0, 0, 0)), cube((2, 2, 0)), math.sqrt(2.0)),                        # parallel edges
    (cube((0, 0, 0)), cube((0.8, 0, 0)), -0.2),                                # overlapping: minus the depth
    (cube((0, 0, 0)), cube((0, 0.3, 0.9), rot("x", 90)), -0.1),                # turned a quarter: the same box
])
def test_box_distance_against_closed_forms(a, b, want):
    assert FC.box_distance(a, b)[0] == pytest.approx(want, abs=1e-12)
    assert FC.box_distance(b, a)[0] == pytest.approx(want, abs=1e-12)
    assert FC.least_box_distance(a, b) == pytest.approx(want, abs=1e-12)


def test_the_separating_gap_is_a_lower_bound():
    """Corner to corner the projections are one unit apart along each face normal, the boxes
    sqrt(3) units apart."""
    a, b = cube((0, 0, 0)), cube((2, 2, 2))
    assert FC.separating_gap(a, b)[0] == pytest.approx(1.0)


def test_segment_distance():
    """The segment distance the boxes' edges are measured with (``opposition.segment_distance``), by
    hand: crossing segments one apart, parallel ones offset along and across, a segment above."""
    def dist(*q):
        return float(segment_distance(p0, p1, *q)[0])

    p0, p1 = np.array([0.0, 0, 0]), np.array([1.0, 0, 0])
    assert dist(np.array([0.5, 1, -1.0]), np.array([0.5, 1, 1.0])) == pytest.approx(1.0)
    assert dist(np.array([3.0, 0, 4.0]), np.array([5.0, 0, 4.0])) == pytest.approx(math.hypot(2.0, 4.0))
    assert dist(np.array([0.2, 2, 0.0]), np.array([0.7, 2, 0.0])) == pytest.approx(2.0)


def test_the_grid_holds_the_collision_checks():
    from phantom_cad.export.interference import SWEEP_FRACTIONS

    assert set(SWEEP_FRACTIONS) <= {round(f, 12) for f in FC.GRID}
