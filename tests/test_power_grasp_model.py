"""``kinematics.power_grasp``: the power grasp's cylinder on the model (no solids). Where it is laid
against the heel, worked by hand from the parameter file's palm; the gaps between the fingers'
shapes and the cylinder against the separating-axis distance of ``finger_clearance`` to a thin box
along the axis; the most distal position where every finger wraps it, and the heel ``size`` puts behind
it. The solids' side (each reference hand wraps the cylinder laid against its heel, MuJoCo holds it)
is tests/cad/test_power_grasp.py and tests/export/test_mjcf.py."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest

from phantom_cad import load_params, units
from phantom_cad.kinematics import power_grasp as PG
from phantom_cad.kinematics.finger_clearance import box_distance, posed_boxes
from phantom_cad.kinematics.forearm_layout import heel_box, heel_clear_y
from phantom_cad.kinematics.model import Hand
from phantom_cad.kinematics.servo_geometry import palm_back
from phantom_cad.kinematics.topology import FINGERS
from phantom_cad.params import load_document, parse

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "params" / "phantom.toml"


def test_the_cylinder_laid_against_the_heel_by_hand():
    """Default hand: the block 24 mm thick, the heel 11 mm under it, 43.8 mm from the palm's back face.
    The 35 mm cylinder 0.5 mm under the palmar face has its axis at z = -12 - 0.5 - 17.5 = -30, 7 mm
    under the heel's face (z = -23): laid 0.5 mm off the heel's lower front edge, its axis lies
    sqrt(18^2 - 7^2) = 16.583 mm in front of the heel."""
    p = load_params(DEFAULT)
    front = units.mm(palm_back(p)) + 43.8
    assert units.mm(heel_box(p)[1][1]) == pytest.approx(front, abs=1e-9)
    assert PG.resting_z(p, 35.0) == pytest.approx(-30.0, abs=1e-12)
    assert PG.laid_axis_y(p, 35.0) == pytest.approx(front + math.sqrt(18.0 ** 2 - 7.0 ** 2), abs=1e-9)
    # a 20 mm cylinder's axis (z = -22.5) lies at the heel's height: 10.5 mm in front of its face
    assert PG.laid_axis_y(p, 20.0) == pytest.approx(front + 10.5, abs=1e-9)
    # a circle whose top passes under the heel is not stopped by it
    assert units.mm(heel_clear_y(p, units.m(-40.0), units.m(10.0))) == pytest.approx(front, abs=1e-9)


def test_a_flat_palm_lays_it_nowhere():
    assert PG.laid_axis_y(load_params(ROOT / "params" / "examples" / "slender.toml"), 35.0) is None


def test_the_cylinder_scales_with_the_hand():
    """The paper's 35 mm on its 189 mm hand, in proportion on the 170 mm hand: 35 x 170 / 189."""
    assert PG.power_grasp_diameter_mm(load_params(DEFAULT)) == pytest.approx(35.0)
    assert PG.power_grasp_diameter_mm(load_params(ROOT / "params" / "examples" / "small.toml")) == pytest.approx(
        35.0 * 170.0 / 189.0)


