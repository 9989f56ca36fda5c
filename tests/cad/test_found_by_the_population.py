"""Files ``phantom-cad size`` wrote for the population study (bench/population.py) that validated and
did not build, kept as regression tests: each builds."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from phantom_cad.cad.registry import part
from phantom_cad.cad.verify import solid_problems
from phantom_cad.params import load_params

pytest.importorskip("build123d")


def _sized(tmp_path, length: str, breadth: str):
    """The parameters ``phantom-cad size --hand-length length --hand-breadth breadth`` writes."""
    out = tmp_path / "sized.toml"
    run = subprocess.run([sys.executable, "-m", "phantom_cad", "size", "--hand-length", length,
                          "--hand-breadth", breadth, "--out", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return load_params(out)


@pytest.mark.slow
def test_a_213_x_85_mm_palm_builds(tmp_path):
    """The palm of ``size --hand-length 213 --hand-breadth 85``: the thumb drive turns at a 1 mm
    sphere onto the CMC axis, and with the sphere's pole and seam where OpenCascade put them the cut
    left no solid at all."""
    pt = part(_sized(tmp_path, "213", "85"), "palm")
    shape = pt.build()
    assert not solid_problems("palm", shape)
    assert pt.verify(shape) == []


@pytest.mark.parametrize("into, out", [((0.1, 0.99, 0.0), (-0.5, -0.05, -0.87)), ((0, 0, 1), (1, 0, 0)),
                                       ((0, 0, -1), (0, 0, -1)), ((1, 0, 0), (-1, 0.001, 0))])
def test_a_turn_spheres_poles_and_seam_lie_off_its_channels(into, out):
    """Both openings of the turn lie on the sphere's equator, and its seam (the edge between the
    poles) opposite them: every point of the seam and both poles at least 90 degrees from each."""
    from phantom_cad.cad.parts.common import turn_sphere

    c = np.array([3.0, -2.0, 1.0])
    s = turn_sphere(c, 1.0, into, out)
    openings = [-np.asarray(into, float) / np.linalg.norm(into), np.asarray(out, float) / np.linalg.norm(out)]
    seam = s.edges()                    # a sphere's one edge: the half circle from pole to pole
    assert len(seam) == 1
    pts = [np.array(tuple(v)) - c for v in s.vertices()]
    pts += [np.array(tuple(e.position_at(t))) - c for e in seam for t in np.linspace(0, 1, 21)]
    for p in pts:
        p = p / np.linalg.norm(p)
        for o in openings:
            assert p @ o <= 1e-6, (p, o)
    assert s.volume == pytest.approx(4.0 / 3.0 * np.pi, rel=1e-6)


@pytest.mark.slow
def test_a_205_9_x_85_mm_thumb_proximal_phalanx_leaves_no_skin(tmp_path):
    """The thumb's proximal phalanx of ``size --hand-length 205.9 --hand-breadth 85``: its eyelet's
    near relief sphere (1 mm) bottomed 0.42 mm above the 16.5 mm phalanx's palmar face, past the end
    of the drive's fan, and left a 0.51 mm skin there (the population's walls row). The well under
    it opens it: nothing of the part stands between the sphere and the face, and every wall
    measured on its mesh is two perimeters (``export.walls``)."""
    from phantom_cad import units
    from phantom_cad.cad.parts.phalanx import eyelet
    from phantom_cad.cad.parts.tendons import link_tendons
    from phantom_cad.export import step_stl
    from phantom_cad.export.walls import thin_walls, wall_bar_mm

    p = _sized(tmp_path, "205.9", "85")
    pt = part(p, "thumb_proximal")
    sec = pt.sec
    _, _, _, (s_near, _) = eyelet(sec, sec.guide_points()[1],
                                  link_tendons(p, pt.link.name).eyelet_toward(sec.guide_points()[1]), clip_palmar=True)
    low, face = s_near[2] - sec.tol.tendon_relief / 2.0, -sec.thickness / 2.0
    assert 0.0 < low - face < 0.8                      # the case: a skin under the sphere
    shape = pt.build()
    assert not solid_problems("thumb_proximal", shape)
    for dy in (-0.5, 0.0, 0.5):
        assert not shape.is_inside((0.0, float(s_near[1]) + dy, (low + face) / 2.0))
    v, f = step_stl.tessellate(shape, units.mm(p.print.stl_tolerance))
    walls = thin_walls(np.asarray(v), np.asarray(f), wall_bar_mm(p))
    assert walls["wall_thinnest"] >= wall_bar_mm(p), walls


@pytest.mark.slow
def test_a_170_4_x_68_4_mm_forearm_leaves_no_roof_over_servo_6s_strand(tmp_path):
    """The forearm module of ``size --hand-length 170.4 --hand-breadth 68.4``: servo 6's strand
    toward the palm, from its tilted pulley, enters the block through the top at about 20 deg, and
    beside the pocket its channel's roof tapered to 0.06 mm (the population's walls row). The slot
    over it opens the channel to the top there: nothing of the part stands over the channel where
    its roof was under a wall, and every wall measured on its mesh is two perimeters."""
    from phantom_cad import units
    from phantom_cad.cad.parts import wrist
    from phantom_cad.cad.parts.forearm import FOREARM_SERVOS
    from phantom_cad.export import step_stl
    from phantom_cad.export.walls import thin_walls, wall_bar_mm

    p = _sized(tmp_path, "170.4", "68.4")
    fa = part(p, "forearm")
    x0, x1, y0, y1, z0, z1 = fa.extents()
    servo6 = FOREARM_SERVOS[-1]
    p0, u = fa.drive_line(servo6, -1.0)
    r = fa.tol.tendon_hole / 2.0
    s = np.linspace(0.0, y1 - y0 + 2.0 * wrist.TAB_LENGTH, 2001)
    axis = p0 + s[:, None] * u
    gap = np.min([fa.pocket_gap(k, axis)[0] for k in FOREARM_SERVOS], axis=0)
    roof = z1 - axis[:, 2] - r
    under = (axis[:, 0] > x0) & (axis[:, 0] < x1) & (axis[:, 1] > y0) & (axis[:, 1] < y1) & (gap > r) \
        & (roof > 0.0) & (roof < 0.8)
    assert under.any()                            # the case: a roof under two perimeters
    shape = fa.build()
    T = np.linalg.inv(fa.T_palm_part())           # the part is placed in its own (the forearm's) frame
    for a, h in zip(axis[under], roof[under]):
        q = T @ np.array([a[0], a[1], a[2] + r + h / 2.0, 1.0])
        assert not shape.is_inside(tuple(float(v) for v in q[:3]))
    v, f = step_stl.tessellate(shape, units.mm(p.print.stl_tolerance))
    walls = thin_walls(np.asarray(v), np.asarray(f), wall_bar_mm(p))
    assert walls["wall_thinnest"] >= wall_bar_mm(p), walls


def _thin_walls(p, shape) -> dict:
    from phantom_cad import units
    from phantom_cad.export import step_stl
    from phantom_cad.export.walls import thin_walls, wall_bar_mm

    v, f = step_stl.tessellate(shape, units.mm(p.print.stl_tolerance))
    return thin_walls(np.asarray(v), np.asarray(f), wall_bar_mm(p))


#: digits-07-man of bench/population.py: per-digit lengths (mm), as ``size --segments`` reads them
_DIGITS_07 = {"thumb": {"metacarpal": 48.0, "proximal": 36.9, "distal": 32.1},
              "index": {"proximal": 43.2, "middle": 28.2, "distal": 18.8},
              "middle": {"proximal": 46.8, "middle": 33.5, "distal": 19.0},
              "ring": {"proximal": 48.3, "middle": 31.4, "distal": 21.7},
              "pinky": {"proximal": 36.1, "middle": 23.5, "distal": 16.5}}


def _strand_into_the_top(fa):
    """Where servo 6's strand toward the palm, from its tilted pulley, runs under the module's top
    less than two perimeters, beside its own pulley's cavity: (points on the axis, their roofs)."""
    from phantom_cad.cad.parts import wrist
    from phantom_cad.cad.parts.forearm import FOREARM_SERVOS

    x0, x1, y0, y1, z0, z1 = fa.extents()
    p0, u = fa.drive_line(FOREARM_SERVOS[-1], -1.0)
    r = fa.tol.tendon_hole / 2.0
    s = np.linspace(0.0, y1 - y0 + 2.0 * wrist.TAB_LENGTH, 4001)
    axis = p0 + s[:, None] * u
    roof = z1 - axis[:, 2] - r
    gap = fa.pocket_gap(FOREARM_SERVOS[-1], axis)[0]
    inside = (axis[:, 0] > x0) & (axis[:, 0] < x1) & (axis[:, 1] > y0) & (axis[:, 1] < y1)
    return inside & (roof > -2.0 * r) & (roof < 0.8) & (gap < r + 0.8), axis, roof


