"""diagnose on data with one or two hidden effects, the data written here independently of the effect
library (tests/calibration/hidden.py: the cosine law, eq. 13 and the hidden physics in numpy; the
play of test_backlash; the sweeps and the noise of test_noise_floor), 0.1 deg noise, magnitudes drawn
per seed from each effect's typical range.

Criteria: the hidden effect is selected (first, when alone), the final MAE is at
most 1.5 x the noise floor estimated from the data, and the fitted model is within 0.5 x that floor
of the noise-free truth (MAE over the measured cells). Physics outside the library is either left
unexplained, on the joints it touches, or explained by a model that matches the truth as closely."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from phantom_cad.calibration.diagnose import diagnose
from phantom_cad.calibration.diagnosis_text import diagnosis_text
from phantom_cad.kinematics.topology import JOINTS

from .hidden import (HAND_EFFECTS, chain_coupling, directions, gravity_sag, hidden_values, ideal_ratios, mcp_angles,
                     slack, soft_stop, truth)
from .test_backlash import played
from .test_noise_floor import NOISE_DEG, POINTS, analytic, measure, sweeps
from .test_plugin import HIDDEN as PLUGIN_KAPPA
from .test_plugin import compliant

EXPECTED_FLOOR = NOISE_DEG * math.sqrt(2 / math.pi)     # MAE of N(0, 0.1 deg)


def chain_of(hand, servo):
    return next(c for c in hand.params.chains if c.spec.servo == servo)


# -- the writers, by known answers worked by hand ------------------------------------------------

def test_directions_of_the_sweeps(hand):
    """Each sweep flexes over POINTS samples and returns: the turning point, commanded twice, still
    flexes; the other servos never move."""
    u, sweep, _ = sweeps(hand)
    d = directions(u, sweep)
    for s in range(6):
        rows = np.flatnonzero(sweep == s)
        assert np.all(d[rows[:POINTS + 1], s] == 1) and np.all(d[rows[POINTS + 1:], s] == -1)
        assert np.all(np.delete(d[rows], s, axis=1) == 0)


def test_cosine_law_and_radius_error_known_answer(hand):
    """e = 0 is test_noise_floor.analytic; with e = 3 %, the chord rebuilt from the MCP angle by the
    law of cosines, L^2 = d1^2 + d2^2 - 2 d1 d2 cos(alpha - q), is shortened by r (1 + e) u."""
    u, sweep, _ = sweeps(hand, points=7)
    assert np.allclose(truth(hand, u, sweep, {}), analytic(hand, u), atol=1e-15)
    e = np.array([0.03, -0.02, 0.04, 0.01, -0.03])
    q = truth(hand, u, sweep, {"pulley_radius_error": e})
    for chain in hand.params.chains:
        g, k = chain.guide, chain.spec.servo
        row = np.flatnonzero(sweep == k)[4]
        q_mcp = q[row, chain.spec.q_index[0]]
        L0 = math.sqrt(g.d1 ** 2 + g.d2 ** 2 - 2 * g.d1 * g.d2 * math.cos(g.alpha))
        L = math.sqrt(g.d1 ** 2 + g.d2 ** 2 - 2 * g.d1 * g.d2 * math.cos(g.alpha - q_mcp))
        assert L0 - L == pytest.approx(chain.servo_radius * (1 + e[k]) * u[row, k], rel=1e-12)
        # PIP/DIP (thumb IP) in the radius ratios of eq. 2
        for i, qi in enumerate(chain.spec.q_index):
            assert q[row, qi] == pytest.approx(q_mcp * chain.radii[0] / chain.radii[i], rel=1e-12)


def test_slack_known_answer(hand):
    """Within the dead band every joint of the chain is exactly 0; beyond it the chain is where the
    slack-free hand is delta earlier."""
    u, sweep, _ = sweeps(hand)
    delta = np.array([2.0, 3.0, 4.0, 1.0, 2.5])
    q = truth(hand, u, sweep, {"tendon_slack": delta})
    for chain in hand.params.chains:
        k = chain.spec.servo
        rows = np.flatnonzero(sweep == k)
        inside = rows[u[rows, k] - hand.u_min[k] < math.radians(delta[k])]
        assert inside.size >= 2                     # the start and the end of the sweep
        assert np.all(q[np.ix_(inside, chain.spec.q_index)] == 0.0)
        row = rows[10]
        shifted = u[[row]].copy()
        shifted[0, k] -= math.radians(delta[k])
        assert np.allclose(q[row], analytic(hand, shifted)[0], atol=1e-15)
    assert np.array_equal(q[sweep == 5, 14], u[sweep == 5, 5])   # the CMC has no tendon


def test_elasticity_known_answer(hand):
    """The thumb solved by hand: M = [[1, 0], [C R_MP, 1 + C R_IP]], C = kappa l / R_IP, so
    q_IP / q_MP = (A_IP - C R_MP) / (1 + C R_IP); per finger, the same numbers as test_plugin.compliant
    (written separately) with its compliances."""
    thumb = chain_of(hand, 0)
    R0, R1 = thumb.radii
    kappa = 0.2
    C = kappa * thumb.path_lengths[0] / R1
    assert chain_coupling(thumb, [kappa])[0] == pytest.approx([1.0, (R0 / R1 - C * R0) / (1 + C * R1)], rel=1e-12)
    u, sweep, _ = sweeps(hand, points=9)
    per_finger = np.array([PLUGIN_KAPPA[c.spec.digit] for c in hand.params.chains])
    assert np.allclose(truth(hand, u, sweep, {"tendon_elasticity_per_finger": per_finger}),
                       compliant(hand, u), atol=1e-13)
    # one compliance for the hand: every chain with the same kappa; the MCP untouched
    q = truth(hand, u, sweep, {"tendon_elasticity": np.array([kappa])})
    q0 = analytic(hand, u)
    for chain in hand.params.chains:
        ratio = chain_coupling(chain, [kappa])[0]
        mcp = chain.spec.q_index[0]
        assert np.allclose(q[:, chain.spec.q_index], q0[:, [mcp]] * ratio, atol=1e-15)


def test_friction_known_answer(hand):
    """The thumb at the same command flexing and extending: the compliance kappa_ref (exp(d mu Theta) - 1),
    Theta = q_MP (A_MP + A_IP), kappa_ref = k_s / EA of [mechanics]; the IP lags flexing and leads
    extending; with an elastic tendon, kappa_ref is its compliance, added to it."""
    u, sweep, _ = sweeps(hand)
    thumb = chain_of(hand, 0)
    mu = 0.2
    q = truth(hand, u, sweep, {"friction_hysteresis": np.array([mu])})
    rows = np.flatnonzero(sweep == 0)
    up, down = rows[20], rows[2 * POINTS - 1 - 20]           # the same command on both branches
    assert u[up, 0] == pytest.approx(u[down, 0], abs=1e-15)
    mech = hand.params.mechanics
    R0, R1 = thumb.radii
    A = ideal_ratios(thumb)
    s = q[up, 1]                                             # the MP (q2) is the cosine law's, untouched
    assert s == pytest.approx(analytic(hand, u[[up]])[0, 1], rel=1e-12) == q[down, 1]
    for row, d in ((up, 1.0), (down, -1.0)):
        C = mech.spring_k / mech.tendon_EA * (math.exp(d * mu * s * A.sum()) - 1.0) * thumb.path_lengths[0] / R1
        assert q[row, 0] == pytest.approx(s * (A[1] - C * R0) / (1 + C * R1), rel=1e-12)
    assert q[up, 0] < s * A[1] < q[down, 0]
    kappa = 0.15
    q2 = truth(hand, u, sweep, {"friction_hysteresis": np.array([mu]), "tendon_elasticity": np.array([kappa])})
    C = kappa * math.exp(mu * s * A.sum()) * thumb.path_lengths[0] / R1
    assert q2[up, 0] == pytest.approx(s * (A[1] - C * R0) / (1 + C * R1), rel=1e-12)


def test_offset_scale_and_backlash_known_answer(hand):
    """Offsets are there at rest; the camera reads (1 + c) of the hand's angle; the play is
    test_backlash.played on the cosine law, and slack acts on what the play delivers."""
    u, sweep, _ = sweeps(hand)
    rng = np.random.default_rng(0)
    o, c = rng.uniform(-2, 2, 15), rng.uniform(-0.04, 0.04, 15)
    q = truth(hand, u, sweep, {"joint_offset": o})
    assert np.allclose(np.degrees(q[np.all(u == 0, axis=1)]), o, atol=1e-12)
    qc = truth(hand, u, sweep, {"joint_offset": o, "camera_scale": c})
    assert np.allclose(qc, q * (1 + c), atol=1e-15)
    w = np.array([3.0, 2.0, 2.5, 1.0, 4.0, 1.5])
    qb = truth(hand, u, sweep, {"backlash": w})
    assert np.allclose(qb, analytic(hand, played(u, sweep, w)), atol=1e-15)
    # at the turning point the play holds the MCP at u_max - b/2 while the command starts back
    k = 1
    rows = np.flatnonzero(sweep == k)
    top = u[rows[POINTS - 1], k] - math.radians(w[k]) / 2
    assert qb[rows[POINTS], 4] == pytest.approx(mcp_angles(hand, np.array([[0, top, 0, 0, 0, 0]]))[0, k])
    delta = np.full(5, 2.0)
    qs = truth(hand, u, sweep, {"backlash": w, "tendon_slack": delta})
    assert np.allclose(qs, analytic(hand, slack(hand, played(u, sweep, w), delta)), atol=1e-15)
    assert np.all(qs[np.flatnonzero(sweep == 0)[-1], :2] == 0.0)      # back at rest: inside the dead band


def test_friction_band_known_answer(hand):
    """With no growth the friction band is the play of test_backlash.played on u1..u5 (none on u6);
    with growth, at the turning point the MCP is held at u_max - (rest + growth) / 2 while the
    command starts back, and back at rest it stays rest / 2 above the command; in series after
    backlash it acts on what the play delivers."""
    u, sweep, _ = sweeps(hand)
    q = truth(hand, u, sweep, {"drive_friction": np.array([2.0, 0.0])})
    w = np.array([2.0, 2.0, 2.0, 2.0, 2.0, 0.0])
    assert np.allclose(q, analytic(hand, played(u, sweep, w)), atol=1e-15)
    rest, growth = 1.0, 3.0
    q = truth(hand, u, sweep, {"drive_friction": np.array([rest, growth])})
    for k in range(5):
        chain = chain_of(hand, k)
        rows = np.flatnonzero(sweep == k)
        top = u[rows[POINTS - 1], k] - math.radians(rest + growth) / 2
        for row in (rows[POINTS - 1], rows[POINTS], rows[POINTS + 1]):   # the top, and the first steps back
            drive = np.zeros((1, 6))
            drive[0, k] = top
            assert q[row, chain.spec.q_index[0]] == pytest.approx(mcp_angles(hand, drive)[0, k], rel=1e-12)
        drive = np.zeros((1, 6))
        drive[0, k] = math.radians(rest) / 2                # the last row, commanded back to 0
        assert q[rows[-1], chain.spec.q_index[0]] == pytest.approx(mcp_angles(hand, drive)[0, k], rel=1e-12)
    b = np.array([3.0, 2.0, 2.5, 1.0, 4.0, 1.5])
    qs = truth(hand, u, sweep, {"backlash": b, "drive_friction": np.array([rest, growth])})
    y = played(u, sweep, b)
    from .hidden import friction_band
    assert np.allclose(qs, analytic(hand, friction_band(hand, y, sweep, rest, growth)), atol=1e-15)


# -- the matrix ----------------------------------------------------------------------------------

def run_hidden(hand, hidden: dict, noise_seed: int, extra=None):
    """diagnose on the written-out data; (diagnosis, its JSON, floor, model-vs-truth MAE in deg)."""
    u, sweep, cj = sweeps(hand)
    q_true = truth(hand, u, sweep, hidden, extra)
    m = measure(hand, u, sweep, cj, q_true, seed=noise_seed)
    d = diagnose(hand, m)
    out = d.to_json()
    floor = d.noise.overall_deg
    ok = np.isfinite(m.q)
    q_fit = d.after.model.predict_measurements(d.after.theta, m)
    vs_truth = float(np.mean(np.abs(np.degrees(q_fit - q_true)[ok])))
    return d, out, floor, vs_truth


def summary(out, floor, vs_truth) -> str:
    return (f"selected {out['selected']}, MAE after {out['mae_deg_after']:.4f} vs floor {floor:.4f} "
            f"(1.5x {1.5 * floor:.4f}), model-vs-truth {vs_truth:.4f} (0.5x {0.5 * floor:.4f}), "
            f"explained {out['explained']}")


def check_fit(out, floor, vs_truth):
    info = summary(out, floor, vs_truth)
    # the floor estimated from the data is the noise's own (else the criteria below would be loose)
    assert abs(floor - EXPECTED_FLOOR) <= 0.25 * EXPECTED_FLOOR, info
    assert out["noise_floor_deg"] == pytest.approx(floor, abs=1e-5)
    assert out["mae_deg_after"] <= 1.5 * floor, info
    assert vs_truth <= 0.5 * floor, info


#: the library's first seven hand effects, then the rest: an effect added to the library appends
#: its cases, so the existing ones keep their seeds (the seeds follow the position in these lists)
FIRST, LATER = HAND_EFFECTS[:7], HAND_EFFECTS[7:]
SINGLES = [*FIRST, "camera_scale", *LATER]
SEEDS = (0, 1, 2)
#: measured failures (strict: they flag when they start passing)
SINGLE_XFAIL: dict[tuple[str, int], str] = {}


def single_cases():
    for name in SINGLES:
        for seed in SEEDS:
            reason = SINGLE_XFAIL.get((name, seed))
            marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
            yield pytest.param(name, seed, marks=marks, id=f"{name}-seed{seed}")


@pytest.mark.parametrize("name, seed", list(single_cases()))
@pytest.mark.slow
def test_one_hidden_effect(hand, name, seed):
    hidden = hidden_values(hand, [name], seed)
    d, out, floor, vs_truth = run_hidden(hand, hidden, noise_seed=1000 + 10 * SINGLES.index(name) + seed)
    info = summary(out, floor, vs_truth)
    assert out["mae_deg_before"] > 3 * floor, info          # the hidden effect is there to be found
    if name == "camera_scale":
        # a measurement-side effect is scored only after no hand effect passes: it must stand alone
        assert out["selected"] == ["camera_scale"], info
    else:
        # per finger: the per-finger compliances are drawn over 0.07-0.27 1/m, apart by far more than
        # the noise resolves, so _simplify must not fold them into the one-value tendon_elasticity
        # (its 4 extra parameters pay); the near-equal case is
        # test_equal_per_finger_compliance_is_simplified
        assert out["selected"][0] == name, info
    check_fit(out, floor, vs_truth)
    assert out["explained"] is True, info


def test_equal_per_finger_compliance_is_simplified(hand):
    """Per-finger compliances equal within 0.002 1/m: the data cannot tell them from one value, and
    diagnose legitimately reports the simpler tendon_elasticity (_simplify, or the first round's
    lower dIC), a model that matches the truth as closely."""
    rng = np.random.default_rng(5)
    kappa = 0.17 + rng.uniform(-0.002, 0.002, 5)
    d, out, floor, vs_truth = run_hidden(hand, {"tendon_elasticity_per_finger": kappa}, noise_seed=1500)
    info = summary(out, floor, vs_truth)
    assert out["selected"] == ["tendon_elasticity"], info
    check_fit(out, floor, vs_truth)
    assert out["explained"] is True, info
    fitted = out["effects"]["tendon_elasticity"]["parameters"]["compliance_per_m"]["value"]
    assert fitted == pytest.approx(kappa.mean(), abs=0.01)


PAIRS = [*itertools.combinations(FIRST, 2), *((h, "camera_scale") for h in FIRST),
         *((h, n) for k, n in enumerate(LATER) for h in (*FIRST, *LATER[:k])), *((n, "camera_scale") for n in LATER)]
#: one compliance per finger on top of a common one is one compliance per finger: the variant
#: contains its simpler form (effects.TendonElasticityPerFinger.simpler), so only it can be selected
NESTED = {("tendon_elasticity", "tendon_elasticity_per_finger"): ["tendon_elasticity_per_finger"]}
#: n_eff of a round has a floor: that of the whole hand family fitted at once (diagnose.py). From
#: the best candidate's residual alone, which the other hidden effect keeps near the clip of rho at
#: 0.95, n_eff would be so small that nothing passed in the three backlash pairs and friction +
#: camera_scale
PAIR_XFAIL: dict[tuple[str, str], str] = {}


def pair_cases():
    for k, (a, b) in enumerate(PAIRS):
        reason = PAIR_XFAIL.get((a, b))
        marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
        yield pytest.param(a, b, k, marks=marks, id=f"{a}+{b}")


#: a hand effect a camera's per-joint scales duplicate exactly on a sweep (a compliance scales each
#: distal joint by a constant, q_k = c_k(kappa) q_MCP): no rule on these data can attribute it, so
#: what is asserted is that the report says so (diagnose._duplicated: "the data cannot tell X from
#: camera_scale", and that a calibrated control law lacks X) and that the fit meets the criteria.
#: Measured: the backward step after camera_scale drops the hidden compliance (dIC -6.8 / -34.0),
#: MAE after 0.0816 / 0.0797 against floors 0.0809 / 0.0776, model-vs-truth 0.0068 / 0.0095 deg.
DUPLICATED_BY_CAMERA = {"tendon_elasticity", "tendon_elasticity_per_finger"}
#: and one it duplicates nearly: a drive pulley's radius error scales its chain's angles as per-joint
#: scales do but for the cosine law's curvature. Measured (seed 100 + k): selected ['camera_scale']
#: only, the backward step dropped the hidden radius errors (dIC -15.6) and a spurious joint offset;
#: with the scales in the fit the radius errors' variance grows 1,750-3,270-fold (the offset's 2-4);
#: MAE after 0.0766 vs floor 0.0782, model-vs-truth 0.0148. Refitted with the scales the radius
#: errors stand at |z| <= 3.0, where spurious ones on camera-only data reach 2.4, so no selection
#: rule can attribute them: the report names the near-duplication instead.
NEARLY_DUPLICATED_BY_CAMERA = {"pulley_radius_error"}


@pytest.mark.parametrize("a, b, k", list(pair_cases()))
@pytest.mark.slow
def test_two_hidden_effects(hand, a, b, k):
    hidden = hidden_values(hand, [a, b], seed=100 + k)
    d, out, floor, vs_truth = run_hidden(hand, hidden, noise_seed=2000 + k)
    info = summary(out, floor, vs_truth)
    if (a, b) in NESTED:
        assert out["selected"] == NESTED[a, b], info
    elif b == "camera_scale" and a in DUPLICATED_BY_CAMERA | NEARLY_DUPLICATED_BY_CAMERA and a not in out["selected"]:
        assert b in out["selected"], info
        named = [n for n in out["notes"] if n.startswith(f"{a} was dropped after camera_scale")]
        words = "cannot tell" if a in DUPLICATED_BY_CAMERA else "barely tell"
        assert named and f"the data {words} {a} from camera_scale" in named[0], (info, out["notes"])
        assert f"a calibrated control law lacks {a}" in named[0]
        # an effect the scales do not duplicate (a joint offset: there at rest), dropped with it, is
        # not said to be duplicated; a spurious one they do (a radius error) may be
        others = [n for n in out["notes"] if " was dropped after camera_scale" in n
                  and n.split(" ", 1)[0] not in DUPLICATED_BY_CAMERA | NEARLY_DUPLICATED_BY_CAMERA]
        assert not any("cannot tell" in n or "barely tell" in n for n in others), out["notes"]
    else:
        assert a in out["selected"] and b in out["selected"], info
    check_fit(out, floor, vs_truth)


@pytest.mark.slow
def test_a_hand_effect_the_camera_duplicates_is_named(hand):
    """A uniform compliance and a camera scale hidden together (DUPLICATED_BY_CAMERA above): the
    attribution cannot be right from these data (a compliance scales each distal joint by a
    constant, a per-joint scale), so the report must say which hand effect the measurement side
    replaced and that the control law lacks it; a joint offset it dropped (separable: it is there
    at rest) gets no such sentence."""
    k = PAIRS.index(("tendon_elasticity", "camera_scale"))
    d, out, floor, vs_truth = run_hidden(hand, hidden_values(hand, ["tendon_elasticity", "camera_scale"], seed=100 + k),
                                         noise_seed=2000 + k)
    notes = {n.split(" ", 1)[0]: n for n in out["notes"] if " was dropped after camera_scale" in n}
    assert "tendon_elasticity" in notes and "joint_offset" in notes, out["notes"]
    assert "the data cannot tell tendon_elasticity from camera_scale (not identifiable together: " in notes["tendon_elasticity"]
    assert "0.71 tendon_elasticity.compliance_per_m" in notes["tendon_elasticity"]    # measured: +-0.71
    assert "a calibrated control law lacks tendon_elasticity" in notes["tendon_elasticity"]
    assert "cannot tell" not in notes["joint_offset"] and "barely tell" not in notes["joint_offset"]


# -- physics outside the library -----------------------------------------------------------------

def test_outside_physics_known_answers(hand):
    """Sag: at rest every finger joint is flexed by its g (links horizontal), the thumb and the CMC
    untouched, and at a flexed row by g cos(sum of the joint angles up to it). Stop: the ring MCP is
    untouched below the stop, and at full travel reaches q_stop + 0.8 (q_free - q_stop)."""
    u, sweep, _ = sweeps(hand)
    q0 = analytic(hand, u)
    g = (1.0, 0.6, 0.3)
    q = truth(hand, u, sweep, {}, gravity_sag(hand, g))
    rest = np.all(u == 0, axis=1)
    for chain in hand.params.chains:
        for i, qi in enumerate(chain.spec.q_index):
            expect = 0.0 if chain.spec.digit == "thumb" else g[i]
            assert np.allclose(np.degrees(q[rest, qi]), expect, atol=1e-12)
    assert np.allclose(q[:, [0, 1, 14]], q0[:, [0, 1, 14]], atol=1e-15)
    row = np.flatnonzero(sweep == 2)[20]                 # middle finger: q8 MCP, q7 PIP, q6 DIP
    phi = np.cumsum(q0[row, [7, 6, 5]])
    assert np.degrees(q[row, [7, 6, 5]] - q0[row, [7, 6, 5]]) == pytest.approx(np.array(g) * np.cos(phi))
    extra, mcp, q_stop = soft_stop(hand)
    q = truth(hand, u, sweep, {}, extra)
    below = q0[:, mcp] <= q_stop
    assert below.sum() > 0.7 * len(u) and np.allclose(q[below], q0[below], atol=1e-15)
    top = np.argmax(q0[:, mcp])
    assert q[top, mcp] == pytest.approx(q_stop + 0.8 * (q0[top, mcp] - q_stop), rel=1e-12)
    assert np.degrees(q0[top, mcp] - q[top, mcp]) > 2.0        # a shortfall well beyond the noise
    assert np.allclose(np.delete(q, mcp, axis=1), np.delete(q0, mcp, axis=1), atol=1e-15)


@pytest.mark.slow
def test_gravity_sag_is_left_or_matched(hand):
    """A joint error that depends on the pose (gravity sag, hidden.gravity_sag: 1.0 / 0.6 / 0.3 deg at
    MCP / PIP / DIP of the four fingers, times the cosine of the link's absolute angle). No library
    effect is the sag, so the one honest outcome is "left", on finger joints, with the signature of
    what is left. What happens (measured): joint_offset +
    camera_scale bring the MAE to 0.092 deg against a 0.082 floor, within the MAE tolerance, but
    that model is 0.045 deg from the truth (the criterion is 0.041) and the residual it leaves is
    correlated from sample to sample (lag-1 autocorrelation 0.17, z 5.0): the whiteness test of the
    verdict (residual.py) says `explained: false`, left q8 and q9, rather than explained on a
    model off the truth."""
    d, out, floor, vs_truth = run_hidden(hand, {}, noise_seed=3000, extra=gravity_sag(hand))
    info = summary(out, floor, vs_truth)
    assert abs(floor - EXPECTED_FLOOR) <= 0.25 * EXPECTED_FLOOR, info
    # no library effect is the sag: the model kept is off the truth by more than the criterion, so
    # the one honest outcome is "not explained", left on finger joints
    assert vs_truth > 0.5 * floor, info
    assert out["explained"] is False, info
    fingers = {j.label for j in JOINTS if j.digit != "thumb"}
    assert out["left"] and set(out["left"]) <= fingers, info
    overall = out["verdict"]["overall"]
    assert overall["white"] is False and overall["whiteness_z"] > 4.0, overall
    # what is left is the same in both directions and on the fingers, not the thumb
    sm = out["signature_match"]["after"]
    assert sm["measured"]["direction"] == "same" and sm["measured"]["digits"] == "some", sm
    assert set(sm["details"]["digits_with_structure"]) <= {"index", "middle", "ring", "pinky"}
    text = "\n".join(diagnosis_text(d, out))
    assert "neighbouring residuals are correlated: lag-1 autocorrelation" in text


def test_soft_stop_is_left_on_its_joint(hand):
    """The ring MCP meets a compliant stop at 85 % of its travel and turns only 80 % of the rest
    (2.4 deg short at full travel). What happens (measured): no library effect passes (the best,
    friction_hysteresis / tendon_elasticity, score dIC +5; pulley_radius_error +13), explained is False
    and the verdict names the ring MCP alone (structured RMS 0.56 deg); the analytic model, all
    diagnose keeps, is off the truth only on the last samples of that one joint."""
    extra, mcp, _ = soft_stop(hand)
    d, out, floor, vs_truth = run_hidden(hand, {}, noise_seed=3000, extra=extra)
    info = summary(out, floor, vs_truth)
    assert abs(floor - EXPECTED_FLOOR) <= 0.25 * EXPECTED_FLOOR, info
    assert out["explained"] is False, info
    assert set(out["left"]) == {f"q{mcp + 1}"}, (info, out["left"])
    assert out["left"][f"q{mcp + 1}"]["structured_rms_deg"] > 0.3
