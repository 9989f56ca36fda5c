"""A scale error of one joint's measurement (a measurement error must not become a change to the
hand) is found as the measurement-side effect ``camera_scale``, and a calibrated file that carries
it leaves the hand's model and its control law untouched. The other way round, a hand effect that
the camera's scales explain as well stays in the hand, and the report says both explain the data;
the scales replace it only on evidence the hand effect cannot produce (a scale on the MCPs).

The data are written here (the paper's cosine law in closed form, test_noise_floor.analytic; the
tendon's compliance by eq. 13 solved row by row, spread over the joints unlike the library's
form), with 0.1 deg noise."""

import numpy as np
import pytest
import tomli_w

from phantom_cad import Hand, load_hand, load_params
from phantom_cad.calibration.diagnose import diagnose
from phantom_cad.calibration.diagnosis_text import diagnosis_text
from phantom_cad.kinematics.topology import DISTAL_JOINTS, Q_COLUMNS
from phantom_cad.params import DEFAULT_PARAMS, load_document

from .hidden import mcp_angles
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


def spread_compliance(hand, u, kappa, weights):
    """q (N, 15) of a hand whose tendons stretch by eq. (13), M q = A q_MCP, with row k >= 1 of M
    e_k + kappa w_k (l_1 + .. + l_k) / R_k R^T: the compliance felt at joint k scaled by w_k (the
    library's form has every w_k = 1; the hand's stretch is spread over its joints a little otherwise)."""
    s = mcp_angles(hand, u)
    q = np.zeros((u.shape[0], 15))
    for chain in hand.params.chains:
        R = np.array(chain.radii)
        M = np.eye(R.size)
        for k in range(1, R.size):
            M[k] += kappa * weights[k] * sum(chain.path_lengths[:k]) / R[k] * R
        ratio = np.linalg.solve(M, R[0] / R)
        for i, qi in enumerate(chain.spec.q_index):
            q[:, qi] = ratio[i] * s[:, chain.spec.servo]
    q[:, 14] = s[:, 5]
    return q


def test_spread_compliance_known_answer(hand):
    """Equal weights: eq. (13) of the library's form, which at kappa = 0 is the analytic model; the
    index chain (R, l from the file) solved by hand for its PIP at w = 1.1."""
    u, sweep, _ = sweeps(hand)
    np.testing.assert_allclose(spread_compliance(hand, u, 0.0, (1, 1, 1)), analytic(hand, u), atol=1e-15)
    chain = next(c for c in hand.params.chains if c.digit == "index")
    R, l = np.array(chain.radii), chain.path_lengths
    # rows 1 and 2 of M q = A q_MCP: q_MCP is 1 (the MCP row is the identity), so
    # q1 (1 + c1 R1) + c1 R2 q2 = A1 - c1 R0 and c2 R1 q1 + q2 (1 + c2 R2) = A2 - c2 R0, c_k = kappa w_k L_k / R_k
    kappa, w = 0.15, (1.0, 1.1, 0.9)
    c1, c2 = kappa * w[1] * l[0] / R[1], kappa * w[2] * (l[0] + l[1]) / R[2]
    A = R[0] / R
    q1, q2 = np.linalg.solve([[1 + c1 * R[1], c1 * R[2]], [c2 * R[1], 1 + c2 * R[2]]],
                             [A[1] - c1 * R[0], A[2] - c2 * R[0]])
    one = np.zeros((1, 6))
    one[0, chain.spec.servo] = 0.5
    q = spread_compliance(hand, one, kappa, w)[0]
    mcp = q[chain.spec.q_index[0]]
    assert q[chain.spec.q_index[1]] == pytest.approx(q1 * mcp, rel=1e-12)
    assert q[chain.spec.q_index[2]] == pytest.approx(q2 * mcp, rel=1e-12)


@pytest.fixture(scope="module")
def spread(hand):
    """A compliance of 0.15 1/m felt 10 % more at the PIP and 10 % less at the DIP than eq. (13) has it."""
    u, sweep, cj = sweeps(hand)
    d = diagnose(hand, measure(hand, u, sweep, cj, spread_compliance(hand, u, 0.15, (1.0, 1.1, 0.9)), seed=0))
    return d, d.to_json()


