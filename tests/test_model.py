"""The kinematic model against answers computed by hand from the paper's equations.

The expected values below are derived in the comments (cosine law with round numbers,
Cramer's rule for eq. 13/14) and typed in, not obtained by calling phantom_cad.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad import Hand, load_hand
from phantom_cad.params import load_params, parse

# A hand whose numbers make the equations easy to do by hand: every chain has
# d1 = d2 = 10 mm, alpha = 90 deg, r = 10 mm, so L0 = 10 sqrt(2) mm (eq. 4).
# At u* = sqrt(2) - 1 rad the chord is L = L0 - r u* = 10 mm, the cosine-law argument is
# (100 + 100 - 100) / 200 = 0.5, the included angle 60 deg, so q_ref = 90 - 60 = 30 deg (eq. 6).
U_STAR = math.sqrt(2.0) - 1.0
Q_REF_STAR = math.pi / 6.0


def easy_document(document):
    for name, f in document["fingers"].items():
        f["guide"] = {"d1_mm": 10.0, "d2_mm": 10.0, "alpha_deg": 90.0}
        f["thickness_mm"] = 16.0      # the d2 guide, 7.07 mm palmar of the axis, stays inside the phalanx
        f["servo_pulley_radius_mm"] = 10.0
        f["servo_travel_deg"] = [0.0, 60.0]
        f["pulley_radius_mm"] = {"dip": 5.0, "pip": 4.0, "mcp": 5.0}
        f["path_length_mm"] = {"mcp_pip": 55.0, "pip_dip": 35.0}
    t = document["thumb"]
    t["guide"] = {"d1_mm": 10.0, "d2_mm": 10.0, "alpha_deg": 90.0}
    t["thickness_mm"] = 16.0
    t["servo_pulley_radius_mm"] = 10.0
    t["servo_travel_deg"] = [0.0, 60.0]
    t["pulley_radius_mm"] = {"ip": 5.0, "mp": 4.0}
    t["path_length_mm"] = {"mp_ip": 40.0}
    t["cmc_gain"] = 1.0
    document["mechanics"] = {"spring_k_N_per_m": 100.0, "tendon_EA_N": 1000.0}
    return document


@pytest.fixture
def easy(document):
    """The easy hand with the paper's compensation, whose eq. (13)/(14) the known answers solve."""
    return Hand(parse(easy_document(document)), compensation="paper")


@pytest.fixture(scope="module")
def paper_hand():
    """The default hand with the paper's compensation (eq. 11-14)."""
    from phantom_cad import load_params

    return Hand(load_params(), compensation="paper")


def test_cosine_law_known_answer(easy):
    u = np.zeros(6)
    u[1] = U_STAR  # index servo
    q = easy.forward(u)
    # eq. (2)-(3): R_DIP:R_PIP:R_MCP = 5:4:5 -> q_DIP:q_PIP:q_MCP = 4:5:4
    assert q[4] == pytest.approx(Q_REF_STAR, abs=1e-12)          # q5 index MCP
    assert q[3] == pytest.approx(1.25 * Q_REF_STAR, abs=1e-12)   # q4 index PIP
    assert q[2] == pytest.approx(Q_REF_STAR, abs=1e-12)          # q3 index DIP
    others = np.delete(q, [2, 3, 4])
    assert np.all(others == 0.0)


def test_ratios_4_5_4_and_thumb_4_5(easy):
    u = np.array([0.3, 0.4, 0.5, 0.6, 0.7, 0.2])
    q = easy.forward(u)
    for base in (2, 5, 8, 11):  # DIP index of each finger
        dip, pip, mcp = q[base], q[base + 1], q[base + 2]
        assert dip / mcp == pytest.approx(4 / 4)
        assert pip / mcp == pytest.approx(5 / 4)
        assert dip / pip == pytest.approx(4 / 5)
    # thumb: R_IP:R_MP = 5:4 -> q_IP = 0.8 q_MP (the paper's eq. 14 prints 1.25: erratum)
    assert q[0] / q[1] == pytest.approx(0.8)
    assert q[14] == pytest.approx(0.2)  # q15 = g u6, g = 1


