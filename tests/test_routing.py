"""The routing model (kinematics/routing.py): every tendon's path, against the mechanism by hand.

Known answers from the parameter files' numbers and the paper's equations, computed here: a loop
strand between joints a and b changes by +-(R_a q_a - R_b q_b) (eq. 2 holds exactly when it keeps
its length), the drive by chord(q_ref) - chord(0) + r u (held joints, the servo winding r u
would stretch it by r u: the chord must shorten by r u, eq. 4-5), the return cord by sum R_i q_i
(eq. 11). MuJoCo's own wrapping of the same routes is compared in tests/export/test_mjcf.py.
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from phantom_cad.kinematics import couplers
from phantom_cad.kinematics import routing
from phantom_cad.kinematics import routing_json
from phantom_cad.kinematics import routing_paths
from phantom_cad.kinematics.model import Hand
from phantom_cad.kinematics.topology import JOINT_NAMES, SERVOS, TENDONS
from phantom_cad.params.io import load_params

ROOT = Path(__file__).resolve().parents[1]
FILES = (ROOT / "params" / "phantom.toml", ROOT / "params" / "examples" / "slender.toml",
         ROOT / "params" / "examples" / "small.toml")
DIGITS = ("thumb", "index", "middle", "ring", "pinky")
KEYS = {"thumb": ("mp", "ip"), **{f: ("mcp", "pip", "dip") for f in DIGITS[1:]}}


def _table(doc, digit):
    return doc["thumb"] if digit == "thumb" else doc["fingers"][digit]


def _params(path, side):
    from phantom_cad.params import load_document, parse

    doc = load_document(path)
    doc["hand"]["side"] = side
    return parse(doc, str(path))


CASES = [(path, side) for path in FILES for side in ("right", "left")]


@pytest.mark.parametrize("path,side", CASES, ids=[f"{p.stem}-{s}" for p, s in CASES])
@pytest.mark.slow
def test_lengths_are_the_mechanism(path, side):
    p = _params(path, side)
    doc = tomllib.loads(path.read_text())
    rest = routing_paths.lengths(p)
    assert {s for r in routing.routes(p) for s in [r.name]} == {t.name for t in TENDONS}
    rng = np.random.default_rng(11)
    for _ in range(8):
        q = rng.uniform(0.0, 1.3, len(JOINT_NAMES))
        u = rng.uniform(0.0, 1.4, len(SERVOS))
        got = routing_paths.lengths(p, q, u)
        qn = dict(zip(JOINT_NAMES, q))
        for k, digit in enumerate(DIGITS):
            t = _table(doc, digit)
            R = {j: v / 1000.0 for j, v in t["pulley_radius_mm"].items()}
            keys = KEYS[digit]
            for a, b in zip(keys, keys[1:]):
                want = R[a] * qn[f"{digit}_{a}"] - R[b] * qn[f"{digit}_{b}"]
                assert got[f"{digit}_{a}_{b}_a"] - rest[f"{digit}_{a}_{b}_a"] == pytest.approx(want, abs=1e-9)
                assert got[f"{digit}_{a}_{b}_b"] - rest[f"{digit}_{a}_{b}_b"] == pytest.approx(-want, abs=1e-9)
            g = t["guide"]
            d1, d2, alpha = g["d1_mm"] / 1000.0, g["d2_mm"] / 1000.0, math.radians(g["alpha_deg"])
            chord = lambda x: math.sqrt(d1 * d1 + d2 * d2 - 2.0 * d1 * d2 * math.cos(alpha - x))  # noqa: E731
            r = t["servo_pulley_radius_mm"] / 1000.0
            want = chord(qn[f"{digit}_{keys[0]}"]) - chord(0.0) + r * u[k]
            assert got[f"{digit}_drive"] - rest[f"{digit}_drive"] == pytest.approx(want, abs=1e-9), digit
            want = sum(R[j] * qn[f"{digit}_{j}"] for j in keys)
            assert got[f"{digit}_return"] - rest[f"{digit}_return"] == pytest.approx(want, abs=1e-9), digit


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
@pytest.mark.slow
def test_over_the_travel_the_loops_hold_and_the_drive_winds(path):
    """Along the model's coupled motion (hand.forward, uncompensated) at 20 commands over each
    servo's travel: every loop strand within 0.02 mm of its rest length, the drive's free part
    shortened by exactly what the servo winds (its whole length within 0.02 mm); a joint leaving
    the coupling by 1 degree changes its loops by >= 0.05 mm."""
    p = load_params(path)
    hand = Hand(p)
    rest = routing_paths.lengths(p)
    loops = [n for n in rest if n.endswith(("_a", "_b"))]
    for frac in np.linspace(0.0, 1.0, 20):
        u = np.array([lo + frac * (hi - lo) for lo, hi in
                      [p.digit(s.digit).chain.travel if s.drive == "tendon" else p.thumb.cmc_travel for s in SERVOS]])
        q = hand.forward(u, compensated=False)
        got = routing_paths.lengths(p, q, u)
        assert max(abs(got[n] - rest[n]) for n in loops) < 2e-5
        assert max(abs(got[f"{d}_drive"] - rest[f"{d}_drive"]) for d in DIGITS) < 2e-5
        for j, name in enumerate(JOINT_NAMES):
            if name.endswith(("_mcp", "_mp", "_cmc")):
                continue
            q2 = q.copy()
            q2[j] += math.radians(1.0)
            moved = routing_paths.lengths(p, q2, u)
            digit = name.split("_")[0]
            assert max(abs(moved[n] - got[n]) for n in loops if n.startswith(digit)) >= 5e-5, name


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_layout_keeps_the_planes_apart(path):
    """In every digit: the loop planes lie inside the slot, one groove and a flank from its edge,
    on alternating sides; the return cord's groove lies in the tongue the second hub leaves,
    a flank from it and from every loop groove."""
    p = load_params(path)
    doc = tomllib.loads(path.read_text())
    for digit in DIGITS:
        t = _table(doc, digit)
        c = doc["print"]["hole_clearance_mm"]
        g = doc["hardware"]["tendon_diameter_mm"] + 2 * c
        gr = doc["cad"]["spring_diameter_mm"] + 2 * c
        s = (t["width_mm"] - 2 * doc["cad"]["cheek_mm"]) / 2
        lay = routing.layout(p, digit)
        xs = [x * 1000 for x in lay.loop_x]
        assert [math.copysign(1, x) for x in xs] == [(-1) ** k for k in range(len(xs))]
        for x in xs:
            assert abs(x) + g / 2 + 0.8 + c == pytest.approx(s, abs=1e-9)
        xr = lay.return_x * 1000
        for x in xs:
            assert abs(xr - x) >= (g + gr) / 2 + 0.8 - 1e-9, digit


def test_routing_document_round_trips(tmp_path):
    p = load_params(FILES[0])
    doc = routing_json.document(p)
    text = json.dumps(doc)
    back = json.loads(text)
    assert [t["name"] for t in back["tendons"]] == [t.name for t in TENDONS]
    rest = routing_paths.lengths(p)
    for t in back["tendons"]:
        assert t["kind"] in ("drive", "coupling", "return", "loop")
        assert len(t["strands"]) == (2 if t["kind"] in ("coupling", "loop") else 1)
        for s in t["strands"]:
            assert s["rest_length_mm"] == pytest.approx(rest[s["name"]] * 1000, abs=1e-6)
            kinds = [e["type"] for e in s["elements"]]
            assert kinds[0] == "anchor" and kinds[-1] == "anchor"
            for k, e in enumerate(s["elements"]):
                if e["type"] == "pulley":       # bracketed by points, as MuJoCo's spatial tendons need
                    assert kinds[k - 1] != "pulley" and kinds[k + 1] != "pulley"


@pytest.mark.parametrize("path,side", CASES, ids=[f"{p.stem}-{s}" for p, s in CASES])
def test_the_finger_drives_are_split_at_the_socket(path, side):
    """The coupler of each finger drive by hand from the file (docs/transmission.md): its envelope
    stop + 2 cords by 1 + stop + 3 cords, its bore two clearances wider, at rest 2 clearances in
    from the socket face and r u_max deeper at full travel; the service angle unwinds the wrap
    from 172 deg at u_max to 8 deg, paying out r (164 deg - travel); its run is the distance from
    the socket's tendon point to the servo pulley's tangent point (frames), its channel that less
    the pulley cavity's reach sqrt((r + m)^2 - r^2); the two strands add up to the drive."""
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics import frames as Fr
    from phantom_cad.kinematics.topology import chain

    p = _params(path, side)
    doc = tomllib.loads(path.read_text())
    hw, c = doc["hardware"], doc["print"]["hole_clearance_mm"]
    stop = hw.get("tendon_stop", {"diameter_mm": 2.0, "length_mm": 3.0})
    d = hw["tendon_diameter_mm"]
    cps = couplers.couplers(p)
    assert sorted(cps) == ["index", "middle", "pinky", "ring"]          # the thumb is not detachable
    rest = routing_paths.lengths(p)
    for f, cp in cps.items():
        src = doc["fingers"][f]
        r, travel = src["servo_pulley_radius_mm"], src["servo_travel_deg"][1]
        assert cp.diameter * 1e3 == pytest.approx(stop["diameter_mm"] + 2 * d)
        assert cp.length * 1e3 == pytest.approx(d + stop["length_mm"] + 3 * d)
        assert cp.bore * 1e3 == pytest.approx(stop["diameter_mm"] + 2 * d + 2 * c)
        assert cp.rest[0] * 1e3 == pytest.approx(2 * c)
        assert cp.full[1] * 1e3 == pytest.approx(2 * c + d + stop["length_mm"] + 3 * d + r * math.radians(travel))
        assert math.degrees(cp.service_angle) == pytest.approx(-(164.0 - travel))
        assert cp.payout * 1e3 == pytest.approx(r * math.radians(164.0 - travel))
        k = chain(f).servo
        exit_ = Fr.socket_tendon_point(p, f)
        tangent = (FL.T_palm_servo(p, k) @ np.array([-r * 1e-3, 0.0, 0.0, 1.0]))[:3]
        if side == "left":
            exit_ = np.diag([-1.0, 1.0, 1.0]) @ exit_
            tangent = np.diag([-1.0, 1.0, 1.0]) @ tangent
        assert cp.run == pytest.approx(float(np.linalg.norm(tangent - exit_)), abs=1e-9)
        lip, wiggle = 2 * d, d + c                       # the cavity: flanges, running room, clearance
        cavity = math.sqrt((r + lip + wiggle) ** 2 - r ** 2)
        assert cp.channel * 1e3 == pytest.approx(cp.run * 1e3 - cavity)
        assert cp.full[1] * 1e3 + c <= cp.channel * 1e3
        assert cp.palm_strand + cp.finger_strand == pytest.approx(rest[f"{f}_drive"], abs=1e-12)


