"""`phantom-cad size` (phantom_cad.sizing, phantom_cad/cli/size.py): each solver against a closed
form or the validator, the sized files validating over the supported range, the reference hand's
own measurements giving back params/phantom.toml, and every impossible, contradictory or malformed
input refused with one error line, exit 2, nothing written."""

from __future__ import annotations

import copy
import math
import subprocess
import sys

import numpy as np
import pytest

from phantom_cad.cad import preflight
from phantom_cad.cli import main
from phantom_cad.kinematics import closed_form as cf
from phantom_cad.kinematics.topology import DIGITS, FINGERS, chain
from phantom_cad.params import parse
from phantom_cad.params.rules import MAX_FINGER_PITCH
from phantom_cad.sizing import Person, build_document, size, template
from phantom_cad.sizing import solvers as S
from phantom_cad.kinematics.dimensions import digit_entry


def entry(doc, digit):
    return digit_entry(doc, digit)


# -- solvers -------------------------------------------------------------------

def test_the_reference_is_the_default_file():
    assert template()["hand"]["hand_length_mm"] == S.REFERENCE_LENGTH


@pytest.mark.parametrize("digit", DIGITS)
def test_servo_travel_reaches_the_first_limit(digit):
    """The default file's travels are the servo angle at which the first joint meets its Table I
    limit, to the half degree below; the model maps the travel inside every limit and half a
    degree more past one."""
    t = entry(template(), digit)
    spec = chain(digit)
    radii = tuple(t["pulley_radius_mm"][k] for k in spec.keys)
    limits = tuple(t["limits_rad"][k][1] for k in spec.keys)
    g = t["guide"]
    hi = S.servo_travel(g["d1_mm"], g["d2_mm"], g["alpha_deg"], t["servo_pulley_radius_mm"], radii, limits)
    assert hi == t["servo_travel_deg"][1]
    c = cf.ideal_coupling(radii)

    def q(u_deg):
        return c * float(cf.reference_angle(math.radians(u_deg), g["d1_mm"], g["d2_mm"], math.radians(g["alpha_deg"]),
                                            t["servo_pulley_radius_mm"]))
    assert all(q(hi) <= limits)
    assert any(q(hi + S.STEP) > limits)


def test_thickness_limit_is_the_phalanx_rule(document):
    """At 165 mm the default's index distal phalanx (16.005 mm) holds at most 16.005 - 0.4 mm of
    thickness (two joint bosses of half the thickness and a clearance each): the validator accepts
    a hair under it and refuses a hair over (the message of a 165 mm default file)."""
    lengths = {s: f * 165.0 for s, f in document["fingers"]["index"]["length_fraction"].items()}
    limits = {k: v[1] for k, v in document["fingers"]["index"]["limits_rad"].items()}
    t, seg = S.thickness_limit(lengths, chain("index").segments, limits, chain("index").keys, 0.2)
    assert seg == "distal" and t == pytest.approx(0.097 * 165.0 - 0.4)
    # the proximal phalanx's far joint (PIP, 92 deg) flexes past 90 deg: 1.5 T + 0.4 < L
    lengths["distal"] = lengths["middle"] = 100.0
    t, seg = S.thickness_limit(lengths, chain("index").segments, limits, chain("index").keys, 0.2)
    assert seg == "proximal" and t == pytest.approx((0.245 * 165.0 - 0.4) / 1.5)
    document["hand"]["hand_length_mm"] = 165.0
    for k in ("index", "middle", "ring", "pinky"):
        document["fingers"][k]["path_length_mm"]["mcp_pip"] = 45.0
    document["fingers"]["index"]["thickness_mm"] = 15.5
    with pytest.raises(Exception, match="distal phalanx"):
        document["fingers"]["index"]["thickness_mm"] = 15.7
        parse(document)


def test_finger_floors_are_the_magnet_and_clevis_rules(document):
    """Closed forms with the default hardware: two 5.4 mm pockets (5 mm magnets, 0.1 mm clearance a
    side, 0.2 mm compensation) one 2.4 mm wall apart and 0.8 mm outside each: 14.8 mm wide; the
    tendon one 2.4 mm wall above the palmar face, its 2 mm relief below the pockets: 12.2 mm thick;
    the validator refuses a pinky just under each."""
    args = ((5.0, 3.0), 2.4, 0.6, 0.2, 0.1, 0.2)
    assert S.finger_thickness_floor(*args, 7.0) == pytest.approx(2 * (2.4 + 1.0 + 2.7))
    assert S.finger_width_floor((5.0, 3.0), 2.4, 0.2, 0.1, 0.2, 2.4, 0.6, 1.5, 0.8) == pytest.approx(14.8)
    document["fingers"]["pinky"]["width_mm"] = 14.7
    with pytest.raises(Exception, match="magnet"):
        parse(document)


