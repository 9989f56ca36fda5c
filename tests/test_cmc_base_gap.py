"""The CMC base's distance to a box (``kinematics.cmc_base_gap``): known answers worked by hand
(a point to a box and to a cylinder, a segment past a box's edge, the hub and the arm beside a
box), the search's constraint against the pre-build check. The distance against OpenCascade's on
the built parts: tests/cad/test_cmc_base_gap_on_solids.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.kinematics import cmc_base_gap as G
from phantom_cad.kinematics import frames as F
from phantom_cad.kinematics import thumb_placement as TP
from phantom_cad.params import DEFAULT_PARAMS, ParamError, load_document, load_params, parse


def test_a_points_signed_distance_to_a_box():
    lo, hi = np.zeros(3), np.ones(3)
    P = np.array([[0.5, 0.5, 3.0],          # over the top face: 2
                  [2.0, 0.5, 3.0],          # past an edge: sqrt(1 + 4)
                  [2.0, 3.0, -2.0],         # past a corner: sqrt(1 + 4 + 4)
                  [0.5, 0.5, 0.9],          # inside, 0.1 under the top
                  [0.2, 0.5, 0.5]])         # inside, 0.2 in from x = 0
    assert G.box_distance(P, lo, hi) == pytest.approx([2.0, math.sqrt(5.0), 3.0, -0.1, -0.2])


def test_a_points_signed_distance_to_a_cylinder():
    P = np.array([[5.0, 0.0, 1.0],          # beside it: 5 - 2
                  [0.0, 1.0, 7.0],          # over its top: 2
                  [3.0, 4.0, -3.0],         # past its bottom rim: (5 - 2, 2)
                  [0.0, 1.5, 2.0],          # inside, 0.5 in from the side
                  [0.0, 0.0, 4.7]])         # inside, 0.3 under the top
    assert G.cylinder_distance(P, 2.0, -1.0, 5.0) == pytest.approx([3.0, 2.0, math.sqrt(13.0), -0.5, -0.3])


def test_the_least_along_segments_finds_a_segments_nearest_point_to_a_box():
    """A segment along x past the box's edge at (y, z) = (1, 1) from 2 and 3 beyond: sqrt(5), reached
    between its ends; a second segment farther off changes nothing; one 10 long through the box's
    middle goes 1/2 deep (a kink, found to within the last bracket)."""
    lo, hi = np.zeros(3), np.ones(3)
    f = lambda p: G.box_distance(p, lo, hi)          # noqa: E731
    a = np.array([[-5.0, 3.0, 4.0], [-5.0, 9.0, 9.0]])
    b = np.array([[7.0, 3.0, 4.0], [7.0, 9.0, 9.0]])
    assert G.least_along(f, a, b) == pytest.approx(math.sqrt(2.0 ** 2 + 3.0 ** 2), abs=1e-9)
    through = (np.array([[-5.0, 0.5, 0.5]]), np.array([[5.0, 0.5, 0.5]]))
    assert G.least_along(f, *through) == pytest.approx(-0.5, abs=10.0 * 8.0 ** -5)     # its last bracket


def _upright():
    """The default hand with its CMC axis along the palm's z (the base's frame the palm's, moved to
    the CMC offset) and the base's solids in that frame."""
    p = load_params()
    T0 = F.trans(*p.palm.thumb_cmc_offset)
    return p, T0, G.cmc_base_solids(p, T0)


@pytest.mark.parametrize("gap_mm", [1.0, 0.2, -0.3])
def test_the_hub_beside_a_box_face_is_the_gap_between_them(gap_mm):
    """A box behind the upright hub (radius thumb.width_mm / 2), its front face ``gap`` behind the
    hub's back: the distance is the gap; a box 0.3 mm into the hub, -0.3."""
    p, T0, solids = _upright()
    r = p.thumb.width / 2.0
    c = T0[:3, 3]
    g = gap_mm * 1e-3
    lo = c + np.array([-0.05, -0.05 - r - g, -0.02])
    hi = c + np.array([0.05, -r - g, 0.02])
    assert G.cmc_base_gap(p, lo, hi, T0) == pytest.approx(g, abs=2e-6)


def test_a_box_edge_past_the_hubs_bottom_rim_is_that_far():
    """A box whose top back edge lies 3 mm behind the hub's side and 4 mm below its palmar face
    (under no part of the arm, which runs forward along +y): 5 mm from the rim."""
    p, T0, solids = _upright()
    r, T = p.thumb.width / 2.0, p.thumb.thickness
    c = T0[:3, 3]
    lo = c + np.array([-0.01, -r - 0.003 - 0.05, -T / 2.0 - 0.004 - 0.05])
    hi = c + np.array([0.01, -r - 0.003, -T / 2.0 - 0.004])
    assert G.cmc_base_gap(p, lo, hi, T0) == pytest.approx(0.005, abs=1e-5)


def test_the_floor_lowers_the_hub_and_the_arm():
    """A box 2 mm under the base's palmar face: 2 mm away, 0.5 mm with its floor 1.5 mm lower."""
    p, T0, solids = _upright()
    T = p.thumb.thickness
    c = T0[:3, 3]
    lo = c + np.array([-0.05, -0.05, -T / 2.0 - 0.002 - 0.01])
    hi = c + np.array([0.05, 0.05, -T / 2.0 - 0.002])
    assert G.cmc_base_gap(p, lo, hi, T0) == pytest.approx(0.002, abs=1e-6)
    assert G.cmc_base_gap(p, lo, hi, T0, floor=-T / 2.0 - 0.0015) == pytest.approx(0.0005, abs=1e-6)


@pytest.mark.parametrize("tilt_deg, refused", [(5.0, False), (8.0, False), (10.0, True)])
def test_the_search_keeps_the_cmc_base_off_the_forearm_module_as_the_pre_build_check_does(tilt_deg, refused):
    """The default CMC axis turned about its third angle (thumb_cmc_axis_deg[2]): at 10 deg its hub
    reaches 0.1 mm into the forearm module's block, which ``cad.preflight`` refuses; the search's
    constraint (the file's module moved with the placement's thenar, the CAD part's floor) is
    positive exactly where the pre-build check refuses the turned file, by the clearance less the
    gap that file's own ``forearm_gap`` measures (its servo row moves a little with the CMC)."""
    from phantom_cad.cad import preflight
    from phantom_cad.kinematics import forearm_layout as FL

    doc = load_document(DEFAULT_PARAMS)
    doc["palm"]["thumb_cmc_axis_deg"][2] += tilt_deg
    turned = parse(doc)
    T0 = F.thumb_cmc_placement(turned.palm.thumb_cmc_offset, turned.palm.thumb_cmc_axis)
    p = load_params()
    v = TP.thenar_constraint(p, floor=preflight.cmc_base_floor(p))(T0)
    try:
        preflight.check(turned)
        why = None
    except ParamError as exc:
        why = str(exc)
    assert (why is not None) == refused and (v > 0.0) == refused, (why, v)
    if refused:
        assert "forearm module's block" in why
        gap = FL.forearm_gap(turned, floor=preflight.cmc_base_floor(turned))
        assert v == pytest.approx(turned.print.hole_clearance + TP.SLACK - gap, abs=0.05e-3)
