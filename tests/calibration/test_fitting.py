"""The bounded-memory fit (fitting.fit_streamed, used for the final fit of a large file) against
scipy's least_squares, the independent implementation the other fits use."""

import numpy as np
import pytest

from phantom_cad.calibration.fitting import Model, Problem, fit, fit_streamed
from phantom_cad.calibration.simulate import simulate


@pytest.mark.parametrize("names, seed", [(["friction_hysteresis", "joint_offset", "tendon_elasticity"], 1),
                                         (["tendon_slack", "pulley_radius_error"], 2)])
@pytest.mark.slow
def test_streamed_fit_matches_least_squares(hand, names, seed, monkeypatch):
    """Same minimum, same sum of squares, same uncertainties as scipy.optimize.least_squares
    (trust region reflective), on blocks smaller than the file so that the sums over blocks count."""
    from phantom_cad.calibration import fitting

    sim = simulate(hand, names, noise_deg=0.1, seed=seed, points=120)
    problem = Problem(hand, sim.measurements)
    model = Model(hand, names, problem)
    monkeypatch.setattr(fitting, "PREDICT_ROWS", 97)
    got = fit_streamed(model, problem)
    want = fit(model, problem)
    scale = np.maximum(want.std, 1e-12)
    assert np.all(np.abs(got.theta - want.theta) <= 1e-3 * scale + 1e-9), (got.theta, want.theta)
    assert got.rss == pytest.approx(want.rss, rel=1e-9)
    np.testing.assert_allclose(got.std, want.std, rtol=1e-3)
    assert got.residual.size == want.residual.size == problem.m


def test_streamed_fit_stays_within_the_bounds(hand):
    """A parameter whose unconstrained optimum lies beyond its bound ends on the bound, as with
    least_squares: elasticity fitted to data made with a negative compliance (tendons that
    lengthen less than rigid) stops at 0."""
    sim = simulate(hand, ["tendon_elasticity"], noise_deg=0.05, seed=3, points=60,
                   explicit={"tendon_elasticity": {"compliance_per_m": 0.2}})
    m = sim.measurements
    # mirror the effect: data = analytic - (effect); the best compliance is then negative
    analytic = hand.forward(m.u)
    mirrored = type(m)(m.u, 2 * analytic - m.q, m.measured, m.sweep, m.sweep_ids, m.t, m.lines, m.source,
                       m.has_sweep_column)
    problem = Problem(hand, mirrored)
    model = Model(hand, ["tendon_elasticity"], problem)
    got, want = fit_streamed(model, problem), fit(model, problem)
    assert model.lower[0] == 0.0
    assert got.theta[0] == pytest.approx(want.theta[0], abs=1e-9)
    assert got.theta[0] == pytest.approx(0.0, abs=1e-9)
