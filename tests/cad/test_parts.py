"""The printable parts, measured from the built solids.

Known answers come from the parameter file's numbers (the document, in its own units) and
textbook geometry written out here; every feature position is read from the B-rep
(cylindrical faces, pocket openings, boolean volumes), never from the part classes.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from phantom_cad.cad import measure
from phantom_cad.cad.verify import verify_part
from phantom_cad.cad import assembly
from phantom_cad.kinematics.topology import FINGERS



def _hand(T, p):
    return (np.asarray(T) @ np.append(np.asarray(p, float), 1.0))[:3]


def _dir(T, d):
    return np.asarray(T)[:3, :3] @ np.asarray(d, float)


def _comp(doc):
    """Half of print.hole_compensation_mm (default 0.2): every hole that takes hardware is modelled
    that much wider in radius than the fit it should print at."""
    return doc["print"].get("hole_compensation_mm", 0.2) / 2


def tendon_hole(doc):
    return doc["hardware"]["tendon_diameter_mm"] + 2 * doc["print"]["hole_clearance_mm"]


# ---------------------------------------------------------------------------
# every part: one valid solid, plausible size
# ---------------------------------------------------------------------------

def test_every_part_is_one_valid_solid(built):
    assert len(built) == 28
    for name, b in built.items():
        rep = measure.solid_report(b.shape)
        assert rep["n_solids"] == 1, name
        assert rep["valid"], name
        assert rep["volume"] > 100.0, name


@pytest.mark.parametrize("kind", ["left", "hand_length_170"])
def test_every_part_of_the_other_hands_is_one_valid_solid(hand_parts, kind):
    """The left and 170 mm hands' parts pass the check the build's workers make of each
    (``cad.verify.verify_part``: one valid solid, measured against the parameters), so tests/cad
    catches an invalid part of these hands without an export."""
    p, shapes = hand_parts(kind)
    assert len(shapes) == 28
    bad = {name: problems for name, shape in shapes.items() if (problems := verify_part(p, name, shape))}
    assert bad == {}


def test_every_part_mirrors_to_a_valid_left_hand_solid(built):
    """A left hand's parts are the right hand's mirrored in x (``assembly.build_part``). OpenCascade
    found faces of valid right-hand solids unorientable after the reflection (a knot pocket
    tangent to its groove's walls; a groove floor cut by a drive pulley's anchor hole), so every
    mirrored part is checked here, not only in the slow left-hand export."""
    import build123d as bd

    bad = [name for name, b in built.items() if not measure.solid_report(b.shape.mirror(bd.Plane.YZ))["valid"]]
    assert bad == []


def test_phalanx_bounding_boxes_match_the_segment_lengths(built, document):
    HL = document["hand"]["hand_length_mm"]
    for f in FINGERS:
        fd = document["fingers"][f]
        W, T = fd["width_mm"], fd["thickness_mm"]
        for seg, far in (("proximal", True), ("middle", True), ("distal", False)):
            L = fd["length_fraction"][seg] * HL
            rep = measure.solid_report(built[f"{f}_{seg}"].shape)
            lo, hi = rep["bbox_min"], rep["bbox_max"]
            assert hi[0] - lo[0] == pytest.approx(W, abs=1e-6)
            # the far end is the clevis boss (radius T/2) beyond the next axis, or the fingertip
            assert hi[1] == pytest.approx(L + T / 2 if far else L, abs=1e-6), (f, seg)
            # the tongue's heel reaches back to the parent's slot wall: T/2 + clearance
            assert lo[1] == pytest.approx(-(T / 2 + document["print"]["hole_clearance_mm"]), abs=1e-6)
            assert hi[2] == pytest.approx(T / 2, abs=1e-6)
            assert T / 2 <= -lo[2] <= T / 2 + 3.0


def test_palm_spans_the_four_sockets_from_the_wrist(built, document):
    rep = measure.solid_report(built["palm"].shape)
    lo, hi = rep["bbox_min"], rep["bbox_max"]
    pitch = document["palm"]["finger_pitch_mm"]
    # at least three pitches plus the outer half widths across, and the dorsal face at +T/2
    assert hi[0] - lo[0] > 3 * pitch + 18.0
    assert hi[2] == pytest.approx(document["palm"]["thickness_mm"] / 2, abs=1e-6)
    # the metacarpal block starts at the wrist crease: the index metacarpal's length behind the
    # index MCP (the thenar housing and its post may reach further back)
    wrist = -document["fingers"]["index"]["length_fraction"]["metacarpal"] * document["hand"]["hand_length_mm"]
    assert lo[1] <= wrist + 1e-6
    assert _is_inside(built["palm"].shape, (20.0, wrist + 0.5, 0.0))


def _is_inside(shape, p) -> bool:
    from build123d import Vector
    return shape.is_inside(Vector(*p))


@pytest.mark.parametrize("k", [1, 2, 3, 4, 5, 6])
def test_forearm_servo_cavity_and_its_front_wall(built, params, document, k):
    from phantom_cad.kinematics import forearm_layout, forearm_stagger
    from phantom_cad.kinematics import frames, routing
    from phantom_cad.kinematics import thenar

    hw, pr = document["hardware"], document["print"]
    r = (document["thumb"]["cmc_pulley_radius_mm"] if k == 6 else
         (document["thumb"] if k == 1 else document["fingers"][FINGERS[k - 2]])["servo_pulley_radius_mm"])
    # by hand: the pulley's flanges stand two tendon diameters above its groove, plus one tendon
    # diameter of running room and a hole clearance: 7 + 2 * 0.6 + 0.6 + 0.2 = 9.0 mm by default
    cavity = r + 3 * hw["tendon_diameter_mm"] + pr["hole_clearance_mm"]
    T = np.linalg.inv(forearm_layout.T_palm_forearm(params)) @ forearm_layout.T_palm_servo(params, k - 1)   # forearm frame
    shaft, axis = T[:3, 3] * 1e3, T[:3, 2]
    shape = built["forearm"].shape
    if forearm_layout.drops_straight(params, k - 1):
        # swept straight up, the cavity is a prism of 32 flats whose insides stand the cavity's
        # radius from the shaft: open to that radius all round in the pulley's plane
        for a in np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False):
            assert not _is_inside(shape, shaft + (cavity - 0.05) * (np.cos(a) * T[:3, 0] + np.sin(a) * T[:3, 1]))
    else:
        measured = [c["radius"] for c in measure.cylinders(shape) if measure.coaxial(c, shaft, axis)]
        assert measured and max(measured) == pytest.approx(cavity, abs=1e-6)
    level = forearm_layout.forearm_rows(params) == 1 or k - 1 in forearm_stagger.staggered_rows(params)[0]
    if k == 6:
        # servo 6's shaft is parallel to the CMC axis and its pulley lies in the CMC pulley's plane
        Tc = frames.T_palm_thumb_cmc_base(params) @ thenar.T_cmc_base_pulley(params)
        Ts = forearm_layout.T_palm_servo(params, k - 1)
        assert Ts[:3, 2] == pytest.approx(Tc[:3, 2], abs=1e-12)
        assert (Ts[:3, 3] - Tc[:3, 3]) @ Tc[:3, 2] == pytest.approx(0.0, abs=1e-12)
    elif k == 1:
        # the drive runs in the pulley's plane to where it turns onto the CMC axis (the routing
        # model's via point): in one row the shaft is dorsal and the drive level, in the rear row
        # the servo is raised and tilted so that the drive slopes down to it
        turn = next(e for r_ in routing.routes(params) for st in r_.strands if st.name == "thumb_drive"
                    for e in st.elements if getattr(e, "role", "") == "over the CMC axis")
        Ts = forearm_layout.T_palm_servo(params, 0)
        assert (np.asarray(turn.pos) - Ts[:3, 3]) @ Ts[:3, 2] == pytest.approx(0.0, abs=1e-12)
        if level:
            assert axis == pytest.approx([0.0, 0.0, 1.0])
            assert Ts[2, 3] == pytest.approx(turn.pos[2], abs=1e-12)
        else:
            assert Ts[2, 3] > turn.pos[2]
    else:
        # a level finger servo's shaft is dorsal (palm z) and its pulley's mid-plane at the tendon
        # height, one wall above the thinnest finger's palmar face; a rear one's stands above it
        thinnest = min(f["thickness_mm"] for f in document["fingers"].values())
        tendon = -thinnest / 2 + document["palm"]["wall_mm"]
        if level:
            assert axis == pytest.approx([0.0, 0.0, 1.0])
            assert shaft[2] == pytest.approx(tendon, abs=1e-9)
        else:
            assert shaft[2] > tendon
    # ahead of the shaft (toward the wrist, along the servo's y in the pulley's plane) the ear slot
    # is open to the dorsal side (the servo drops in) as far as the ears reach with a clearance,
    # flange_span / 2 - shaft_offset + clearance (farther than the cavity by default); beyond it
    # at least a palm wall of material stands before the module's front face
    w = document["palm"]["wall_mm"]
    y = T[:3, 1]
    ears = document["servo"]["flange_span_mm"] / 2 - document["cad"]["servo_shaft_offset_mm"] + pr["hole_clearance_mm"]
    front = max(ears, cavity)
    assert not _is_inside(shape, shaft + y * (front - 0.1))
    assert _is_inside(shape, shaft + y * (front + 0.1))
    assert _is_inside(shape, shaft + y * (front + w - 0.1))


def test_forearm_drives_leave_straight_for_their_sockets(built, params):
    """Each finger's drive leaves its pulley along the servo's y at the tangent point (-r, 0, 0):
    the line from there along y passes the socket's tendon exit (in the pulley's plane: level in
    one row, sloping down from a raised rear servo), so the distance from the pulley centre to that
    line is r, and the exit lies ahead."""
    from phantom_cad.kinematics import forearm_layout
    from phantom_cad.kinematics import frames

    for k, f in enumerate(FINGERS, start=1):
        T = forearm_layout.T_palm_servo(params, k)
        C, y = T[:3, 3] * 1e3, T[:3, 1]
        E = frames.socket_tendon_point(params, f) * 1e3
        r = params.fingers[f].chain.servo_radius * 1e3
        d = E - C
        assert d @ T[:3, 2] == pytest.approx(0.0, abs=1e-9)
        perp = d - (d @ y) * y
        assert np.linalg.norm(perp) == pytest.approx(r, abs=1e-9) and d @ y > 0
        # and on the side the tendon leaves: the servo's -x
        assert perp @ T[:3, 0] == pytest.approx(-r, abs=1e-9)


def test_forearm_front_wall_holes_only_where_a_drive_runs(built, params, document):
    """Straight on from each pulley's tangent points along the servo's y, mid-way through the
    module's front wall: a drive's channel is open there on the servo's -x (the CMC loop's on both
    sides); on a tendon servo's +x, where no cable leaves, the wall is solid where the module is
    (no hole that carries no tendon; in two rows the ulnar servo's +x runs past the module's side)."""
    from phantom_cad.cad.parts import wrist
    from phantom_cad.kinematics import forearm_layout, servo_geometry
    from phantom_cad.kinematics import frames
    from phantom_cad.kinematics.topology import SERVO_MOUNT, SERVOS

    T_fp = np.linalg.inv(forearm_layout.T_palm_forearm(params))
    mid_wall = servo_geometry.forearm_front(params) * 1e3 - document["palm"]["wall_mm"] / 2     # palm y (mm)
    shape = built["forearm"].shape
    held = [s.index for s in SERVOS if SERVO_MOUNT[s.drive] == "forearm"]
    assert len(held) == 6
    for k in held:
        T = forearm_layout.T_palm_servo(params, k)
        for side in (-1.0, 1.0):
            tangent = T[:3, 3] * 1e3 + side * frames.servo_radius(params, k) * 1e3 * T[:3, 0]
            y = T[:3, 1]
            p = tangent + y * (mid_wall - tangent[1]) / y[1]
            inside = _is_inside(shape, (T_fp @ np.array([*(p / 1e3), 1.0]))[:3] * 1e3)
            carries = side < 0 or SERVOS[k].drive == "loop"
            x0, x1 = wrist.forearm_block(params)[:2]
            if carries or x0 < p[0] < x1:
                assert inside == (not carries), (k, side, p)


def test_forearm_width_is_the_built_blocks_breadth(built, params, document):
    """``forearm_layout.forearm_width`` is the built module's breadth (its bounding box across the
    forearm, read from the solid), and its limit is 80 mm at the paper's 189 mm hand length."""
    from phantom_cad.kinematics import forearm_layout, servo_geometry

    box = built["forearm"].shape.bounding_box()
    assert box.max.X - box.min.X == pytest.approx(forearm_layout.forearm_width(params) * 1e3, abs=1e-6)
    assert servo_geometry.forearm_width_limit(params) * 1e3 == pytest.approx(
        80.0 * document["hand"]["hand_length_mm"] / 189.0, abs=1e-9)