def test_guides_keep_the_reference_where_they_fit_and_the_rules_where_not():
    assert S.guide((12.0, 10.0, 100.0), 16.0, 0.6, 0.2, 1.2, 13.0) == (12.0, 10.0, 100.0)
    d1, d2, alpha = S.guide((12.0, 10.0, 100.0), 12.5, 0.6, 0.2, 1.2, 13.0)
    c = math.cos(math.radians(alpha) / 2)
    assert 12.5 / 2 + 0.2 + 0.6 <= d2 and d2 * c <= 12.5 / 2 - 0.5 and d1 * c <= 12.5 / 2 + 1.0


def test_path_length_keeps_the_wrap_and_the_crossed_span():
    assert S.path_length(46.305, 1.695, 5.0, 4.0) == 48.0
    # a phalanx barely longer than its pulleys: the crossed span binds
    assert S.path_length(20.0, -5.0, 5.0, 4.0) == math.ceil(math.sqrt(20.0 ** 2 - 9.0 ** 2))


def test_palm_layout_gives_the_default_pitch_and_clears_the_bases(document):
    from phantom_cad.kinematics.dimensions import finger_columns
    from phantom_cad.params.rules import base_room

    widths = {f: document["fingers"][f]["width_mm"] for f in FINGERS}
    meta = {f: document["fingers"][f]["length_fraction"]["metacarpal"] * 189.0 for f in FINGERS}
    assert S.palm_layout(widths, meta, 5.0, 13.0, 0.2) == (20.5, widths)
    big = {f: 18.5 for f in FINGERS}
    meta = {f: v * 230.0 / 189.0 for f, v in meta.items()}
    pitch, w = S.palm_layout(big, meta, 5.0, 13.0, 0.2)
    assert pitch <= MAX_FINGER_PITCH * 1e3
    cols = finger_columns(pitch * 1e-3, math.radians(5.0), [meta[f] * 1e-3 for f in FINGERS])
    for (a, b), ca, cb in zip(zip(FINGERS, FINGERS[1:]), cols, cols[1:]):
        room = base_room(ca, cb, 13e-3) * 1e3
        assert room >= (w[a] + w[b]) / 2 + 0.2 - 1e-9


def _flexed(doc, pitch=None):
    """(least distance in mm, pair) of neighbouring fingers' boxes over their commands' grid."""
    from phantom_cad.kinematics.finger_clearance import neighbour_clearance
    from phantom_cad.kinematics.model import Hand

    if pitch is not None:
        doc = copy.deepcopy(doc)
        doc["palm"]["finger_pitch_mm"] = pitch
    p = parse(doc)
    gap, pair = neighbour_clearance(p, Hand(p))
    return gap * 1e3, pair


