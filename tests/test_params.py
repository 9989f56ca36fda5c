"""Parameter files: every rule gives its own clear message (field, value, rule)."""

from __future__ import annotations

import math

import pytest

from phantom_cad.params import ParamError, dump_params, load_params, parse


def refuse(document, message):
    with pytest.raises(ParamError) as info:
        parse(document)
    assert str(info.value) == message
    return info.value


def test_default_file_is_valid():
    p = load_params()
    assert p.name == "phantom" and p.side == "right"
    assert set(p.fingers) == {"index", "middle", "ring", "pinky"}
    # Buchholz et al. 1992: index proximal = 0.245 HL, HL = 189 mm
    assert p.fingers["index"].proximal == pytest.approx(0.245 * 0.189)
    # 5:4:5 radii; the thumb's 5:4
    assert p.fingers["middle"].chain.radii == pytest.approx((0.005, 0.004, 0.005))
    assert p.thumb.chain.radii == pytest.approx((0.004, 0.005))  # (MP, IP)
    assert p.palm.arc_offset == pytest.approx(math.radians(5.0))


def test_derived_quantities_from_parameters():
    p = load_params()
    g = p.fingers["index"].chain.guide
    # eq. (4), by hand: d1 = 12, d2 = 10 mm, alpha = 100 deg
    assert g.L0 == pytest.approx(math.sqrt(144 + 100 - 240 * math.cos(math.radians(100))) * 1e-3)
    assert tuple(p.thumb.chain.ideal_coupling) == pytest.approx((1.0, 0.8))  # not 1.25 (erratum)
    assert tuple(p.fingers["ring"].chain.ideal_coupling) == pytest.approx((1.0, 1.25, 1.0))
    # palm arc: adjacent MCPs finger_pitch apart turning by 5 deg lie on radius pitch / (2 sin 2.5 deg)
    assert p.palm.arc_radius == pytest.approx(0.0205 / (2 * math.sin(math.radians(2.5))))


def test_digest_is_stable_and_sensitive(document):
    a = parse(document).digest
    assert parse(document).digest == a
    document["fingers"]["index"]["width_mm"] = 17.5
    assert parse(document).digest != a


def test_dump_and_reload(tmp_path, document):
    path = tmp_path / "copy.toml"
    dump_params(document, path)
    assert load_params(path).digest == parse(document).digest


def test_dump_refuses_invalid_and_writes_nothing(tmp_path, document):
    document["hand"]["side"] = "up"
    path = tmp_path / "bad.toml"
    with pytest.raises(ParamError):
        dump_params(document, path)
    assert not path.exists() and list(tmp_path.iterdir()) == []


def test_unknown_top_level_key(document):
    document["colour"] = 1
    refuse(document, "colour = 1: unknown key 'colour' (allowed: schema_version, hand, fingers, "
                     "thumb, mechanics, palm, servo, hardware, print, cad, plugins, effects)")


def test_plugins_must_be_a_list_of_paths(document):
    document["plugins"] = "my_effect.py"
    refuse(document, "plugins = 'my_effect.py': must be a list of file paths (Python files that register "
                     "effects, relative to this parameter file)")
    document["plugins"] = ["ok.py", 3]
    refuse(document, "plugins = ['ok.py', 3]: must be a list of file paths (Python files that register "
                     "effects, relative to this parameter file)")


def test_a_missing_plugin_is_named(document, tmp_path):
    from phantom_cad.calibration.effects import PARAMS_EFFECTS

    document["plugins"] = ["nowhere/my_effect.py"]
    source = str(tmp_path / "hand.toml")
    parse(document, source)   # without an effect library the params layer loads no plugin
    with pytest.raises(ParamError) as info:
        parse(document, source, effects=PARAMS_EFFECTS)
    assert str(info.value) == (f"{source}: plugins[0]: plugin {tmp_path / 'nowhere' / 'my_effect.py'}: "
                               "no such file")


