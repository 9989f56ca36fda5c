"""The fingertip force model (kinematics.force) against a straight finger worked by hand, against
the virtual work of the tendons and the plate along the figure-eight coupling (finite differences
of the chord, the return cord and the pad's position, not the model's levers), and the pad's
levers against finite differences of the pad's position."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad import Hand, load_params
from phantom_cad.kinematics import force
from phantom_cad.kinematics.frames import T_distal_pad, fingertip
from phantom_cad.kinematics.link_frames import link_transforms
from phantom_cad.kinematics.topology import CMC_Q, DIGITS, N_JOINTS, chain, digit_links
from phantom_cad.params import parse
from tests.support.hands import hand_document


@pytest.fixture(scope="module")
def params():
    return load_params()


@pytest.fixture(scope="module")
def posture(params):
    """Every servo at half its travel, the joints where the routed statics put them."""
    hand = Hand(params)
    return hand.forward((hand.u_min + hand.u_max) / 2.0, compensated=True)


def _pad(params, q, digit):
    """(p, n) of the pad, palm frame, from the link frames and the pad's frame alone."""
    T = link_transforms(params, q)[digit_links(digit)[-1].name] @ T_distal_pad(params, digit)
    return T[:3, 3], T[:3, 2]


def test_a_straight_index_pressing_a_plate_as_worked_by_hand(params):
    """q = 0: the return cord is slack (T = k_s R.q = 0) and the pad normal, 45 deg from the palmar
    face, has the lever y / sqrt 2 - r / 2 about a joint y ahead of it along the finger (the pad at
    depth r / sqrt 2 below the tip's axis). With R = 5:4:5 the coupling weights are 1, 1.25, 1, the
    drive's arm d1 d2 sin(alpha) / L0: f = (tau / r_s) arm / (m_MCP + 1.25 m_PIP + m_DIP)."""
    f = params.fingers["index"]
    g = f.chain.guide
    _, r, _ = fingertip(params, "index")
    tip = f.distal - r + r / math.sqrt(2.0)                 # pad's y ahead of the DIP axis
    ys = (f.proximal + f.middle + tip, f.middle + tip, tip)  # MCP, PIP, DIP
    m = [y / math.sqrt(2.0) - r / 2.0 for y in ys]
    L0 = math.sqrt(g.d1 ** 2 + g.d2 ** 2 - 2.0 * g.d1 * g.d2 * math.cos(g.alpha))
    arm = g.d1 * g.d2 * math.sin(g.alpha) / L0
    expected = params.servo.stall_torque / f.chain.servo_radius * arm / (m[0] + 1.25 * m[1] + m[2])
    got = force.digit_force(params, np.zeros(N_JOINTS), "index")
    assert got.force == pytest.approx(expected, rel=1e-12)
    assert got.return_tension == 0.0
    assert got.levers == pytest.approx(m, rel=1e-12)
    # the loops: the DIP's torque f m_DIP over R_DIP on the PIP-DIP loop, plus the PIP's on the MCP-PIP one
    R = f.chain.radii
    assert got.loop_tensions == pytest.approx([got.force * (m[1] / R[1] + m[2] / R[2]), got.force * m[2] / R[2]])


@pytest.mark.parametrize("digit", DIGITS)
def test_the_force_does_the_virtual_work_of_the_tendons(params, posture, digit):
    """Flex the chain by ds along the figure-eight coupling (q_k += (R_0 / R_k) ds): the drive
    shortens by dc (the chord by the law of cosines), the return cord lengthens by R.A ds, the pad
    moves into the plate by n.dp. At equilibrium F_d dc - T R.A ds = f n.dp."""
    c = params.digit(digit).chain
    R = np.asarray(c.radii)
    A = R[0] / R
    g = c.guide
    idx = list(c.spec.q_index)

    def chord(q0):
        return math.sqrt(g.d1 ** 2 + g.d2 ** 2 - 2.0 * g.d1 * g.d2 * math.cos(g.alpha - q0))

    h = 1e-6
    lo, hi = posture.copy(), posture.copy()
    lo[idx] -= A * h
    hi[idx] += A * h
    shortening = (chord(lo[idx[0]]) - chord(hi[idx[0]])) / (2 * h)
    (p_lo, _), (p_hi, _), (_, n) = _pad(params, lo, digit), _pad(params, hi, digit), _pad(params, posture, digit)
    into = float(n @ (p_hi - p_lo)) / (2 * h)
    T = params.mechanics.spring_k * float(R @ posture[idx])
    drive = params.servo.stall_torque / c.servo_radius
    expected = (drive * shortening - T * float(R @ A)) / into
    got = force.digit_force(params, posture, digit)
    assert got.force == pytest.approx(expected, rel=1e-7)
    assert got.force > 0.0
    assert got.return_tension == pytest.approx(T)


@pytest.mark.parametrize("digit", DIGITS)
def test_the_levers_are_the_pads_normal_velocity(params, posture, digit):
    joints = list(chain(digit).q_index) + ([CMC_Q] if digit == "thumb" else [])
    _, n, levers = force.pad_levers(params, posture, digit)
    h = 1e-6
    for k, i in enumerate(joints):
        lo, hi = posture.copy(), posture.copy()
        lo[i] -= h
        hi[i] += h
        rate = float(n @ (_pad(params, hi, digit)[0] - _pad(params, lo, digit)[0])) / (2 * h)
        assert levers[k] == pytest.approx(rate, rel=1e-6, abs=1e-10)


