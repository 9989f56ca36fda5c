"""The [cad] parameters and the fit rules the parts add to the schema: each bad input gets
its exact error (field, value, rule). Numbers below are worked out by hand from the
default file (params/phantom.toml)."""

from __future__ import annotations

import copy
import itertools
import math

import numpy as np
import pytest

from phantom_cad import ParamError
from phantom_cad.params import parse


def _fails(document, edit):
    doc = copy.deepcopy(document)
    edit(doc)
    with pytest.raises(ParamError) as exc:
        parse(doc)
    return exc.value


def test_default_cad_values_in_si(params):
    cad = params.cad
    assert cad.finger_base_length == pytest.approx(0.013)
    assert cad.cheek == pytest.approx(0.0024)
    assert cad.eyelet_length == pytest.approx(0.0012)
    assert cad.horn_hole_radius == pytest.approx(0.004)


def test_cad_table_is_required(document):
    e = _fails(document, lambda d: d.pop("cad"))
    assert (e.field, e.value, e.rule) == ("cad", None, "is required but missing")


def test_unknown_cad_key(document):
    e = _fails(document, lambda d: d["cad"].__setitem__("fillet_mm", 1.0))
    assert e.field == "cad.fillet_mm"


def test_cheek_too_thick_for_the_pinky_tongue(document):
    # ring (the first too narrow): 17 - 2*4 = 9 mm slot; hub 0.2 + 2*0.8 + (0.6 + 0.4) = 2.8 mm,
    # twice (hub + 0.2 + 0.8) = 7.6 mm, and the return groove 1.5 + 0.4 = 1.9 mm: 9.5 mm
    e = _fails(document, lambda d: d["cad"].__setitem__("cheek_mm", 4.0))
    assert e.field == "cad.cheek_mm"
    assert e.value == pytest.approx(4.0)
    assert e.rule == ("leaves a 9.000 mm clevis slot in fingers.ring.width_mm = 17; "
                      "a loop hub, the tongue and its return groove need 9.500 mm")


def test_finger_base_too_short_for_the_magnets(document):
    # index: 3 mm magnet + 0.1 clearance, 0.8 wall, the hub groove 1 mm past the 8 mm boss: 12.9 mm
    e = _fails(document, lambda d: d["cad"].__setitem__("finger_base_length_mm", 12.8))
    assert e.field == "cad.finger_base_length_mm"
    assert e.rule == ("must be >= 12.900 mm (fingers.index: the magnet pockets (magnet thickness + "
                      "clearance), a wall of 0.8 mm and the MCP loop hub's groove (1 mm past the boss, half the "
                      "thickness))")


def test_a_thick_finger_needs_a_longer_base(document):
    """16.5 mm: the groove's rim (9.25 mm from the MCP axis) 0.65 mm from the pockets' floor (9.9 mm)."""
    def thick(d):
        d["fingers"]["middle"]["thickness_mm"] = 16.5
    e = _fails(document, thick)
    assert e.field == "cad.finger_base_length_mm"
    assert e.rule.startswith("must be >= 13.150 mm (fingers.middle:")


def test_finger_bases_too_long_collide(document):
    """By hand: the index column turns by -7.5 deg from its MCP at the origin, the middle by -2.5 deg
    from its MCP 20.5 mm along the -5 deg chord, stepped back along its column by its shorter
    metacarpal (0.373 vs 0.374 of 189 mm). A 30 mm base puts each magnet face 30 mm behind its
    MCP; the nearer face to the other column's centreline sets the room."""
    d = math.radians
    mcp_i = (0.0, 0.0)
    step = (0.373 - 0.374) * 189.0
    mcp_m = (20.5 * math.cos(d(-5)) + step * math.sin(d(-2.5)), -20.5 * math.sin(d(-5)) + step * math.cos(d(-2.5)))

    def face(mcp, phi):
        return (mcp[0] - 30.0 * math.sin(d(phi)), mcp[1] - 30.0 * math.cos(d(phi)))

    def to_line(pt, mcp, phi):
        ux, uy = math.sin(d(phi)), math.cos(d(phi))
        return abs((pt[0] - mcp[0]) * uy - (pt[1] - mcp[1]) * ux)

    room = min(to_line(face(mcp_i, -7.5), mcp_m, -2.5), to_line(face(mcp_m, -2.5), mcp_i, -7.5))
    e = _fails(document, lambda d: d["cad"].__setitem__("finger_base_length_mm", 30.0))
    assert e.field == "cad.finger_base_length_mm"
    assert e.rule == (f"the index and middle bases are {room:.3f} mm apart at their magnet faces "
                      f"(palm.arc_offset_deg = 5), they need 18.200 mm (half widths + hole_clearance)")
    assert f"{room:.3f}" == "17.849"


