"""Plots that do not mislead, read from the matplotlib figures the report
functions return: the MAE bars carry the noise floor and flag joints made worse; a few outliers do
not set the residual plot's y range (they are clipped to its edge and marked); one-direction data
say so on the hysteresis plot. The data: the closed-form cosine law of test_noise_floor, Gaussian
noise and glitches written here."""

import math

import numpy as np
import pytest

from phantom_cad.calibration.data import Measurements
from phantom_cad.calibration.report import plot_hysteresis, plot_mae, plot_residuals, robust_limits
from phantom_cad.calibration.residual import made_worse

from .test_noise_floor import analytic, measure, sweeps

GLITCHES = [(50, 3, 20.0), (65, 3, -15.0), (140, 9, 12.0)]       # (row, joint, deg)


def noisy(hand, seed=1):
    u, sweep, cj = sweeps(hand, points=20)
    q_true = analytic(hand, u)
    return measure(hand, u, sweep, cj, q_true, seed), q_true


def by_gid(fig, gid):
    return [a for ax in fig.axes for a in ax.get_children() if a.get_gid() == gid]


def test_robust_limits_known_answer():
    # quartiles 1.0, 3.0 of 0..4 (plus one far point): fences -5, 9; the far point is left out
    v = np.array([0.0, 1.0, 2.0, 3.0, 4.0, 100.0])
    q1, q3 = np.percentile(v, [25, 75])
    assert 100.0 > q3 + 3 * (q3 - q1)
    lo, hi = robust_limits(v)
    assert lo == pytest.approx(0.0 - 0.08 * 4.0) and hi == pytest.approx(4.0 + 0.08 * 4.0)
    # without outliers the range holds every value, and 0
    lo, hi = robust_limits(np.array([1.0, 1.5, 2.0]))
    assert lo < 0.0 and hi > 2.0


@pytest.mark.slow
def test_outliers_do_not_set_the_residual_range(hand, tmp_path):
    m, q_true = noisy(hand)
    r_clean = (m.q - q_true) * 180 / math.pi
    for row, j, g in GLITCHES:
        assert np.isfinite(m.q[row, j])
        m.q[row, j] += math.radians(g)
    fig = plot_residuals(tmp_path / "r.png", m, q_true, "t")
    assert (tmp_path / "r.png").stat().st_size > 0
    lo, hi = fig.axes[0].get_ylim()
    # every ordinary cell is inside the range, and the range is set by them (0.1 deg noise: < 1 deg)
    ok = np.isfinite(r_clean)
    assert lo <= np.nanmin(r_clean) and hi >= np.nanmax(r_clean)
    assert hi - lo < 1.0
    # the glitches are drawn on the edge (triangles) at their servo angles, and counted per panel
    clipped = by_gid(fig, "clipped")
    ys = sorted(y for a in clipped for y in a.get_ydata())
    assert ys == sorted([lo, hi, hi])
    xs = sorted(x for a in clipped for x in a.get_xdata())
    s_of = {3: 1, 9: 3}
    assert xs == pytest.approx(sorted(math.degrees(m.u[row, s_of[j]]) for row, j, _ in GLITCHES))
    notes = sorted(t.get_text() for t in by_gid(fig, "clipped_note"))
    largest = {j: max(((r_clean[row, j] + g) for row, jj, g in GLITCHES if jj == j), key=abs) for j in (3, 9)}
    assert notes == [f"1 outside the range (largest {largest[9]:+.2f} deg)",
                     f"2 outside the range (largest {largest[3]:+.2f} deg)"]
    # the plotted points inside the range: every other measured cell
    inside = sum(len(a.get_xdata()) for ax in fig.axes for a in ax.get_lines()
                 if a.get_marker() == "o")
    assert inside == int(ok.sum()) - len(GLITCHES)


@pytest.mark.slow
def test_no_outlier_nothing_clipped(hand, tmp_path):
    m, q_true = noisy(hand, seed=2)
    fig = plot_residuals(tmp_path / "r.png", m, q_true, "t")
    r = (m.q - q_true) * 180 / math.pi
    lo, hi = fig.axes[0].get_ylim()
    assert lo <= np.nanmin(r) and hi >= np.nanmax(r)
    assert by_gid(fig, "clipped") == [] and by_gid(fig, "clipped_note") == []


