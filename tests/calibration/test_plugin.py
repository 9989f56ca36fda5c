"""A user's own effect end to end: --plugin on the four commands, a calibrated file that names its
plugin and is read by load_hand, params validate / show and compare -p; the fitted file reproduces
the fit (tendon_elasticity = 0 does not zero a user's tension-stage effect); an effect the
control law cannot invert is refused by fit; broken plugin files are named with their line.

The data: per-finger tendon compliance, written out here (eq. 13 by hand on the closed-form cosine
law of test_noise_floor), 0.1 deg noise."""

import json
import math
import re

import numpy as np
import pytest

from phantom_cad.calibration.data import write_measurements
from phantom_cad.calibration.labels import Labels

from ._cli import run_cli as run
from .test_noise_floor import NOISE_DEG, analytic, measure, sweeps

PLUGIN = '''"""A user's effect: the tendon compliance differs per finger."""
from phantom_cad.calibration.effects import Effect, Param, register_effect
from phantom_cad.kinematics.topology import CHAINS


@register_effect
class FingerCompliance(Effect):
    name = "finger_compliance"
    stage = "tension"
    order = 25                  # runs before tendon_elasticity (order 30)
    explanation = ("distal joints lag in proportion to flexion, by a different amount on each "
                   "finger: each tendon has its own compliance")
    formula = "k_s / EA of chain k = c_k (eq. 13 per finger)"
    signature = "negative on PIP/DIP/IP, growing with flexion, different per finger; MCP untouched"
    reference = "test plugin (docs/effects.md)"

    def parameters(self, hand):
        return [Param(f"{c.digit}_per_m", 0.0, 5.0, (0.05, 0.3), False, c.q_index[1:], True,
                      f"k_s / EA of the {c.digit} tendon, 1/m") for c in CHAINS]

    def apply(self, ctx, x):
        ctx.compliance += x     # adds to the base k_s / EA (0 in the analytic model)
'''

NOT_INVERTIBLE = '''from phantom_cad.calibration.effects import Effect, Param, register_effect


@register_effect
class CmcGain(Effect):
    name = "cmc_gain"
    stage = "joint"
    explanation = "q15 drifts in proportion to u6"

    def parameters(self, hand):
        return [Param("relative", -0.3, 0.3, (0.02, 0.05), True, (14,), True, "CMC gain error")]

    def apply(self, ctx, x):
        ctx.q[:, 14] += x[0] * ctx.s[:, 5]
'''

HIDDEN = {"thumb": 0.2, "index": 0.35, "middle": 0.1, "ring": 0.3, "pinky": 0.15}   # k_s / EA, 1/m


def compliant(hand, u):
    """q (N, 15): eq. (13)/(14) with the compliance of each finger, M q = A q_ref, written out here:
    row k >= 1 of M is e_k + C_k R with C_k = kappa (sum of the path lengths up to joint k) / R_k."""
    q = analytic(hand, u)
    for chain in hand.params.chains:
        kappa = HIDDEN[chain.spec.digit]
        R = np.array(chain.radii)
        A = R[0] / R
        M = np.eye(R.size)
        for k in range(1, R.size):
            M[k] += kappa * sum(chain.path_lengths[:k]) / R[k] * R
        v = np.linalg.solve(M, A)
        q_ref = q[:, chain.spec.q_index[0]]
        for k, qi in enumerate(chain.spec.q_index):
            q[:, qi] = v[k] * q_ref
    return q




@pytest.fixture(scope="module")
def files(hand, tmp_path_factory):
    d = tmp_path_factory.mktemp("plugin")
    (d / "plugins").mkdir()
    (d / "plugins" / "finger.py").write_text(PLUGIN)
    (d / "plugins" / "cmc_gain.py").write_text(NOT_INVERTIBLE)
    u, sweep, cj = sweeps(hand)
    m = measure(hand, u, sweep, cj, compliant(hand, u), seed=11)
    write_measurements(d / "data.csv", m.u, m.q, sweep=Labels(m.sweep_ids, m.sweep), q_columns=m.q_columns,
                       comments=["closed-form data with per-finger compliance (tests/calibration/test_plugin.py)"])
    return d


@pytest.fixture(scope="module")
def calibrated(files):
    """fit with the plugin on the module's data: (its process result, the calibrated file)."""
    out = files / "cal" / "calibrated.toml"
    (files / "cal").mkdir(exist_ok=True)
    r = run("fit", files / "data.csv", "--effects", "finger_compliance", "--out", out,
            "--plugin", files / "plugins" / "finger.py")
    return r, out


def mae_line(text, label):
    return float(re.search(label + r"\s+([0-9.]+)", text).group(1))