@pytest.mark.slow
def test_a_170_4_x_81_6_mm_forearm_is_one_solid(tmp_path):
    """The forearm module of ``size --hand-length 170.4 --hand-breadth 81.6``: servo 6's strand
    enters the block through its top where it leaves its pulley's cavity, and the slot over it
    ended where the channel met the cavity: a crumb of 0.001 mm^3 stood loose between the two
    (the module had 2 solids). The slot runs on into the cavity: one solid, walls two perimeters."""
    p = _sized(tmp_path, "170.4", "81.6")
    fa = part(p, "forearm")
    near, _, _ = _strand_into_the_top(fa)
    assert near.any()                               # the case: the strand enters the top by its cavity
    shape = fa.build()
    assert not solid_problems("forearm", shape)
    walls = _thin_walls(p, shape)
    assert walls["wall_thinnest"] >= _bar(p), walls


def _bar(p) -> float:
    from phantom_cad.export.walls import wall_bar_mm

    return wall_bar_mm(p)


@pytest.mark.slow
def test_digits_07s_forearm_leaves_no_sliver_beside_servo_6s_cavity(monkeypatch):
    """digits-07-man of the population (190.2 x 85 mm, per-digit lengths given) at the CMC placement
    the search found then, in one row of servos as it was built then (its hand is now built from
    two): where servo 6's strand enters the module's top as it leaves its pulley's cavity, the slot
    over it ended at the cavity and left a wedge 0.32 mm thick between them (the population's walls
    row). Every wall of the module is two perimeters."""
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics import memo
    from phantom_cad.params import parse
    from phantom_cad.sizing import Person, build_document

    monkeypatch.setattr(FL, "forearm_rows", lambda params: 1)
    memo.clear()        # what its digest memoised with two rows

    doc = build_document(Person(190.2, 85.0, "right", "digits-07-man", _DIGITS_07))
    doc["palm"].update(heel_length_mm=46.3, thumb_cmc_offset_mm=[-30.5286, -74.6346, -28.1564],
                       thumb_cmc_axis_deg=[-32.2672, 13.4271, -73.7064])
    p = parse(doc)
    fa = part(p, "forearm")
    near, _, _ = _strand_into_the_top(fa)
    assert near.any()
    shape = fa.build()
    memo.clear()
    assert not solid_problems("forearm", shape)
    walls = _thin_walls(p, shape)
    assert walls["wall_thinnest"] >= _bar(p), walls