# ---------------------------------------------------------------------------
# pulley grooves at their radii
# ---------------------------------------------------------------------------

def _table(document, digit):
    return document["thumb"] if digit == "thumb" else document["fingers"][digit]


def _band(shape, axis_point, width):
    """The groove floor about an x axis through axis_point: (radius, x of the band's middle)."""
    cs = [c for c in measure.cylinders(shape) if measure.coaxial(c, axis_point, (1, 0, 0))
          and abs(c["length"] - width) < 1e-3]
    c = min(cs, key=lambda c: c["radius"])
    return c["radius"], float(c["centre"][0])


def _planes(document, digit):
    """By hand (docs/transmission.md): loop plane |x| = slot/2 - clearance - 0.8 mm flank - groove/2;
    return plane x = -(slot/2 - hub - clearance - flank - return groove/2), hub = clearance + 2 flanks + groove."""
    t = _table(document, digit)
    c, d = document["print"]["hole_clearance_mm"], document["hardware"]["tendon_diameter_mm"]
    s = (t["width_mm"] - 2 * document["cad"]["cheek_mm"]) / 2
    g, gr = d + 2 * c, document["cad"]["spring_diameter_mm"] + 2 * c
    hub = c + 2 * 0.8 + g
    return s - c - 0.8 - g / 2, -(s - hub - c - 0.8 - gr / 2), g, gr


