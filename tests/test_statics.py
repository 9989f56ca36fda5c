"""The routed compensation (kinematics.statics, ``Hand(compensation="routed")``) against the
statics of the printed routing written out here by hand, as tests/export/test_mjcf.py checks the
twin: the return cord pulls with T = k_s sum R_i q_i; loop k carries (n - 1 - k) T and gives
R_k q_k - R_{k+1} q_{k+1} by its strands' stretch over their whole rest lengths (the routing
model's lengths at rest); the drive pulls with n T R_0 over its moment arm d1 d2 sin(alpha - s) / L
and stretches over its rest length. The reference angle is found here by scipy's brentq on
that equation, not by the model's Newton steps.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad import Hand, load_params
from phantom_cad.kinematics import routing_paths
from phantom_cad.kinematics.topology import CHAINS
from phantom_cad.params import ParamError, parse

brentq = pytest.importorskip("scipy.optimize").brentq


@pytest.fixture(scope="module")
def params():
    return load_params()


@pytest.fixture(scope="module")
def rest(params):
    """Every strand's rest length (m), from the routing model."""
    return routing_paths.lengths(params)


def _preloaded(document, preload):
    document["mechanics"]["loop_preload_N"] = preload
    return parse(document)


def _loop_give(F, La, Lb, EA, P):
    """A loop's give under a net tension F: both strands share it while the slack-side one keeps
    tension, then the taut one alone (its preload spent first)."""
    if F < P * (1.0 + Lb / La):
        return F / (EA * (1.0 / La + 1.0 / Lb))
    return (F - P) * La / EA


def _loops(params, rest, digit):
    """Per loop (reference side first): (rest length of the strand that pulls, of its partner).
    Under the return cord's load the distal joint lags: the strand that pulls is the one the
    routing's length law lengthens when the loop's proximal joint flexes alone (the twin's
    stretched strand, tests/export/test_mjcf.py)."""
    chain = params.digit(digit).chain
    keys = chain.joints
    out = []
    for k in range(len(keys) - 1):
        a, b = (rest[f"{digit}_{keys[k]}_{keys[k + 1]}_{x}"] for x in "ab")
        q = np.zeros(15)
        q[chain.spec.q_index[k]] = 0.1
        bent = routing_paths.lengths(params, q)
        out.append((a, b) if bent[f"{digit}_{keys[k]}_{keys[k + 1]}_a"] > a else (b, a))
    return out


def _by_hand(params, rest, digit, u):
    """(q of the chain, reference first) at servo angle u, from the statics by hand."""
    chain = params.digit(digit).chain
    n = len(chain.joints)
    R = chain.radii
    k_s, EA, P = params.mechanics.spring_k, params.mechanics.tendon_EA, params.mechanics.loop_preload
    loops = _loops(params, rest, digit)

    def joints(s):
        # q_j from s: solve the loop chain for T by bisection on T = k_s R.q (monotone)
        def q_of(T):
            q = [s]
            for k in range(n - 1):
                give = _loop_give((n - 1 - k) * T, *loops[k], EA, P)
                q.append((R[k] * q[k] - give) / R[k + 1])
            return q
        T = brentq(lambda T: T - k_s * sum(r * x for r, x in zip(R, q_of(T))), 0.0, 1e3, xtol=1e-15, rtol=1e-15)
        return q_of(T), T

    g = chain.guide
    d1, d2, alpha, r = g.d1, g.d2, g.alpha, chain.servo_radius
    L0 = math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha))

    def residual(s):
        _, T = joints(s)
        L = math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha - s))
        arm = d1 * d2 * math.sin(alpha - s) / L
        return L - (L0 - r * u + n * T * R[0] / arm * rest[f"{digit}_drive"] / EA)

    s = brentq(residual, 0.0, alpha - 0.05, xtol=1e-15, rtol=1e-15)
    return joints(s)[0]


@pytest.mark.parametrize("preload", [0.0, 1.5, 20.0])
def test_forward_is_the_statics_by_hand(params, rest, document, preload):
    """Every chain at 5 commands over its travel: the model's joints within 1e-9 rad of the
    statics solved here (with a 1.5 N preload the loops go one-sided inside the travel)."""
    p = params if preload == 0.0 else _preloaded(document, preload)
    hand = Hand(p)
    for spec in CHAINS:
        chain = p.digit(spec.digit).chain
        for f in (0.1, 0.3, 0.5, 0.8, 1.0):
            u = hand.u_min.copy()
            u[spec.servo] = chain.travel[0] + f * (chain.travel[1] - chain.travel[0])
            q = hand.forward(u, compensated=True)[list(spec.q_index)]
            assert np.allclose(q, _by_hand(p, rest, spec.digit, u[spec.servo]), atol=1e-9, rtol=0), (spec.digit, f)