@pytest.mark.slow
def test_a_170_4_x_85_mm_palm_keeps_two_perimeters_round_the_tab_screw(tmp_path):
    """The palm of ``size --hand-length 170.4 --hand-breadth 85``: the forearm tab's radial screw,
    half a tab length in from the tab's end, drilled its pilot (three diameters deep into a 21.5 mm
    palm) 0.40 mm beside the thumb drive's channel (the population's walls row). The screw moves in
    along the tab off the channel; both parts drill it there, and every wall measured on the palm's
    mesh is two perimeters. (The placement is pinned to the one the search gave it then; the
    reference's, scaled, which ``size`` now keeps where it opposes, leaves the screw in place.)"""
    from phantom_cad.cad.parts import wrist
    from phantom_cad.export.walls import wall_bar_mm
    from phantom_cad.params import parse
    from phantom_cad.sizing import Person, build_document

    doc = build_document(Person(170.4, 85.0))
    doc["palm"].update(heel_length_mm=36.7, magnet_lift_mm=0.7, thumb_cmc_offset_mm=[-21.7723, -62.5895, -28.7133],
                       thumb_cmc_axis_deg=[-29.0935, 12.2702, -71.5575])
    p = parse(doc)
    pa = part(p, "palm")
    (place, inward), _ = wrist.tab_screw_places(p)
    radial = pa.tab_screws()[0]
    assert inward * (radial[0] - place[0]) > 0.0                   # the case: moved in off its place
    assert np.allclose(part(p, "forearm").tab_screws(), pa.tab_screws(), atol=0.0)
    walls = _thin_walls(p, pa.build())
    assert walls["wall_thinnest"] >= wall_bar_mm(p), walls