def test_guide_eyelet_inside_the_boss(document):
    # a 2 mm eyelet and index 17.8 mm thick: 8.9 + 0.2 + 1 = 10.1 mm > d2 = 10 (its 18.33 mm distal
    # still takes two 17.8 + 2 * 0.2 mm joint bosses; a 14 mm base holds its magnets and hub groove)
    def edit(d):
        d["cad"]["eyelet_length_mm"] = 2.0
        d["cad"]["finger_base_length_mm"] = 14.0
        d["fingers"]["index"]["thickness_mm"] = 17.8
    e = _fails(document, edit)
    assert (e.field, e.value) == ("fingers.index.guide.d2_mm", 10.0)
    assert e.rule == ("must be >= 10.100 mm (half the thickness + hole_clearance + half cad.eyelet_length): "
                      "the phalanx guide eyelet must clear the joint boss")


def test_horn_circle_outside_the_pulley(document):
    # the screw's clearance hole (2 + 2 x 0.2 + 0.2 hole compensation = 2.6 mm): 7 - 2.6/2 - 0.6 = 5.1 mm
    e = _fails(document, lambda d: d["cad"].__setitem__("horn_hole_radius_mm", 5.5))
    assert e.field == "cad.horn_hole_radius_mm"
    assert e.rule == "must be <= 5.100 mm so the horn screws stay inside the fingers.index pulley radius 7 mm"


def test_spring_channel_wider_than_the_cheek(document):
    e = _fails(document, lambda d: d["cad"].__setitem__("spring_diameter_mm", 2.0))
    assert e.field == "cad.spring_diameter_mm"
    assert e.rule == "its channel (2.4 mm with clearance) must fit inside a clevis cheek (cheek_mm = 2.4)"


def test_a_wide_servo_widens_the_forearm_row(document):
    """No tendon passes under a neighbouring servo in the one row (``forearm_layout.row_servos``): a
    14 mm wide body validates, though 14/2 + 2 x 0.2 + 0.3 > 7 mm. Two
    neighbours' least pitch is the wider of their two pulley cavities (radius r + 2 x 0.6 + 0.6 +
    0.2: 9.0 mm for a finger's 7 mm pulley, 10.0 mm for the CMC loop's 8 mm) and the body with its
    clearances, plus a palm wall: 20.4 mm between two tendon servos and 21.4 mm beside servo 6 for a
    12.1 or 14 mm body, 22.8 mm for a 20 mm body (about the widest whose servo 6 keeps its flange
    pilots in the module: tests/test_params.py); where the servos, turned toward their targets by
    different angles, would come closer than a wall, the gap widens. Measured by hand: every pair
    of neighbours' body and ear rectangles (grown by the clearance, at the servo's mid-plane) at
    least a wall apart, sampled densely on their outlines."""
    from phantom_cad.cad import preflight
    from phantom_cad.kinematics import forearm_layout as FL, frames as F, servo_geometry as SG
    from phantom_cad.kinematics.topology import SERVOS
    from phantom_cad.params import parse

    def outline(T, lo, hi):
        t = np.linspace(0.0, 1.0, 60)
        pts = [np.c_[lo[0] + (hi[0] - lo[0]) * t, np.full_like(t, y)] for y in (lo[1], hi[1])]
        pts += [np.c_[np.full_like(t, x), lo[1] + (hi[1] - lo[1]) * t] for x in (lo[0], hi[0])]
        P = np.vstack(pts)
        return P @ T[:2, :2].T + T[:2, 3]

    cavity = {True: 8.0 + 3 * 0.6 + 0.2, False: 7.0 + 3 * 0.6 + 0.2}        # servo 6's, a tendon servo's
    for width in (14.0, 20.0):
        doc = copy.deepcopy(document)
        doc["servo"]["body_mm"] = [23.2, width, 25.3]
        if width == 20.0:
            # the wider row turns the pinky's drive further off its socket's axis: its coupler bore
            # would leave 0.75 mm to a magnet pocket (couplers.pocket_walls), 0.84 mm with the
            # pockets 0.1 mm higher
            doc["palm"]["magnet_lift_mm"] = 0.1
        p = parse(doc)
        preflight.check(p)
        ks = sorted(FL.row_servos(p), key=lambda k: FL.row_servos(p)[k][0, 3])
        row = [FL.row_servos(p)[k] for k in ks]
        for (ka, Ta), (kb, Tb) in zip(zip(ks, row), zip(ks[1:], row[1:])):
            loop = {SERVOS[ka].drive == "loop", SERVOS[kb].drive == "loop"}
            pitch = max(cavity[True in loop] + cavity[False], width + 0.4) + 2.4
            assert (Tb[0, 3] - Ta[0, 3]) * 1e3 >= pitch - 1e-9, (width, ka, kb)
        assert SG.forearm_pitch(p) * 1e3 == pytest.approx(max(cavity[True] + cavity[False], width + 0.4) + 2.4)
        c, L, span, off = 0.2, 23.2, doc["servo"]["flange_span_mm"], doc["cad"]["servo_shaft_offset_mm"]
        boxes = [((-width / 2 - c, -off - L / 2 - c), (width / 2 + c, -off + L / 2 + c)),
                 ((-width / 2 - c, -off - span / 2 - c), (width / 2 + c, -off + span / 2 + c))]
        for Ta, Tb in zip(row, row[1:]):
            Ta, Tb = F.to_mm(Ta), F.to_mm(Tb)
            A = np.vstack([outline(Ta, lo, hi) for lo, hi in boxes])
            B = np.vstack([outline(Tb, lo, hi) for lo, hi in boxes])
            d = np.sqrt(((A[:, None, :] - B[None, :, :]) ** 2).sum(-1)).min()
            assert d >= doc["palm"]["wall_mm"] - 1e-6, (width, d)


