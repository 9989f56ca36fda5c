"""The printed fingertips without CAD (``kinematics.printed_tips``): a point's distance to a tip and
two tips' distance against answers worked by hand; the pinch on the 170.4 x 76.8 mm hand whose
thumb's tip end, not its pad, meets the index's on the solids (tests/cad/test_printed_tips_on_solids.py
measures the same hands with OpenCascade)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad import make_hand
from phantom_cad.kinematics import frames as F
from phantom_cad.kinematics import opposition
from phantom_cad.kinematics.printed_tips import SPACING_MM, PrintedTip, printed_pinch, tips_distance
from phantom_cad.params import load_params

from tests.support.hands import rim_hand, under_ring_hand

#: a tip of 20 mm with a 6 mm half cylinder, 16 mm wide and 12 mm thick, its box from y = 4 mm
TIP = PrintedTip(length=20.0, radius=6.0, half_width=8.0, half_thickness=6.0, back=4.0)


def rot_y(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def posed(R=np.eye(3), t=(0.0, 0.0, 0.0)) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


@pytest.mark.parametrize("point, want", [
    ((0.0, 25.0, 0.0), 5.0),                        # beyond the tip's end, on its axis: L + 5
    ((0.0, 14.0 + 3.0 * math.sqrt(2.0), 3.0 * math.sqrt(2.0) + 0.0), 0.0),   # inside the half cylinder
    ((0.0, 14.0 + 10.0 / math.sqrt(2.0), -10.0 / math.sqrt(2.0)), 4.0),     # 45 deg off the axis, 10 from it
    ((0.0, 10.0, -9.0), 3.0),                       # under the palmar face
    ((11.0, 10.0, 0.0), 3.0),                       # beside the side face
    ((11.0, 14.0 + 10.0, 0.0), 5.0),                # past the rim: 3 across, 4 along
    ((11.0, 10.0, 10.0), 5.0),                      # past the box's edge: 3 across, 4 up
    ((0.0, 2.0, 0.0), 2.0),                         # behind the box (the clevis slot's back)
])
def test_a_points_distance_to_the_tip(point, want):
    d, q = TIP.closest(np.array([point], float))
    assert d[0] == pytest.approx(want, abs=1e-12)
    d2, _ = TIP.closest(q)
    assert d2[0] == pytest.approx(0.0, abs=1e-12)              # the nearest point lies on the tip
    assert np.linalg.norm(q[0] - point) == pytest.approx(want, abs=1e-12)


def test_the_samples_lie_on_the_surface_rims_included():
    s = TIP.surface
    d, _ = TIP.closest(s)
    assert np.all(d <= 1e-12)
    # on the boundary: a step outward along some axis leaves the tip
    out = np.max(np.stack([TIP.closest(s + e)[0] for e in 1e-6 * np.vstack([np.eye(3), -np.eye(3)])]), axis=0)
    assert np.all(out > 0.0)
    # the rims' extreme points are sampled: the tip's end on both rims, the box's corners
    for p in ((8.0, 20.0, 0.0), (-8.0, 20.0, 0.0), (8.0, 14.0, -6.0), (-8.0, 14.0, 6.0), (8.0, 4.0, -6.0)):
        assert np.min(np.linalg.norm(s - p, axis=1)) <= 1e-9, p
    # and no point of the surface is farther than a spacing from a sample
    rng = np.random.default_rng(1)
    a = rng.uniform(-math.pi / 2.0, math.pi / 2.0, 200)
    x = rng.uniform(-8.0, 8.0, 200)
    arc = np.c_[x, 14.0 + 6.0 * np.cos(a), 6.0 * np.sin(a)]
    gaps = np.min(np.linalg.norm(arc[:, None] - s[None], axis=2), axis=1)
    assert gaps.max() <= SPACING_MM


def test_two_tips_end_to_end():
    """Tip b turned half a turn about z, its end 3 mm beyond a's: 3 mm between the ends' apexes."""
    Tb = posed(np.diag([-1.0, -1.0, 1.0]), (0.0, 43.0, 0.0))
    d, pa, pb = tips_distance(TIP, posed(), TIP, Tb)
    assert d == pytest.approx(3.0, abs=1e-9)
    assert pa[1] == pytest.approx(20.0) and pb[1] == pytest.approx(23.0)


@pytest.mark.parametrize("tilt_deg", [10.0, 30.0, 50.0])
def test_a_tilted_tips_rim_meets_a_flat_face(tilt_deg):
    """Tip b tilted about y under a's palmar face: its highest point is a corner of its dorsal rim,
    w sin(t) + h cos(t) above its axis; placed so that corner stands 1.5 mm under the face, the two
    are 1.5 mm apart there, where capsules about the same axes would be farther."""
    t = math.radians(tilt_deg)
    top = 8.0 * math.sin(t) + 6.0 * math.cos(t)
    Tb = posed(rot_y(t), (0.0, 4.0, -6.0 - 1.5 - top))
    d, pa, pb = tips_distance(TIP, posed(), TIP, Tb)
    assert d == pytest.approx(1.5, abs=1e-9)
    assert pa[2] == pytest.approx(-6.0) and pb[2] == pytest.approx(-7.5)
    corner = rot_y(t) @ np.array([-8.0, 0.0, 6.0]) + Tb[:3, 3]        # its dorsal rim at -x, rising with t
    assert pb[[0, 2]] == pytest.approx(corner[[0, 2]], abs=1e-9)


def test_the_tip_is_the_parts_shape():
    """The tip the default index's distal phalanx is built with (``cad.parts.phalanx``): the
    file's length, half the thickness as the tip's radius, the width, and the clevis slot's back."""
    p = load_params()
    tip = PrintedTip.of(p, "index")
    d = p.digit("index")
    assert tip.length == pytest.approx(d.distal * 1e3) and tip.radius == pytest.approx(d.thickness * 1e3 / 2.0)
    assert tip.half_width == pytest.approx(d.width * 1e3 / 2.0)
    assert tip.back == pytest.approx(F.slot_back(d.thickness, p.print.hole_clearance) * 1e3)