# the coupling loops' grooves on the link after their second joint, and the return cord's on every
# joint's child: (digit, link segment, joint, loop plane sign or None)
LOOP_GROOVES = [(f, "middle", "pip", 1) for f in FINGERS] + [(f, "distal", "dip", -1) for f in FINGERS] \
    + [("thumb", "distal", "ip", 1)]
RETURN_GROOVES = [(f, seg, j) for f in FINGERS for seg, j in (("proximal", "mcp"), ("middle", "pip"), ("distal", "dip"))] \
    + [("thumb", "proximal", "mp"), ("thumb", "distal", "ip")]
# the loops' hubs: on the link before their first joint, at that joint's axis (y along the link)
HUBS = [(f, "base", "mcp", 1, None) for f in FINGERS] + [(f, "proximal", "pip", -1, "proximal") for f in FINGERS] \
    + [("thumb", "cmc_base", "mp", 1, "metacarpal")]


@pytest.mark.parametrize("digit,segment,joint,sign", LOOP_GROOVES)
def test_loop_groove_floor_is_R_less_half_a_tendon(built, document, digit, segment, joint, sign):
    r, x = _band(built[f"{digit}_{segment}"].shape, (0, 0, 0), _planes(document, digit)[2])
    R = _table(document, digit)["pulley_radius_mm"][joint]
    assert r == pytest.approx(R - document["hardware"]["tendon_diameter_mm"] / 2, abs=1e-6)
    assert x == pytest.approx(sign * _planes(document, digit)[0], abs=1e-6)


@pytest.mark.parametrize("digit,segment,joint", RETURN_GROOVES)
def test_return_groove_floor_is_R_less_half_a_cord(built, document, digit, segment, joint):
    r, x = _band(built[f"{digit}_{segment}"].shape, (0, 0, 0), _planes(document, digit)[3])
    R = _table(document, digit)["pulley_radius_mm"][joint]
    assert r == pytest.approx(R - document["cad"]["spring_diameter_mm"] / 2, abs=1e-6)
    assert x == pytest.approx(_planes(document, digit)[1], abs=1e-6)


@pytest.mark.parametrize("digit,segment,joint,sign,length", HUBS)
def test_loop_hub_floor_is_R_less_half_a_tendon(built, document, digit, segment, joint, sign, length):
    y = 0.0 if length is None else _table(document, digit)["length_fraction"][length] * document["hand"]["hand_length_mm"]
    r, x = _band(built[f"{digit}_{segment}"].shape, (0, y, 0), _planes(document, digit)[2])
    R = _table(document, digit)["pulley_radius_mm"][joint]
    assert r == pytest.approx(R - document["hardware"]["tendon_diameter_mm"] / 2, abs=1e-6)
    assert x == pytest.approx(sign * _planes(document, digit)[0], abs=1e-6)


def test_finger_grooves_are_5_4_5(built, document):
    """The return cord's moment arms (floor + half the cord), measured, in the paper's 5:4:5."""
    half = document["cad"]["spring_diameter_mm"] / 2
    for f in FINGERS:
        w = _planes(document, f)[3]
        r = [_band(built[f"{f}_{s}"].shape, (0, 0, 0), w)[0] + half for s in ("distal", "middle", "proximal")]
        assert np.allclose(np.array(r) / r[0] * 5.0, [5.0, 4.0, 5.0])


@pytest.mark.parametrize("k", [1, 2, 3, 4, 5])
def test_servo_pulley_groove_radius_is_r(built, document, k):
    r = measure.measure_groove_radius(built[f"servo_pulley_{k}"].shape, (0, 0, 0), (0, 0, 1), tendon_hole(document))
    src = document["thumb"] if k == 1 else document["fingers"][FINGERS[k - 2]]
    # the tendon's centreline runs at r_j (eq. 5): the floor lies half a tendon inside
    assert r == pytest.approx(src["servo_pulley_radius_mm"] - document["hardware"]["tendon_diameter_mm"] / 2, abs=1e-6)


@pytest.mark.parametrize("k", [1, 2, 3, 4, 5])
def test_servo_pulley_anchor_at_the_clamp_and_clear_of_the_horn_screws(built, document, k):
    """The knot well (an axial hole of twice the tendon hole's diameter) sits at the polar angle
    where the drive is clamped: the wrap at u = 0 is the largest of (8 deg, 172 deg - travel), so
    that the service angle below the travel pays the most cord out, and the clamp is at
    180 deg + 172 deg - travel = 352 deg - travel; every horn-screw hole stands a print wall away
    from it."""
    src = document["thumb"] if k == 1 else document["fingers"][FINGERS[k - 2]]
    travel = src["servo_travel_deg"][1]
    pr, hw = document["print"], document["hardware"]
    well_r = tendon_hole(document)
    screw_r = hw["screw_diameter_mm"] / 2 + pr["hole_clearance_mm"] + _comp(document)
    axial = [c for c in measure.cylinders(built[f"servo_pulley_{k}"].shape)
             if abs(abs(c["direction"][2]) - 1.0) < 1e-9 and np.hypot(*c["point"][:2]) > 1.0]
    wells = [c for c in axial if abs(c["radius"] - well_r) < 1e-6]
    screws = [c for c in axial if abs(c["radius"] - screw_r) < 1e-6]
    assert len(wells) == 1 and len(screws) == 2
    w = wells[0]["point"][:2]
    angle = math.degrees(math.atan2(w[1], w[0])) % 360.0
    assert angle == pytest.approx(352.0 - travel, abs=1e-6)
    for sc in screws:
        wall = np.linalg.norm(sc["point"][:2] - w) - well_r - screw_r
        assert wall >= document["palm"]["wall_mm"]


