"""drive_friction (the drive tendon's friction band, a play whose width follows the spring's tension)
against the band written out row by row in tests/calibration/hidden.py (friction_band: its own loop,
its own cosine law), and its composition with backlash."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.calibration.effects import History, get_effect, run_pipeline

from .hidden import directions, friction_band, truth
from .test_backlash import played
from .test_noise_floor import analytic, sweeps


@pytest.fixture(scope="module")
def recording(hand):
    u, sweep, _ = sweeps(hand)
    d = directions(u, sweep)
    return u, sweep, d, History(u, sweep, d)


def test_alone_is_the_band_written_out(hand, recording):
    u, sweep, d, hist = recording
    x = np.array([1.5, 2.0])
    q = run_pipeline(hand, [(get_effect("drive_friction"), x)], u, d, 0.0, hist)
    assert np.allclose(q, analytic(hand, friction_band(hand, u, sweep, *x)), atol=1e-12)
    # the MCP is in the band: below the analytic model flexing, above it extending, on every finger
    q0 = analytic(hand, u)
    for chain in hand.params.chains:
        k, mcp = chain.spec.servo, chain.spec.q_index[0]
        rows = np.flatnonzero((sweep == k) & (u[:, k] > 0.2) & (u[:, k] < hand.u_max[k] - 0.2))
        assert np.all((q[rows, mcp] - q0[rows, mcp]) * d[rows, k] < 0)
    # the CMC's direct drive has no tendon: untouched
    assert np.array_equal(q[:, 14], q0[:, 14])


def test_in_series_with_backlash(hand, recording):
    """Two plays in series act as one of the summed width (exact for constant widths: the effect
    takes the band's width at the command, the writer at what the play delivers; the difference is
    the band's growth across the play's half width: measured at most 0.03 deg here)."""
    u, sweep, d, hist = recording
    x = np.array([1.5, 0.0])
    b = np.array([3.0, 2.0, 2.5, 1.0, 3.5, 1.5])
    items = [(get_effect("drive_friction"), x), (get_effect("backlash"), b)]
    q = run_pipeline(hand, items, u, d, 0.0, hist)
    assert np.allclose(q, truth(hand, u, sweep, {"backlash": b, "drive_friction": x}), atol=1e-12)
    assert np.allclose(q, analytic(hand, played(u, sweep, b + np.append(np.full(5, 1.5), 0.0))), atol=1e-12)
    x = np.array([1.5, 2.0])
    q = run_pipeline(hand, [(get_effect("drive_friction"), x), (get_effect("backlash"), b)], u, d, 0.0, hist)
    t = truth(hand, u, sweep, {"backlash": b, "drive_friction": x})
    assert np.degrees(np.abs(q - t)).max() <= 0.05
    # listed in either order, the same result (stage and order sort them)
    q_rev = run_pipeline(hand, [(get_effect("backlash"), b), (get_effect("drive_friction"), x)], u, d, 0.0, hist)
    assert np.array_equal(q, q_rev)


def test_a_batch_of_rows_uses_the_whole_history(hand, recording):
    u, sweep, d, hist = recording
    items = [(get_effect("drive_friction"), np.array([1.0, 2.5])), (get_effect("backlash"), np.full(6, 2.0))]
    whole = run_pipeline(hand, items, u, d, 0.0, hist)
    rows = np.arange(7, len(u), 5)
    part = run_pipeline(hand, items, u[rows], d[rows], 0.0, hist, rows)
    assert np.array_equal(part, whole[rows])


def test_without_history_nothing_and_the_control_law_aims_at_the_middle(hand, recording):
    u, sweep, d, hist = recording
    eff = get_effect("drive_friction")
    x = np.array([2.0, 2.0])
    assert np.allclose(run_pipeline(hand, [(eff, x)], u, d, 0.0), analytic(hand, u), atol=1e-13)
    assert eff.invertible and np.array_equal(eff.invert(hand, u, x), u)
    # the band's width at rest and at full flexion, from its parameters (file units: degrees)
    w = 2 * np.degrees(eff.band(eff.tension(hand, np.stack([hand.u_min, hand.u_max])), x))
    assert w[:, :5] == pytest.approx(np.array([[2.0] * 5, [4.0] * 5]), abs=1e-12)
    assert np.all(w[:, 5] == 0.0)


def test_a_servo_effect_between_the_two_plays_is_kept(hand, recording):
    """The servo stage keeps one play of the summed widths and replaces only its own contribution:
    an effect ordered between backlash (5) and drive_friction (7) (here a constant 1 deg on u2)
    acts as it would after both."""
    from phantom_cad.calibration.effects import Effect

    class Shift(Effect):
        name, stage = "shift_u2", "servo"

        def __init__(self, order):
            self.order = order

        def apply(self, ctx, x):
            ctx.u_eff[:, 1] += np.radians(1.0)

    u, sweep, d, hist = recording
    b = np.full(6, 2.0)
    x = np.array([1.0, 1.5])
    plays = [(get_effect("backlash"), b), (get_effect("drive_friction"), x)]
    between = run_pipeline(hand, [*plays, (Shift(6), np.zeros(0))], u, d, 0.0, hist)
    after = run_pipeline(hand, [*plays, (Shift(8), np.zeros(0))], u, d, 0.0, hist)
    without = run_pipeline(hand, plays, u, d, 0.0, hist)
    assert np.allclose(between, after, rtol=0, atol=1e-14)
    assert not np.allclose(between, without)