def test_thumb_known_answer(easy):
    u = np.zeros(6)
    u[0] = U_STAR
    q = easy.forward(u)
    assert q[1] == pytest.approx(Q_REF_STAR, abs=1e-12)
    assert q[0] == pytest.approx(0.8 * Q_REF_STAR, abs=1e-12)


def cramer3(M, b):
    (a, b_, c), (d, e, f), (g, h, i) = M
    det = a * (e * i - f * h) - b_ * (d * i - f * g) + c * (d * h - e * g)
    out = []
    for k in range(3):
        Mk = [list(row) for row in M]
        for r in range(3):
            Mk[r][k] = b[r]
        (a2, b2, c2), (d2, e2, f2), (g2, h2, i2) = Mk
        out.append((a2 * (e2 * i2 - f2 * h2) - b2 * (d2 * i2 - f2 * g2) + c2 * (d2 * h2 - e2 * g2)) / det)
    return out


def test_compensation_known_answer(easy):
    # eq. (13) with k_s = 100 N/m, EA = 1000 N, R = (5, 4, 5) mm, L_MCP,PIP = 55 mm, L_PIP,DIP = 35 mm:
    # C_PIP = 100 * 0.055 / (1000 * 0.004) = 1.375 /m, C_DIP = 100 * 0.090 / (1000 * 0.005) = 1.8 /m
    M = [[1.0, 0.0, 0.0],
         [1.375 * 0.005, 1.0 + 1.375 * 0.004, 1.375 * 0.005],
         [1.8 * 0.005, 1.8 * 0.004, 1.0 + 1.8 * 0.005]]
    mcp, pip, dip = cramer3(M, [Q_REF_STAR, 1.25 * Q_REF_STAR, Q_REF_STAR])
    assert mcp == pytest.approx(Q_REF_STAR)
    u = np.zeros(6)
    u[1] = U_STAR
    q = easy.forward(u, compensated=True)
    assert q[4] == pytest.approx(mcp, abs=1e-12)
    assert q[3] == pytest.approx(pip, abs=1e-12)
    assert q[2] == pytest.approx(dip, abs=1e-12)
    # by hand: det = 1.0055 * 1.009 - 0.006875 * 0.0072 = 1.0145,
    # q_PIP / q_MCP = (1.243125 * 1.009 - 0.006875 * 0.991) / det = 1.2475 / 1.0145,
    # q_DIP / q_MCP = (1.0055 * 0.991 - 0.0072 * 1.243125) / det = 0.9875 / 1.0145
    assert pip / mcp == pytest.approx(1.2475 / 1.0145, rel=1e-9)
    assert dip / mcp == pytest.approx(0.9875 / 1.0145, rel=1e-9)


def test_thumb_compensation_known_answer(easy):
    # eq. (14) with the erratum fixed: [[1, 0], [C R_MP, 1 + C R_IP]] [q_MP, q_IP] = [1, 0.8] q_MP,
    # C = k_s L_MP,IP / (EA R_IP) = 100 * 0.040 / (1000 * 0.005) = 0.8 /m
    C = 0.8
    q_ip = (0.8 - C * 0.004) / (1.0 + C * 0.005) * Q_REF_STAR
    u = np.zeros(6)
    u[0] = U_STAR
    q = easy.forward(u, compensated=True)
    assert q[1] == pytest.approx(Q_REF_STAR, abs=1e-12)
    assert q[0] == pytest.approx(q_ip, abs=1e-12)


def test_compensation_satisfies_eq12(paper_hand):
    # q_comp = q_ideal - b(q_comp): the deviation of eq. (12), evaluated on the actual angles
    u = np.linspace(paper_hand.u_min, paper_hand.u_max, 25)
    q_ideal = paper_hand.forward(u)
    q_comp = paper_hand.forward(u, compensated=True)
    k_s, EA = paper_hand.params.mechanics.spring_k, paper_hand.params.mechanics.tendon_EA
    idx = paper_hand.params.fingers["index"].chain
    R_mcp, R_pip, R_dip = idx.radii
    L1, L2 = idx.path_lengths
    T = k_s * (R_dip * q_comp[:, 2] + R_pip * q_comp[:, 3] + R_mcp * q_comp[:, 4])     # eq. (11)
    assert np.allclose(q_ideal[:, 3] - q_comp[:, 3], T * L1 / (EA * R_pip), atol=1e-14)
    assert np.allclose(q_ideal[:, 2] - q_comp[:, 2], T * (L1 + L2) / (EA * R_dip), atol=1e-14)
    assert np.array_equal(q_ideal[:, 4], q_comp[:, 4])  # MCP uncompensated
    assert np.array_equal(q_ideal[:, 14], q_comp[:, 14])  # CMC uncompensated
    assert np.allclose(paper_hand.bias(q_comp), q_ideal - q_comp, atol=1e-14)