def test_a_left_hand_presses_as_hard_as_a_right_one(params, posture):
    doc = hand_document("default")
    doc["hand"]["side"] = "left"
    left = parse(doc)
    for a, b in zip(force.fingertip_forces(params, posture), force.fingertip_forces(left, posture)):
        assert a.force == pytest.approx(b.force, rel=1e-12)


def test_the_force_is_affine_in_the_stall_torque(params, posture):
    """Twice the torque gives twice the drive's share; the return cord's share stays."""
    f0, f1, f2 = (np.array([x.force for x in force.fingertip_forces(params, posture, t)]) for t in (0.0, 0.2, 0.4))
    assert f2 - f1 == pytest.approx(f1 - f0, rel=1e-12)
    assert np.all(f0 < 0.0)     # without the servo the return cord pulls the pads off the plates


# -- the servo catalogue ------------------------------------------------------------

def test_the_default_file_writes_out_the_scs0009(params):
    from phantom_cad.params import servos

    entry = servos.CATALOGUE[servos.DEFAULT]
    assert params.servo.model is None and servos.named(params.servo) == servos.DEFAULT
    assert params.servo.stall_torque == entry.stall_torque_Nm
    assert [round(v * 1e3, 9) for v in params.servo.body] == list(entry.body_mm)
    assert round(params.servo.flange_span * 1e3, 9) == entry.flange_span_mm


def test_a_file_names_a_catalogue_servo_and_its_own_numbers_win():
    from phantom_cad.params import servos

    doc = hand_document("default")
    doc["servo"] = {"model": "mg90s", "stall_torque_Nm": 0.2}
    got = parse(doc).servo
    entry = servos.CATALOGUE["mg90s"]
    assert got.model == "mg90s" and got.stall_torque == 0.2
    assert got.speed == pytest.approx(math.radians(entry.speed_deg_s))
    assert [v * 1e3 for v in got.body] == pytest.approx(entry.body_mm)


@pytest.mark.parametrize("servo, message", [
    ({"model": "sg90"}, "servo.model = 'sg90': must be one of: scs0009, mg90s, xl330-m288"),
    ({"model": "xl330-m288"}, "servo.flange_span_mm = None: is required: the catalogue's xl330-m288"),
])
def test_a_bad_servo_is_one_line(servo, message):
    from phantom_cad.params import ParamError

    doc = hand_document("default")
    doc["servo"] = servo
    with pytest.raises(ParamError) as err:
        parse(doc)
    assert message in str(err.value) and "\n" not in str(err.value)


# -- the command --------------------------------------------------------------------

def _run(capsys, *args):
    from phantom_cad.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["force", *args])
    out = capsys.readouterr()
    return exit_.value.code, out.out, out.err


def test_the_command_prints_the_model_at_half_travel(capsys, params, posture):
    import json

    code, out, _ = _run(capsys, "--json")
    assert code == 0
    got = json.loads(out)
    assert got["servo"] == "scs0009" and got["stall_torque_Nm"] == 0.226
    for f in force.fingertip_forces(params, posture):
        assert got["digits"][f.digit]["force_N"] == pytest.approx(f.force, abs=1e-6)
    code, out, _ = _run(capsys)
    assert code == 0 and out.splitlines()[2].split()[:2] == ["thumb", f"{got['digits']['thumb']['force_N']:.2f}"]


def test_the_command_scales_with_a_catalogue_servo(capsys):
    import json

    half = json.loads(_run(capsys, "--json")[1])["digits"]
    xl = json.loads(_run(capsys, "--json", "--servo", "xl330-m288")[1])["digits"]
    assert xl["index"]["drive_tension_N"] == pytest.approx(half["index"]["drive_tension_N"] * 0.52 / 0.226)
    assert xl["index"]["force_N"] > 2.0 * half["index"]["force_N"]


@pytest.mark.parametrize("args, message", [
    (("--u", "1,2"), "--u '1,2': must be 6 comma-separated angles in degrees"),
    (("--u", "100,0,0,0,0,0"), "--u: u1 = 100 deg is outside its travel [0, 81.5] deg"),
    (("--q", "0,0,0,0,0,0,0,0,0,0,0,0,0,0,100"), "--q: q15 = 100 deg is outside Table I's [0, 89.9544] deg"),
    (("--u", "0,0,0,0,0,0", "--q", "0"), "--u and --q: give the posture one way"),
    (("--servo", "sg90"), "--servo 'sg90': not in the catalogue (scs0009, mg90s, xl330-m288)"),
])
def test_bad_input_is_one_error_line(capsys, args, message):
    code, out, err = _run(capsys, *args)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and message in err and err.count("\n") == 1


def test_force_imports_no_cad_library():
    import subprocess
    import sys

    code = ("import sys; from phantom_cad.cli import main\n"
            "try:\n"
            "    main(['force'])\n"
            "except SystemExit as e:\n"
            "    assert e.code == 0, e.code\n"
            "assert not any(m.split('.')[0] in ('build123d', 'OCP', 'cadquery', 'mujoco') for m in sys.modules)\n")
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)


def test_size_reports_the_forces_at_half_travel(params, posture):
    from phantom_cad.cli.size import report

    line = report(params, searched=False)[-1]
    assert line.startswith("fingertip force at half travel")
    assert line.endswith(", ".join(f"{f.digit} {f.force:.2f}" for f in force.fingertip_forces(params, posture)))