def test_flexed_neighbours_stay_apart_on_the_sized_hand():
    """160 x 72 mm: four 15 mm fingers, so the widest finger and 2.5 mm give a 17.5 mm pitch, at which
    the ring's distal phalanx, fully flexed, and the pinky's, at 95 % of its travel, overlap by
    0.26 mm as boxes (and ``phantom-cad check`` finds the two parts overlapping, 0.2 mm^3).
    The solver raises the pitch to 18 mm, where every neighbouring pair's boxes stay
    FLEXED_CLEARANCE (0.1 mm) apart over every pair of commands (every 5 % of each travel)."""
    doc = build_document(Person(160.0, 72.0))
    assert {entry(doc, f)["width_mm"] for f in FINGERS} == {15.0}
    assert doc["palm"]["finger_pitch_mm"] == 18.0
    gap, _ = _flexed(doc)
    assert gap >= S.FLEXED_CLEARANCE
    old, pair = _flexed(doc, 17.5)
    assert pair == ("ring", "pinky") and old == pytest.approx(-0.26, abs=0.01)
    # the boxes' own overlap, by a corner: the ring's distal box at full travel holds a point of the
    # pinky's at 95 % (a point-in-box test, apart from the distance's algorithm)
    from phantom_cad.kinematics.finger_clearance import link_boxes
    from phantom_cad.kinematics.link_frames import link_transforms
    from phantom_cad.kinematics.model import Hand

    doc["palm"]["finger_pitch_mm"] = 17.5
    p = parse(doc)
    h = Hand(p)

    def distal(finger, f):
        u = np.array(h.u_min, float)
        s = FINGERS.index(finger) + 1
        u[s] += f * (h.u_max[s] - h.u_min[s])
        T = link_transforms(p, h.forward(u), mirrored=False)[f"{finger}_distal"]
        c, half = link_boxes(p, finger)[f"{finger}_distal"][0]
        return T, c, half

    Tr, cr, hr = distal("ring", 1.0)
    Tp, cp, hp = distal("pinky", 0.95)
    # points on the pinky's box's faces (1 mm apart, in its link frame), in the ring's link frame
    g = [np.linspace(c - h, c + h, int(2 * h / 1e-3) + 2) for c, h in zip(cp, hp)]
    pts = np.stack(np.meshgrid(*g, indexing="ij"), -1).reshape(-1, 3)
    pts = pts[np.any(np.isclose(np.abs(pts - cp), hp), axis=1)]
    local = (np.linalg.inv(Tr) @ (Tp @ np.c_[pts, np.ones(len(pts))].T))[:3].T
    assert np.any(np.all(np.abs(local - cr) < hr, axis=1))


def test_flexed_neighbours_stay_apart_on_the_reference_hand():
    """The reference hand's 20.5 mm pitch keeps its flexed neighbours' boxes 0.12 mm apart (the index
    and middle); at 20 mm they would overlap as boxes."""
    doc = template()
    gap, pair = _flexed(doc)
    assert pair == ("index", "middle") and S.FLEXED_CLEARANCE <= gap == pytest.approx(0.124, abs=0.001)
    assert _flexed(doc, 20.0)[0] < 0.0


# -- the sized files -------------------------------------------------------------

def test_the_reference_measurements_give_the_default_file():
    """The default hand's own measurements (189 mm, the 85 mm breadth of the 50th-percentile man its
    widths were chosen for, its fractions) give back params/phantom.toml, value for value."""
    doc = build_document(Person(189.0, 85.0, name="phantom"))
    assert doc == template()


@pytest.mark.parametrize("hl", [150.0, 160.0, 170.0, 189.0, 205.0, 215.0, 230.0])
@pytest.mark.parametrize("breadth", [65.0, 85.0, 105.0])
def test_every_size_in_the_range_validates(hl, breadth):
    """Across the supported range, the reference's placement scaled (what the search starts
    from and falls back on) makes a file that passes `params validate`'s rules."""
    p = parse(build_document(Person(hl, breadth)))
    preflight.check(p)
    assert p.palm.finger_pitch <= MAX_FINGER_PITCH + 1e-12


def test_measured_segments_are_used():
    doc = build_document(Person(180.0, 80.0, segments={"index": {"proximal": 40.5, "middle": 23.0, "distal": 17.5,
                                                                  "width": 16.0},
                                                        "thumb": {"metacarpal": 45.0, "proximal": 31.0,
                                                                  "distal": 25.0}}))
    assert doc["fingers"]["index"]["length_fraction"]["proximal"] * 180.0 == pytest.approx(40.5, abs=1e-3)
    assert doc["thumb"]["length_fraction"]["metacarpal"] * 180.0 == pytest.approx(45.0, abs=1e-3)
    assert doc["fingers"]["index"]["width_mm"] == 16.0
    preflight.check(parse(doc))


# -- refusals ------------------------------------------------------------------------

def run(argv, capsys):
    with pytest.raises(SystemExit) as exit_:
        main([str(a) for a in argv])
    cap = capsys.readouterr()
    return exit_.value.code, cap.out, cap.err


