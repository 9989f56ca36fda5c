"""Human scale, measured on the built solids of the default hand, its left twin and a
hand of hand_length_mm 170 (params/examples/small.toml).

A 95th-percentile adult palm is about 95 mm broad at the metacarpal heads (hand length 189 mm;
the target scales with the hand length) and at most 35 mm thick (the palm's heel included), with
nothing hanging below its palmar face. All six servos sit in the forearm module behind the palm (docs/parts.md): servo 6
turns the CMC through a cable loop, and the palm's thenar holds the CMC base's column.
"""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.cad import assembly
from phantom_cad.cad import measure
from phantom_cad.canon import plain
from phantom_cad.kinematics import forearm_layout, servo_geometry
from phantom_cad.kinematics import frames
from phantom_cad.kinematics import link_frames
from phantom_cad.kinematics import thenar
from phantom_cad.kinematics.topology import FINGERS, SERVO_MOUNT, SERVOS

from tests.support.hands import HANDS


@pytest.fixture(scope="module", params=HANDS)
def hand(request, hand_parts):
    p, shapes = hand_parts(request.param)
    T = assembly.pose_transforms(p)
    names = ("palm", "forearm") + tuple(f"{f}_base" for f in FINGERS)
    solids = {n: measure.placed(shapes[n], T[n]) for n in names}
    return request.param, p, plain(p.document), solids


def _section(shape, y: float, xs=(-500.0, 500.0)):
    """The shape's material in a 0.2 mm slice about y (palm frame) between xs, as a bounding box
    (lo, hi) or None where there is none."""
    import build123d as bd
    x0, x1 = xs
    cut = shape.intersect(bd.Solid.make_box(x1 - x0, 0.2, 1000.0, bd.Plane(origin=(x0, y - 0.1, -500.0))))
    if cut is None or not list(cut):
        return None
    bb = (cut if not isinstance(cut, list) else bd.Compound(cut)).bounding_box()
    return np.array([bb.min.X, bb.min.Y, bb.min.Z]), np.array([bb.max.X, bb.max.Y, bb.max.Z])


def _limit(doc) -> float:
    return 95.0 * doc["hand"]["hand_length_mm"] / 189.0


def test_the_knuckles_are_human_broad(hand):
    """Breadth at the metacarpal heads: from the index base's radial side to the pinky base's
    ulnar side, the finger bases (which carry the MCPs) placed at rest."""
    _, p, doc, solids = hand
    xs = []
    for f in FINGERS:
        bb = solids[f"{f}_base"].bounding_box()
        xs += [bb.min.X, bb.max.X]
    breadth = max(xs) - min(xs)
    # the four columns at pitch on the arc (three chords, 5 deg apart) plus the outer half widths
    # bound it from below
    pitch = doc["palm"]["finger_pitch_mm"]
    assert breadth > 3 * pitch * np.cos(np.radians(7.5)) + (doc["fingers"]["index"]["width_mm"]
                                                           + doc["fingers"]["pinky"]["width_mm"]) / 2 - 1.0
    assert breadth <= _limit(doc)