def test_default_hand_distal_error_is_paper_sized(paper_hand):
    # the default k_s / EA were chosen so the analytic model misses the index DIP by about
    # a degree on a uniform sweep, as the paper measured (1.15 deg MAE)
    u = np.zeros((201, 6))
    u[:, 1] = np.linspace(paper_hand.u_min[1], paper_hand.u_max[1], 201)
    diff = np.degrees(paper_hand.forward(u) - paper_hand.forward(u, compensated=True))
    assert 0.8 < np.abs(diff[:, 2]).mean() < 1.5
    assert np.abs(diff[:, 2]).max() < 2.5


@pytest.mark.parametrize("compensated", [False, True])
def test_round_trip_whole_travel(hand, compensated):
    grid = np.linspace(0.0, 1.0, 201)[:, None]
    u = hand.u_min + grid * (hand.u_max - hand.u_min)
    q = hand.forward(u, compensated=compensated)
    assert np.all(q >= hand.q_min - 1e-12) and np.all(q <= hand.q_max + 1e-12)
    assert np.allclose(hand.inverse(q, compensated=compensated), u, atol=1e-10, rtol=0)


def test_round_trip_random_mixed_poses(hand):
    rng = np.random.default_rng(0)
    u = rng.uniform(hand.u_min, hand.u_max, size=(1000, 6))
    assert np.allclose(hand.inverse(hand.forward(u, True), True), u, atol=1e-10, rtol=0)


def test_targets_outside_workspace_are_clipped(hand):
    q = np.full(15, 10.0)
    assert np.allclose(hand.inverse(q), hand.u_max)
    assert np.allclose(hand.inverse(-q), hand.u_min)
    # clipping happens in joint space first: a target beyond one joint's limit acts as the limit
    q = hand.forward(0.5 * hand.u_max, compensated=True)
    beyond = q.copy()
    beyond[14] = 3.0  # CMC far past its 1.57 limit
    u = hand.inverse(beyond)
    # clipped to q15 = 1.57 rad, then to the servo travel: 89.9 deg = 1.5691 rad < 1.57
    assert u[5] == pytest.approx(math.radians(89.9), abs=1e-12)
    assert np.allclose(u[:5], 0.5 * hand.u_max[:5])


def test_projection_onto_finger_curve(easy):
    # target (MCP, PIP, DIP) = (0.5, 0.5, 0.5) is off the index curve c s with c = (1, 1.25, 1)
    # (ideal). Least squares: s = c.q / c.c = 1.625 / 3.5625.
    s = 1.625 / 3.5625
    # cosine law inverted by hand: L = sqrt(d1^2 + d2^2 - 2 d1 d2 cos(alpha - s)), u = (L0 - L) / r
    L = math.sqrt(200.0 - 200.0 * math.cos(math.pi / 2 - s))
    u_expected = (10.0 * math.sqrt(2.0) - L) / 10.0
    q = np.zeros(15)
    q[[4, 3, 2]] = 0.5
    u = easy.inverse(q, compensated=False)
    assert u[1] == pytest.approx(u_expected, abs=1e-12)
    # the projection is the closest reachable pose: moving the servo either way is worse
    def dist(uu):
        return np.sum((easy.forward(uu, compensated=False)[2:5] - q[2:5]) ** 2)
    for du in (-1e-4, 1e-4):
        v = u.copy()
        v[1] += du
        assert dist(v) > dist(u)


def test_inverse_respects_servo_travel(hand):
    rng = np.random.default_rng(1)
    q = rng.uniform(-1.0, 3.0, size=(5000, 15))
    for compensated in (False, True):
        u = hand.inverse(q, compensated=compensated)
        assert np.all(u >= hand.u_min) and np.all(u <= hand.u_max)