SEGMENTS = {
    "middle longer than the hand": ("[middle]\nproximal = 60\nmiddle = 40\ndistal = 30\n", "middle finger"),
    "unknown key": ("[index]\nproximal = 40\nnail = 3\n", "unknown key"),
    "unknown table": ("[toe]\nproximal = 40\n", "unknown table"),
    "negative length": ("[index]\nproximal = -40\n", "must be > 0"),
    "missing value": ("[index]\nproximal =\n", "not valid TOML"),
    "a string": ("[index]\nproximal = \"forty\"\n", "must be a length"),
    "a finger's metacarpal": ("[index]\nmetacarpal = 70\n", "unknown key"),
    "distal too short": ("[pinky]\ndistal = 9\n", "pinky distal phalanx"),
}


@pytest.mark.parametrize("case", sorted(SEGMENTS))
def test_bad_segments_are_one_error_line(tmp_path, capsys, case):
    text, words = SEGMENTS[case]
    seg = tmp_path / "person.toml"
    seg.write_text(text)
    out = tmp_path / "hand.toml"
    code, stdout, err = run(["size", "--hand-length", 170, "--hand-breadth", 75, "--segments", seg, "--out", out,
                             "--no-search"], capsys)
    lines = err.splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: "), err
    assert words in lines[0]
    assert not out.exists()


@pytest.mark.parametrize("argv, words", [
    (["--hand-length", 100, "--hand-breadth", 75], "distal phalanx"),
    (["--hand-length", 500, "--hand-breadth", 75], "nearest that works: --hand-length 400"),
    (["--hand-length", 170, "--hand-breadth", 40], "nearest that works: --hand-breadth 65"),
    (["--hand-length", -170, "--hand-breadth", 75], "nearest that works: --hand-length 50"),
    (["--hand-length", "nan", "--hand-breadth", 75], "must lie in"),
    (["--hand-length", 170], "--hand-breadth"),
    (["--hand-length", 170, "--hand-breadth", 75, "--side", "up"], "right or left"),
    (["--hand-length", 170, "--hand-breadth", 75, "--name", "a b"], "--name"),
])
def test_bad_arguments_are_one_error_line(tmp_path, capsys, argv, words):
    out = tmp_path / "hand.toml"
    code, stdout, err = run(["size", *argv, "--out", out, "--no-search"], capsys)
    lines = err.splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: "), err
    assert words in lines[0]
    assert not out.exists()


DOCUMENTED = {
    # a hand too short for the thinnest finger its base allows (docs/sizing.md, refusals)
    "a 100 mm hand": (
        [], 100,
        "error: --hand-length 100: the index distal phalanx (9.70 mm) leaves the index at most 9.30 mm thick (its "
        "two joint bosses and clearances must fit in it), the index needs at least 10.50 mm (the tendon enters its "
        "base below two 3 x 2 mm magnet pockets, one palm wall above the palmar face); nearest that works: "
        "--hand-length 118"),
    "a middle finger longer than the hand": (
        "[middle]\nproximal = 60\nmiddle = 40\ndistal = 30\n", 170,
        "error: the middle finger (metacarpal + proximal + middle + distal = 193.4 mm, proximal, middle, distal from "
        "--segments) must be shorter than the hand length (170 mm, wrist crease to the middle fingertip: the carpus "
        "lies between); nearest that works: --hand-length 194, or middle-finger segments 24.4 mm shorter in all"),
    "an unknown key": (
        "[index]\nproximal = 40\nnail = 3\n", 170,
        "error: {seg}: index.nail: unknown key (allowed in [index]: proximal, middle, distal, width, lengths in mm, "
        "joint centre to joint centre)"),
    "a negative length": (
        "[index]\nproximal = -40\n", 170,
        "error: {seg}: index.proximal = -40 mm: must be > 0 mm (a length, joint centre to joint centre)"),
    "a negative hand length": (
        [], -170,
        "error: --hand-length -170: must lie in [50, 400] mm, the lengths the sizing tries (docs/sizing.md); nearest "
        "that works: --hand-length 50"),
}


@pytest.mark.parametrize("case", sorted(DOCUMENTED))
def test_the_documented_refusals(tmp_path, capsys, case):
    """Each bad input docs/sizing.md lists: its one line, exit 2, nothing written."""
    text, length, want = DOCUMENTED[case]
    seg = tmp_path / "person.toml"
    argv = ["size", "--hand-length", length, "--hand-breadth", 75, "--out", tmp_path / "hand.toml", "--no-search"]
    if text:
        seg.write_text(text)
        argv += ["--segments", seg]
    code, stdout, err = run(argv, capsys)
    assert (code, err.splitlines(), stdout) == (2, [want.format(seg=seg)], "")
    assert sorted(q.name for q in tmp_path.iterdir()) == (["person.toml"] if text else [])


