"""``kinematics.power_grasp.close_onto``, the bisection both grasps close a digit with, on distances written
out by hand (no solids)."""

import pytest

from phantom_cad.kinematics.power_grasp import CONFUSION_MM, REACH_MM, close_onto


def test_it_stops_in_the_band():
    # d(s) = 3 - 4 s: 3 mm at rest, past contact at the end; s = 0.5 gives 1 mm (in the band)
    s, (d, _) = close_onto(lambda s: (3.0 - 4.0 * s, None))
    assert (s, d) == (0.5, 1.0)


def test_a_distance_under_the_confusion_tolerance_is_a_contact():
    # OpenCascade's distance of overlapping solids can come out a few 1e-15 mm instead of 0: at s = 0.5
    # this one does (the digit is 0.5 mm into the other), and the bisection goes back to s = 0.25
    def d(s):
        return max(1.5 - 4.0 * s, 5e-15), None

    s, (dist, _) = close_onto(d)
    assert s == 0.25 and dist == pytest.approx(0.5)
    assert dist > CONFUSION_MM


def test_already_in_reach_or_never():
    assert close_onto(lambda s: (REACH_MM / 2.0, None)) is None
    assert close_onto(lambda s: (2.0 * REACH_MM, None)) is None
