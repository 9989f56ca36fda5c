"""History-dependent effects: the pipeline receives the sweep and the row order (effects.History,
Context.rows), and the library's backlash (play at every reversal) is selected by diagnose on data
whose backlash is written out here, row by row (never simulate or the effect classes), on the
closed-form cosine law of test_noise_floor."""

import math

import numpy as np
import pytest

from phantom_cad.calibration.data import Measurements
from phantom_cad.calibration.diagnose import diagnose
from phantom_cad.calibration.residual import MAE_PER_SIGMA

from .test_noise_floor import NOISE_DEG, analytic, measure, sweeps


def played(u, sweep, widths_deg):
    """The servo angle that reaches the tendon: the output of a play of full width b (deg) per
    servo, row by row: it moves only when the command is more than b/2 away, then trails it by b/2;
    each sweep starts with the output at the command."""
    y = np.array(u, dtype=float)
    for s in range(u.shape[1]):
        half = math.radians(widths_deg[s]) / 2.0
        out = None
        for k in range(len(u)):
            if k == 0 or sweep[k] != sweep[k - 1]:
                out = u[k, s]
            elif u[k, s] - out > half:
                out = u[k, s] - half
            elif out - u[k, s] > half:
                out = u[k, s] + half
            y[k, s] = out
    return y


def test_the_play_written_here_known_answer():
    u = np.radians([[0.0], [1.0], [3.0], [5.0], [4.0], [2.0], [1.0]])
    y = played(u, np.zeros(7, dtype=int), [2.0])
    assert np.degrees(y[:, 0]) == pytest.approx([0.0, 0.0, 2.0, 4.0, 4.0, 3.0, 2.0])


