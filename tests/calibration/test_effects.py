"""Known answers for each effect's formula, computed by hand from the paper's equations
(eq. 4-6 cosine law, eq. 11-13 compliance matrix, the capstan equation), and the hook that
puts fitted effects into Hand.forward / Hand.inverse."""

import math

import numpy as np
import pytest

from phantom_cad import Hand, ParamError, load_params, make_hand
from phantom_cad.calibration.effects import PARAMS_EFFECTS, get_effect, run_pipeline
from phantom_cad.params import dump_params, parse
from phantom_cad.canon import plain as _plain

# the default index finger, read off params/phantom.toml by hand (mm, degrees)
D1, D2, ALPHA, R_SERVO = 12.0, 10.0, math.radians(100.0), 7.0
R_MCP, R_PIP, R_DIP = 5.0, 4.0, 5.0
L_MCP_PIP, L_PIP_DIP = 48.0, 29.0
K_S, EA = 200.0, 1500.0
U_INDEX = 1  # servo u2


def q_mcp(u, r=R_SERVO):
    """Eq. (4)-(6) by hand."""
    L0 = math.sqrt(D1 ** 2 + D2 ** 2 - 2 * D1 * D2 * math.cos(ALPHA))
    L = L0 - r * u
    return ALPHA - math.acos((D1 ** 2 + D2 ** 2 - L ** 2) / (2 * D1 * D2))


def index_chain(s, compliance_per_m):
    """Eq. (13) by hand: M q = A q_MCP, order MCP, PIP, DIP, lengths in metres."""
    c_pip = compliance_per_m * (L_MCP_PIP / 1000) / (R_PIP / 1000)
    c_dip = compliance_per_m * ((L_MCP_PIP + L_PIP_DIP) / 1000) / (R_DIP / 1000)
    R = np.array([R_MCP, R_PIP, R_DIP]) / 1000
    M = np.array([[1.0, 0.0, 0.0],
                  [c_pip * R[0], 1 + c_pip * R[1], c_pip * R[2]],
                  [c_dip * R[0], c_dip * R[1], 1 + c_dip * R[2]]])
    A = np.array([1.0, 1.25, 1.0])
    return np.linalg.solve(M, A) * s


def u_index(value):
    u = np.zeros((1, 6))
    u[0, U_INDEX] = value
    return u


def pipeline(hand, effects, u, direction=None, compliance=0.0):
    items = [(get_effect(n), np.array(x, dtype=float)) for n, x in effects.items()]
    return run_pipeline(hand, items, u, direction, compliance)[0]


def test_analytic_pipeline_is_the_cosine_law(hand):
    q = pipeline(hand, {}, u_index(0.9))
    s = q_mcp(0.9)
    # q3 DIP, q4 PIP, q5 MCP: 4:5:4
    assert q[4] == pytest.approx(s, abs=1e-12)
    assert q[3] == pytest.approx(1.25 * s, abs=1e-12)
    assert q[2] == pytest.approx(s, abs=1e-12)


def test_slack_known_answer(hand):
    delta = [0.0, 3.0, 0.0, 0.0, 0.0]              # u2 dead band 3 degrees
    q = pipeline(hand, {"tendon_slack": delta}, u_index(0.9))
    s = q_mcp(0.9 - math.radians(3.0))
    assert q[4] == pytest.approx(s, abs=1e-12)
    assert q[2] == pytest.approx(s, abs=1e-12)
    # inside the dead band nothing moves
    q = pipeline(hand, {"tendon_slack": delta}, u_index(math.radians(2.0)))
    assert np.allclose(q, 0.0)


def test_pulley_radius_error_known_answer(hand):
    e = [0.0, 0.03, 0.0, 0.0, 0.0]
    q = pipeline(hand, {"pulley_radius_error": e}, u_index(0.9))
    s = q_mcp(0.9, R_SERVO * 1.03)
    assert q[4] == pytest.approx(s, abs=1e-12)
    assert q[3] == pytest.approx(1.25 * s, abs=1e-12)


def test_joint_offset_known_answer(hand):
    x = np.zeros(15)
    x[2] = 1.5                                    # q3 +1.5 degrees
    x[14] = -0.5                                  # q15 -0.5 degrees
    q = pipeline(hand, {"joint_offset": x}, np.zeros((1, 6)))
    assert q[2] == pytest.approx(math.radians(1.5), abs=1e-15)
    assert q[14] == pytest.approx(math.radians(-0.5), abs=1e-15)
    assert np.count_nonzero(q) == 2


def test_tendon_elasticity_known_answer(hand):
    q = pipeline(hand, {"tendon_elasticity": [0.2]}, u_index(0.9))
    expected = index_chain(q_mcp(0.9), 0.2)
    assert q[[4, 3, 2]] == pytest.approx(expected, abs=1e-12)
    # by hand: C_PIP R_MCP = 0.2 * 0.048 / 0.004 * 0.005 = 0.012
    assert expected[0] == pytest.approx(q_mcp(0.9))


@pytest.fixture(scope="module")
def paper():
    """The default hand with the paper's compensation (eq. 11-14), the base fitted effects build on."""
    return Hand(load_params(), compensation="paper")


def test_tendon_elasticity_at_the_file_ratio_is_the_papers_compensation(paper):
    hand = paper
    u = np.zeros((5, 6))
    u[:, :] = np.linspace(0.1, 1.2, 5)[:, None] * (hand.u_max / hand.u_max.max())
    q = run_pipeline(hand, [(get_effect("tendon_elasticity"), np.array([K_S / EA]))], u, None, 0.0)
    assert np.allclose(q, hand.forward(u, compensated=True), atol=1e-12)


