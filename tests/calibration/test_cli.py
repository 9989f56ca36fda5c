"""The four commands end to end: simulate -> diagnose -> fit -> a parameter file the model uses."""

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from phantom_cad import load_hand
from phantom_cad.calibration.data import read_measurements

pytestmark = pytest.mark.slow     # each test runs the command line in processes of its own


def run(*args):
    return subprocess.run([str(Path(sys.executable).parent / "phantom-cad"), *map(str, args)],
                          capture_output=True, text=True)


@pytest.fixture(scope="module")
def workflow(tmp_path_factory):
    d = tmp_path_factory.mktemp("cal")
    data = d / "sim.csv"
    r = run("simulate", "--effects", "tendon_slack,joint_offset", "--seed", "3", "--points", "15",
            "--effect-param", "tendon_slack.u2_deg=3", "--out", data)
    assert r.returncode == 0, r.stderr
    return d, data


def test_simulate_writes_the_format(workflow):
    _, data = workflow
    m = read_measurements(data)
    assert len(m) == 6 * 30 and m.sweep_ids == ("u1", "u2", "u3", "u4", "u5", "u6")
    assert "# hidden: tendon_slack: u2_deg=3; joint_offset:" in data.read_text()
    # the measured servo sweeps flex then extend over the whole travel
    hand = load_hand()
    u2 = m.u[m.sweep == 1, 1]
    assert u2.max() == pytest.approx(hand.u_max[1]) and u2[0] == u2[-1] == 0.0