@pytest.mark.slow
def test_the_plugin_path_end_to_end(hand, files, calibrated):
    d = files
    data = d / "data.csv"
    r = run("fit", data, "--effects", "finger_compliance", "--out", d / "refused.toml")
    assert r.returncode == 2 and "unknown effect 'finger_compliance'" in r.stderr
    assert not (d / "refused.toml").exists()
    r, out = calibrated
    assert r.returncode == 0, r.stderr
    before, after = map(float, re.search(r"MAE ([0-9.]+) deg \(analytic\) -> ([0-9.]+) deg", r.stdout).groups())
    floor = NOISE_DEG * math.sqrt(2 / math.pi)
    assert before > 3 * floor and after <= 1.2 * floor
    text = out.read_text()
    assert 'plugins = [\n    "../plugins/finger.py",\n]' in text or 'plugins = ["../plugins/finger.py"]' in text
    # fitted per-finger compliances near the hidden ones
    from phantom_cad.params import load_document

    fitted = load_document(out)["effects"]["finger_compliance"]
    for digit, kappa in HIDDEN.items():
        assert fitted[f"{digit}_per_m"] == pytest.approx(kappa, rel=0.15), digit
    # a fresh process reads the calibrated file without any option
    r = run("params", "validate", out)
    assert r.returncode == 0 and r.stdout.startswith("OK "), r.stderr
    r = run("params", "show", "-p", out)
    assert r.returncode == 0, r.stderr
    r = run("compare", data, "-p", out)
    assert r.returncode == 0, r.stderr
    overall = re.search(r"overall\s+([0-9.]+)\s+[0-9.]+\s+[0-9.]+\s+([0-9.]+)", r.stdout)
    applied_before, applied_after = map(float, overall.groups())
    # what the calibrated file applies is what fit reported (tendon_elasticity = 0 must not
    # override the user's tension-stage effect)
    assert applied_after == pytest.approx(after, abs=0.0015)
    assert applied_before == pytest.approx(before, abs=0.0015)
    assert "calibrated (finger_compliance + tendon_elasticity)" in r.stdout


@pytest.mark.slow
def test_the_calibrated_control_law_uses_the_plugin(files, calibrated):
    from phantom_cad import load_hand
    from phantom_cad.calibration.effects import unload_plugin

    r, out = calibrated
    assert r.returncode == 0, r.stderr
    try:
        hand = load_hand(out)
        assert hand.effects.names == ("finger_compliance", "tendon_elasticity")
        u0 = np.array([0.3, 0.8, 0.5, 0.9, 0.7, 0.6])
        target = hand.forward(u0, compensated=True)
        assert np.allclose(hand.inverse(target, compensated=True), u0, atol=1e-9)
        # the index finger's hidden compliance bends its DIP by more than a degree at u2 = 0.8 rad
        assert math.degrees(abs(target[2] - load_hand().forward(u0)[2])) > 1.0
    finally:
        unload_plugin(files / "plugins" / "finger.py")


@pytest.mark.slow
def test_diagnose_and_simulate_take_the_plugin(files):
    d = files
    r = run("diagnose", d / "data.csv", "--plugin", d / "plugins" / "finger.py", "--json", d / "d.json",
            "--candidates", "finger_compliance,tendon_elasticity")
    assert r.returncode == 0, r.stderr
    out = json.loads((d / "d.json").read_text())
    assert out["selected"][0] == "finger_compliance"
    assert out["explained"] is True
    r = run("simulate", "--plugin", d / "plugins" / "finger.py", "--effects", "finger_compliance",
            "--points", "5", "--out", d / "sim.csv")
    assert r.returncode == 0, r.stderr


@pytest.mark.slow
def test_fit_refuses_an_effect_the_control_law_cannot_invert(files):
    d = files
    r = run("fit", d / "data.csv", "--plugin", d / "plugins" / "cmc_gain.py", "--effects", "cmc_gain",
            "--out", d / "never.toml")
    assert r.returncode == 2
    assert r.stderr.startswith("error: --effects cmc_gain: effect 'cmc_gain' (joint stage) has no invert()")
    assert not (d / "never.toml").exists()


@pytest.mark.parametrize("command", ["simulate", "compare", "diagnose", "fit"])
@pytest.mark.parametrize("body, message", [
    (None, "no such file"),
    ("import numpy\n\nx = (\n", "line 3: syntax error"),
    ("import numpy\nimport no_such_module_xyz\n", "line 2: ModuleNotFoundError: No module named 'no_such_module_xyz'"),
    ("x = 1\n", "registers no effect"),
    ("from phantom_cad.calibration.effects import JointOffset, register_effect\n\n"
     "register_effect(JointOffset)\n", "effect 'joint_offset' is already defined"),
])
@pytest.mark.slow
def test_a_broken_plugin_is_one_error_line(files, command, body, message, tmp_path):
    path = tmp_path / "broken.py"
    if body is not None:
        path.write_text(body)
    args = {"simulate": ["--out", tmp_path / "s.csv"], "compare": [files / "data.csv"],
            "diagnose": [files / "data.csv"], "fit": [files / "data.csv", "--effects", "joint_offset",
                                                       "--out", tmp_path / "f.toml"]}[command]
    r = run(command, *args, "--plugin", path)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith(f"error: --plugin: plugin {path}: {message}")
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr


def test_hand_inverse_refuses_an_effect_it_cannot_invert(files, tmp_path):
    """A hand-written file with a joint-stage effect without invert(): forward uses it, the control
    law raises rather than drop the effect silently."""
    from phantom_cad import load_hand
    from phantom_cad.calibration.effects import unload_plugin
    from phantom_cad.params import ParamError, load_document
    from phantom_cad.params.io import DEFAULT_PARAMS, dumps

    doc = load_document(DEFAULT_PARAMS)
    doc["plugins"] = [str(files / "plugins" / "cmc_gain.py")]
    doc["effects"] = {"cmc_gain": {"relative": 0.05}}
    path = tmp_path / "hand.toml"
    path.write_text(dumps(doc))
    try:
        hand = load_hand(path)
        u0 = np.array([0.3, 0.8, 0.5, 0.9, 0.7, 0.6])
        q = hand.forward(u0, compensated=True)
        assert q[14] == pytest.approx(1.05 * 0.6, abs=1e-12)       # q15 = (1 + 0.05) u6
        with pytest.raises(ParamError, match=r"effects.cmc_gain = \{'relative': 0.05\}: the joint-stage effect "
                                             r"'cmc_gain' has no invert\(\)"):
            hand.inverse(q, compensated=True)
    finally:
        unload_plugin(files / "plugins" / "cmc_gain.py")