def test_the_effect_library_is_handed_in(document, tmp_path):
    """The params layer keeps no registry of its own: it loads plugins and checks [effects.*]
    tables through the library the caller passes, and only through it."""
    calls = []

    class Library:
        def load_plugin(self, path, field_name, source):
            calls.append(("plugin", path, field_name, source))

        def check(self, effects, source):
            calls.append(("check", effects, source))
            raise ParamError("effects.toy", "x", "refused by the library", source)

    document["plugins"] = ["sub/toy.py"]
    document["effects"] = {"toy": {"x": 1.0}}
    source = str(tmp_path / "hand.toml")
    p = parse(document, source)   # without a library: the shape only, kept as written
    assert p.plugins == ("sub/toy.py",) and dict(p.effects["toy"]) == {"x": 1.0} and not calls
    with pytest.raises(ParamError, match="refused by the library"):
        parse(document, source, effects=Library())
    assert calls == [("plugin", str(tmp_path / "sub" / "toy.py"), "plugins[0]", source),
                     ("check", {"toy": {"x": 1.0}}, source)]


def test_finger_name_typo(document):
    document["fingers"]["indx"] = document["fingers"].pop("index")
    refuse(document, "fingers.indx = '{...}': unknown finger 'indx' (allowed: index, middle, ring, pinky)")


def test_missing_finger(document):
    del document["fingers"]["pinky"]
    refuse(document, "fingers.pinky = None: is required but missing")


def test_unknown_key_in_finger_lists_allowed(document):
    document["fingers"]["ring"]["colour"] = "red"
    refuse(document, "fingers.ring.colour = 'red': unknown key 'colour' (allowed: length_fraction, "
                     "width_mm, thickness_mm, pulley_radius_mm, guide, servo_pulley_radius_mm, "
                     "servo_travel_deg, limits_rad, path_length_mm)")


def test_a_horn_radius_for_servo_6_under_the_cmc_names_the_loop_pulley(document):
    """Servo 6 turns the CMC through a cable loop (docs/parameters.md): a horn radius under the CMC
    is refused, naming the key to use."""
    document["thumb"]["cmc_horn_radius_mm"] = 7.0
    refuse(document, "thumb.cmc_horn_radius_mm = 7.0: not a parameter: servo 6 does not sit under the CMC "
                     "(it turns it through a cable loop from the forearm module): name the loop's pulley "
                     "radius cmc_pulley_radius_mm instead (docs/parameters.md)")


def test_radius_not_positive(document):
    document["fingers"]["index"]["pulley_radius_mm"]["pip"] = -4.0
    refuse(document, "fingers.index.pulley_radius_mm.pip = -4.0: must be > 0")


def test_text_in_a_number(document):
    document["hand"]["hand_length_mm"] = "189"
    refuse(document, "hand.hand_length_mm = '189': must be a number")


def test_boolean_is_not_a_number(document):
    document["print"]["infill"] = True
    refuse(document, "print.infill = True: must be a number")


def test_side(document):
    document["hand"]["side"] = "middle"
    refuse(document, "hand.side = 'middle': must be one of: right, left")


def test_schema_version(document):
    document["schema_version"] = 2
    refuse(document, "schema_version = 2: must be 1")


def test_alpha_below_mcp_limit(document):
    document["fingers"]["middle"]["guide"]["alpha_deg"] = 70.0
    refuse(document, "fingers.middle.guide.alpha_deg = 70.0: must exceed the MCP upper limit "
                     "fingers.middle.limits_rad.mcp = 1.24 rad (71.05 deg): eq. (6) gives q_MCP <= alpha")


def test_cosine_law_argument_leaves_its_domain(document):
    document["fingers"]["index"]["servo_travel_deg"] = [0.0, 150.0]
    # by hand: L0 = sqrt(144 + 100 - 240 cos 100 deg) = 16.902 mm, L = L0 - 7 mm * 2.61799 = -1.424 mm,
    # argument = (244 - 2.0278) / 240 = 1.0082; admissible chords [|12 - 10|, 12 + 10] = [2, 22] mm
    refuse(document, "fingers.index.servo_travel_deg = [0.0, 150.0]: the cosine-law argument "
                     "(d1^2 + d2^2 - L^2) / (2 d1 d2) is 1.0082 at u = 150 deg, outside [-1, 1] "
                     "(chord L = L0 - r u = -1.424 mm must stay in [2.000, 22.000] mm)")


