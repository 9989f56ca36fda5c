"""No collisions: the hand posed over a grid of servo commands (0, 25, 50, 75, 90 and
100 % of each servo's travel; the fingers independently, the thumb's flexion across its CMC
range), every pair of parts measured with manifold3d on the parts' meshes
(``export.interference.command_sweep``). A joint's parent and child, and the designed contacts,
may touch; a thumb part against a finger part is a pinch contact (reported, with the commands).

The reported overlaps are confirmed by OpenCascade's boolean on the solids themselves, and a hand
with a 19.5 mm finger pitch (too narrow) must show the flexed index and middle fingers running into
each other (the check can fail).
"""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad import make_hand
from phantom_cad.cad import assembly
from phantom_cad.cad import measure
from phantom_cad.export import step_stl
from phantom_cad.export.interference import command_sweep, may_touch
from phantom_cad.kinematics.topology import SERVOS, link

from tests.support.hands import HANDS

FRACTIONS = (0.0, 0.25, 0.5, 0.75, 0.9, 1.0)


def _sweep(p, meshes: dict):
    return command_sweep(meshes, make_hand(p), lambda q: assembly.pose_transforms(p, q),
                         may_touch(assembly.designed_contacts(p)))


def _occ_overlap(p, shapes: dict, pair, commands: dict) -> float:
    """The overlap (mm^3) of a pair at servo commands (label -> fraction of the travel), by
    OpenCascade on the solids: the commands mapped to joint angles by the model's forward map."""
    hand = make_hand(p)
    u = np.array(hand.u_min, float)
    for s in SERVOS:
        if s.label in commands:
            u[s.index] += commands[s.label] * (hand.u_max[s.index] - hand.u_min[s.index])
    T = assembly.pose_transforms(p, hand.forward(u))
    a, b = pair
    return measure.intersection_volume(measure.placed(shapes[a], T[a]), measure.placed(shapes[b], T[b]))


@pytest.fixture(scope="module", params=HANDS)
def hand(request, hand_parts, hand_meshes):
    p, shapes = hand_parts(request.param)
    return request.param, p, shapes, _sweep(p, hand_meshes(request.param))


def test_no_two_parts_collide_over_the_command_grid(hand):
    name, p, shapes, r = hand
    # every digit alone (the thumb over flexion x CMC: 6 x 6; each finger 6), every two digits
    # together (the thumb with a finger: 36 x 6; two fingers: 6 x 6)
    n = len(FRACTIONS)
    assert r["fractions"] == list(FRACTIONS)
    assert r["poses"] == n * n + 4 * n + 4 * n ** 3 + 6 * n ** 2
    assert r["collisions"] == [], r["collisions"]


def test_pinch_contacts_are_reported_and_real(hand):
    """The thumb closes onto the index: the sweep reports thumb-finger overlaps (pinch contacts a
    controller must respect), each with the least thumb flexion where it occurs; the largest is
    confirmed by OpenCascade on the solids at its commands."""
    name, p, shapes, r = hand
    assert r["pinch"], "the thumb never reaches a finger"
    for e in r["pinch"]:
        digits = {link(n).digit for n in e["parts"]}
        assert "thumb" in digits and len(digits) == 2
        assert 0.0 <= e["from_thumb_flexion"] <= e["commands"]["u1"]
    big = r["pinch"][0]
    occ = _occ_overlap(p, shapes, big["parts"], big["commands"])
    assert occ == pytest.approx(big["volume_mm3"], rel=0.05, abs=0.05)


@pytest.mark.slow
def test_the_old_finger_pitch_collides(document, variant):
    """At a 19.5 mm finger pitch the columns fan out by 5 deg and the fully flexed index and middle
    fingers, which point back toward the wrist, converge into each other: the sweep finds it, and
    OpenCascade measures the same overlap on the solids."""
    p = variant(lambda d: d["palm"].__setitem__("finger_pitch_mm", 19.5))
    names = [n for n in assembly.part_names(p) if link(n).digit in ("index", "middle")]
    shapes = {n: assembly.build_part(p, n).shape for n in names}
    tol = p.print.stl_tolerance * 1e3
    r = _sweep(p, {n: step_stl.tessellate(s, tol) for n, s in shapes.items()})
    pairs = {tuple(e["parts"]): e for e in r["collisions"]}
    e = pairs[("index_distal", "middle_distal")]
    assert e["volume_mm3"] > 5.0 and e["commands"] == {"u2": 1.0, "u3": 1.0}
    occ = _occ_overlap(p, shapes, e["parts"], e["commands"])
    assert occ == pytest.approx(e["volume_mm3"], rel=0.05)