def test_the_default_hands_pads_meet_on_the_printed_tips():
    h = make_hand(load_params())
    for f in opposition.OPPOSED:
        c = printed_pinch(h, f)
        assert c is not None and 0.0 < c.distance_mm <= 1.0, f


def test_a_thumb_whose_tip_end_meets_the_index_is_found():
    """On the capsules its pads meet squarely (margin > 0); on the printed tips the thumb's rim at
    its tip's end meets the index pad first at every one of the model's contacts."""
    h = rim_hand()
    reach = opposition.reach(h)
    assert all(reach[f].margin > 0.0 for f in opposition.OPPOSED)
    assert printed_pinch(h, "index") is None
    assert printed_pinch(h, "middle") is not None and printed_pinch(h, "ring") is not None


def test_the_middle_phalanx_is_the_parts_width_and_thickness_to_the_dip_axis():
    """The default ring's middle phalanx: a point under its palmar face halfway along is that far
    from it, a point on the DIP axis 1 mm beyond its rounded end is 1 mm off, and one just past the
    PIP axis's plane inside its width is in it."""
    from phantom_cad.kinematics.topology import digit_links

    p = load_params()
    mid = PrintedTip.middle_of(p, "ring")
    d = p.digit("ring")
    L = F.segment_length(p, digit_links("ring")[-2]) * 1e3
    h = d.thickness * 1e3 / 2.0
    pts = np.array([[0.0, L / 2.0, -h - 2.0], [0.0, L + h + 1.0, 0.0], [d.width * 1e3 / 2.0 - 0.1, 0.1, 0.0]])
    dist, _ = mid.closest(pts)
    assert dist == pytest.approx([2.0, 1.0, 0.0], abs=1e-9)


def test_a_thumb_reaching_under_the_ring_is_passed_over():
    """The population's 213 x 75 mm hand: at the ring's second contact the thumb's tip meets the
    ring's middle phalanx as the pads come within reach (the solids overlap there:
    tests/cad/test_printed_tips_on_solids.py); the pinch found is a later contact, its tip clear."""
    from phantom_cad.kinematics import link_frames as LF
    from phantom_cad.kinematics.topology import digit_links

    h = under_ring_hand()
    c = printed_pinch(h, "ring")
    assert c is not None and any("middle phalanx" in why for why in c.tried), c
    T = LF.link_transforms(h.params, h.forward(c.u, compensated=True), mirrored=False)
    d, _, _ = tips_distance(PrintedTip.of(h.params, "thumb"), F.to_mm(T["thumb_distal"]),
                            PrintedTip.middle_of(h.params, "ring"), F.to_mm(T[digit_links("ring")[-2].name]))
    assert d > 0.0