def _sampled_clearance(a, b, T, r, document, n=4001):
    """By hand, in mm: the least distance from n points along the segment ab (palm frame) to a
    servo at T's body and ears (boxes grown by the hole clearance, from the servo's dimensions as
    the file gives them) and its pulley cavity (radius r + 3 tendon diameters + a hole clearance,
    half a pulley width and a hole clearance each side of the mid-plane); at most the true least
    distance plus half the spacing of the points."""
    sv, cad, c = document["servo"], document["cad"], document["print"]["hole_clearance_mm"]
    L, W, H = sv["body_mm"]
    top = -(cad["servo_pulley_width_mm"] / 2 + c)
    ears = (top - cad["servo_ear_offset_mm"] - cad["servo_ear_thickness_mm"], top - cad["servo_ear_offset_mm"])
    y0 = -cad["servo_shaft_offset_mm"]
    boxes = [((-W / 2, y0 - L / 2, top - H), (W / 2, y0 + L / 2, top)),
             ((-W / 2, y0 - sv["flange_span_mm"] / 2, ears[0]), (W / 2, y0 + sv["flange_span_mm"] / 2, ears[1]))]
    t = np.linspace(0.0, 1.0, n)[:, None]
    q = (a + (b - a) * t - T[:3, 3]) @ T[:3, :3]            # in the servo frame
    d = [np.linalg.norm(np.maximum(np.maximum(np.array(lo) - c - q, q - np.array(hi) - c), 0.0), axis=1)
         for lo, hi in boxes]
    rc = r + 3 * document["hardware"]["tendon_diameter_mm"] + c
    h = cad["servo_pulley_width_mm"] / 2 + c
    d.append(np.hypot(np.maximum(np.hypot(q[:, 0], q[:, 1]) - rc, 0.0), np.maximum(np.abs(q[:, 2]) - h, 0.0)))
    return float(np.min(d)), float(np.linalg.norm(b - a)) / (n - 1) / 2