def test_friction_known_answer(hand):
    mu = 0.1
    s = q_mcp(0.9)
    theta = s * (1.0 + 1.25 + 1.0)                # wrap = sum of the chain's joint angles
    for d in (+1.0, -1.0):
        direction = np.zeros((1, 6))
        direction[0, U_INDEX] = d
        q = pipeline(hand, {"friction_hysteresis": [mu]}, u_index(0.9), direction)
        kappa = (K_S / EA) * (math.exp(d * mu * theta) - 1.0)
        assert q[[4, 3, 2]] == pytest.approx(index_chain(s, kappa), abs=1e-12)
    flex = pipeline(hand, {"friction_hysteresis": [mu]}, u_index(0.9), np.array([[0, 1, 0, 0, 0, 0.0]]))
    ext = pipeline(hand, {"friction_hysteresis": [mu]}, u_index(0.9), np.array([[0, -1, 0, 0, 0, 0.0]]))
    # the DIP lags when flexing, leads when extending; the MCP is untouched
    assert flex[2] < q_mcp(0.9) < ext[2]
    assert flex[4] == ext[4] == pytest.approx(q_mcp(0.9))
    # unknown direction: no friction
    none = pipeline(hand, {"friction_hysteresis": [mu]}, u_index(0.9), None)
    assert none[2] == pytest.approx(q_mcp(0.9), abs=1e-15)


# -- the hook: fitted effects in a parameter file --------------------------------------------

def with_effects(effects):
    doc = _plain(load_params().document)
    doc["effects"] = effects
    return make_hand(parse(doc, "test.toml", effects=PARAMS_EFFECTS))


def test_no_effects_no_stack(hand):
    assert hand.effects is None


def test_effects_reach_forward_and_compensated_semantics(paper):
    hand = paper
    u = np.linspace(hand.u_min, hand.u_max, 7)
    same = with_effects({"tendon_elasticity": {"compliance_per_m": K_S / EA}})
    assert np.allclose(same.forward(u, compensated=True), hand.forward(u, compensated=True), atol=1e-12)
    assert np.allclose(same.forward(u, compensated=False), hand.forward(u, compensated=False), atol=1e-12)
    off = with_effects({"joint_offset": {"q3_deg": 2.0}})
    diff = off.forward(u) - hand.forward(u)
    assert np.allclose(diff[:, 2], math.radians(2.0)) and np.allclose(np.delete(diff, 2, axis=1), 0.0)


def test_inverse_inverts_the_effects(hand):
    calibrated = with_effects({
        "tendon_slack": {"u2_deg": 2.0, "u1_deg": 1.0},
        "pulley_radius_error": {"u3_relative": 0.03},
        "joint_offset": {"q5_deg": 1.0},
        "tendon_elasticity": {"compliance_per_m": 0.2},
        "friction_hysteresis": {"mu": 0.1},
    })
    u = np.linspace(hand.u_min + 0.1, hand.u_max - 0.05, 9)
    for compensated in (True, False):
        q = calibrated.forward(u, compensated)
        u_back = calibrated.inverse(q, compensated)
        assert np.allclose(u_back, u, atol=1e-9)
    # and the plain model's inverse would miss the effects by degrees
    assert np.abs(hand.inverse(calibrated.forward(u, True)) - u).max() > math.radians(1.0)


@pytest.mark.parametrize("effects, message", [
    ({"warp_drive": {"x": 1.0}},
     "effects.warp_drive = 'warp_drive': unknown effect (known: tendon_slack, pulley_radius_error, "
     "tendon_elasticity, tendon_elasticity_per_finger, friction_hysteresis, joint_offset, camera_scale, "
     "backlash, drive_friction, routed_elasticity, routed_elasticity_per_finger)"),
    ({"friction_hysteresis": {"mu": 2.0}},
     "effects.friction_hysteresis.mu = 2.0: must lie in [0, 1] (physical bounds: friction coefficient of "
     "the tendon on its pulleys and guides)"),
    ({"friction_hysteresis": {"mu": "high"}},
     "effects.friction_hysteresis.mu = 'high': must be a finite number"),
    ({"tendon_slack": {"u6_deg": 1.0}},
     "effects.tendon_slack.u6_deg = 1.0: unknown parameter of tendon_slack (allowed: u1_deg, u2_deg, u3_deg, "
     "u4_deg, u5_deg)"),
])
def test_bad_effects_refused_at_load(tmp_path, effects, message):
    from phantom_cad import load_hand

    import tomli_w

    doc = _plain(load_params().document)
    doc["effects"] = effects
    path = tmp_path / "bad.toml"
    path.write_text(tomli_w.dumps(doc))
    for load in (load_params, load_hand):   # refused by validation itself, not only by the model
        with pytest.raises(ParamError) as exc:
            load(path)
        assert str(exc.value) == f"{path}: {message}"
        assert exc.value.field.startswith("effects.")
    with pytest.raises(ParamError):           # and never written by dump_params
        dump_params(doc, tmp_path / "never.toml", effects=PARAMS_EFFECTS)
    assert not (tmp_path / "never.toml").exists()
    # the params layer alone checks the tables' shape, not their meaning: the library is handed in
    from phantom_cad.params import load_params as params_layer_load

    assert dict(params_layer_load(path).effects) == effects
    with pytest.raises(ParamError) as exc:
        params_layer_load(path, effects=PARAMS_EFFECTS)
    assert str(exc.value) == f"{path}: {message}"