def test_the_cmc_loop_pulleys_have_equal_grooves(built, document):
    """Servo 6's pulley and the CMC pulley: groove floors half a tendon inside r6 and r6 / cmc_gain
    (measured about each pulley's axis): equal radii at the default gain of 1, so q15 = u6."""
    r6, g = document["thumb"]["cmc_pulley_radius_mm"], document["thumb"]["cmc_gain"]
    d = document["hardware"]["tendon_diameter_mm"]
    hole = d + 2 * document["print"]["hole_clearance_mm"]
    for name, r in (("servo_pulley_6", r6), ("thumb_cmc_pulley", r6 / g)):
        assert measure.measure_groove_radius(built[name].shape, (0, 0, 0), (0, 0, 1), hole) == \
            pytest.approx(r - d / 2, abs=1e-6)


# ---------------------------------------------------------------------------
# MCP guides at d1, d2, alpha in the assembled rest pose
# ---------------------------------------------------------------------------

def _axle_axis(shape, T, doc):
    """The press-fit axle bore of a clevis, in the hand frame (measured)."""
    r = (doc["hardware"]["axle_diameter_mm"] - doc["print"]["press_fit_interference_mm"]) / 2 + _comp(doc)
    cs = [c for c in measure.cylinders(shape) if abs(c["radius"] - r) < 1e-6]
    assert cs
    near = min(cs, key=lambda c: np.linalg.norm(c["point"] - np.dot(c["point"], c["direction"]) * c["direction"]))
    return _hand(T, near["point"]), _dir(T, near["direction"])


def _eyelet(shape, T, doc):
    hits = measure.eyelet_centres(shape, tendon_hole(doc) / 2, doc["cad"]["eyelet_length_mm"])
    assert len(hits) == 1
    return _hand(T, hits[0]["centre"])


def _guide_geometry(axis_point, axis_dir, G1, G2):
    d = axis_dir / np.linalg.norm(axis_dir)
    v1 = G1 - axis_point
    v1 -= (v1 @ d) * d
    v2 = G2 - axis_point
    v2 -= (v2 @ d) * d
    ang = math.acos(float(v1 @ v2 / np.linalg.norm(v1) / np.linalg.norm(v2)))
    return float(np.linalg.norm(v1)), float(np.linalg.norm(v2)), ang


@pytest.mark.parametrize("finger", FINGERS)
def test_mcp_guides_at_d1_d2_alpha(built, document, finger):
    base, prox = built[f"{finger}_base"], built[f"{finger}_proximal"]
    a, d = _axle_axis(base.shape, base.T_hand_link, document)
    G1 = _eyelet(base.shape, base.T_hand_link, document)
    G2 = _eyelet(prox.shape, prox.T_hand_link, document)
    d1, d2, alpha = _guide_geometry(a, d, G1, G2)
    g = document["fingers"][finger]["guide"]
    assert d1 == pytest.approx(g["d1_mm"], abs=0.02)
    assert d2 == pytest.approx(g["d2_mm"], abs=0.02)
    assert math.degrees(alpha) == pytest.approx(g["alpha_deg"], abs=0.1)
    # eq. (4): the chord between the guides at rest
    L0 = math.sqrt(g["d1_mm"] ** 2 + g["d2_mm"] ** 2 - 2 * g["d1_mm"] * g["d2_mm"] * math.cos(math.radians(g["alpha_deg"])))
    assert np.linalg.norm(G1 - G2) == pytest.approx(L0, abs=0.03)
    # both guides lie on the palmar side
    assert G1[2] < 0 and G2[2] < 0


def test_thumb_mp_guides_at_d1_d2_alpha(built, document):
    base, prox = built["thumb_cmc_base"], built["thumb_proximal"]
    a, d = _axle_axis(base.shape, base.T_hand_link, document)
    G1 = _eyelet(base.shape, base.T_hand_link, document)
    G2 = _eyelet(prox.shape, prox.T_hand_link, document)
    d1, d2, alpha = _guide_geometry(a, d, G1, G2)
    g = document["thumb"]["guide"]
    assert (d1, d2) == (pytest.approx(g["d1_mm"], abs=0.02), pytest.approx(g["d2_mm"], abs=0.02))
    assert math.degrees(alpha) == pytest.approx(g["alpha_deg"], abs=0.1)


def test_thumb_cmc_base_prints_on_its_palmar_pad(built, document, params):
    """The CMC base rests on its palmar face, deepened to a pad as low as the MP guide's
    boss reaches (the guide sits inside the palmar face, its boss does not): the planar faces
    looking straight down at its lowest z cover more than a quarter of its footprint
    (``export.orient``'s rule); laid that way its MP axis is flat, so every blocker of its MP hub
    groove holds."""
    from build123d import GeomType

    base = built["thumb_cmc_base"]
    bb = base.shape.bounding_box()
    T = document["thumb"]["thickness_mm"]
    low = [f for f in base.shape.faces() if f.geom_type == GeomType.PLANE
           and f.normal_at().Z < -1.0 + 1e-9 and abs(f.center().Z - bb.min.Z) < 1e-6]
    assert sum(f.area for f in low) > 0.25 * bb.size.X * bb.size.Y
    assert bb.min.Z < -T / 2.0 - 1.0            # the boss hangs 1.9 mm below the palmar face
    up = np.asarray(base.print_rotation)[2]
    assert np.allclose(up, (0.0, 0.0, 1.0))
    grooves = [b for b in base.blockers if b.label.startswith("groove")]
    assert grooves and all(b.holds(up) for b in grooves)
    # its verification measures the pad: the solid cut 0.5 mm off its palmar side fails it, by
    # exactly that (the grooves, the guide and the rest untouched)
    from build123d import Box, Pos

    from phantom_cad.cad import registry

    part = registry.part(params, "thumb_cmc_base")
    size = bb.size.X + 2.0, bb.size.Y + 2.0, 1.0
    shaved = base.shape - Pos(bb.center().X, bb.center().Y, bb.min.Z) * Box(*size)
    assert part.verify(base.shape) == []
    assert part.verify(shaved) == [f"thumb_cmc_base: lowest z measures {bb.min.Z + 0.5:.4f}, "
                                   f"expected {bb.min.Z:.4f} mm"]