@pytest.mark.parametrize("example", [None, "small", "slender"])
def test_every_drive_clears_every_other_servo(document, example):
    """Every drive runs from its pulley to the module's front face (``forearm_layout.drive_runs``)
    at least a tendon hole's radius and the thinnest printable wall (0.5 + 0.8 mm by default) from
    every other servo's body, ears and pulley cavity: its channel keeps a wall to their pockets (the
    least is the CMC loop's ulnar strand beside the thumb's servo: 3.57 mm on the default hand, 2.36
    mm on the small one). ``forearm_layout.drive_clearances`` (shrinking brackets on each shape) against
    the distance sampled along the run, from the servo's dimensions in the file."""
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics.topology import SERVOS
    from phantom_cad.params import load_document
    from phantom_cad.params.rules import MIN_WALL
    from phantom_cad.units import MM

    doc = document if example is None else load_document(f"params/examples/{example}.toml")
    p = parse(doc)
    servos = FL.forearm_servos(p)
    got = FL.drive_clearances(p)
    runs = FL.drive_runs(p)
    assert len(runs) == 7 and len(got) == 7 * 5          # the loop's two strands, five drives
    hole = doc["hardware"]["tendon_diameter_mm"] + 2 * doc["print"]["hole_clearance_mm"]
    for k, side, a, b in runs:
        for j, T in servos.items():
            if j == k:
                continue
            r = (doc["thumb"]["cmc_pulley_radius_mm"] if SERVOS[j].drive == "loop" else
                 (doc["thumb"] if SERVOS[j].digit == "thumb" else doc["fingers"][SERVOS[j].digit])
                 ["servo_pulley_radius_mm"])
            sampled, slack = _sampled_clearance(a * 1e3, b * 1e3, F_mm(T), r, doc)
            assert got[(k, side, j)] * 1e3 == pytest.approx(sampled, abs=slack + 1e-6), (k, side, j)
            assert got[(k, side, j)] * 1e3 >= hole / 2 + MIN_WALL / MM - 1e-9, (k, side, j)


def _envelope_by_hand(document, r, n=720):
    """In mm, servo frame: a servo's body and ears (boxes grown by the hole clearance) and its pulley
    cavity's rims (radius r + 3 tendon diameters + a hole clearance, half a pulley width and a hole
    clearance either side of the mid-plane), from the file's numbers."""
    sv, cad, c = document["servo"], document["cad"], document["print"]["hole_clearance_mm"]
    L, W, H = sv["body_mm"]
    top = -(cad["servo_pulley_width_mm"] / 2 + c)
    e1 = top - cad["servo_ear_offset_mm"]
    y0 = -cad["servo_shaft_offset_mm"]
    s = sv["flange_span_mm"]
    pts = [(x, y, z) for x in (-W / 2 - c, W / 2 + c) for y in (y0 - L / 2 - c, y0 + L / 2 + c)
           for z in (top - H - c, top + c)]
    pts += [(x, y, z) for x in (-W / 2 - c, W / 2 + c) for y in (y0 - s / 2 - c, y0 + s / 2 + c)
            for z in (e1 - cad["servo_ear_thickness_mm"] - c, e1 + c)]
    rc = r + 3 * document["hardware"]["tendon_diameter_mm"] + c
    a = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    h = cad["servo_pulley_width_mm"] / 2 + c
    rims = [np.c_[rc * np.cos(a), rc * np.sin(a), np.full_like(a, z)] for z in (-h, h)]
    return np.vstack([np.array(pts)] + rims)


def _servo_radius(document, k):
    from phantom_cad.kinematics.topology import SERVOS

    if SERVOS[k].drive == "loop":
        return document["thumb"]["cmc_pulley_radius_mm"]
    digit = SERVOS[k].digit
    return (document["thumb"] if digit == "thumb" else document["fingers"][digit])["servo_pulley_radius_mm"]