def test_coupling_is_the_loop_statics(params, rest):
    """Without preload the coupling is linear, q = c q_ref: by hand for the index finger, loop 0
    carries 2T over its taut strand, loop 1 T, T = k_s R.q (a 3 x 3 system at q_ref = 1)."""
    hand = Hand(params)
    R_mcp, R_pip, R_dip = params.digit("index").chain.radii
    kappa = params.mechanics.spring_k / params.mechanics.tendon_EA
    (L0, _), (L1, _) = _loops(params, rest, "index")
    # q_MCP = 1; R_MCP - R_PIP q_PIP = 2 kappa L0 R.q; R_PIP q_PIP - R_DIP q_DIP = kappa L1 R.q
    M = np.array([[1.0, 0.0, 0.0],
                  [2 * kappa * L0 * R_mcp, R_pip + 2 * kappa * L0 * R_pip, 2 * kappa * L0 * R_dip],
                  [kappa * L1 * R_mcp, -R_pip + kappa * L1 * R_pip, R_dip + kappa * L1 * R_dip]])
    c = np.linalg.solve(M, [1.0, R_mcp, 0.0])
    spec = CHAINS[1]
    assert np.allclose(hand.coupling_compensated[spec.servo, list(spec.q_index)], c, atol=1e-12, rtol=0)


@pytest.mark.parametrize("compensation", ["routed", "paper"])
@pytest.mark.parametrize("preload", [0.0, 1.5])
def test_control_law_inverts_the_forward(params, document, compensation, preload):
    """inverse(forward(u)) = u over the whole travel, every servo, within 1e-9 rad."""
    p = params if preload == 0.0 else _preloaded(document, preload)
    hand = Hand(p, compensation=compensation)
    rng = np.random.default_rng(1)
    grid = np.vstack([np.linspace(0.0, 1.0, 201)[:, None] * np.ones(6), rng.random((500, 6))])
    u = hand.u_min + grid * (hand.u_max - hand.u_min)
    assert np.abs(hand.inverse(hand.forward(u, compensated=True)) - u).max() < 1e-9


def test_batched_forward_is_the_single_pose_forward(params):
    """A batch larger than a block gives what each pose gives alone."""
    hand = Hand(params)
    u = hand.u_min + np.random.default_rng(2).random((20000, 6)) * (hand.u_max - hand.u_min)
    q = hand.forward(u, compensated=True)
    for i in (0, 8191, 8192, 19999):
        assert np.allclose(q[i], hand.forward(u[i], compensated=True), atol=1e-12, rtol=0)


def test_jacobian_is_the_slope_of_the_forward(params):
    hand = Hand(params)
    u = 0.5 * (hand.u_min + hand.u_max)
    J = hand.jacobian(u, compensated=True)
    h = 1e-6
    for k in range(6):
        du = np.zeros(6)
        du[k] = h
        slope = (hand.forward(u + du, compensated=True) - hand.forward(u - du, compensated=True)) / (2 * h)
        assert np.allclose(J[:, k], slope, atol=1e-7)


def test_the_paper_form_stays_available(params):
    """compensation="paper" is eq. (13)/(14); the analytic model is the same for both."""
    routed, paper = Hand(params), Hand(params, compensation="paper")
    assert (routed.compensation, paper.compensation) == ("routed", "paper")
    assert np.array_equal(paper.coupling_compensated, paper.coupling_matrix(paper.compliance))
    u = 0.7 * paper.u_max
    assert np.array_equal(routed.forward(u), paper.forward(u))
    with pytest.raises(ValueError, match="compensation must be one of routed, paper"):
        Hand(params, compensation="lumped")


def test_loop_preload_is_checked(document):
    for bad in (-1.0, 20.5):
        document["mechanics"]["loop_preload_N"] = bad
        with pytest.raises(ParamError) as e:
            parse(document)
        assert "mechanics.loop_preload_N" in str(e.value) and "\n" not in str(e.value)


def test_fast_solve_is_the_solve_to_convergence(params):
    """The batched forward's Newton steps from the fitted start (more steps than it needs too)
    and beyond the travel (where the fit does not hold) agree with the solve to convergence."""
    from phantom_cad.kinematics import statics

    hand = Hand(params)
    law = hand._law
    assert law.steps >= 1
    u = hand.u_min + np.linspace(-0.1, 1.1, 301)[:, None] * (hand.u_max - hand.u_min)
    exact = np.stack([statics.reference_angle(u[:, k], c, s)
                      for k, (c, s) in enumerate(zip(params.chains, hand.statics))], axis=-1)
    assert np.abs(law.reference_angles(u[:, :5]) - exact).max() < statics.FAST_TOLERANCE
    steps = law.steps
    try:
        law.steps = steps + 2
        assert np.abs(law.reference_angles(u[:, :5]) - exact).max() < 1e-12
    finally:
        law.steps = steps


def test_too_soft_a_tendon_is_refused(document):
    """Below about 45 N (default k_s and routing) the routed statics leave the middle DIP no
    coupling: the hand is refused with one line naming EA (the paper's form allows 24 N)."""
    document["mechanics"]["tendon_EA_N"] = 40.0
    p = parse(document)
    with pytest.raises(ParamError) as e:
        Hand(p)
    assert str(e.value).startswith("mechanics.tendon_EA_N = 40.0: ") and "middle DIP" in str(e.value)
    assert "\n" not in str(e.value)
    Hand(p, compensation="paper")
