"""The shared vector helpers (kinematics/vectors.py) and the digit lookup (kinematics/dimensions.py),
on answers worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.kinematics.dimensions import digit_entry, digit_field, digit_path
from phantom_cad.kinematics.vectors import (clipped_acos, nearest_on_box, nearest_on_cylinder, nearest_on_swept,
                                            perpendicular_frame)


def test_clipped_acos_by_hand():
    # a dot product rounded just past +-1 is the angle 0 or pi, not a math domain error
    assert clipped_acos(1.0 + 1e-15) == 0.0
    assert clipped_acos(-1.0 - 1e-15) == math.pi
    assert clipped_acos(0.5) == pytest.approx(math.pi / 3.0)
    assert isinstance(clipped_acos(np.float64(0.5)), float)
    got = clipped_acos(np.array([1.5, 0.0, -2.0]))
    assert isinstance(got, np.ndarray)
    assert np.allclose(got, [0.0, math.pi / 2.0, math.pi])


@pytest.mark.parametrize("u", [(1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.6, 0.0, 0.8), (1.0, 2.0, -3.0)])
def test_perpendicular_frame_is_right_handed_and_orthonormal(u):
    u = np.asarray(u) / np.linalg.norm(u)
    v, w = perpendicular_frame(u)
    R = np.column_stack([u, v, w])
    assert np.allclose(R.T @ R, np.eye(3))
    assert np.linalg.det(R) == pytest.approx(1.0)


def test_perpendicular_frame_along_x_by_hand():
    # the axis least along x is y: v = x cross y = z, w = x cross z = -y
    v, w = perpendicular_frame([1.0, 0.0, 0.0])
    assert np.allclose(v, [0.0, 0.0, 1.0]) and np.allclose(w, [0.0, -1.0, 0.0])


def test_nearest_on_a_box_by_hand():
    """The unit cube: (2, 3, 0.5) is nearest its edge at (1, 1, 0.5), sqrt(1 + 4) away; a point
    inside is its own nearest point; a box open up (z to infinity) is 0 above it."""
    q = np.array([[2.0, 3.0, 0.5], [0.5, 0.5, 0.5], [0.5, 0.5, 7.0]])
    d, n = nearest_on_box(q, (0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    assert d.tolist() == pytest.approx([math.sqrt(5.0), 0.0, 6.0])
    assert np.allclose(n, [[1.0, 1.0, 0.5], [0.5, 0.5, 0.5], [0.5, 0.5, 1.0]])
    assert nearest_on_box(q[2:], (0.0, 0.0, 0.0), (1.0, 1.0, np.inf))[0].tolist() == [0.0]


def test_nearest_on_a_cylinder_by_hand():
    """Radius 2 about z from 0 to 1: (3, 4, 5) is 5 from the axis, nearest the rim at (1.2, 1.6, 1):
    (1.8, 2.4, 4) away, 5; open up, 3 (its radial distance); a point on the axis inside is its own."""
    q = np.array([[3.0, 4.0, 5.0], [0.0, 0.0, 0.5]])
    d, n = nearest_on_cylinder(q, 0.0, 1.0, 2.0)
    assert d.tolist() == pytest.approx([5.0, 0.0])
    assert np.allclose(n, [[1.2, 1.6, 1.0], [0.0, 0.0, 0.5]])
    assert nearest_on_cylinder(q[:1], 0.0, np.inf, 2.0)[0].tolist() == pytest.approx([3.0])



def test_nearest_on_a_swept_box_by_hand():
    """The unit cube swept along (1, 0, 1) / sqrt 2 by 10 sqrt 2 (to [10, 11] x [0, 1] x [10, 11]):
    across x-z a band between the lines x - z = -1 and x - z = 1. (0.5, 0.5, -1) is 1 under the
    first cube; (5.5, 0.5, 5.5) inside; (8, 0.5, 3) 4 / sqrt 2 past the line x - z = 1, nearest
    (6, 0.5, 5); (15, 0.5, 15) off the last cube's corner (11, 0.5, 11), 4 sqrt 2; (5.5, 3, 5.5) 2
    beside the band."""
    e = np.array([1.0, 0.0, 1.0]) / math.sqrt(2.0)
    q = np.array([[0.5, 0.5, -1.0], [5.5, 0.5, 5.5], [8.0, 0.5, 3.0], [15.0, 0.5, 15.0], [5.5, 3.0, 5.5]])
    d, n = nearest_on_swept(q, lambda x: nearest_on_box(x, (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)), e, 10.0 * math.sqrt(2.0))
    assert d.tolist() == pytest.approx([1.0, 0.0, 2.0 * math.sqrt(2.0), 4.0 * math.sqrt(2.0), 2.0], abs=1e-7)
    assert np.allclose(n[[0, 1, 2, 3]], [[0.5, 0.5, 0.0], [5.5, 0.5, 5.5], [6.0, 0.5, 5.0], [11.0, 0.5, 11.0]], atol=1e-7)
    assert np.allclose(np.linalg.norm(q - n, axis=1), d)


def test_nearest_on_a_swept_cylinder_by_hand():
    """A disc of radius 2, z from 0 to 1, swept 5 up its own axis is the cylinder from 0 to 6:
    (3, 4, 3) is 3 from its side; (0, 0, 9) 3 above its top."""
    q = np.array([[3.0, 4.0, 3.0], [0.0, 0.0, 9.0]])
    d, _ = nearest_on_swept(q, lambda x: nearest_on_cylinder(x, 0.0, 1.0, 2.0), np.array([0.0, 0.0, 1.0]), 5.0)
    assert d.tolist() == pytest.approx([3.0, 3.0], abs=1e-7)

def test_a_digit_in_the_parameter_file():
    doc = {"thumb": {"width_mm": 1}, "fingers": {"ring": {"width_mm": 2}}}
    assert digit_path("thumb") == ("thumb",) and digit_path("ring") == ("fingers", "ring")
    assert digit_field("thumb") == "thumb" and digit_field("ring") == "fingers.ring"
    assert digit_entry(doc, "thumb") == {"width_mm": 1}
    assert digit_entry(doc, "ring") == {"width_mm": 2}

    class Hand:
        thumb, fingers = "the thumb", {"ring": "the ring finger"}

    assert digit_entry(Hand(), "thumb") == "the thumb" and digit_entry(Hand(), "ring") == "the ring finger"