def test_a_hand_effect_the_camera_explains_as_well_stays_in_the_hand(spread):
    d, out = spread
    # the hand's stretch is in the calibrated model, at about the compliance that made the data
    assert "tendon_elasticity" in out["selected"] and "camera_scale" not in out["selected"], out["selected"]
    eff = out["effects"]["tendon_elasticity"]
    assert eff["side"] == "hand"
    assert eff["parameters"]["compliance_per_m"]["value"] == pytest.approx(0.15, abs=0.01)
    # the 15 scales did pass on what the hand's effects leave (the compliance's spread), so both explain the data
    assert any(c["effect"] == "camera_scale" and c["passes"] for r in out["rounds"] for c in r)
    (a,) = [a for a in out["ambiguities"] if a.get("kind") == "hand_or_measurement"]
    assert a["kept"] == "tendon_elasticity" and a["withdrawn"] == "camera_scale"
    assert a["effects"] == ["tendon_elasticity", "camera_scale"]
    # the scales show nothing where no tendon stretch reaches: the MCPs, MP and CMC
    outside = [Q_COLUMNS[j] for j in range(15) if j not in DISTAL_JOINTS]
    assert a["outside"]["joints"] == outside
    assert a["outside"]["heldout_ratio"] is None or a["outside"]["heldout_ratio"] >= 0.99
    assert a["mae_deg"]["with_measurement_instead"] <= a["mae_deg"]["with_hand_effect"]
    assert "angle gauge" in a["experiment"] and "weight on the fingertip" in a["experiment"]
    assert a["signature"]["mismatches"] == []
    text = "\n".join(diagnosis_text(d, out))
    assert ("both explain the data (round 4): tendon_elasticity (the hand; MAE " in text
            and "so tendon_elasticity is kept: the control law needs it; the analytic model's residual has "
                "tendon_elasticity's signature. To separate them: photograph the printed angle gauge" in text), text


def test_camera_scales_replace_a_hand_effect_on_evidence(hand):
    """The camera reads the distal joints 5 % small (as a tendon's stretch would) and the MCPs, MP
    and CMC 2 % large (as none does): the hand family first takes a compliance, the scales replace
    it on the joints it cannot move, and the note says so."""
    u, sweep, cj = sweeps(hand)
    c = np.full(15, 0.02)
    c[list(DISTAL_JOINTS)] = -0.05
    d = diagnose(hand, measure(hand, u, sweep, cj, analytic(hand, u) * (1.0 + c), seed=3))
    out = d.to_json()
    assert out["selected"] == ["camera_scale"] and out["explained"] is True, out["selected"]
    assert out["rounds"][0][0]["effect"] == "tendon_elasticity" and out["rounds"][0][0]["passes"]
    assert not [a for a in out["ambiguities"] if a.get("kind") == "hand_or_measurement"]
    (note,) = [n for n in out["notes"] if n.startswith("tendon_elasticity was dropped after camera_scale")]
    assert "the data cannot tell tendon_elasticity from camera_scale" in note
    assert "camera_scale replaced it on evidence of its own: on the joints tendon_elasticity cannot move " \
           "(q2, q5, q8, q11, q14, q15) it passes alone" in note
    fitted = out["effects"]["camera_scale"]["parameters"]
    for j in range(15):
        assert fitted[f"{Q_COLUMNS[j]}_relative"]["value"] == pytest.approx(c[j], abs=0.004), Q_COLUMNS[j]


@pytest.mark.slow       # the command line, in a process of its own
def test_the_calibrated_file_keeps_the_hand_effect(spread, tmp_path):
    """What diagnose selected, fitted and written by `fit`: the file carries the tendon's
    compliance (the control law compensates it) and no camera scale."""
    from phantom_cad.calibration.data import write_measurements
    from phantom_cad.calibration.labels import Labels

    from ._cli import run_cli

    d, out = spread
    m = d.measurements
    write_measurements(tmp_path / "data.csv", m.u, m.q, sweep=Labels(m.sweep_ids, m.sweep), q_columns=m.q_columns)
    r = run_cli("fit", tmp_path / "data.csv", "--effects", ",".join(out["selected"]), "--out", tmp_path / "cal.toml")
    assert r.returncode == 0, r.stderr
    effects = load_document(tmp_path / "cal.toml")["effects"]
    assert "camera_scale" not in effects
    assert effects["tendon_elasticity"]["compliance_per_m"] == pytest.approx(0.15, abs=0.01)
    assert "tendon_elasticity" in load_hand(tmp_path / "cal.toml").effects.names