def _forearm_of(length: float, breadth: float):
    """The forearm module of the document ``size --hand-length LENGTH --hand-breadth BREADTH``
    writes (the reference's CMC placement scaled, which opposes on these hands)."""
    from phantom_cad.params import parse
    from phantom_cad.sizing import Person, build_document

    return part(parse(build_document(Person(length, breadth))), "forearm")


@pytest.mark.slow
def test_a_184_6_x_68_4_mm_forearm_leaves_no_sliver_by_a_drive_slot():
    """The forearm module of ``size --hand-length 184.6 --hand-breadth 68.4`` (two rows of servos):
    a finger drive runs beside its own servo's pocket under a flank and is joined to it by a slot
    (``ServoMount.drive_slot``). With the slot's faces tangent to the channel's cylinder, the cut
    left a loose sliver 0.05 x 5.1 x 0.3 mm between them (the module had 2 solids)."""
    from phantom_cad.cad.parts.forearm import FOREARM_SERVOS

    fa = _forearm_of(184.6, 68.4)
    assert any(fa.drive_slot(k, fa.tol.tendon_hole, side=s) is not None
               for k in FOREARM_SERVOS for s in fa.strand_sides(k))          # the case
    shape = fa.build()
    assert not solid_problems("forearm", shape)
    assert fa.verify(shape) == []


@pytest.mark.slow
def test_a_191_7_x_68_4_mm_forearm_is_a_valid_solid():
    """The forearm module of ``size --hand-length 191.7 --hand-breadth 68.4`` (two rows): a drive's
    channel runs into a neighbouring servo's pocket by a slot (``Forearm.pocket_slots``); with the
    slot's faces tangent to the channel's cylinder the cut left a channel face OpenCascade finds
    invalid (the module did not build)."""
    from phantom_cad.cad.parts.forearm import FOREARM_SERVOS

    fa = _forearm_of(191.7, 68.4)
    reach = 400.0
    assert any(fa.pocket_slots(k, s, reach) for k in FOREARM_SERVOS for s in fa.strand_sides(k))   # the case
    shape = fa.build()
    assert not solid_problems("forearm", shape)
    assert fa.verify(shape) == []



def _palm_of(length: float, breadth: float, **placement):
    """The palm of the document ``size --hand-length LENGTH --hand-breadth BREADTH`` writes, at the
    CMC placement given (``palm`` keys) where the search found one then."""
    from phantom_cad.params import parse
    from phantom_cad.sizing import Person, build_document

    doc = build_document(Person(length, breadth))
    doc["palm"].update(placement)
    p = parse(doc)
    return p, part(p, "palm")


#: L205_9-m05-B76_8 of the population: the CMC placement its search found (the reference's, scaled,
#: did not oppose)
_L205_9_M05 = dict(heel_length_mm=47.6, thumb_cmc_offset_mm=[-37.5481, -80.4638, -25.342],
                   thumb_cmc_axis_deg=[-25.0397, 5.6132, -84.1392])