def test_a_coupler_without_room_is_refused(monkeypatch):
    """Two rules, by hand for the default hand. A 4 mm stop makes the coupler 0.6 + 4 + 1.8 =
    6.4 mm long: at the service angle (164 - 93 = 71 deg of unwinding, 7 mm x 1.239 rad = 8.67 mm)
    the index's comes 8.67 - 0.4 - 6.4 = 1.87 mm out, less than the stop's 2 mm diameter. That rule
    binds first on the default hand: with the servos in the forearm module every drive runs more
    than 50 mm from its socket to its pulley. The channel rule is checked with a pulley cavity made
    to fill the run: the channel is the run (the tangent length from the socket's tendon exit to
    the pulley circle, both at the tendon height: sqrt(|E - C|^2 - r^2)) less the cavity's
    sqrt((r + m)^2 - r^2)."""
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics import frames as F
    from phantom_cad.params import ParamError, load_document, parse

    doc = load_document(FILES[0])
    doc["hardware"]["tendon_stop"] = {"diameter_mm": 2.0, "length_mm": 4.0}
    with pytest.raises(ParamError) as e:
        couplers.couplers(parse(doc))
    assert e.value.field == "hardware.tendon_stop.length_mm"
    assert "the index coupler (6.40 mm) comes 1.87 mm out of the socket" in str(e.value)
    for module, memo in ((routing, "_ROUTES"), (routing_paths, "_RUNS"), (couplers, "_COUPLERS")):
        monkeypatch.setattr(module, memo, {})
    p = parse(load_document(FILES[0]))
    E = F.socket_tendon_point(p, "index") * 1e3
    C = FL.T_palm_servo(p, 1)[:3, 3] * 1e3
    r = 7.0
    run = math.sqrt(float((E - C) @ (E - C)) - r * r)
    m = run                                      # a cavity margin as long as the run
    monkeypatch.setattr(couplers.F, "pulley_cavity_margin", lambda params: m * 1e-3)
    channel = run - math.sqrt((r + m) ** 2 - r * r)
    with pytest.raises(ParamError) as e:
        couplers.couplers(p)
    assert e.value.field == "hardware.tendon_stop.length_mm"
    travel = 7.0 * math.radians(93.0)
    need = 0.4 + (0.6 + 3.0 + 1.8) + travel + 0.2
    assert (f"the index drive's coupler (stop, loop and knot: 5.40 mm) travels {travel:.2f} mm" in str(e.value))
    assert f"needs {need:.2f} mm of channel, it has {channel:.2f} mm" in str(e.value)