def test_chord_negative_inside_the_travel(document):
    # a 20 mm servo pulley keeps the argument inside [-1, 1] at both ends of
    # the travel, but the chord L = L0 - r u is linear in u and changes sign inside it.
    # By hand: L0 = 16.902 mm (above), L(93 deg) = 16.902 - 20 * 1.62316 = -15.561 mm;
    # at the ends the argument is cos(100 deg) = -0.1736 and (244 - 242.15) / 240 = 0.0077, but at
    # L = 0 it reaches (144 + 100) / 240 = 1.0167
    document["fingers"]["index"]["servo_pulley_radius_mm"] = 20.0
    refuse(document, "fingers.index.servo_travel_deg = [0.0, 93.0]: the chord L = L0 - r u is -15.561 mm "
                     "at u = 93 deg, outside [2.000, 22.000] mm: inside the travel it leaves the cosine "
                     "law's domain (the argument reaches 1.0167 at L = 0)")


def test_travel_image_outside_limits(document):
    document["fingers"]["index"]["limits_rad"]["mcp"] = [0.0, 1.0]
    # eq. (6) by hand at u = 93 deg: L = L0 - 7 mm * 93 pi / 180
    L = math.sqrt(144 + 100 - 240 * math.cos(math.radians(100))) - 7 * math.radians(93)
    q = math.radians(100) - math.acos((244 - L * L) / 240)
    refuse(document, f"fingers.index.servo_travel_deg = [0.0, 93.0]: at u = 93 deg the model puts index MCP "
                     f"at {q:.4f} rad, outside its limits fingers.index.limits_rad.mcp = [0, 1]: "
                     "the servo travel must map inside the workspace")


def test_thumb_travel_image_uses_the_5_4_ratio(document):
    # eq. (8) by hand: d1 = 11, d2 = 9 mm, alpha = 100 deg, r1 = 7 mm, u = 81.5 deg; q_IP = 0.8 q_MP
    document["thumb"]["limits_rad"]["ip"] = [0.0, 0.9]
    L = math.sqrt(121 + 81 - 198 * math.cos(math.radians(100))) - 7 * math.radians(81.5)
    q_ip = 0.8 * (math.radians(100) - math.acos((202 - L * L) / 198))
    refuse(document, f"thumb.servo_travel_deg = [0.0, 81.5]: at u = 81.5 deg the model puts thumb IP at "
                     f"{q_ip:.4f} rad, outside its limits thumb.limits_rad.ip = [0, 0.9]: "
                     "the servo travel must map inside the workspace")


def test_cmc_travel_outside_limits(document):
    document["thumb"]["cmc_servo_travel_deg"] = [0.0, 90.0]
    refuse(document, "thumb.cmc_servo_travel_deg = [0.0, 90.0]: q15 = cmc_gain * u6 = 1.5708 rad at "
                     "u6 = 90 deg is outside the CMC limits [0, 1.57]: the servo travel must map inside the workspace")


def test_interval_order(document):
    document["fingers"]["ring"]["limits_rad"]["dip"] = [1.29, 0.0]
    refuse(document, "fingers.ring.limits_rad.dip = [1.29, 0.0]: low must be < high")


def test_rest_pose_inside_limits(document):
    document["fingers"]["ring"]["limits_rad"]["dip"] = [0.1, 1.29]
    refuse(document, "fingers.ring.limits_rad.dip = [0.1, 1.29]: low must be <= 0 "
                     "(the rest pose q = 0 must lie in the workspace)")


def test_missing_key(document):
    del document["fingers"]["ring"]["guide"]
    refuse(document, "fingers.ring.guide = None: is required but missing")


def test_path_length_shorter_than_the_phalanx(document):
    document["fingers"]["index"]["path_length_mm"]["mcp_pip"] = 30.0
    # proximal = 0.245 * 189 = 46.305 mm, crossing between R = 5 and 4 mm: sqrt(46.305^2 - 9^2) = 45.42 mm
    refuse(document, "fingers.index.path_length_mm.mcp_pip = 30.0: must be >= 45.42 mm, the crossed-tendon "
                     "span of the proximal segment between its pulleys")