def test_made_worse_known_answer():
    floor = {"q3": 0.08, "q4": 0.08, "q5": 0.08}
    cells = {"q3": 36, "q4": 36, "q5": 36}
    # margin 3 x 0.08 / 6 = 0.04 deg
    before = {"q3": 1.0, "q4": 0.10, "q5": 0.10}
    after = {"q3": 0.09, "q4": 0.139, "q5": 0.141}
    assert made_worse(before, after, floor, cells) == ["q5"]


def test_mae_bars_carry_the_floor_and_flag_worse_joints(hand, tmp_path):
    before = {"q3": 1.0, "q4": 0.10, "q5": 0.10}
    after = {"q3": 0.09, "q4": 0.139, "q5": 0.30}
    floor = {"q3": 0.07, "q4": 0.08, "q5": 0.09}
    fig = plot_mae(tmp_path / "m.png", before, after, ("a", "b"), "MAE", floor, 0.08, ["q5"])
    ax = fig.axes[0]
    line, = by_gid(fig, "noise_floor")
    assert list(line.get_ydata()) == [0.08, 0.08]
    ticks = by_gid(fig, "noise_floor_joint")
    segs = [seg for coll in ticks for seg in coll.get_segments()]
    assert sorted(float(seg[0][1]) for seg in segs) == [0.07, 0.08, 0.09]
    labels = {t.get_text(): t.get_color() for t in ax.get_xticklabels()}
    assert labels == {"q3": "black", "q4": "black", "q5!": "red"}
    worse, = by_gid(fig, "worse")
    assert worse.get_position()[0] == 2 and worse.get_text() == "worse"
    assert "worse after: q5" in ax.get_title()
    # bars far above the floor (1.0 > 20 x 0.07 is false here: linear axis); 2 deg -> log axis
    assert ax.get_yscale() == "linear"
    fig = plot_mae(tmp_path / "m.png", {"q3": 2.0}, {"q3": 0.08}, floor={"q3": 0.08}, noise_floor=0.08)
    assert fig.axes[0].get_yscale() == "log" and fig.axes[0].get_ylim()[0] < 0.08
    # nothing worse: no flag
    fig = plot_mae(tmp_path / "m.png", before, before, floor=floor, noise_floor=0.08)
    assert by_gid(fig, "worse") == [] and "worse" not in fig.axes[0].get_title()


@pytest.mark.slow
def test_one_direction_data_say_so_on_the_hysteresis_plot(hand, tmp_path):
    m, q_true = noisy(hand, seed=3)
    fig = plot_hysteresis(tmp_path / "h.png", m, q_true, q_true, "both")
    assert by_gid(fig, "one_direction") == [] and "one direction" not in fig._suptitle.get_text()
    keep = np.ones(len(m), dtype=bool)
    for rows in m.sweeps():
        keep[rows[rows.size // 2:]] = False                         # flexing halves only
    one = Measurements(m.u[keep], m.q[keep], m.measured, m.sweep[keep], m.sweep_ids, None, m.lines[keep],
                       "<test>", True)
    fig = plot_hysteresis(tmp_path / "h.png", one, q_true[keep], q_true[keep], "one")
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert len(panels) == 15
    notes = by_gid(fig, "one_direction")
    assert len(notes) == 15 and {n.axes for n in notes} == set(panels)
    assert "one direction only" in fig._suptitle.get_text()


@pytest.mark.slow
def test_one_joints_structure_is_inside_the_range(hand, tmp_path):
    """A 2 deg sinusoid left on q4 alone (the others: 0.1 deg noise) is the picture's subject: the
    shared range holds all of it, nothing is drawn as clipped. (Pooled over all joints, the Tukey
    fences of the noise clipped it at about +-1 deg: 45 points per panel on the edge.)"""
    m, q_true = noisy(hand, seed=3)
    q_model = q_true.copy()
    wave = 2.0 * np.sin(2 * np.pi * np.degrees(m.u[:, 1]) / 40.0)
    q_model[:, 3] -= np.radians(wave)
    fig = plot_residuals(tmp_path / "r.png", m, q_model, "t")
    r = (m.q - q_model) * 180 / math.pi
    lo, hi = fig.axes[0].get_ylim()
    assert np.nanmax(r[:, 3]) > 1.9 and lo <= np.nanmin(r) and hi >= np.nanmax(r)
    assert by_gid(fig, "clipped") == []