def test_cylinder_floor_against_closed_forms():
    """``common.cylinder_floor``: a level cylinder's lowest line is r under its axis, an upright
    one's its lower end; a tilted one against its tessellation (trimesh, 256 sides)."""
    trimesh = pytest.importorskip("trimesh")
    from phantom_cad.cad.parts.common import cylinder_floor

    assert cylinder_floor((0, 0, 1.0), (5.0, 0, 1.0), 2.0) == pytest.approx(-1.0, abs=1e-12)
    assert cylinder_floor((0, 0, 3.0), (0, 0, -2.0), 2.0) == pytest.approx(-2.0, abs=1e-12)
    p0, p1, r = np.array([1.0, 2.0, 3.0]), np.array([4.0, -2.0, 1.0]), 1.5
    u = (p1 - p0) / np.linalg.norm(p1 - p0)
    m = trimesh.creation.cylinder(radius=r, segment=np.array([p0, p1]), sections=256)
    # the lower end circle's lowest point: its centre's z less r sin(angle from z)
    assert cylinder_floor(p0, p1, r) == pytest.approx(1.0 - r * math.sqrt(1.0 - u[2] ** 2), abs=1e-12)
    assert cylinder_floor(p0, p1, r) == pytest.approx(m.bounds[0, 2], abs=1e-3)


# ---------------------------------------------------------------------------
# palm sockets and magnets
# ---------------------------------------------------------------------------

def _magnet_r(doc):
    return doc["hardware"]["magnet"]["diameter_mm"] / 2 + doc["print"]["magnet_clearance_mm"] + _comp(doc)


def test_palm_sockets_are_arc_offset_apart(built, document):
    pockets = measure.circular_pockets(built["palm"].shape, _magnet_r(document))
    assert len(pockets) == 8
    # group the pocket axes (the socket face normals) into the four sockets, ordered radial -> ulnar
    normals = []
    for p in sorted(pockets, key=lambda p: p["centre"][0]):
        if not normals or np.linalg.norm(p["facing"] - normals[-1]) > 1e-9:
            normals.append(p["facing"])
    assert len(normals) == 4
    for a, b in zip(normals, normals[1:]):
        ang = math.degrees(math.acos(float(np.clip(a @ b, -1, 1))))
        assert ang == pytest.approx(document["palm"]["arc_offset_deg"], abs=1e-6)
        # the fan opens toward the ulnar side (x grows from index to pinky)
        assert np.cross(a, b)[2] < 0
    # the sockets face distally
    assert all(n[1] > 0.95 for n in normals)


def test_palm_socket_faces_step_with_the_metacarpals(built, document):
    """The stepped metacarpal heads, measured on the palm: the magnet pockets' openings lie on each
    socket's face, whose centre is the MCP (on the 5 deg arc, chords 20.5 mm at -5 / 0 / +5 deg,
    then stepped along its column, turned -7.5 / -2.5 / 2.5 / 7.5 deg, by its metacarpal less the
    index's) less a finger base length along the column: the knuckle line is not a symmetric arc."""
    pockets = sorted(measure.circular_pockets(built["palm"].shape, _magnet_r(document)), key=lambda p: p["centre"][0])
    hl, base = document["hand"]["hand_length_mm"], document["cad"]["finger_base_length_mm"]
    pitch, d = document["palm"]["finger_pitch_mm"], math.radians
    meta = [document["fingers"][f]["length_fraction"]["metacarpal"] * hl for f in FINGERS]
    x = y = 0.0
    faces = []
    for i, phi in enumerate((-7.5, -2.5, 2.5, 7.5)):
        if i:
            m = (i - 2) * 5.0
            x, y = x + pitch * math.cos(d(m)), y - pitch * math.sin(d(m))
        step = meta[i] - meta[0] - base
        faces.append((x + step * math.sin(d(phi)), y + step * math.cos(d(phi))))
    for i, (fx, fy) in enumerate(faces):
        pair = pockets[2 * i: 2 * i + 2]
        mid = (pair[0]["centre"] + pair[1]["centre"]) / 2.0
        assert mid[:2] == pytest.approx([fx, fy], abs=1e-6)
    # the stepped line of the socket faces: the middle's 1.5 mm ahead of the index's, the ring's 5.5
    # and the pinky's 14.8 mm behind it, along the palm's y (a symmetric arc would give 1.8 / 1.8 / 0)
    ys = [fy - faces[0][1] for _, fy in faces]
    assert [round(v, 1) for v in ys[1:]] == [1.5, -5.5, -14.8]


@pytest.mark.parametrize("finger", FINGERS)
def test_magnet_sockets_coincide_with_the_palm(built, document, finger):
    r = _magnet_r(document)
    base = built[f"{finger}_base"]
    palm = built["palm"]
    mine = [(_hand(base.T_hand_link, p["centre"]), _dir(base.T_hand_link, p["facing"]))
            for p in measure.circular_pockets(base.shape, r)]
    theirs = [(p["centre"], p["facing"]) for p in measure.circular_pockets(palm.shape, r)]
    assert len(mine) == 2
    for c, n in mine:
        match = [(c2, n2) for c2, n2 in theirs if np.linalg.norm(c2 - c) < 1e-6]
        assert len(match) == 1, (finger, c)
        assert match[0][1] @ n == pytest.approx(-1.0, abs=1e-9)   # opposite facing
    # the depth holds the magnet plus its clearance
    for p in measure.circular_pockets(base.shape, r):
        assert p["depth"] == pytest.approx(document["hardware"]["magnet"]["thickness_mm"]
                                           + document["print"]["magnet_clearance_mm"], abs=1e-6)


# ---------------------------------------------------------------------------
# mating seats: axles in both parts, screws in the CMC base and its hub
# ---------------------------------------------------------------------------

JOINTS = [(f"{f}_{a}", f"{f}_{b}") for f in FINGERS for a, b in (("base", "proximal"), ("proximal", "middle"),
                                                                   ("middle", "distal"))] \
    + [("thumb_cmc_base", "thumb_proximal"), ("thumb_proximal", "thumb_distal")]