def test_the_staggered_rows_fit_a_human_forearm(document):
    """``forearm_stagger.staggered_servos``: two rows of three within a forearm's breadth at the
    reference hand (at most 80 mm with a palm wall each side, measured on the envelopes built here
    from the file's servo: 76.9 mm); servo 6, the middle and the pinky servos in front, the thumb,
    index and ring servos behind, a palm wall behind them; each drive straight through its target
    (servo 6's strands tangent to the CMC pulley: its radius from its centre); servo 6 in the CMC
    pulley's plane with its shaft along the CMC axis; the servos of each row a palm wall apart in
    plan (their envelopes sampled densely); the front row a palm wall behind the module's front."""
    from phantom_cad.kinematics import forearm_stagger as FS, frames as F, servo_geometry as SG, thenar
    from phantom_cad.kinematics.topology import CHAINS, SERVOS

    p = parse(document)
    S = {k: F_mm(T) for k, T in FS.staggered_servos(p).items()}
    servo = {c.digit: c.servo for c in CHAINS}
    front, rear = FS.staggered_rows(p)
    assert set(front) == {5, servo["middle"], servo["pinky"]}
    assert set(rear) == {servo["thumb"], servo["index"], servo["ring"]}
    env = {k: _envelope_by_hand(document, _servo_radius(document, k)) @ T[:3, :3].T + T[:3, 3] for k, T in S.items()}
    xs = np.concatenate([e[:, 0] for e in env.values()])
    wall = document["palm"]["wall_mm"]
    width = xs.max() - xs.min() + 2 * wall
    assert width <= 80.0 * document["hand"]["hand_length_mm"] / 189.0
    assert width == pytest.approx(76.9, abs=0.05)
    assert SG.forearm_width_limit(p) * 1e3 == pytest.approx(80.0)
    front_face = SG.forearm_front(p) * 1e3
    assert max(env[k][:, 1].max() for k in front) <= front_face - wall + 1e-6
    assert max(env[k][:, 1].max() for k in rear) <= min(env[k][:, 1].min() for k in front) - wall + 1e-6
    for row in (front, rear):
        for a, b in zip(row, row[1:]):
            d = np.sqrt(((env[a][:, None, :2] - env[b][None, :, :2]) ** 2).sum(-1)).min()
            assert d >= wall - 0.02, (a, b, d)          # sampled rims: within 0.02 mm of the circle
    for k, T in S.items():
        r = _servo_radius(document, k)
        E = SG.servo_target(p, k) * 1e3
        for side in ((-1.0, 1.0) if SERVOS[k].drive == "loop" else (-1.0,)):
            t0 = T[:3, 3] + side * r * T[:3, 0]
            off = np.linalg.norm(np.cross(E - t0, T[:3, 1]))
            assert off == pytest.approx(r if SERVOS[k].drive == "loop" else 0.0, abs=1e-6), (k, side)
    Tc = F.T_palm_thumb_cmc_base(p) @ thenar.T_cmc_base_pulley(p)
    assert S[5][:3, 2] == pytest.approx(Tc[:3, 2], abs=1e-12)
    assert (S[5][:3, 3] / 1e3 - Tc[:3, 3]) @ Tc[:3, 2] == pytest.approx(0.0, abs=1e-12)


def test_two_rows_where_they_fit_a_human_forearm(document):
    """``forearm_stagger.two_rows``: the two staggered rows where their width (76.9 mm, the servo
    does not scale) is within 80 mm x hand length / 189 mm: at 182 mm (limit 77.04 mm), not at
    181 mm (76.61 mm)."""
    from phantom_cad.kinematics import forearm_stagger as FS, servo_geometry as SG

    for length, fits in ((182.0, True), (181.0, False)):
        doc = copy.deepcopy(document)
        doc["hand"]["hand_length_mm"] = length
        p = parse(doc)
        assert SG.forearm_width_limit(p) * 1e3 == pytest.approx(80.0 * length / 189.0)
        assert FS.two_rows(p) is fits, length


def test_the_staggered_rows_drives_clear_every_servo_and_each_other(document):
    """In ``forearm_stagger.staggered_servos`` every drive, from its pulley to its target, runs at
    least half a tendon hole and a palm wall (0.5 + 2.4 mm) from every other servo's body, ears and
    pulley cavity within the module (the rear row stands raised so that its drives pass over the
    front row), and at least a tendon hole and a palm wall from every other drive (no two cross),
    sampled along the runs."""
    from phantom_cad.kinematics import forearm_stagger as FS, servo_geometry as SG
    from phantom_cad.kinematics.topology import SERVOS

    p = parse(document)
    S = FS.staggered_servos(p)
    hole = document["hardware"]["tendon_diameter_mm"] + 2 * document["print"]["hole_clearance_mm"]
    wall = document["palm"]["wall_mm"]
    runs = SG.drive_runs_of(p, S)
    for k, side, a, b in runs:
        for j, T in S.items():
            if j != k:
                d, slack = _sampled_clearance(a * 1e3, b * 1e3, F_mm(T), _servo_radius(document, j), document)
                assert d >= hole / 2 + wall - slack - 1e-6, (k, side, j, d)
    full = []
    for k, side, a, _ in runs:
        u = S[k][:3, 1]
        E = SG.servo_target(p, k)
        full.append((k, a * 1e3, (a + u * ((E - a) @ u)) * 1e3))
    t = np.linspace(0.0, 1.0, 800)[:, None]
    for (k, a, b), (j, c, d) in itertools.combinations(full, 2):
        if k != j:
            A, B = a + (b - a) * t, c + (d - c) * t
            gap = np.sqrt(((A[:, None] - B[None]) ** 2).sum(-1)).min()
            assert gap >= hole + wall, (k, j, gap)
    assert all(SERVOS[k].drive == "loop" or S[k][2, 3] * 1e3 >= -4.6 - 1e-9 for k in S)