def test_thumb_path_length_shorter_than_its_proximal(document):
    document["thumb"]["path_length_mm"]["mp_ip"] = 20.0
    span = math.sqrt((0.196 * 189) ** 2 - (4 + 5) ** 2)   # proximal 0.196 HL, R_MP + R_IP = 9 mm
    refuse(document, f"thumb.path_length_mm.mp_ip = 20.0: must be >= {span:.2f} mm, the crossed-tendon "
                     "span of the proximal segment between its pulleys")


def test_finger_wider_than_pitch(document):
    document["fingers"]["middle"]["width_mm"] = 25.0
    refuse(document, "fingers.middle.width_mm = 25.0: must be < palm.finger_pitch_mm = 20.5 "
                     "(adjacent fingers would overlap)")


def test_axle_larger_than_bearing_bore(document):
    document["hardware"]["axle_diameter_mm"] = 4.0
    refuse(document, "hardware.axle_diameter_mm = 4.0: must be <= hardware.bearing.bore_mm = 3")


def test_fraction_out_of_range(document):
    document["fingers"]["pinky"]["length_fraction"]["distal"] = 1.5
    refuse(document, "fingers.pinky.length_fraction.distal = 1.5: must be < 1")


def test_not_finite(document):
    document["mechanics"]["tendon_EA_N"] = float("inf")
    refuse(document, "mechanics.tendon_EA_N = inf: must be finite")