def test_a_segments_table_may_leave_keys_out(tmp_path, capsys):
    """No key of a segments table is required: a table with the index's proximal phalanx alone gives
    that phalanx the measured length and every other segment and width the reference's (the
    reference fraction of the hand length, the reference width in proportion to the breadth)."""
    import tomllib

    seg = tmp_path / "person.toml"
    seg.write_text("[index]\nproximal = 46.3\n")
    out = tmp_path / "hand.toml"
    code, _, err = run(["size", "--hand-length", 189, "--hand-breadth", 85, "--segments", seg, "--out", out,
                        "--no-search"], capsys)
    assert code == 0, err
    doc, ref = tomllib.loads(out.read_text()), template()
    got, want = doc["fingers"]["index"], ref["fingers"]["index"]
    assert got["length_fraction"]["proximal"] * 189.0 == pytest.approx(46.3, abs=1e-4)
    assert {k: v for k, v in got["length_fraction"].items() if k != "proximal"} == \
        {k: v for k, v in want["length_fraction"].items() if k != "proximal"}
    assert got["width_mm"] == want["width_mm"] and doc["fingers"]["middle"] == ref["fingers"]["middle"]


def test_a_hand_whose_thumb_misses_a_pad_is_refused(tmp_path, capsys):
    """150 mm long and 105 mm broad, the reference placement scaled: the ring's pad never faces the
    thumb's; the line names it and the breadth of the reference's proportion, which works."""
    out = tmp_path / "hand.toml"
    code, _, err = run(["size", "--hand-length", 150, "--hand-breadth", 105, "--out", out, "--no-search"], capsys)
    lines = err.splitlines()
    assert code == 2 and len(lines) == 1, err
    assert "the ring pad never faces the thumb's" in lines[0] and "nearest that works: --hand-breadth 67" in lines[0]
    assert not out.exists()
    code, _, err = run(["size", "--hand-length", 150, "--hand-breadth", 67, "--out", out, "--no-search"], capsys)
    assert code == 0 and out.exists(), err


def test_a_user_file_is_not_replaced(tmp_path, capsys):
    out = tmp_path / "mine.toml"
    out.write_text("my notes\n")
    code, _, err = run(["size", "--hand-length", 170, "--hand-breadth", 75, "--out", out, "--no-search"], capsys)
    assert code == 2 and "refusing to replace" in err
    assert out.read_text() == "my notes\n"


def test_size_imports_no_cad_library(tmp_path):
    code = ("import sys; from phantom_cad.cli import main\n"
            "try:\n"
            f"    main(['size', '--hand-length', '170', '--hand-breadth', '75', '--out', {str(tmp_path / 'h.toml')!r}, "
            "'--no-search'])\n"
            "except SystemExit as e:\n"
            "    assert e.code == 0, e.code\n"
            "assert not any(m.split('.')[0] in ('build123d', 'OCP', 'cadquery') for m in sys.modules)\n")
    subprocess.run([sys.executable, "-c", code], check=True)


# -- the command, with the placement search (seconds a hand) -----------------------

@pytest.mark.slow
def test_the_reference_measurements_give_the_default_hand():
    """With the search, the default hand's own measurements give its joint limits, coupling ratios
    and opposition: every joint limit and coupling ratio as the file's, the pads meeting within
    1 mm and the margin within 0.5 deg of params/phantom.toml's."""
    from phantom_cad import load_hand
    from phantom_cad.kinematics import opposition
    from phantom_cad.kinematics.model import Hand

    ref = load_hand()
    got = size(Person(189.0, 85.0, name="phantom"), check=preflight.check)
    hand = Hand(got.params)
    assert hand.q_max == pytest.approx(ref.q_max) and hand.q_min == pytest.approx(ref.q_min)
    assert hand.coupling_compensated == pytest.approx(ref.coupling_compensated, abs=1e-3)
    a, b = opposition.reach(hand), opposition.reach(ref)
    for f in opposition.OPPOSED:
        assert a[f].gap == pytest.approx(b[f].gap, abs=1e-3)
        assert a[f].margin == pytest.approx(b[f].margin, abs=math.radians(0.5))