def F_mm(T):
    """A transform (m) in mm."""
    out = np.array(T, float)
    out[:3, 3] *= 1e3
    return out


def test_convex_hull_2d_is_qhulls():
    """``servo_geometry.convex_hull_2d`` (the servo row's outlines) against scipy's Qhull: the same vertices in
    the same counter-clockwise cycle, on random clouds, the servo pulley's 24-gon with its swept copy,
    a square with points on its edges and corners repeated; no area is an error."""
    from scipy.spatial import ConvexHull

    from phantom_cad.kinematics import servo_geometry as SG

    def cycle(P, idx):                # the hull's points as a cycle from its lowest (x, y): a point
        pts = [tuple(P[int(i)]) for i in idx]       # repeated may be either index
        k = pts.index(min(pts))
        return pts[k:] + pts[:k]

    rng = np.random.default_rng(7)
    a = np.linspace(0.0, 2.0 * math.pi, 24, endpoint=False)
    gon = np.c_[np.cos(a), np.sin(a)] * 9.0
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5], [0, 0], [1, 1],
                       [0.5, 0.5]], float)
    clouds = [rng.normal(size=(n, 2)) * rng.uniform(1e-3, 10.0) for n in (3, 4, 10, 50, 400)]
    clouds += [np.vstack([gon, gon + [3.0, -1.5]]), square]
    for P in clouds:
        assert cycle(P, SG.convex_hull_2d(P)) == cycle(P, ConvexHull(P).vertices), P[:4]
    with pytest.raises(ValueError, match="no area"):
        SG.convex_hull_2d(np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]))


def test_shaft_offset_beyond_the_body(document):
    e = _fails(document, lambda d: d["cad"].__setitem__("servo_shaft_offset_mm", 11.6))
    assert e.field == "cad.servo_shaft_offset_mm"
    assert e.rule == "must be < half the servo body length (11.6 mm)"


def test_nonpositive_cad_value(document):
    e = _fails(document, lambda d: d["cad"].__setitem__("eyelet_length_mm", 0.0))
    assert (e.field, e.value, e.rule) == ("cad.eyelet_length_mm", 0.0, "must be > 0")


def test_base_guide_behind_the_magnet_face(document):
    # 14 sin(50 deg) + 1.2/2 + (sqrt(3) + 2) * (0.6/2 + 0.2) = 13.191 mm > 13 mm
    reach = 14 * math.sin(math.radians(50)) + 0.6 + (math.sqrt(3) + 2) * 0.5
    e = _fails(document, lambda d: d["fingers"]["middle"]["guide"].__setitem__("d1_mm", 14.0))
    assert (e.field, e.value) == ("fingers.middle.guide.d1_mm", 14.0)
    assert e.rule == (f"puts the guide eyelet {reach:.3f} mm behind the MCP axis, beyond the finger base's "
                      "magnet face (cad.finger_base_length_mm = 13)")
    assert f"{reach:.3f}" == "13.191"


def test_module_stop_margin_range(document):
    e = _fails(document, lambda d: d["cad"].__setitem__("module_stop_margin_deg", 12.0))
    assert (e.field, e.value, e.rule) == ("cad.module_stop_margin_deg", 12.0, "must be <= 10")


def test_servo_ears_off_the_body(document):
    e = _fails(document, lambda d: d["cad"].__setitem__("servo_ear_offset_mm", 23.0))
    assert e.field == "cad.servo_ear_offset_mm"
    assert e.rule == ("with servo_ear_thickness_mm = 2.5 the ears must lie on the servo body "
                      "(height servo.body_mm[2] = 25.3)")