def test_invalid_toml_file(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[hand\nname = 'x'\n")
    with pytest.raises(ParamError) as info:
        load_params(path)
    assert str(info.value).startswith(f"{path}: <file> = '{path}': is not valid TOML: ")


def test_missing_file(tmp_path):
    path = tmp_path / "nope.toml"
    with pytest.raises(ParamError) as info:
        load_params(path)
    assert str(info.value) == f"<file> = '{path}': no such parameter file"


def test_error_names_the_file(tmp_path, document):
    import tomli_w

    document["fingers"]["index"]["guide"]["d1_mm"] = 0
    path = tmp_path / "hand.toml"
    path.write_text(tomli_w.dumps(document))
    with pytest.raises(ParamError) as info:
        load_params(path)
    assert str(info.value) == f"{path}: fingers.index.guide.d1_mm = 0: must be > 0"
    assert info.value.field == "fingers.index.guide.d1_mm" and info.value.rule == "must be > 0"


def test_params_are_frozen():
    p = load_params()
    with pytest.raises(Exception):
        p.name = "x"
    with pytest.raises(TypeError):
        p.fingers["index"] = None


def test_unreadable_parameter_files(tmp_path):
    """A binary file, a folder and a symlink loop are refused with one error line, no traceback."""
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    loop = tmp_path / "loop.toml"
    loop.symlink_to(loop)
    cases = [(binary, "is not UTF-8 text (invalid start byte at byte 0)"),
             (tmp_path, "is a folder, not a parameter file"),
             (loop, "cannot be read (Too many levels of symbolic links)")]
    for path, rule in cases:
        with pytest.raises(ParamError) as info:
            load_params(path)
        assert str(info.value) == f"<file> = {str(path)!r}: {rule}"


# ---------------------------------------------------------------------------
# files that would validate and not build are refused, each by the rule
# the build relied on (the property test, tests/test_validation_builds.py, checks the rest)
# ---------------------------------------------------------------------------

def _field(document, path, value):
    node = document
    keys = path.split(".")
    for k in keys[:-1]:
        node = node[k]
    node[keys[-1]] = value


@pytest.mark.parametrize("path, value, field, words", [
    # pockets of 17 + 2 x 0.1 (magnet clearance) + 0.2 (hole compensation) = 17.4 mm:
    # 2 x 17.4 + 2.4 + 2 x 0.8 = 38.8 mm across an 18 mm index face
    ("hardware.magnet.diameter_mm", 17.0, "hardware.magnet.diameter_mm", "38.800 mm) must fit across"),
    ("palm.wall_mm", 0.001, "palm.wall_mm", "must be >= 0.8 mm"),
    # 2 x 5.4 + 30 + 2 x 0.8 = 42.4 mm
    ("palm.wall_mm", 30.0, "hardware.magnet.diameter_mm", "(42.400 mm) must fit across"),
    # 5.4 + 2 x 2.4 = 10.2 mm
    ("palm.thickness_mm", 1.0, "palm.thickness_mm", "must be >= 10.200 mm"),
    # the thickest finger (16) + 2 x 0.2
    ("palm.thickness_mm", 16.2, "palm.thickness_mm", "must exceed the thickest finger (16 mm)"),
    ("palm.heel_height_mm", -1.0, "palm.heel_height_mm", "must be >= 0"),
    ("palm.magnet_lift_mm", -0.1, "palm.magnet_lift_mm", "must be >= 0"),
    # 5.4 mm pockets keep 0.8 mm under the 14 mm pinky's dorsal face up to 7 - 0.8 - 2.7 = 3.5 mm
    ("palm.magnet_lift_mm", 3.6, "palm.magnet_lift_mm", "must be <= 3.500 mm"),
    # a heel of height 11 (the file's) and no length
    ("palm.heel_length_mm", 0.0, "palm.heel_length_mm", "must be > 0 with the other heel dimension"),
    ("print.stl_tolerance_mm", 1e-9, "print.stl_tolerance_mm", "must be >= 0.001"),
    # PrusaSlicer's limit for a 0.4 mm nozzle is 0.75 x 0.4 = 0.3 mm
    ("print.layer_height_mm", 0.32, "print.layer_height_mm", "must be <= 0.3"),
    ("print.layer_height_mm", 0.0, "print.layer_height_mm", "must be >= 0.05"),
    # 0.05 x 189 = 9.45 mm < 16 + 2 x 0.2
    ("fingers.index.length_fraction.distal", 0.05, "fingers.index.length_fraction.distal", "16.40 mm"),
    # thumb metacarpal 0.06 x 189 = 11.34 mm < 10 (hub) + 7.5 + 0.2
    ("thumb.length_fraction.metacarpal", 0.06, "thumb.length_fraction.metacarpal", "CMC hub"),
    ("hand.hand_length_mm", 1e308, "hand.hand_length_mm", "must lie within +-1e+06"),
    ("hand.hand_length_mm", 5000.0, "hand.hand_length_mm", "must be <= 1000"),
    # eq. (13): kappa = 200 / 1e-300 takes the whole PIP motion back
    ("mechanics.tendon_EA_N", 1e-300, "mechanics.tendon_EA_N", "a coupled joint must flex"),
    # a groove of radius 8.5 mm does not fit in a 16 mm boss; 1.5 mm cuts into the 3.4 mm axle bore
    ("fingers.index.pulley_radius_mm.dip", 8.5, "fingers.index.pulley_radius_mm.dip", "joint boss's surface"),
    # the return cord's 1.9 mm channel at R = 6.5 mm leaves 8 - 6.5 - 0.95 = 0.55 mm under the dorsal face
    ("fingers.index.pulley_radius_mm.dip", 6.5, "fingers.index.pulley_radius_mm.dip", "must be <= 6.250 mm"),
    # found by the property test (seed 4): these validated and did not build
    ("fingers.pinky.limits_rad.dip", [0.0, 2.728821], "fingers.pinky.limits_rad.dip", "flexion up to 120 deg"),
    ("palm.finger_pitch_mm", 22.0, "palm.finger_pitch_mm", "must be <= 21 mm"),
    # found by the property test (seed 4): a thumb eyelet 43.2 cos 50 = 27.768 mm below the MP axis
    # floats below the 15 mm metacarpal (2 solids) and the proximal phalanx's boolean ran out of memory;
    # room = 7.5 + 2 x 0.5 = 8.5 mm
    ("thumb.guide.d1_mm", 43.2, "thumb.guide.d1_mm", "27.768 mm below the joint axis"),
    ("thumb.guide.d1_mm", 13.3, "thumb.guide.d1_mm", "(<= 8.500 mm"),        # 13.3 cos 50 = 8.549
    # a 0.11 x 189 = 20.79 mm metacarpal leaves 10.79 mm of arm in front of the 10 mm hub; the eyelet
    # reaches 11 sin 50 + 1.2 / 2 + (sqrt 3 + 2) 0.5 = 8.4265 + 0.6 + 1.8660 = 10.8925 mm behind the MP axis
    ("thumb.length_fraction.metacarpal", 0.11, "thumb.guide.d1_mm", "10.893 mm behind the MP axis"),
])
def test_rules_the_build_relies_on(document, path, value, field, words):
    _field(document, path, value)
    with pytest.raises(ParamError) as info:
        parse(document)
    assert info.value.field == field
    assert words in info.value.rule


def test_thumb_eyelet_depth_bound_by_hand(document):
    """13.2 cos 50 deg = 8.485 mm <= 8.5 mm: the deepest thumb eyelet at the default alpha validates
    (and builds: all three thumb parts were built at 13.2 mm, one valid solid each)."""
    _field(document, "thumb.guide.d1_mm", 13.2)
    parse(document)


def test_finger_eyelet_depth_bound_by_hand(document):
    """At alpha = 92 deg the base's reach allows d1 up to (13 - 2.866) / sin 46 = 14.09 mm, but
    14 cos 46 = 9.725 mm is deeper than 16 / 2 + 1 = 9 mm."""
    _field(document, "fingers.index.guide", {"d1_mm": 14.0, "d2_mm": 10.0, "alpha_deg": 92.0})
    with pytest.raises(ParamError) as info:
        parse(document)
    assert info.value.field == "fingers.index.guide.d1_mm" and "9.725 mm below" in info.value.rule
    assert "(<= 9.000 mm" in info.value.rule


def test_compliance_limit_matches_eq_13_by_hand(document):
    """The DIP coupling of eq. (13) by hand: A_DIP = 1, v_DIP = (path to the DIP) / R_DIP,
    R.A = 5 + 4 x 1.25 + 5 = 15 mm, R.v = the sum of the paths to PIP and DIP, so
    a_DIP = 1 - v_DIP k 15 / (1 + k R.v) vanishes at k = 1 / (15 v_DIP - R.v):
    index (48 + 29 = 77 mm): k = 1 / (231 - 125) per mm; middle (52 + 34 = 86): 1 / (258 - 138);
    ring (81): 1 / (243 - 129); pinky (64): 1 / (192 - 104); thumb IP: 0.8 - 8 k 8 / (1 + 40 k),
    k = 1 / 40. EA = k_s / k with k_s = 200 N/m: 21.2, 24.0, 22.8, 17.6, 8.0 N; the middle DIP goes first."""
    limit = 200.0 * 0.120
    document["mechanics"]["tendon_EA_N"] = limit * 1.01
    parse(document)
    document["mechanics"]["tendon_EA_N"] = limit * 0.99
    with pytest.raises(ParamError) as info:
        parse(document)
    assert info.value.field == "mechanics.tendon_EA_N" and "middle DIP" in info.value.rule


def test_hand_name_makes_a_file_name(document):
    document["hand"]["name"] = "a" * 65
    with pytest.raises(ParamError) as info:
        parse(document)
    assert info.value.field == "hand.name" and "at most 64 characters" in info.value.rule
    document["hand"]["name"] = "h\u00e4nd"      # not ASCII
    with pytest.raises(ParamError):
        parse(document)
    document["hand"]["name"] = "a" * 64
    assert parse(document).name == "a" * 64


def test_parallel_fingers(document):
    """arc_offset_deg = 0 (documented as allowed): a straight row, finger_pitch apart, no division by
    zero; each MCP stepped straight along y by its metacarpal less the index's (the stepped heads)."""
    import numpy as np

    from phantom_cad.kinematics import frames

    document["palm"]["arc_offset_deg"] = 0.0
    p = parse(document)
    assert p.palm.arc_radius == math.inf
    hl = document["hand"]["hand_length_mm"]
    meta = [document["fingers"][f]["length_fraction"]["metacarpal"] * hl for f in ("index", "middle", "ring", "pinky")]
    for i in range(4):
        want = [20.5 * i, meta[i] - meta[0], 0.0]
        assert np.allclose(frames.mcp_position(p, i) * 1e3, want, atol=1e-12)


def test_stepped_metacarpal_heads(document):
    """The default hand's knuckle line by hand: on the 5 degree arc (chords 20.5 mm at -5, 0, +5
    degrees), each MCP then steps along its own column (turned by -7.5, -2.5, 2.5, 7.5 degrees) by
    its metacarpal less the index's (0.374, 0.373, 0.336, 0.295 of 189 mm)."""
    import numpy as np

    from phantom_cad.kinematics import frames

    p = parse(document)
    d = math.radians
    arc = [(0.0, 0.0)]
    for m in (-5.0, 0.0, 5.0):
        x, y = arc[-1]
        arc.append((x + 20.5 * math.cos(d(m)), y - 20.5 * math.sin(d(m))))
    steps = [(f - 0.374) * 189.0 for f in (0.374, 0.373, 0.336, 0.295)]
    for i, ((x, y), s, phi) in enumerate(zip(arc, steps, (-7.5, -2.5, 2.5, 7.5))):
        want = [x + s * math.sin(d(phi)), y + s * math.cos(d(phi)), 0.0]
        assert np.allclose(frames.mcp_position(p, i) * 1e3, want, atol=1e-9)
    # the knuckle line: middle 1.6 mm ahead of the index, ring 5.4 and pinky 14.8 mm behind it
    ys = [frames.mcp_position(p, i)[1] * 1e3 for i in range(4)]
    assert [round(v, 1) for v in ys] == [0.0, 1.6, -5.4, -14.8]


def _refused_by_the_command_line(tmp_path, capsys, document) -> tuple[str, list]:
    """``params validate`` and ``build`` on ``document`` written to a file: (the file, and each
    command's (exit code, stderr lines, what the build wrote))."""
    import tomli_w

    from phantom_cad.cli import main

    path = tmp_path / "hand.toml"
    path.write_text(tomli_w.dumps(document), encoding="utf-8")
    out = []
    for argv in (["params", "validate", str(path)], ["build", "--params", str(path), "--out", str(tmp_path / "out")]):
        with pytest.raises(SystemExit) as exit_:
            main(argv)
        err = capsys.readouterr().err.splitlines()
        out.append((exit_.value.code, err, sorted(q.name for q in tmp_path.iterdir())))
    return str(path), out


def test_a_servo_body_too_long_for_its_flange_screws(tmp_path, capsys, document):
    """Each flange screw's pilot lies mid-ear, (flange_span - length) / 4 beyond the body's end; the
    body's pocket is a hole clearance wider. A 30 mm body under a 32.3 mm flange leaves 0.575 mm,
    less than the 1.8 mm pilot's radius (0.8 x 2 + 0.2 mm hole compensation): the pilots break into
    the pocket and the forearm module's check counts none of its 12 (found with a 32.6 mm palm,
    which plays no part). The limit with a 0.8 mm wall: 32.3 - 4 (0.9 + 0.2 + 0.8) = 24.7 mm."""
    document["servo"]["body_mm"] = [30.0, 12.1, 25.3]
    document["palm"]["thickness_mm"] = 32.6
    path, runs = _refused_by_the_command_line(tmp_path, capsys, document)
    want = (f"error: {path}: servo.body_mm = [30.0, 12.1, 25.3]: a body 30 mm long leaves the flange ears "
            "(servo.flange_span_mm = 32.3) too short for their screw pilots (1.800 mm, mid-ear, with "
            "hole_compensation) and a 0.8 mm wall to the body's pocket: the length must be <= 24.700 mm")
    for code, err, files in runs:
        assert (code, err, files) == (2, [want], ["hand.toml"])
    document["servo"]["body_mm"] = [24.69, 12.1, 25.3]
    parse(document)


def test_the_thenar_keeps_clear_of_the_finger_sockets_magnet_pockets(tmp_path, capsys, document):
    """The CMC 25.085 mm behind the index MCP (from 73.78; found with a 2.5 mm screw, which plays no
    part): the CMC pulley's cavity (radius 8 + its margin, about the CMC axis) reaches 0.414 mm into
    the index socket's radial magnet pocket and the palm's check finds 7 pockets of 8. Refused
    below a 0.8 mm gap; at 26.99 mm the gap is 0.80 mm (the palm builds:
    tests/cad/test_found_by_the_property_test.py)."""
    document["palm"]["thumb_cmc_offset_mm"] = [-25.75, -25.085, -32.81]
    document["hardware"]["screw_diameter_mm"] = 2.5
    path, runs = _refused_by_the_command_line(tmp_path, capsys, document)
    want = (f"error: {path}: palm.thumb_cmc_offset_mm = [-25.75, -25.085, -32.81]: with palm.thumb_cmc_axis_deg "
            "the palm's CMC pulley's cavity comes -0.414 mm from the fingers.index socket's magnet pockets "
            "(negative: into them); the gap must be >= 0.8 mm, two perimeters")
    for code, err, files in runs:
        assert (code, err, files) == (2, [want], ["hand.toml"])


def test_servo_6s_flange_pilots_open_inside_the_forearm_module(tmp_path, capsys, document):
    """A servo body 34.36 mm wide (found by the property test; 21 mm is enough): the row spaces the
    servos by their width, servo 6 (u6, its shaft along the tilted CMC axis, its pulley in the CMC
    pulley's plane) moves radial and, in that tilted plane, up: its radial flange pilot opens 17.3 mm
    above the module's top (12 + 2.4 mm) and the forearm's check finds 11 pilots of 12. At 20 mm it
    opens 0.06 mm below the top and the forearm builds (tests/cad/test_found_by_the_property_test.py)."""
    document["servo"]["body_mm"] = [23.2, 34.355052, 25.3]
    path, runs = _refused_by_the_command_line(tmp_path, capsys, document)
    want = (f"error: {path}: servo.body_mm = [23.2, 34.355052, 25.3]: places servo u6's flange screw pilot "
            "17.318 mm above the forearm module's top (palm.thickness_mm / 2 + palm.wall_mm = 14.4 mm): the pilot "
            "must open at or below it, so that the screw's thread gets its full depth in the module")
    for code, err, files in runs:
        assert (code, err, files) == (2, [want], ["hand.toml"])


def test_the_cmc_base_keeps_clear_of_the_palms_heel(tmp_path, capsys, document):
    """The CMC 54.1 mm below the index MCP (from 32.81; found by the property test, seed 7, and with
    a 2.5 mm screw, which plays no part): along the tilted CMC axis the CMC base moves ulnar under
    the palm's heel, its column and hub 5.4 mm into it, and the build stops: palm x thumb_cmc_base
    210 mm^3 at rest. Refused below a clearance (0.2 mm); at 40.0 mm the gap is 0.242 mm and the
    two parts stand apart (tests/cad/test_found_by_the_property_test.py)."""
    document["palm"]["thumb_cmc_offset_mm"] = [-25.75, -73.78, -54.104009]
    document["hardware"]["screw_diameter_mm"] = 2.5
    path, runs = _refused_by_the_command_line(tmp_path, capsys, document)
    want = (f"error: {path}: palm.thumb_cmc_offset_mm = [-25.75, -73.78, -54.104009]: with palm.thumb_cmc_axis_deg "
            "and the palm's heel (palm.heel_height_mm = 11, palm.heel_length_mm = 43.8) the CMC base (its hub, its "
            "column up to the palm and its arm) comes -5.395 mm from the heel (negative: into it); the gap must be "
            ">= print.hole_clearance_mm = 0.2 mm")
    for code, err, files in runs:
        assert (code, err, files) == (2, [want], ["hand.toml"])


def test_tendons_too_soft_for_the_routed_statics(tmp_path, capsys, document):
    """The model's compensation is the printed routing's statics (kinematics.statics): each loop
    carries the return cord's pull on every joint beyond it and stretches over its whole strand, so
    it takes back more of a coupled joint's motion than the paper's eq. (13) says. At EA = 35 N the
    middle finger's DIP would extend while its MCP flexes (eq. 13 alone still gives it a positive
    coupling down to about 24 N): ``params validate`` and ``build`` refuse the file, as ``Hand``
    would; at 50 N it validates."""
    document["mechanics"]["tendon_EA_N"] = 35.0
    parse(document)                                   # eq. (13)'s own check passes
    path, runs = _refused_by_the_command_line(tmp_path, capsys, document)
    for code, err, files in runs:
        assert code == 2 and files == ["hand.toml"] and len(err) == 1, (code, err, files)
        assert err[0].startswith(f"error: {path}: mechanics.tendon_EA_N = 35.0: with spring_k_N_per_m = 200 the "
                                 "strands' stretch (the routed statics) leaves middle DIP a coupling of -0.1"), err
    from phantom_cad.cad import preflight

    document["mechanics"]["tendon_EA_N"] = 50.0
    preflight.check(parse(document))