def test_servo_boxes_and_wrist_by_hand():
    """The servo's body and flange-ear boxes (the one description the palm's pockets and the coming
    forearm layout use) and the wrist crease, from the file's numbers."""
    from phantom_cad.kinematics import servo_geometry as SG
    from phantom_cad.kinematics import frames as F

    path = ROOT / "params" / "phantom.toml"
    doc = tomllib.loads(path.read_text())
    p = load_params(path)
    L, W, H = doc["servo"]["body_mm"]
    cad, c = doc["cad"], doc["print"]["hole_clearance_mm"]
    top = -(cad["servo_pulley_width_mm"] / 2 + c)                  # the output face under the pulley
    off = cad["servo_shaft_offset_mm"]
    boxes = {k: (np.array(lo) * 1e3, np.array(hi) * 1e3) for k, (lo, hi) in SG.servo_boxes(p).items()}
    np.testing.assert_allclose(boxes["body"][0], [-W / 2, -off - L / 2, top - H], atol=1e-9)
    np.testing.assert_allclose(boxes["body"][1], [W / 2, -off + L / 2, top], atol=1e-9)
    ear_top = top - cad["servo_ear_offset_mm"]
    span = doc["servo"]["flange_span_mm"]
    np.testing.assert_allclose(boxes["ears"][0], [-W / 2, -off - span / 2, ear_top - cad["servo_ear_thickness_mm"]],
                               atol=1e-9)
    np.testing.assert_allclose(boxes["ears"][1], [W / 2, -off + span / 2, ear_top], atol=1e-9)
    hl = doc["hand"]["hand_length_mm"]
    assert F.wrist_y(p) * 1e3 == pytest.approx(-doc["fingers"]["index"]["length_fraction"]["metacarpal"] * hl)


