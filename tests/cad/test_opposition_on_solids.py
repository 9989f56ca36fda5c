"""Opposition on the solids: the thumb's pad reaches the index, middle and ring pads
(surface distance <= 1 mm, no interpenetration) at servo commands within the travel; default
hand, left hand and the 170 mm hand (params/examples/small.toml).

``cad.grasp.solid_contact`` finds the commands: of the kinematic model's contacts (squarest first,
at most eight distinct thumb commands), the first where the finger, flexing from rest onto the
still thumb, comes within (0, 1] mm of it with the closest points on both pads. What it returns is
measured again here, each with a tool of its own: the commands within the travel (the hand's
u_min / u_max); OpenCascade's distance between the two distal phalanges posed there; the closest
points on the pads (in each distal link's frame, on its palmar half, z <= 0, and its distal half,
y >= L / 2: the fingertip's pad or the tip's end, not its back or its clevis), written out here
from the parameter file's lengths; no common volume between the two tips (OpenCascade's boolean);
and no two parts of the hand interpenetrating (manifold3d on the meshes; a joint's parent and
child and the designed contacts may touch).
"""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad import make_hand
from phantom_cad.cad import assembly, grasp
from phantom_cad.cad import measure
from phantom_cad.export.interference import interference, may_touch
from phantom_cad.kinematics import opposition

from tests.support.hands import HANDS

#: the surface distance (mm) the pads must come within
REACH_MM = 1.0
#: manifold3d's overlap (mm^3) that counts as interpenetration: the command sweep's bar
#: (``export.interference.SWEEP_TOL_MM3``, the meshes' chord error on parts that nearly touch)
OVERLAP_MM3 = 0.01


@pytest.fixture(scope="module", params=HANDS)
def hand(request, hand_parts, hand_meshes):
    p, shapes = hand_parts(request.param)
    return request.param, p, shapes, hand_meshes(request.param), may_touch(assembly.designed_contacts(p))


def _tip_length_mm(p, digit: str) -> float:
    """The distal segment's length (mm) from the parameter file: its ``length_fraction.distal``
    times ``hand.hand_length_mm``."""
    doc = p.document
    d = doc["thumb"] if digit == "thumb" else doc["fingers"][digit]
    return float(d["length_fraction"]["distal"]) * float(doc["hand"]["hand_length_mm"])


def _in_link(T, point) -> np.ndarray:
    """A hand-frame point (mm) in a link's frame (mm), by the inverse rigid transform R^T (x - t)."""
    R, t = T[:3, :3], T[:3, 3]
    return R.T @ (np.asarray(point, float) - t)


@pytest.mark.parametrize("finger", opposition.OPPOSED)
def test_the_thumb_pad_reaches_the_fingertip_pad(hand, finger):
    kind, p, shapes, meshes, allowed = hand
    h = make_hand(p)
    c = grasp.solid_contact(h, shapes, finger, reach_mm=REACH_MM)
    assert c is not None, f"{kind}: the thumb's pad does not reach the {finger}'s on the solids"
    assert np.all(c.u >= h.u_min - 1e-12) and np.all(c.u <= h.u_max + 1e-12)
    T = assembly.pose_transforms(p, h.forward(c.u, compensated=True))
    a_name, b_name = "thumb_distal", f"{finger}_distal"
    a, b = measure.placed(shapes[a_name], T[a_name]), measure.placed(shapes[b_name], T[b_name])
    d = a.distance_to(b)
    assert 0.0 < d <= REACH_MM and d == pytest.approx(c.distance_mm, abs=1e-9), (kind, finger, d)
    for name, digit, point in ((a_name, "thumb", c.thumb_point), (b_name, finger, c.finger_point)):
        assert measure.placed(shapes[name], T[name]).distance_to(tuple(point)) == pytest.approx(0.0, abs=1e-6)
        x = _in_link(T[name], point)
        assert x[2] <= 0.0 and x[1] >= _tip_length_mm(p, digit) / 2.0, (kind, finger, name, x)
    # no interpenetration: the two tips share no volume, and no two parts of the hand overlap
    assert measure.intersection_volume(a, b) == 0.0
    r = interference(meshes, T, allowed, tol_mm3=OVERLAP_MM3)
    assert r["collisions"] == [], (kind, finger, r["collisions"])