@pytest.mark.parametrize("parent,child", JOINTS)
def test_axle_bore_and_bearing_seats_are_coaxial(built, document, parent, child):
    P, Cb = built[parent], built[child]
    hw, pr = document["hardware"], document["print"]
    press = (hw["axle_diameter_mm"] - pr["press_fit_interference_mm"]) / 2 + _comp(document)
    seat = (hw["bearing"]["outer_mm"] - pr["press_fit_interference_mm"]) / 2 + _comp(document)
    clear = (hw["axle_diameter_mm"] + 2 * pr["hole_clearance_mm"]) / 2 + _comp(document)
    # the child's bearing seat (one, where it fits beside the grooves) and clearance bore sit on
    # its own x axis
    seats = [c for c in measure.cylinders(Cb.shape) if abs(c["radius"] - seat) < 1e-6]
    assert len(seats) <= 1 and all(measure.coaxial(c, (0, 0, 0), (1, 0, 0)) for c in seats)
    assert all(c["length"] == pytest.approx(hw["bearing"]["width_mm"], abs=1e-6) for c in seats)
    assert any(abs(c["radius"] - clear) < 1e-6 and measure.coaxial(c, (0, 0, 0), (1, 0, 0))
               for c in measure.cylinders(Cb.shape))
    # the parent's press-fit bore, taken to the hand frame, is the child's axis at rest
    a = _hand(Cb.T_hand_link, (0, 0, 0))
    d = _dir(Cb.T_hand_link, (1, 0, 0))
    bores = [c for c in measure.cylinders(P.shape) if abs(c["radius"] - press) < 1e-6]
    assert any(measure.point_line_distance(_hand(P.T_hand_link, c["point"]), a, d) < 1e-6
               and abs(abs(_dir(P.T_hand_link, c["direction"]) @ d) - 1) < 1e-9 for c in bores)


def test_the_cmc_pulley_sits_keyed_on_the_column_in_the_palms_journal(built, document):
    """The CMC base's column (radius cad.cmc_column_radius_mm, 3.5 mm by default), the palm's journal
    and the CMC pulley's bore (the column's radius and a hole clearance; the pulley's compensated)
    are coaxial with the CMC axis at rest, measured in the placed solids; the pulley's flat and
    the column's flat (1 mm deep) touch: one plane, facing each other."""
    from phantom_cad.cad.parts.thumb import KEY_DEPTH

    pr = document["print"]
    rc = document["cad"].get("cmc_column_radius_mm", 3.5)
    base, palm, pul = built["thumb_cmc_base"], built["palm"], built["thumb_cmc_pulley"]
    a, d = _hand(base.T_hand_link, (0, 0, 0)), _dir(base.T_hand_link, (0, 0, 1))

    def on_axis(part, r):
        return [c for c in measure.cylinders(part.shape) if abs(c["radius"] - r) < 1e-6
                and measure.point_line_distance(_hand(part.T_hand_link, c["point"]), a, d) < 1e-6
                and abs(abs(_dir(part.T_hand_link, c["direction"]) @ d) - 1) < 1e-9]

    assert on_axis(base, rc)
    assert on_axis(palm, rc + pr["hole_clearance_mm"])
    assert on_axis(pul, rc + pr["hole_clearance_mm"] + _comp(document))
    flats = {}
    for name, part, want in (("column", base, rc - KEY_DEPTH), ("pulley", pul, rc - KEY_DEPTH)):
        for f in measure.planar_faces(part.shape):
            n = _dir(part.T_hand_link, f["normal"])
            p = _hand(part.T_hand_link, f["centre"])
            if abs(n @ d) < 1e-9 and abs(measure.point_line_distance(p, a, d) - want) < 1e-6:
                flats[name] = n
    # the column's flat faces out of the column, the pulley's into its bore: opposite normals
    assert set(flats) == {"column", "pulley"} and flats["column"] @ flats["pulley"] == pytest.approx(-1.0)


# ---------------------------------------------------------------------------
# the assembled hand at rest
# ---------------------------------------------------------------------------

def test_no_two_parts_intersect_at_rest(placed, params):
    allowed = {frozenset((a, b)) for a, b, _ in assembly.designed_contacts(params)}
    bad = []
    for a, b in itertools.combinations(sorted(placed), 2):
        v = measure.intersection_volume(placed[a], placed[b])
        tol = 1e-2 if frozenset((a, b)) in allowed else 1e-3
        if v > tol:
            bad.append((a, b, round(v, 4)))
    assert bad == []


STOPS = [(f, j, p, c) for f in FINGERS for j, p, c in (("mcp", "base", "proximal"), ("pip", "proximal", "middle"),
                                                          ("dip", "middle", "distal"))] \
    + [("thumb", "mp", "cmc_base", "proximal"), ("thumb", "ip", "proximal", "distal")]


@pytest.mark.parametrize("digit,joint,parent,child", STOPS)
def test_hard_stop_engages_at_the_limit(built, document, params, digit, joint, parent, child):
    """Each joint turns freely up to its Table I limit and is blocked 1 degree beyond it."""
    from phantom_cad.kinematics.topology import joint_index
    P, Cp = built[f"{digit}_{parent}"], built[f"{digit}_{child}"]
    table = document["thumb"] if digit == "thumb" else document["fingers"][digit]
    q_max = table["limits_rad"][joint][1]
    if joint == "mcp":   # the finger module's own MCP stop lies beyond the palm's
        q_max += math.radians(document["cad"]["module_stop_margin_deg"])
    vols = []
    for q in (q_max, q_max + math.radians(1.0)):
        qv = np.zeros(15)
        qv[joint_index(digit, joint)] = q
        T = assembly.pose_transforms(params, qv)
        vols.append(measure.intersection_volume(measure.placed(P.shape, T[f"{digit}_{parent}"]),
                                              measure.placed(Cp.shape, T[f"{digit}_{child}"])))
    assert vols[0] < 1e-3
    assert vols[1] > 0.05


@pytest.mark.parametrize("finger", FINGERS)
def test_palm_housing_limits_mcp_flexion(built, document, params, finger):
    """The palm's flexion limiter stops the proximal phalanx at the Table I MCP limit, before
    the finger module's own stop."""
    from phantom_cad.kinematics.topology import joint_index
    q_max = document["fingers"][finger]["limits_rad"]["mcp"][1]
    palm, prox = built["palm"], built[f"{finger}_proximal"]
    vols = []
    for q in (0.0, q_max, q_max + math.radians(1.0)):
        qv = np.zeros(15)
        qv[joint_index(finger, "mcp")] = q
        T = assembly.pose_transforms(params, qv)
        vols.append(measure.intersection_volume(palm.shape, measure.placed(prox.shape, T[f"{finger}_proximal"])))
    assert vols[0] < 1e-3 and vols[1] < 1e-3
    assert vols[2] > 0.05


def test_half_flexed_hand_has_no_interference(built, params, document):
    """At half of every joint's upper limit no two parts overlap (joint pairs may touch)."""
    from phantom_cad.kinematics.topology import JOINT_NAMES
    q = np.zeros(15)
    for i, name in enumerate(JOINT_NAMES):
        digit, joint = name.split("_")
        table = document["thumb"] if digit == "thumb" else document["fingers"][digit]
        q[i] = 0.5 * table["limits_rad"][joint][1]
    T = assembly.pose_transforms(params, q)
    placed = {n: measure.placed(b.shape, T[n]) for n, b in built.items()}
    allowed = {frozenset((a, b)) for a, b, _ in assembly.designed_contacts(params)}
    bad = []
    for a, b in itertools.combinations(sorted(placed), 2):
        v = measure.intersection_volume(placed[a], placed[b])
        if v > (1e-2 if frozenset((a, b)) in allowed else 1e-3):
            bad.append((a, b, round(v, 4)))
    assert bad == []


