"""The printed tips without CAD (``kinematics.printed_tips``) against the built distal phalanges
measured by OpenCascade (``cad.grasp.solid_contact``): the same pinch is found at the same commands,
the tips' distance there within the samples' spacing of OpenCascade's, and where the solids' pads
do not meet, neither do the printed tips'. The reference hands and the 170.4 x 76.8 mm hand whose
thumb's tip end meets the index pad (tests/test_printed_tips.py)."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad import make_hand, units
from phantom_cad.cad import assembly, grasp
from phantom_cad.cad.measure import placed
from phantom_cad.cad.registry import part
from phantom_cad.kinematics import frames as F
from phantom_cad.kinematics import link_frames as LF
from phantom_cad.kinematics import opposition
from phantom_cad.kinematics.topology import chain
from phantom_cad.kinematics.printed_tips import SPACING_MM, PrintedTip, printed_pinch, tips_distance

from tests.support.hands import HANDS, rim_hand, under_ring_hand

pytest.importorskip("build123d")

DISTAL = ("thumb_distal", "index_distal", "middle_distal", "ring_distal")


def _agree(hand, shapes, finger):
    """The pinch on the printed tips and on the solids: both found at the same commands or neither."""
    c = printed_pinch(hand, finger)
    s = grasp.solid_contact(hand, shapes, finger)
    assert (c is None) == (s is None), (finger, c, s)
    if c is None:
        return None
    # the same model contact (the thumb's commands); the finger's within the bisection's reach of
    # the solids', where the two distances differ by the parts' grooves and the samples' spacing
    k = chain(finger).servo
    others = [i for i in range(len(c.u)) if i != k]
    assert np.array_equal(c.u[others], s.u[others]), (finger, c.u, s.u)
    assert abs(c.u[k] - s.u[k]) <= units.rad(2.0), (finger, c.u, s.u)
    return c, s


@pytest.mark.slow
@pytest.mark.parametrize("kind", HANDS)
def test_the_reference_hands_pinch_where_the_solids_do(kind, hand_parts):
    p, shapes = hand_parts(kind)
    h = make_hand(p)
    for f in opposition.OPPOSED:
        assert _agree(h, shapes, f) is not None, (kind, f)


@pytest.mark.slow
def test_a_thumb_whose_tip_end_meets_the_index_misses_on_both():
    h = rim_hand()
    p = h.params
    shapes = {n: part(p, n).build() for n in DISTAL}
    assert _agree(h, shapes, "index") is None
    for f in ("middle", "ring"):
        c, s = _agree(h, shapes, f)
        # at the solids' commands: OpenCascade's distance and the printed tips', within the
        # samples' spacing (the parts' grooves and anchors lie off the pads)
        T = assembly.pose_transforms(p, h.forward(s.u, compensated=True))
        b = f"{f}_distal"
        d_occ = placed(shapes["thumb_distal"], T["thumb_distal"]).distance_to(placed(shapes[b], T[b]))
        R = LF.link_transforms(p, h.forward(s.u, compensated=True), mirrored=False)
        d, _, _ = tips_distance(PrintedTip.of(p, "thumb"), F.to_mm(R["thumb_distal"]), PrintedTip.of(p, f),
                                F.to_mm(R[b]))
        assert abs(d - d_occ) <= SPACING_MM, (f, d, d_occ)


@pytest.mark.slow
def test_a_thumb_reaching_under_the_ring_is_passed_over_on_both():
    """The population's 213 x 75 mm hand: at the ring contact the printed tips pass over for the
    middle phalanx, the thumb's and the ring's solids reach within the pinch's reach pad to pad
    while the thumb's distal phalanx overlaps the ring's middle one (OpenCascade's boolean); both
    then find the ring pinch at the same later contact."""
    from phantom_cad.cad import measure
    from phantom_cad.kinematics.power_grasp import close_onto

    h = under_ring_hand()
    p = h.params
    shapes = {n: part(p, n).build() for n in ("thumb_distal", "ring_distal", "ring_middle")}
    c, s = _agree(h, shapes, "ring")
    passed = [u for u in opposition.contact_commands(h, "ring")]
    k = chain("ring").servo
    # the contact the printed tips passed over for the middle phalanx: the one before the found
    i = next(i for i, u in enumerate(passed) if np.array_equal(np.delete(u, k), np.delete(c.u, k)))
    u_end = passed[i - 1]

    def measure_at(f):
        u = u_end.copy()
        u[k] = f * u_end[k]
        T = assembly.pose_transforms(p, h.forward(u, compensated=True))
        a, b = placed(shapes["thumb_distal"], T["thumb_distal"]), placed(shapes["ring_distal"], T["ring_distal"])
        return a.distance_to(b), T

    found = close_onto(measure_at, grasp.REACH_MM)
    assert found is not None
    _, (_, T) = found
    overlap = measure.intersection_volume(placed(shapes["thumb_distal"], T["thumb_distal"]),
                                          placed(shapes["ring_middle"], T["ring_middle"]))
    assert overlap > 0.0