@pytest.mark.parametrize("path,side", CASES, ids=[f"{p.stem}-{s}" for p, s in CASES])
@pytest.mark.slow
def test_the_cmc_loop_holds_q15_at_cmc_gain_u6(path, side):
    """The CMC loop's two strands (docs/transmission.md): turning servo 6's pulley by u6 changes
    their paths by +- r6 u6, turning the CMC by q15 by -+ (r6 / cmc_gain) q15, by hand from the file's
    r6 (both pulleys in one plane: the strands are straight and the wraps planar); so with q15 =
    cmc_gain u6 both keep their lengths over the whole travel."""
    p = _params(path, side)
    doc = tomllib.loads(Path(path).read_text())
    r6, g = doc["thumb"]["cmc_pulley_radius_mm"] * 1e-3, doc["thumb"]["cmc_gain"]
    rest = routing_paths.lengths(p)
    for u6 in np.linspace(0.0, math.radians(doc["thumb"]["cmc_servo_travel_deg"][1]), 7):
        q, u = np.zeros(15), np.zeros(6)
        u[5] = u6
        L = routing_paths.lengths(p, q, u)
        assert L["thumb_cmc_loop_a"] - rest["thumb_cmc_loop_a"] == pytest.approx(r6 * u6, abs=1e-12)
        assert L["thumb_cmc_loop_b"] - rest["thumb_cmc_loop_b"] == pytest.approx(-r6 * u6, abs=1e-12)
        q[14] = g * u6
        L = routing_paths.lengths(p, q, u)
        for s in ("a", "b"):
            assert L[f"thumb_cmc_loop_{s}"] == pytest.approx(rest[f"thumb_cmc_loop_{s}"], abs=1e-12)