@pytest.mark.parametrize("finger", FINGERS)
def test_the_gaps_are_the_shapes_distances_to_the_axis(finger):
    """Over the first half of each finger's travel (every shape apart from the axis), the gap of
    ``cylinder_gaps`` at each pose is the least separating-axis distance of its shapes
    (``finger_clearance.box_distance``, corners and edges in 3D: the boxes, and each rounded end's
    axis as a box of no thickness, less the end's radius) to a 2 m box 1e-9 mm thin along the
    cylinder's axis, less the cylinder's radius."""
    from phantom_cad.kinematics.finger_clearance import rounded_ends

    p = load_params(DEFAULT)
    hand = Hand(p, None, "paper")
    y, z, D = -30.0, -30.0, 35.0
    segments, links, radii = PG.posed_links(p, hand)[finger]
    ends = rounded_ends(p, finger)
    assert sorted(set(radii[radii > 0])) == sorted(set(units.mm(r) for _, r in ends.values()))
    gap, point, box = PG.cylinder_gaps(segments, radii, D, y, z)
    moving = posed_boxes(p, hand, PG.CONTACT_GRID, compensated=True, rounded=True)[finger][1]
    n = len(links)
    axis = (np.tile(units.m(np.array([0.0, y, z])), (n, 1)), np.tile(np.eye(3), (n, 1, 1)),
            np.tile([1.0, 1e-12, 1e-12], (n, 1)))
    half = np.flatnonzero(PG.CONTACT_GRID <= 0.5)
    assert gap[half].min() > 0.0
    for i in half[::20]:
        shapes = tuple(v[i * n:(i + 1) * n] for v in moving)
        want = units.mm(box_distance(shapes, axis)) - radii - D / 2.0
        assert gap[i] == pytest.approx(want.min(), abs=1e-6)
        assert int(box[i]) == int(want.argmin())
        assert np.hypot(*(point[i] - [y, z])) - radii[box[i]] - D / 2.0 == pytest.approx(gap[i], abs=1e-9)


def test_the_wrapping_axis_is_the_first_that_wraps():
    """On the default hand every finger's first contact lies past the equator at the wrapping axis,
    and half a step nearer the knuckles one finger meets the cylinder first on its distal side (the
    pinky's proximal phalanx)."""
    p = load_params(DEFAULT)
    hand = Hand(p, None, "paper")
    y = PG.wrapping_axis_y(p, hand, 35.0)
    assert y is not None and y < 0.0
    at = PG.first_contacts(p, hand, 35.0, y)
    assert all(c is not None and c[2] > 90.0 for c in at.values()), at
    nearer = PG.first_contacts(p, hand, 35.0, y + PG.AXIS_STEP_MM)
    assert [(f, c[1]) for f, c in nearer.items() if c is None or c[2] <= 90.0] == [("pinky", "pinky_proximal")]
    # far in front of the fingers nothing reaches it; a cylinder in the fingers' way at rest counts for none
    far = PG.first_contacts(p, hand, 35.0, 200.0)
    assert far == {f: None for f in FINGERS}
    assert PG.first_contacts(p, hand, 35.0, 0.0, axis_z_mm=-10.0) == {f: None for f in FINGERS}


@pytest.mark.parametrize("hl, breadth", [(160.0, 72.0), (205.0, 95.0)])
def test_the_sized_heel_lays_the_cylinder_behind_the_wrapping_axis(hl, breadth):
    """``size`` puts the heel where the cylinder laid against it lies ``HEEL_MARGIN`` behind the
    wrapping axis (to the 0.1 mm its length is rounded to), and as deep as the palm envelope leaves
    under the block."""
    from phantom_cad.sizing import HEEL_MARGIN, Person, build_document
    from phantom_cad.sizing import solvers as S

    doc = build_document(Person(hl, breadth))
    p = parse(doc)
    D = PG.power_grasp_diameter_mm(p)
    wraps = PG.wrapping_axis_y(p, Hand(p, compensation="paper"), D)
    assert PG.laid_axis_y(p, D) == pytest.approx(wraps - HEEL_MARGIN, abs=0.05 + 1e-9)
    envelope = S.PALM_ENVELOPE[1] * hl / S.REFERENCE_LENGTH
    assert doc["palm"]["heel_height_mm"] == max(S.scaled(11.0, hl), S.down(envelope - doc["palm"]["thickness_mm"]))
    assert doc["palm"]["thickness_mm"] + doc["palm"]["heel_height_mm"] <= envelope + 1e-9 or \
        doc["palm"]["heel_height_mm"] == S.scaled(11.0, hl)


def test_the_default_file_keeps_the_heel_size_solves():
    """params/phantom.toml's heel is the one ``size`` solves for its own measurements."""
    from phantom_cad.sizing import heel

    doc = load_document(DEFAULT)
    solved = copy.deepcopy(doc)
    heel(solved)
    assert solved["palm"] == doc["palm"]