# ---------------------------------------------------------------------------
# parameters move the measured features
# ---------------------------------------------------------------------------

def test_changed_pulley_radius_moves_the_groove(variant, document):
    def edit(doc):
        doc["fingers"]["middle"]["pulley_radius_mm"]["pip"] = 4.6
    p = variant(edit)
    shape = assembly.build_part(p, "middle_middle").shape
    assert measure.measure_groove_radius(shape, (0, 0, 0), (1, 0, 0), tendon_hole(document)) == pytest.approx(4.6 - 0.3)


def test_changed_d1_moves_the_base_guide(variant, document):
    def edit(doc):
        doc["fingers"]["ring"]["guide"]["d1_mm"] = 12.8
    p = variant(edit)
    b = assembly.build_part(p, "ring_base")
    a, d = _axle_axis(b.shape, np.eye(4), document)
    G1 = _eyelet(b.shape, np.eye(4), document)
    assert measure.point_line_distance(G1, a, d) == pytest.approx(12.8, abs=0.02)


def test_changed_servo_radius_moves_the_servo_groove(variant, document):
    def edit(doc):
        doc["fingers"]["pinky"]["servo_pulley_radius_mm"] = 7.5
        doc["fingers"]["pinky"]["servo_travel_deg"] = [0.0, 80.0]
    p = variant(edit)
    shape = assembly.build_part(p, "servo_pulley_5").shape
    assert measure.measure_groove_radius(shape, (0, 0, 0), (0, 0, 1), tendon_hole(document)) == pytest.approx(7.5 - 0.3)


def test_changed_arc_offset_turns_the_sockets(variant, document):
    def edit(doc):
        doc["palm"]["arc_offset_deg"] = 4.0
    p = variant(edit)
    # the socket normals are the finger bases' y axes: measure on two bases' magnet pockets
    T = assembly.pose_transforms(p)
    shape = assembly.build_part(p, "ring_base").shape
    pk = measure.circular_pockets(shape, _magnet_r(document))
    n_ring = -_dir(T["ring_base"], pk[0]["facing"])
    n_middle = -_dir(T["middle_base"], pk[0]["facing"])
    assert math.degrees(math.acos(float(n_ring @ n_middle))) == pytest.approx(4.0, abs=1e-6)


# ---------------------------------------------------------------------------
# left hand
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["index_proximal", "thumb_cmc_base", "palm"])
def test_left_hand_is_the_mirror_image(built, variant, name):
    def edit(doc):
        doc["hand"]["side"] = "left"
    p = variant(edit)
    left = assembly.build_part(p, name)
    right = built[name]
    rl, rr = measure.solid_report(left.shape), measure.solid_report(right.shape)
    assert rl["valid"] and rl["n_solids"] == 1
    assert verify_part(p, name, left.shape) == []
    assert rl["volume"] == pytest.approx(rr["volume"], rel=1e-6)
    assert np.allclose(rl["bbox_min"], [-rr["bbox_max"][0], rr["bbox_min"][1], rr["bbox_min"][2]], atol=1e-6)
    assert np.allclose(rl["bbox_max"], [-rr["bbox_min"][0], rr["bbox_max"][1], rr["bbox_max"][2]], atol=1e-6)
    # placed in the hand: the mirror of the right hand's placed part in the palm's y-z plane
    pl = measure.solid_report(measure.placed(left.shape, left.T_hand_link))
    pr = measure.solid_report(measure.placed(right.shape, right.T_hand_link))
    assert np.allclose(pl["bbox_min"], [-pr["bbox_max"][0], pr["bbox_min"][1], pr["bbox_min"][2]], atol=1e-3)
    assert np.allclose(pl["bbox_max"], [-pr["bbox_min"][0], pr["bbox_max"][1], pr["bbox_max"][2]], atol=1e-3)


# ---------------------------------------------------------------------------
# tendon routing: socket -> servo pulley
# ---------------------------------------------------------------------------

def _line_distance(p1, d1, p2, d2):
    n = np.cross(d1, d2)
    if np.linalg.norm(n) < 1e-12:
        return measure.point_line_distance(p2, p1, d1)
    return abs((p2 - p1) @ n) / np.linalg.norm(n)


@pytest.mark.parametrize("k,finger", [(2, "index"), (3, "middle"), (4, "ring"), (5, "pinky")])
def test_palm_tendon_channel_joins_base_and_pulley(built, document, k, finger):
    """The palm's tendon channel starts where the finger base's tendon channel crosses the
    magnet face and runs tangent to its servo pulley's groove (distance r_j from the axis)."""
    palm, base, pulley = built["palm"], built[f"{finger}_base"], built[f"servo_pulley_{k}"]
    channels = [c for c in measure.cylinders(palm.shape) if abs(c["radius"] - tendon_hole(document) / 2) < 1e-6]
    # the base's entry channel (a clearance hole) crosses the magnet face y = -base length
    Lb = document["cad"]["finger_base_length_mm"]
    entries = []
    for c in measure.cylinders(base.shape):
        if abs(c["radius"] - tendon_hole(document) / 2) < 1e-6 and abs(c["direction"][1]) > 1e-6:
            t = (-Lb - c["point"][1]) / c["direction"][1]
            entries.append(_hand(base.T_hand_link, c["point"] + t * c["direction"]))
    # the pulley's groove axis, measured
    r = document["fingers"][finger]["servo_pulley_radius_mm"]
    floor = r - document["hardware"]["tendon_diameter_mm"] / 2       # the centreline runs at r
    groove = [c for c in measure.cylinders(pulley.shape) if abs(c["radius"] - floor) < 1e-6]
    assert groove
    pa, pd = _hand(pulley.T_hand_link, groove[0]["point"]), _dir(pulley.T_hand_link, groove[0]["direction"])
    hits = 0
    for c in channels:
        p, d = c["point"], c["direction"]
        through_entry = any(measure.point_line_distance(e, p, d) < 1e-6 for e in entries)
        if through_entry:
            hits += 1
            assert _line_distance(p, d, pa, pd) == pytest.approx(r, abs=1e-6)
            assert abs(d @ pd) < 1e-9   # the tendon leaves in the pulley's plane
    assert hits == 1


# ---------------------------------------------------------------------------
# verify_part: what the build uses to refuse a broken part
# ---------------------------------------------------------------------------