@pytest.mark.parametrize("shape", [(), (1,), (7,), (2, 3), (4, 1, 5)])
def test_batch_shapes(hand, shape):
    rng = np.random.default_rng(2)
    u = rng.uniform(hand.u_min, hand.u_max, size=shape + (6,))
    for compensated in (False, True):
        q = hand.forward(u, compensated=compensated)
        assert q.shape == shape + (15,)
        flat = u.reshape(-1, 6)
        loop = np.array([hand.forward(x, compensated=compensated) for x in flat])
        assert np.allclose(q.reshape(-1, 15), loop)
        back = hand.inverse(q, compensated=compensated)
        assert back.shape == shape + (6,)
        J = hand.jacobian(u, compensated=compensated)
        assert J.shape == shape + (15, 6)


def test_bad_shapes_are_refused(hand):
    with pytest.raises(ValueError, match=r"u must have shape \(\.\.\., 6\), got \(5,\)"):
        hand.forward(np.zeros(5))
    with pytest.raises(ValueError, match=r"q_d must have shape \(\.\.\., 15\), got \(3, 6\)"):
        hand.inverse(np.zeros((3, 6)))


def test_jacobian_matches_finite_differences(hand):
    rng = np.random.default_rng(3)
    u = rng.uniform(hand.u_min + 0.05, hand.u_max - 0.05, size=(20, 6))
    for compensated in (False, True):
        J = hand.jacobian(u, compensated=compensated)
        h = 1e-6
        for j in range(6):
            du = np.zeros(6)
            du[j] = h
            fd = (hand.forward(u + du, compensated) - hand.forward(u - du, compensated)) / (2 * h)
            assert np.allclose(J[..., j], fd, atol=1e-7)
        # block sparsity: 15 non-zeros when every servo is away from zero slope
        assert np.count_nonzero(J[0]) == 15


def test_H_is_block_sparse_and_reproduces_forward(hand):
    u = np.array([0.4, 0.9, 0.8, 0.7, 0.6, 0.5])
    H = hand.H(u)
    assert H.shape == (15, 6)
    assert np.count_nonzero(H) == 15
    assert np.allclose(H @ u, hand.forward(u))
    assert H[14, 5] == 1.0
    # at u = 0 H is its limit, the slope of each q(u_j)
    H0 = hand.H(np.zeros(6))
    assert np.allclose(H0, hand.jacobian(np.zeros(6)))


def test_load_hand_default_and_path(tmp_path, default_document):
    import tomli_w

    from tests.conftest import DEFAULT_PARAMS

    h1 = load_hand()
    h2 = load_hand(DEFAULT_PARAMS)
    assert h1.params.digest == h2.params.digest
    doc = dict(default_document)
    doc["hand"] = dict(doc["hand"], name="other")
    path = tmp_path / "other.toml"
    path.write_text(tomli_w.dumps(doc))
    h3 = load_hand(str(path))
    assert h3.params.name == "other" and h3.params.digest != h1.params.digest


def test_beyond_the_cosine_law_domain_the_joint_stops_folded(hand):
    # far past the servo travel the chord would shorten below |d1 - d2|: the reference joint stops at
    # alpha (folded) instead of returning NaN, the same answer with and without fitted effects
    from phantom_cad.calibration.effects import run_pipeline

    u = hand.u_max * 1.6
    q = hand.forward(u)
    assert np.all(np.isfinite(q))
    assert q[4] == pytest.approx(math.radians(100.0))        # index MCP = alpha = 100 deg
    assert np.allclose(run_pipeline(hand, [], u[None], None, 0.0)[0], q, atol=1e-15)


def test_hand_refuses_parameters_with_effects_it_was_not_given():
    from phantom_cad import make_hand
    from phantom_cad.canon import plain

    doc = plain(load_params().document)
    doc["effects"] = {"joint_offset": {"q3_deg": 1.0}}
    params = parse(doc, "calibrated.toml")
    with pytest.raises(ValueError, match="carry fitted effects"):
        Hand(params)
    assert make_hand(params).effects is not None