def test_pipeline_backlash_on_a_subset_of_rows_uses_the_whole_history(hand):
    """A fold or a block of rows sees the same play output as the whole file: the state comes from
    the history, not from the rows the batch happens to hold."""
    from phantom_cad.calibration.effects import History, get_effect, run_pipeline

    u, sweep, _ = sweeps(hand, points=12)
    widths = [3.0, 2.0, 2.5, 1.0, 4.0, 1.5]
    m = Measurements(u, np.full((len(u), 15), np.nan), np.ones(15, bool), sweep, tuple("abcdef"), None,
                     np.arange(len(u)) + 2, "<test>", True)
    h = History.of(m)
    items = [(get_effect("backlash"), np.array(widths))]
    q_all = run_pipeline(hand, items, u, m.direction, 0.0, h)
    assert np.allclose(q_all, analytic(hand, played(u, sweep, widths)), atol=1e-12)
    rows = np.arange(5, len(u), 7)
    q_sub = run_pipeline(hand, items, u[rows], m.direction[rows], 0.0, h, rows)
    assert np.allclose(q_sub, q_all[rows], atol=1e-12)
    # without a history (Hand.forward, the control law) backlash is not applied
    assert np.allclose(run_pipeline(hand, items, u, m.direction, 0.0), analytic(hand, u), atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_diagnose_selects_backlash_and_reaches_the_noise(hand, seed):
    rng = np.random.default_rng([seed, 77])
    widths = rng.uniform(2.5, 3.5, 6)                       # deg, every servo
    u, sweep, cj = sweeps(hand)
    q_clean = analytic(hand, played(u, sweep, widths))
    m = measure(hand, u, sweep, cj, q_clean, seed=100 + seed)
    d = diagnose(hand, m)
    out = d.to_json()
    floor = out["noise_floor_deg"]
    assert abs(floor - NOISE_DEG * MAE_PER_SIGMA) < 0.2 * NOISE_DEG * MAE_PER_SIGMA
    assert out["selected"][0] == "backlash", out["selected"]
    assert out["mae_deg_before"] > 5 * floor
    assert out["mae_deg_after"] <= 1.5 * floor and out["explained"] is True
    fitted = out["effects"]["backlash"]["parameters"]
    for s in range(6):
        assert fitted[f"u{s + 1}_deg"]["value"] == pytest.approx(widths[s], abs=0.15), s
    # the fitted model against the noise-free truth, on every measured cell
    q_fit = d.after.model.predict_measurements(d.after.theta, m)
    ok = np.isfinite(m.q)
    assert np.mean(np.abs(np.degrees(q_fit - q_clean)[ok])) <= 0.5 * floor
    # the analytic model's residual shows backlash's declared signature; drive_friction's (a play
    # whose width may grow with tension: trend "any") shares it: the fit, not the signature, tells
    # a per-servo width from one band law for the hand
    sm = out["signature_match"]["before"]
    assert sm["measured"]["direction"] == "flips" and sm["measured"]["reversal"] == "jump"
    assert sm["measured"]["joints"] == "all" and sm["measured"]["trend"] == "flat"
    assert sm["effects_with_this_signature"] == ["backlash", "drive_friction"]


@pytest.mark.slow
def test_fit_writes_backlash_and_the_file_reproduces_it(hand, tmp_path):
    """The written file's forward, given the recording's history, reproduces the fit; its control
    law runs (backlash aims at the middle of the play)."""
    import subprocess
    import sys
    from pathlib import Path

    from phantom_cad import load_hand
    from phantom_cad.calibration.data import write_measurements
    from phantom_cad.calibration.labels import Labels

    widths = [3.0, 2.0, 2.5, 1.5, 3.5, 2.0]
    u, sweep, cj = sweeps(hand)
    m = measure(hand, u, sweep, cj, analytic(hand, played(u, sweep, widths)), seed=9)
    data, out = tmp_path / "data.csv", tmp_path / "cal.toml"
    write_measurements(data, m.u, m.q, sweep=Labels(m.sweep_ids, m.sweep), q_columns=m.q_columns)
    root = Path(__file__).resolve().parents[2]
    r = subprocess.run([sys.executable, "-c", "from phantom_cad.cli import main; main()", "fit", str(data),
                        "--effects", "backlash", "--out", str(out)], capture_output=True, text=True, cwd=root,
                       env={**__import__("os").environ, "PYTHONPATH": str(root)})
    assert r.returncode == 0, r.stderr
    from phantom_cad.params import load_document

    fitted = load_document(out)["effects"]["backlash"]
    for s in range(6):
        assert fitted[f"u{s + 1}_deg"] == pytest.approx(widths[s], abs=0.15)
    cal = load_hand(out)
    q0 = cal.forward(u[:3], compensated=True)
    assert np.allclose(cal.inverse(q0, compensated=True), u[:3], atol=1e-9)


def test_slack_acts_on_the_plays_output(hand):
    """The play is in the servo's drive, the slack in the tendon after it: u_eff = slack(play(u)).
    Known answer by hand (index servo u2, u_min = 0, play 4 deg, slack 3 deg): commands 0, 2, 6, 9,
    7, 5 deg -> play 0, 0, 4, 7, 7, 7 -> slack max(play - 3, 0) = 0, 0, 1, 4, 4, 4 deg. (The sum
    slack(u) + play(u) - u the library computed before gives 0, -2, 1, 4, 4, 4: a joint pulled
    2 deg past rest inside the dead band.)"""
    from phantom_cad.calibration.effects import History, get_effect, run_pipeline

    cmd = np.radians([0.0, 2.0, 6.0, 9.0, 7.0, 5.0])
    u = np.zeros((cmd.size, 6))
    u[:, 1] = cmd
    sweep = np.zeros(cmd.size, dtype=int)
    direction = np.zeros((cmd.size, 6))
    direction[1:, 1] = np.sign(np.diff(cmd))
    h = History(u, sweep, direction)
    width = np.zeros(6)
    width[1] = 4.0
    slack = np.zeros(5)
    slack[1] = 3.0
    assert hand.u_min[1] == 0.0
    for items in ([(get_effect("tendon_slack"), slack), (get_effect("backlash"), width)],
                  [(get_effect("backlash"), width), (get_effect("tendon_slack"), slack)]):
        q = run_pipeline(hand, items, u, direction, 0.0, h)
        want = hand.forward(np.column_stack([np.zeros(cmd.size), np.radians([0, 0, 1, 4, 4, 4]),
                                             np.zeros((cmd.size, 4))]), compensated=False)
        np.testing.assert_allclose(q, want, atol=1e-12)


def test_the_pipeline_does_not_depend_on_the_listed_order(hand):
    """friction_hysteresis and the per-finger elasticity: the same parameters listed either way
    give the same q (they shared order 31, and the output depended on the selection's order)."""
    from phantom_cad.calibration.effects import get_effect, run_pipeline

    rng = np.random.default_rng(0)
    u = rng.uniform(hand.u_min, hand.u_max, (40, 6))
    direction = np.where(rng.uniform(size=(40, 6)) < 0.5, -1.0, 1.0)
    a = (get_effect("friction_hysteresis"), np.array([0.2]))
    b = (get_effect("tendon_elasticity_per_finger"), np.array([0.1, 0.3, 0.2, 0.25, 0.15]))
    np.testing.assert_array_equal(run_pipeline(hand, [a, b], u, direction), run_pipeline(hand, [b, a], u, direction))
