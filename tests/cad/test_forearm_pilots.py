"""The flange pilots of a servo whose pocket opens up the forearm module rather than along its
shaft (``forearm_layout.drops_straight``: servo 6 in the two rows, tilted with the CMC axis). The
pocket is swept along ``Forearm.drop_vector``, square to the body's length, so it keeps to the
pilots the wall it has along the shaft however the CMC axis turns the servo: measured with
OpenCascade on the swept solids."""

from __future__ import annotations

import copy

import pytest

from phantom_cad.cad.parts.forearm import Forearm
from phantom_cad.kinematics.dimensions import servo_pilot_wall
from phantom_cad.kinematics import forearm_layout as FL
from phantom_cad.params import DEFAULT_PARAMS, load_document, parse
from phantom_cad.sizing import magnet_lift
from phantom_cad.units import mm

pytest.importorskip("build123d")


def _turned(axis_deg: tuple[float, float, float]):
    """The default hand with its CMC axis turned by ``axis_deg`` (roll, pitch, yaw; servo 6 turns
    with it), the magnet pockets lifted as ``size`` lifts them for the placement."""
    doc = copy.deepcopy(load_document(DEFAULT_PARAMS))
    doc["palm"]["thumb_cmc_axis_deg"] = [a + d for a, d in zip(doc["palm"]["thumb_cmc_axis_deg"], axis_deg)]
    magnet_lift(doc)
    return parse(doc)


#: turns of the CMC axis at which the pocket swept straight up the module's z came within 0.2 mm of
#: a pilot (and on a sized hand cut one open: the module's check found 11 of its 12 pilots)
TURNS = [(0.0, 0.0, 0.0), (0.0, 6.0, 0.0), (6.0, 0.0, 0.0), (0.0, 0.0, 10.0)]


@pytest.mark.parametrize("turn", TURNS, ids=lambda t: "roll {:g} pitch {:g} yaw {:g}".format(*t))
def test_the_swept_pocket_keeps_the_pilots_wall(turn):
    """Each pilot of servo 6 (its cylinder from the ear's underside down its depth) against the
    body pocket swept along the drop as the module cuts it (BRepExtrema's distance): the wall along
    the shaft, (flange span - body length) / 4 - pilot / 2 - clearance (1.175 mm by default)."""
    from phantom_cad.cad.parts.common import box, cylinder, swept_along, transform

    p = _turned(turn)
    fa = Forearm(p)
    t = fa.tol
    wall = mm(servo_pilot_wall(p.servo.body[0], p.servo.flange_span, t.screw_pilot / 1e3, p.print.hole_clearance))
    dropped = [k for k in range(6) if FL.drops_straight(p, k)]
    assert dropped, "servo 6 drops in along its drop vector"
    for k in dropped:
        T = fa.T_servo(k)
        lo, hi = fa.open_pockets(k, fa.cavity_span(k)[1])[0]
        pocket = swept_along(transform(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]), T), fa.drop_vector(k))
        for c in fa.screw_points(k):
            pilot = transform(cylinder(c, c - [0.0, 0.0, t.clearance + t.screw_engagement], t.screw_pilot / 2.0), T)
            assert min(pilot.distance_to(s) for s in pocket) == pytest.approx(wall, abs=1e-3), (turn, k)