def test_the_metacarpal_block_is_the_palms_thickness(hand):
    """Slices of the palm solid across its metacarpal block (ulnar of the thenar block, which
    overlaps the block's radial edge to join it, to the pinky socket; from the wrist crease to the
    socket faces: the tendon servos sat there before), each exactly the palm's thickness: top at
    +T/2, bottom at -T/2, nothing below the palmar face there; over the heel (from the palm's back
    face heel_length_mm distally) the bottom at -T/2 - heel_height_mm, at most 35 mm in all."""
    kind, p, doc, solids = hand
    from phantom_cad.cad.parts import wrist as W

    palm = solids["palm"]
    T = doc["palm"]["thickness_mm"]
    H, L = doc["palm"]["heel_height_mm"], doc["palm"]["heel_length_mm"]
    assert T + H <= 35.0 and H > 0.0
    heel_front = palm.bounding_box().min.Y + L      # the palm's back face is its most proximal point
    x0, x1 = W.socket_x(p)
    x0 = max(x0, max(v[:, 0].max() for v in thenar.thenar_points(p).values()) * 1e3)   # ulnar of the thenar
    if kind == "left":
        x0, x1 = -x1, -x0
    wrist = -doc["fingers"]["index"]["length_fraction"]["metacarpal"] * doc["hand"]["hand_length_mm"]
    faces = min(frames.T_palm_socket(p, f)[1, 3] for f in FINGERS) * 1e3 - doc["fingers"]["pinky"]["width_mm"]
    assert wrist + 2.0 < heel_front < frames.T_palm_socket(p, "pinky")[1, 3] * 1e3 - 6.0
    # behind the heel's front, and the first 5 mm in front of it (on the 170 mm hand the heel reaches
    # past where the sockets' turned corners may begin)
    ys = [*np.linspace(wrist + 1.0, heel_front - 1.0, 4), *np.linspace(heel_front + 1.0, max(faces, heel_front + 5.0), 3)]
    for y in ys:
        lo, hi = _section(palm, float(y), (x0 + 0.5, x1 - 0.5))
        bottom = -T / 2 - (H if y < heel_front else 0.0)
        assert hi[2] == pytest.approx(T / 2, abs=1e-6) and lo[2] == pytest.approx(bottom, abs=1e-6), (kind, y)


def test_the_palm_is_human_broad(hand):
    """The palm solid's breadth (its bounding box across x, the thenar included) within the
    95th-percentile envelope."""
    kind, p, doc, solids = hand
    bb = solids["palm"].bounding_box()
    assert bb.max.X - bb.min.X <= _limit(doc)
    # its ulnar face is the one the placement search's human edge starts from
    ulnar = bb.max.X if kind != "left" else -bb.min.X
    assert ulnar == pytest.approx(forearm_layout.metacarpal_x(p)[1] * 1e3, abs=1e-6)


def test_the_servos_sit_behind_the_palm(hand):
    """The six servos' pulleys lie behind the palm's back face (the wrist crease, or the back of
    the thenar: at most the carpus, hand length less the middle finger's bones, behind it), and the
    forearm module reaches ahead of it only with its tab on the palm's dorsal face."""
    kind, p, doc, solids = hand
    hl = doc["hand"]["hand_length_mm"]
    wrist = -doc["fingers"]["index"]["length_fraction"]["metacarpal"] * hl
    carpus = hl * (1 - sum(doc["fingers"]["middle"]["length_fraction"].values()))
    back = solids["palm"].bounding_box().min.Y
    assert wrist - carpus - 1e-6 <= back <= wrist
    Ts = link_frames.link_transforms(p)
    assert all(SERVO_MOUNT[s.drive] == "forearm" for s in SERVOS)
    for s in SERVOS:
        assert Ts[s.link][1, 3] * 1e3 < back
    fa = solids["forearm"]
    ahead = _section(fa, back + 1.0)
    assert ahead is not None
    assert ahead[0][2] == pytest.approx(doc["palm"]["thickness_mm"] / 2, abs=1e-6)     # on the dorsal face
    behind = _section(fa, servo_geometry.forearm_front(p) * 1e3 - 2.0)
    assert behind[0][2] < -doc["palm"]["thickness_mm"] / 2                               # the module's body


def test_nothing_hangs_below_the_palm_face(hand):
    """The palm solid lies between its palmar face (the heel's, where it has one) and its dorsal face
    (the thenar block included: the CMC base hangs below, on its column); the palm is at most 35 mm
    thick, the heel included."""
    _, p, doc, solids = hand
    T, H = doc["palm"]["thickness_mm"], doc["palm"]["heel_height_mm"]
    bb = solids["palm"].bounding_box()
    assert T + H <= 35.0
    assert bb.min.Z == pytest.approx(-T / 2 - H, abs=1e-6) and bb.max.Z == pytest.approx(T / 2, abs=1e-6)