# the palm's layout (phantom_cad.cad.preflight), run by `params validate` and every build
def test_long_flange_ears_move_the_forearm_row_back(document):
    """The tendon servos sit in the forearm module: longer flange ears cannot reach the sockets'
    magnet pockets (they did when the servos sat in the palm), they move the row back. The row's
    front is where the servos' envelopes (ears grown by a clearance, ahead of the shaft by
    flange_span / 2 - shaft_offset) end, one palm wall behind the module's front face: by hand,
    4 mm more span moves the row 2 mm further back from that face."""
    from phantom_cad.kinematics import forearm_layout as FL, servo_geometry as SG
    from phantom_cad.params import parse

    doc = copy.deepcopy(document)
    p0 = parse(doc)
    doc["servo"]["flange_span_mm"] = document["servo"]["flange_span_mm"] + 4.0
    p1 = parse(doc)
    y0 = {k: T[1, 3] * 1e3 for k, T in FL.row_servos(p0).items()}
    y1 = {k: T[1, 3] * 1e3 for k, T in FL.row_servos(p1).items()}
    ahead = document["servo"]["flange_span_mm"] / 2 - document["cad"]["servo_shaft_offset_mm"]
    cavity = 8.0 + 2 * 0.6 + 0.6 + 0.2                # the largest pulley (the CMC loop's): r + lip + cord + clearance
    assert ahead > cavity                              # the ears set the row's front today
    # the module's front face stands behind the palm (no servo at the CMC any more): it stays; the
    # row moves back by what the ears grew ahead along the servo that reaches furthest forward: at
    # most 2 mm (less along a turned or tilted servo's y), the same for every servo
    assert SG.forearm_front(p1) == SG.forearm_front(p0)
    dy = [y1[k] - y0[k] for k in y0]
    assert -2.0 - 1e-9 <= dy[0] < -1.0 and all(v == pytest.approx(dy[0], abs=1e-9) for v in dy)


def test_a_heel_past_the_metacarpal_block_is_refused(variant):
    """The heel lies under the metacarpal block, from the palm's back face: one reaching further than
    the block is long (the palm solid's flat palmar stretch ends at the block's front, behind the
    finger sockets' limiters) is refused, naming the field; the file's 40 mm builds (test_human_scale)."""
    from phantom_cad.cad import preflight

    p = variant(lambda d: d["palm"].__setitem__("heel_length_mm", 100.0))
    with pytest.raises(ParamError) as exc:
        preflight.check(p)
    assert exc.value.field == "palm.heel_length_mm" and exc.value.value == 100.0
    assert "the heel lies under the metacarpal block" in exc.value.rule
    preflight.check(variant(lambda d: d["palm"].__setitem__("heel_length_mm", 40.0)))


def test_a_cmc_axis_tilted_past_60_deg_is_refused(variant):
    """The palm holds the CMC on a column along its axis, which climbs into the palm: rolled 70
    deg about x, the axis is 70 deg from the palm's normal."""
    from phantom_cad.cad import preflight

    p = variant(lambda d: d["palm"].__setitem__("thumb_cmc_axis_deg", [70.0, 0.0, 0.0]))
    with pytest.raises(ParamError) as exc:
        preflight.check(p)
    assert exc.value.field == "palm.thumb_cmc_axis_deg" and exc.value.value == [70.0, 0.0, 0.0]
    assert "tilts the CMC axis 70.0 deg from the palm's normal" in exc.value.rule


def test_a_cmc_base_into_the_palm_is_refused(variant):
    """The CMC axis along the palm's normal, the CMC centre 19 mm below the MCP plane: the CMC base's
    top (half the thumb's 15 mm thickness above its centre) at -11.5 mm, 0.7 mm too close to the
    palm's palmar face (-12 mm) less a clearance (0.2 mm)."""
    from phantom_cad.cad import preflight

    def change(d):
        d["palm"]["thumb_cmc_axis_deg"] = [0.0, 0.0, 0.0]
        d["palm"]["thumb_cmc_offset_mm"] = [-25.0, -70.0, -19.0]

    with pytest.raises(ParamError) as exc:
        preflight.check(variant(change))
    assert exc.value.field == "palm.thumb_cmc_offset_mm" and exc.value.value == [-25.0, -70.0, -19.0]
    assert "comes 0.700 mm too close to the palm's palmar face" in exc.value.rule