@pytest.mark.parametrize("size", [None, (205.9, 76.8), (160.0, 72.0)])
def test_the_open_space_beside_the_palm_is_outside_every_piece_of_it(size):
    """Every point of :meth:`Palm.outside_regions` (their open sides cut 40 mm out) lies outside
    every convex piece the palm is fused from (the default hand and two sized ones)."""
    from phantom_cad.cad.kernel import import_build123d

    b = import_build123d()
    pa = part(load_params("params/phantom.toml"), "palm") if size is None else _palm_of(*size, **(
        _L205_9_M05 if size == (205.9, 76.8) else {}))[1]
    body, _ = pa.solids()
    rng = np.random.default_rng(0)
    for T, lo, hi in pa.outside_regions():
        lo_, hi_ = np.maximum(lo, -40.0 + np.minimum(hi, 0.0)), np.minimum(hi, 40.0 + np.maximum(lo, 0.0))
        local = lo_ + rng.random((40, 3)) * (hi_ - lo_)
        for q in local @ T[:3, :3].T + T[:3, 3]:
            for piece in body:
                assert not piece.is_inside(b.Vector(*q), tolerance=1e-6), (lo, hi, q)


def test_a_gap_filler_stays_behind_the_knuckles():
    """On the 205.9 x 76.8 mm hand (L205_9-m05-B76_8's placement) the gap between the index and middle socket blocks is filled:
    every point of both socket faces (sampled across each, 0.1 mm apart) lies at least a clearance
    ahead of the filler's front, and the filler reaches into the slab; the default hand has none."""
    assert part(load_params("params/phantom.toml"), "palm").gap_fillers() == []
    _, pa = _palm_of(205.9, 76.8, **_L205_9_M05)
    fillers = pa.gap_fillers()
    assert len(fillers) == 1
    lo, hi = fillers[0]
    assert lo[1] < pa.extents()[3]
    for f in ("index", "middle"):
        T, (blo, bhi) = pa.T_socket(f), pa.socket_box(f)
        xs = np.arange(blo[0], bhi[0], 0.1)
        face = np.column_stack([xs, np.zeros_like(xs), np.zeros_like(xs), np.ones_like(xs)]) @ T.T
        between = (face[:, 0] >= lo[0]) & (face[:, 0] <= hi[0])
        assert between.any()
        assert np.all(face[between, 1] >= hi[1] + pa.tol.clearance - 1e-9)


@pytest.mark.slow
def test_a_205_9_x_76_8_mm_palm_keeps_two_perimeters_where_drives_pass_its_sides():
    """The palm of ``size --hand-length 205.9 --hand-breadth 76.8`` at the placement its search found
    then (two rows of servos): the index
    drive leaves the metacarpal block's radial face at 9 deg ahead of the thenar block, and left a
    lip 0.06 mm thick along it; the middle finger's coupler bore, slanting toward its servo, ran
    0.4 mm beside the gap between the index and middle socket blocks (the population's walls row).
    The drive is opened to the side by a slot and the gap is filled: every wall measured on the
    palm's mesh is two perimeters."""
    from phantom_cad.cad.parts.common import channel_slots
    from phantom_cad.kinematics.dimensions import FLANK

    p, pa = _palm_of(205.9, 76.8, **_L205_9_M05)
    e, t = pa.finger_drive("index")
    u = (t - e) / np.linalg.norm(t - e)
    assert channel_slots(e, u, float(np.linalg.norm(t - e)), pa.tol.tendon_hole / 2.0, [pa.outside_gap],
                         FLANK * 1e3)                                    # the case: a slot to the side
    assert pa.gap_fillers()                                              # and a filled gap
    shape = pa.build()
    assert not solid_problems("palm", shape)
    walls = _thin_walls(p, shape)
    assert walls["wall_thinnest"] >= _bar(p), walls
