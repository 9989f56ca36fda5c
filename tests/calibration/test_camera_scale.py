"""A scale error of one joint's measurement (a measurement error must not become a change to the
hand) is found as the measurement-side effect ``camera_scale``, and a calibrated file that carries
it leaves the hand's model and its control law untouched.

The data are written here (the paper's cosine law in closed form, test_noise_floor.analytic), with
the measured angle of q9 read 3 % large, and 0.1 deg noise."""

import numpy as np
import pytest
import tomli_w

from phantom_cad import Hand, load_hand, load_params
from phantom_cad.calibration.diagnose import diagnose
from phantom_cad.params import DEFAULT_PARAMS, load_document

from .test_noise_floor import analytic, measure, sweeps

J, SCALE = 8, 0.03          # q9


@pytest.fixture(scope="module")
def diagnosis(hand):
    u, sweep, cj = sweeps(hand)
    q = analytic(hand, u)
    q[:, J] *= 1.0 + SCALE
    return diagnose(hand, measure(hand, u, sweep, cj, q, seed=4)).to_json()


def test_a_camera_scale_is_found_on_the_measurement_side(diagnosis):
    out = diagnosis
    assert out["selected"] == ["camera_scale"]
    eff = out["effects"]["camera_scale"]
    assert eff["side"] == "measurement"
    p = eff["parameters"][f"q{J + 1}_relative"]
    assert p["value"] == pytest.approx(SCALE, abs=0.003)
    assert out["explained"] is True
    # the other joints' measurement scales are not bent toward the error
    others = [v["value"] for k, v in eff["parameters"].items() if k != f"q{J + 1}_relative"]
    assert max(abs(v) for v in others) < 0.005


def test_a_calibrated_camera_scale_never_enters_the_hand(tmp_path):
    doc = load_document(DEFAULT_PARAMS)
    doc["effects"] = {"camera_scale": {f"q{J + 1}_relative": SCALE}}
    path = tmp_path / "calibrated.toml"
    path.write_text(tomli_w.dumps(doc))
    # a calibrated hand builds on the paper's compensation: the plain hand to compare with is that one
    plain, cal = Hand(load_params(), compensation="paper"), load_hand(path)
    rng = np.random.default_rng(0)
    u = rng.uniform(plain.u_min, plain.u_max, (50, 6))
    for compensated in (False, True):
        np.testing.assert_allclose(cal.forward(u, compensated=compensated),
                                   plain.forward(u, compensated=compensated), atol=1e-9)
    q = plain.forward(u, compensated=True)
    np.testing.assert_allclose(cal.inverse(q, compensated=True), plain.inverse(q, compensated=True), atol=1e-9)
    # what the measurement reads: q9 3 % large, the rest as the hand
    read = cal.effects.forward(cal, u, True, measured=True)
    expect = q.copy()
    expect[:, J] *= 1.0 + SCALE
    np.testing.assert_allclose(read, expect, atol=1e-9)