def test_a_thin_palm_under_a_tilted_cmc_is_refused(variant):
    """The CMC axis rolled 45 deg, the palm 18 mm thick: by hand (thenar.thenar) the CMC pulley's
    cavity (radius 8 + 1.2 + 0.6 + 0.2 = 10 mm, half height 3 + 0.2 mm, tilted 45 deg) has its lowest
    rim a wall (2.4 mm) above the palmar face: its centre at -9 + 2.4 + 10 sin 45 + 3.2 cos 45; the
    drive turns 3.2 + 2.4 + 1.0 mm further up the axis, at -9 + 2.4 + 13.2 sin 45 + 6.6 cos 45 +
    ... ; it needs a relief (1.0 mm) and a wall (2.4 mm) under the dorsal face (+9 mm)."""
    from phantom_cad.cad import preflight

    s45 = math.sqrt(0.5)
    z_pulley = -9.0 + 2.4 + 10.0 * s45 + 3.2 * s45
    z_turn = z_pulley + (3.2 + 2.4 + 1.0) * s45
    short = z_turn + 1.0 + 2.4 - 9.0

    def change(d):
        d["palm"]["thickness_mm"] = 18.0
        d["palm"]["thumb_cmc_axis_deg"] = [45.0, 0.0, 0.0]
        d["palm"]["thumb_cmc_offset_mm"] = [-25.0, -70.0, -30.0]

    with pytest.raises(ParamError) as exc:
        preflight.check(variant(change))
    assert exc.value.field == "palm.thickness_mm" and exc.value.value == 18.0
    assert short > 0.0 and f"{short:.3f} mm short of a relief and a wall under the dorsal face" in exc.value.rule


def test_a_loop_without_a_clamp_position_is_a_param_error(tmp_path, document):
    """The index pulleys 1.25 times larger (MCP 6.25, PIP 5, DIP 6.25 mm: the largest whose return
    cord's channel keeps its wall under the 16 mm finger's dorsal face) and the DIP flexing to
    2.09 rad: the PIP-DIP loop's strands leave the middle phalanx's groove at
    gamma = acos((R_PIP + R_DIP) / L_middle) from its axis, and a clamp on the DIP groove keeps both
    wraps inside (8, 172 deg) only while the DIP travel (limit + 3 deg) stays under 2 gamma - 16 deg.
    By hand: L_middle = 0.143 x 189 = 27.027 mm, gamma = acos(11.25 / 27.027) = 65.40 deg, so
    114.80 deg < 119.75 + 3 deg. Validation refuses the file rather than the build stopping on a
    ValueError."""
    import subprocess
    import sys

    import tomli_w

    doc = copy.deepcopy(document)
    f = doc["fingers"]["index"]
    f["pulley_radius_mm"] = {k: 1.25 * v for k, v in f["pulley_radius_mm"].items()}
    f["limits_rad"]["dip"] = [0.0, 2.09]
    L = f["length_fraction"]["middle"] * doc["hand"]["hand_length_mm"]
    gamma = math.degrees(math.acos((f["pulley_radius_mm"]["pip"] + f["pulley_radius_mm"]["dip"]) / L))
    allowed = 2 * gamma - 16.0
    assert math.degrees(2.09) + 3.0 > allowed
    path = tmp_path / "big_pulleys.toml"
    path.write_text(tomli_w.dumps(doc))
    r = subprocess.run([sys.executable, "-m", "phantom_cad", "params", "validate", str(path)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    line = r.stderr.strip()
    assert "\n" not in line and str(path) in line         # one line naming the file
    assert "fingers.index.limits_rad.dip = [0.0, 2.09]" in line
    assert f"{allowed:.2f} deg" in line and "no clamp position" in line


@pytest.mark.parametrize("width, ok", [(10.0, True), (18.0, False)])
def test_bearing_width_rule(variant, width, ok):
    """One bearing per joint, seated where it fits beside the tendon grooves: a 10 mm wide bearing
    (twice it is wider than the 18 mm index, which the two-bearings rule refused) validates, and no
    tongue of the default hand has room for it (a 10 mm seat leaves 8 mm of an 18 mm finger for
    its clevis cheeks (2 x 2.4 mm), the loop hub and the grooves), so the BOM lists no bearing;
    as wide as the finger is refused."""
    from phantom_cad.cad import materials

    edit = lambda d: d["hardware"]["bearing"].__setitem__("width_mm", width)  # noqa: E731
    if not ok:
        with pytest.raises(ParamError) as exc:
            variant(edit)
        assert exc.value.field == "hardware.bearing.width_mm" and "fingers.index.width_mm = 18" in exc.value.rule
        return
    rows = [r for r in materials.bill_of_materials(variant(edit)) if r["item"] == "bearing"]
    assert rows == []