def test_diagnose_json_and_report(workflow):
    d, data = workflow
    r = run("diagnose", data, "--json", d / "d.json", "--report", d / "rep")
    assert r.returncode == 0, r.stderr
    out = json.loads((d / "d.json").read_text())
    assert sorted(out["selected"]) == ["joint_offset", "tendon_slack"]
    assert out["mae_deg_after"] < 0.15 < 1.0 < out["mae_deg_before"]
    slack = out["effects"]["tendon_slack"]["parameters"]
    assert set(slack) == {f"u{j}_deg" for j in range(1, 6)}
    assert slack["u2_deg"]["value"] == pytest.approx(3.0, abs=3 * slack["u2_deg"]["std"] + 0.05)
    for k in ("u1_deg", "u3_deg", "u4_deg", "u5_deg"):   # explicit u2 only: the others are 0
        assert abs(slack[k]["value"]) < 3 * slack[k]["std"] + 0.05
    assert "why: joints lag by a constant servo angle" in r.stdout
    # every joint's MAE falls from well above the floor: none is flagged as made worse
    assert out["made_worse"] == [] and "made worse" not in r.stdout
    for png in ("residual_before.png", "residual_after.png", "mae.png", "hysteresis.png"):
        assert (d / "rep" / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "![MAE](mae.png)" in (d / "rep" / "report.md").read_text()


def test_fit_writes_a_parameter_file_the_control_law_uses(workflow):
    d, data = workflow
    out = d / "calibrated.toml"
    r = run("fit", data, "--effects", "tendon_slack,joint_offset", "--out", out)
    assert r.returncode == 0, r.stderr
    hand = load_hand(out)
    assert hand.effects.names == ("tendon_slack", "tendon_elasticity", "joint_offset")
    m = read_measurements(data)
    q = hand.forward(m.u, compensated=True)
    resid = np.degrees(np.nanmean(np.abs(m.q - q)))
    assert resid < 0.15                          # the calibrated model reproduces the measurements
    plain = load_hand()
    assert np.degrees(np.nanmean(np.abs(m.q - plain.forward(m.u)))) > 1.0
    # the control law now inverts the calibrated hand: the pose the real hand reaches at u0 is
    # commanded back as u0; the uncalibrated law misses it by the slack and the offsets
    u0 = np.array([0.3, 0.8, 0.5, 0.9, 0.7, 0.6])
    target = hand.forward(u0, compensated=True)
    assert np.allclose(hand.inverse(target, compensated=True), u0, atol=1e-9)
    assert math.degrees(abs(plain.inverse(target, compensated=False)[1] - u0[1])) > 2.0


def test_fitted_friction_survives_the_parameter_file(tmp_path):
    # friction fitted without elasticity: `fit` writes tendon_elasticity.compliance_per_m = 0, which
    # must switch the base compensation off without also switching the friction off
    data, out = tmp_path / "fr.csv", tmp_path / "fr.toml"
    r = run("simulate", "--effects", "friction_hysteresis", "--effect-param", "friction_hysteresis.mu=0.2",
            "--seed", "5", "--points", "20", "--out", data)
    assert r.returncode == 0, r.stderr
    r = run("fit", data, "--effects", "friction_hysteresis", "--out", out)
    assert r.returncode == 0, r.stderr
    assert load_hand(out).params.effects["tendon_elasticity"]["compliance_per_m"] == 0.0
    r = run("compare", data, "--params", out, "--report", tmp_path / "cmp")
    assert r.returncode == 0, r.stderr
    metrics = json.loads((tmp_path / "cmp" / "metrics.json").read_text())
    floor = 0.1 * math.sqrt(2 / math.pi)          # MAE of N(0, 0.1 deg) noise
    assert metrics["before"]["overall"]["mae"] > 2 * floor
    assert metrics["after"]["overall"]["mae"] < 1.5 * floor


def test_compare_prints_metrics(workflow):
    d, data = workflow
    r = run("compare", data, "--effects", "tendon_slack", "--report", d / "cmp")
    assert r.returncode == 0, r.stderr
    assert "after = fitted tendon_slack" in r.stdout
    metrics = json.loads((d / "cmp" / "metrics.json").read_text())
    assert metrics["after"]["overall"]["mae"] < metrics["before"]["overall"]["mae"]
    assert set(metrics["before"]["per_joint"]["q3"]) == {"mae", "rms", "max", "n"}


@pytest.mark.parametrize("args, message", [
    (["diagnose", "{dir}/missing.csv"], "error: {dir}/missing.csv: no such file"),
    (["simulate", "--effects", "gravity", "--out", "{dir}/x.csv"],
     "error: --effects gravity: unknown effect 'gravity' (known: tendon_slack, pulley_radius_error, "
     "tendon_elasticity, tendon_elasticity_per_finger, friction_hysteresis, joint_offset, camera_scale, "
     "backlash, drive_friction, routed_elasticity, routed_elasticity_per_finger, or none)"),
    (["simulate", "--effects", "tendon_slack", "--effect-param", "friction_hysteresis.mu=0.1", "--out", "{dir}/x.csv"],
     "error: --effect-param friction_hysteresis.*: effect 'friction_hysteresis' is not in --effects"),
    (["simulate", "--effects", "friction_hysteresis", "--effect-param", "friction_hysteresis.mu=3", "--out",
      "{dir}/x.csv"],
     "error: --effect-param: effects.friction_hysteresis.mu = 3.0: must lie in [0, 1] (physical bounds: "
     "friction coefficient of the tendon on its pulleys and guides)"),
    (["fit", "{dir}/bad.csv", "--effects", "joint_offset", "--out", "{dir}/c.toml"],
     "error: {dir}/bad.csv, line 3, column u2: 45 looks like degrees (angles are radians, |angle| <= 2 pi); "
     "convert it or pass --degrees"),
])
def test_bad_input_exit_2(tmp_path, args, message):
    (tmp_path / "bad.csv").write_text("u1,u2,u3,u4,u5,u6,q3\n0,0,0,0,0,0,0\n0,45,0,0,0,0,0.5\n")
    r = run(*[a.format(dir=tmp_path) for a in args])
    assert r.returncode == 2
    assert r.stderr.strip() == message.format(dir=tmp_path)
    assert not (tmp_path / "x.csv").exists() and not (tmp_path / "c.toml").exists()


def test_calibration_commands_do_not_import_cad():
    code = ("import sys; from phantom_cad import cli; import phantom_cad.cli.calibration, "
            "phantom_cad.calibration.diagnose, phantom_cad.calibration.report; "
            "print(any(m.split('.')[0] in ('OCP', 'build123d', 'cadquery') for m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.stdout.strip() == "False"


def test_simulate_is_deterministic(tmp_path):
    for name in ("a.csv", "b.csv"):
        r = run("simulate", "--effects", "friction_hysteresis,joint_offset", "--seed", "5", "--points", "4",
                "--out", tmp_path / name)
        assert r.returncode == 0, r.stderr
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    r = run("simulate", "--effects", "friction_hysteresis,joint_offset", "--seed", "6", "--points", "4",
            "--out", tmp_path / "c.csv")
    assert (tmp_path / "a.csv").read_bytes() != (tmp_path / "c.csv").read_bytes()


def test_simulate_degrees_reads_back_as_the_radian_file(tmp_path):
    rad, deg = tmp_path / "rad.csv", tmp_path / "deg.csv"
    for path, extra in ((rad, []), (deg, ["--degrees"])):
        r = run("simulate", "--effects", "tendon_slack", "--seed", "2", "--points", "5", "--out", path, *extra)
        assert r.returncode == 0, r.stderr
    a, b = read_measurements(rad), read_measurements(deg, degrees=True)
    assert np.allclose(a.u, b.u, atol=1e-10)
    assert np.allclose(a.q, b.q, atol=1e-10, equal_nan=True)
    # the file itself holds degrees: its largest servo cell is the radian file's, converted
    cells = [float(x) for line in deg.read_text().splitlines() if not line.startswith(("#", "sweep"))
             for x in line.split(",")[1:7]]
    assert max(cells) == pytest.approx(math.degrees(a.u.max()), abs=1e-8)


@pytest.mark.parametrize("args, message", [
    # NaN noise would write a file of empty cells; a negative seed and 1e8 points would crash
    (["simulate", "--noise-deg", "nan", "--out", "{dir}/x.csv"], "error: --noise-deg nan: must be a finite number >= 0"),
    (["simulate", "--seed", "-1", "--out", "{dir}/x.csv"], "error: --seed -1: must be >= 0"),
    (["simulate", "--points", "100000000", "--out", "{dir}/x.csv"],
     "error: --points 100000000: must be in [2, 100000] (the file has about 12 x points rows)"),
    # a file without joint columns: fit wrote an empty calibrated file (MAE nan), compare crashed
    (["fit", "{dir}/nojoints.csv", "--effects", "joint_offset", "--out", "{dir}/c.toml"],
     "error: {dir}/nojoints.csv: no joint angle was measured (every q cell is empty)"),
    (["compare", "{dir}/nojoints.csv"], "error: {dir}/nojoints.csv: no joint angle was measured (every q cell is empty)"),
])
def test_refused_without_writing(tmp_path, args, message):
    (tmp_path / "nojoints.csv").write_text("u1,u2,u3,u4,u5,u6\n0,0,0,0,0,0\n0,0.5,0,0,0,0\n0,1.0,0,0,0,0\n")
    r = run(*[a.format(dir=tmp_path) for a in args])
    assert r.returncode == 2
    assert r.stderr.strip() == message.format(dir=tmp_path)
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "x.csv").exists() and not (tmp_path / "c.toml").exists()