@pytest.mark.slow
@pytest.mark.parametrize("argv", [
    ["--hand-length", 160, "--hand-breadth", 72],
    ["--hand-length", 205, "--hand-breadth", 95, "--side", "left"],
    ["--hand-length", 180, "--hand-breadth", 80, "--segments", "{SEG}"],
], ids=["160x72", "205x95-left", "segments"])
def test_the_command_writes_a_file_that_validates(tmp_path, argv, request):
    """(160 x 72 is the run's sized hand: the command's run of tests/conftest.py ``sized_file``.)"""
    from tests.conftest import SIZED_HAND

    if argv == ["--hand-length", SIZED_HAND[0], "--hand-breadth", SIZED_HAND[1]]:
        out, proc = request.getfixturevalue("sized_file")
    else:
        seg = tmp_path / "person.toml"
        seg.write_text("[index]\nproximal = 40.5\nmiddle = 23.0\ndistal = 17.5\n"
                       "[thumb]\nmetacarpal = 45.0\nproximal = 31.0\ndistal = 25.0\n")
        out = tmp_path / "person_hand.toml"
        argv = [str(a).replace("{SEG}", str(seg)) for a in argv]
        proc = subprocess.run([sys.executable, "-m", "phantom_cad", "size", *argv, "--out", str(out)],
                              capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    for words in ("reach at full travel", "opposition", "power grasp", "palm:", "thinnest designed wall",
                  "fingertip force at half travel"):
        assert words in proc.stdout
    proc = subprocess.run([sys.executable, "-m", "phantom_cad", "params", "validate", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.startswith("OK"), proc.stderr
    from phantom_cad.kinematics import opposition
    from phantom_cad.kinematics.model import Hand
    from phantom_cad.params import load_params

    reach = opposition.reach(Hand(load_params(out)))
    assert all(reach[f].gap <= 0.0 for f in opposition.OPPOSED)
    # the heel where sizing.heel puts it at the placement written (the 205 mm hand's is searched: the
    # thenar moves the palm's back face, from which the heel's length counts)
    from phantom_cad.params import load_document
    from phantom_cad.sizing import heel

    doc = load_document(out)
    solved = copy.deepcopy(doc)
    heel(solved)
    assert solved["palm"] == doc["palm"]
    # what a second run writes over is its own output
    assert out.read_text().startswith("# phantom-cad size:")


def test_a_sized_hand_builds(sized_hand):
    """One sized hand, 160 x 72 mm (tests/conftest.py), built by the build pipeline: it raises
    BuildError when a part fails its verification or parts intersect at the rest pose."""
    doc, result = sized_hand
    assert result.params_digest == parse(doc).digest and result.hand == doc["hand"]["name"]


def test_pulley_radii_keep_the_ratio_inside_the_boss():
    assert S.pulley_radii((5.0, 4.0, 5.0), 16.0, 1.8, 1.5, 1.9) == (5.0, 4.0, 5.0)
    # 11 mm thick: the return cord's 1.9 mm channel at the largest radius keeps 0.8 mm under the
    # dorsal face: R = 5.5 - 0.95 - 0.8 = 3.75 mm, the 5:4 ratio kept
    assert S.pulley_radii((5.0, 4.0, 5.0), 11.0, 1.8, 1.5, 1.9) == (3.75, 3.0, 3.75)
    # the sized 160 x 72 mm hand's ring, pinky and thumb, 12.5 mm thick: 6.25 - 0.95 - 0.8 = 4.5 mm
    assert S.pulley_radii((5.0, 4.0, 5.0), 12.5, 1.8, 1.5, 1.9) == (4.5, 3.6, 4.5)
    # the smallest would no longer clear the axle bore and half a cord
    assert all(math.isnan(v) for v in S.pulley_radii((5.0, 4.0, 5.0), 9.0, 1.8, 1.5, 1.9))


def test_section_moves_the_target_inside_the_bounds():
    assert S.section(15.26, 12.2, 16.0) == 15.5
    assert S.section(11.0, 12.2, 16.0) == 12.5
    assert S.section(17.0, 12.2, 15.605) == 15.5
    assert math.isnan(S.section(14.0, 12.2, 12.4))


def test_palm_thickness_is_the_thinnest_that_keeps_the_turn():
    """At 150 mm the reference's palm scaled (18.5 mm) leaves the thumb drive's turn short of its
    wall under the dorsal face: the solver raises it to the first half millimetre that keeps it."""
    from phantom_cad.kinematics import frames as F
    from phantom_cad.kinematics import thenar as TH
    from phantom_cad.sizing import palm_thickness

    doc = build_document(Person(150.0, 65.0))
    t = doc["palm"]["thickness_mm"]
    assert t > S.scaled(24.0, 150.0)
    assert palm_thickness(doc) == t

    def turn(thickness):
        d = dict(doc, palm=dict(doc["palm"], thickness_mm=thickness))
        p = parse(d)
        return TH.thenar_margins(p, F.T_palm_thumb_cmc_base(p))["turn"]
    assert turn(t) >= 0.0 > turn(t - S.STEP)


def test_the_nearest_length_that_works_is_where_the_rules_start_to_hold():
    from phantom_cad.sizing import nearest_length

    n = nearest_length(Person(100.0, 75.0), preflight.check)
    assert n is not None and 100.0 < n < 150.0
    preflight.check(parse(build_document(Person(n, 75.0))))
    with pytest.raises(Exception):
        preflight.check(parse(build_document(Person(n - 1.0, 75.0))))


def test_a_left_hand_is_the_right_one_mirrored():
    right = build_document(Person(205.0, 95.0))
    left = build_document(Person(205.0, 95.0, side="left"))
    assert left["hand"]["side"] == "left" and dict(left, hand=right["hand"]) == right
    preflight.check(parse(left))


def test_the_print_aids_refuse_before_a_file_is_written(tmp_path, capsys, monkeypatch):
    """A file the angle gauge cannot be made for would validate and then fail its build: the
    preflight rules construct the print aids. With the marks' least pitch at the full 3 mm, the
    156.3 mm hand's 22.2 mm faces (7 marks need 22.5) are refused before anything is written."""
    from phantom_cad.cad import gauge

    monkeypatch.setattr(gauge, "MARK_MIN_PITCH", gauge.MARK_PITCH)
    out = tmp_path / "small.toml"
    code, _, err = run(["size", "--hand-length", 156.3, "--hand-breadth", 68.4, "--out", out, "--no-search"], capsys)
    assert code == 2 and err.startswith("error: ") and len(err.splitlines()) == 1
    assert "the angle gauge's faces (22.2 mm" in err and "need (22.5 mm)" in err
    assert not out.exists()


def test_a_placement_whose_thumb_tip_end_meets_a_pad_is_not_kept():
    """The 170.4 x 76.8 mm hand at a placement whose capsules meet every pad inside the cone but
    whose thumb's tip end meets the index pad on the printed tips (tests/test_printed_tips.py):
    it ranks below a placement that meets all three there, even one with a smaller margin, and
    were it the best, the refusal names the index and the printed tips."""
    from dataclasses import replace

    from phantom_cad.sizing import Sizing, _opposition, opposition_refusal
    from tests.support.hands import rim_hand

    p = rim_hand().params
    margin, unpinched = _opposition(p)
    assert margin > 0.0 and unpinched == ("index",)
    rim = Sizing(p.document, p, margin, True, unpinched)
    assert not rim.opposes
    assert replace(rim, margin=0.0, unpinched=()).rank > rim.rank
    assert replace(rim, margin=0.0, unpinched=()).opposes
    line = opposition_refusal(Person(170.4, 76.8, "right", "rim"), rim, preflight.check, False, 0)
    assert line.startswith("--hand-length 170.4 --hand-breadth 76.8: on the printed tips the thumb's pad meets "
                           "no index pad"), line


def test_the_report_gives_the_pinch_on_the_printed_tips():
    """The default hand's line: where OpenCascade finds the pinches on the built tips
    (tests/cad/test_printed_tips_on_solids.py; 0.911, 0.831 and 0.552 mm there)."""
    from phantom_cad.cli.size import report
    from phantom_cad.params import load_params

    line = next(s for s in report(load_params(), False) if "on the printed tips" in s)
    assert ("index 0.76 mm at u1 8.2, u6 27.0, index 40.7 deg; middle 0.84 mm at u1 4.1, u6 9.0, middle 53.0 deg; "
            "ring 0.26 mm at u1 0.0, u6 4.5, ring 50.3 deg") in line