def test_verify_part_accepts_every_default_part(built, params):
    assert {n: verify_part(params, n, b.shape) for n, b in built.items()} == {n: [] for n in built}


def test_verify_part_reports_a_wrong_groove(variant, params):
    p = variant(lambda d: d["fingers"]["middle"]["pulley_radius_mm"].__setitem__("pip", 4.6))
    shape = assembly.build_part(p, "middle_middle").shape
    # both grooves on the PIP tongue moved 0.6 mm out: the loop's (floor R - 0.3) and the return cord's (R - 0.75)
    assert verify_part(params, "middle_middle", shape) == [
        "middle_middle: pip loop groove floor measures 4.3000, expected 3.7000 mm",
        "middle_middle: pip return groove floor measures 3.8500, expected 3.2500 mm"]


def test_verify_part_reports_several_solids(params):
    import build123d as bd
    two = bd.Compound([bd.Box(1, 1, 1), bd.Pos(5, 0, 0) * bd.Box(1, 1, 1)])
    assert verify_part(params, "servo_pulley_2", two) == ["servo_pulley_2: 2 solids, expected 1"]
    assert verify_part(params, "servo_pulley_2", bd.Box(4, 4, 4)) == [
        "servo_pulley_2: groove radius measures nothing, expected 6.7000 mm"]


def test_thumb_tendon_reaches_the_cmc_base_on_its_axis(built, document):
    """The palm drops the thumb tendon onto the CMC axis above the CMC pulley's cavity (measured:
    the axis of the CMC base's column) and the column carries it down that axis, so CMC rotation
    leaves the tendon length alone."""
    palm, base = built["palm"], built["thumb_cmc_base"]
    rc = document["cad"].get("cmc_column_radius_mm", 3.5)
    column = [c for c in measure.cylinders(base.shape) if abs(c["radius"] - rc) < 1e-6]
    assert column
    a, d = _hand(base.T_hand_link, column[0]["point"]), _dir(base.T_hand_link, column[0]["direction"])
    for part in (palm, base):
        holes = [c for c in measure.cylinders(part.shape) if abs(c["radius"] - tendon_hole(document) / 2) < 1e-6]
        on_axis = [c for c in holes if measure.point_line_distance(_hand(part.T_hand_link, c["point"]), a, d) < 1e-6
                   and abs(abs(_dir(part.T_hand_link, c["direction"]) @ d) - 1) < 1e-9]
        assert len(on_axis) >= 1, part.name


def _pilots_and_pairs(shape, document):
    hw, sv = document["hardware"], document["servo"]
    pilot = 0.8 * hw["screw_diameter_mm"] / 2 + _comp(document)    # the pilot ratio's default: 1.6 mm for M2
    holes = [c for c in measure.cylinders(shape) if abs(c["radius"] - pilot) < 1e-6]
    # mid-ear on both ends: (body length / 2 + flange span / 2) apart, along the body length
    spacing = sv["body_mm"][0] / 2 + sv["flange_span_mm"] / 2
    pairs = 0
    for a, b in itertools.combinations(holes, 2):
        if abs(abs(a["direction"] @ b["direction"]) - 1) < 1e-9:
            v = b["centre"] - a["centre"]
            v_perp = v - (v @ a["direction"]) * a["direction"]
            if abs(v @ a["direction"]) < 1e-6 and abs(np.linalg.norm(v_perp) - spacing) < 1e-6:
                pairs += 1   # the same servo: side by side at the same depth
    return holes, pairs


def test_two_flange_screw_pilots_per_servo(built, document, placed):
    """Twelve pilots in the forearm module (servos 1-6), none for a servo in the palm, and the
    palm's two under the forearm tab's clearance holes (coaxial, measured in the hand)."""
    hw = document["hardware"]
    holes, pairs = _pilots_and_pairs(built["forearm"].shape, document)
    assert len(holes) == 12 and pairs == 6
    # each servo pilot is 3 screw diameters deep below the ear slot (plus one clearance); exactly 3 on
    # the default hand, measured to the last bits of a double
    assert all(c["length"] >= 3 * hw["screw_diameter_mm"] - 1e-9 for c in holes)
    holes, pairs = _pilots_and_pairs(built["palm"].shape, document)
    assert len(holes) == 2 and pairs == 0
    # the tab's clearance holes (screw + 2 clearances) over the palm's two other pilots
    clear = hw["screw_diameter_mm"] / 2 + document["print"]["hole_clearance_mm"] + _comp(document)
    tab = [c for c in measure.cylinders(placed["forearm"]) if abs(c["radius"] - clear) < 1e-6]
    pil = [c for c in measure.cylinders(placed["palm"]) if abs(c["radius"] - 0.8 * hw["screw_diameter_mm"] / 2 - _comp(document)) < 1e-6
           and abs(abs(c["direction"][2]) - 1) < 1e-9]
    assert len(tab) == 2 and len(pil) == 2
    for c in tab:
        assert any(measure.coaxial(c, p["point"], p["direction"]) for p in pil)


# ---------------------------------------------------------------------------
# every knot of the routing model sits in a well cut in material
# ---------------------------------------------------------------------------

def test_every_knot_well_is_cut_in_material(built, params):
    """A knot (the return cord's two ends, the drive's end behind G2) pulls on the part around
    its well: at the knot, 1 mm beyond the well's wall (the well is the tendon hole plus a
    clearance wide, about 1.4 mm), the part has material on both sides across the digit and behind it (away from its cord).
    (The routing model once put the finger bases' return knot in the open MCP clevis slot.)"""
    from phantom_cad.kinematics import routing

    r = (params.hardware.tendon_diameter * 1e3 + 4 * params.print.hole_clearance * 1e3) / 2 + 1.0
    knots = []     # (link, knot, the point its cord leaves toward), mm, link frame
    for rt in routing.routes(params, right_handed=True):
        for st in rt.strands:
            for e, nb in ((st.elements[0], st.elements[1]), (st.elements[-1], st.elements[-2])):
                if getattr(e, "kind", None) == "anchor" and e.role == "knot":
                    assert nb.link == e.link
                    knots.append((e.link, np.asarray(e.pos) * 1e3, np.asarray(nb.pos) * 1e3))
    assert len(knots) == 10        # 5 return cords x 2 ends
    missing = []
    for link_name, p, toward in knots:
        shape = built[link_name].shape
        back = (p - toward) / np.linalg.norm(p - toward)     # behind the knot, away from its cord
        for d in ((r, 0, 0), (-r, 0, 0), r * back):
            q = p + np.asarray(d)
            if not shape.is_inside(tuple(q)):
                missing.append((link_name, tuple(np.round(q, 2))))
    assert not missing, missing
