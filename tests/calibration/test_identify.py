"""Identifiability (calibration/identify.py): parameter combinations the data cannot separate are
reported as such, with no uncertainty, and with the recording that would separate them computed
from the model.

Known answers, by construction: two test effects written here add, to joint q4 (index PIP), a
constant ``a`` and ``b * direction`` (direction +1 flexing, -1 extending). On data that only
flex, q4 = model + a + b for every row: the two columns of the Jacobian are identical, so the
combination (a - b) / sqrt(2) (unit weights +-0.707 in the scaled space) is invisible, and a
recording of servo u2 (the index's) *extending* moves q4 by 2 b. On data that flex and extend,
both are identified. An offset and a second constant offset on the same joint can never be
separated: no recording moves their difference."""

import math

import numpy as np
import pytest

from phantom_cad.calibration.effects import REGISTRY, Effect, Param, register_effect
from phantom_cad.calibration.fitting import Model, Problem, fit
from phantom_cad.calibration.identify import combinations

from .test_noise_floor import analytic, measure, sweeps

J = 3                     # q4, the index PIP (driven by servo u2, index 1)
TRUE = {"a": 0.8, "b": 0.3}


class _Const(Effect):
    stage = "joint"
    order = 91

    def parameters(self, hand):
        return [Param("q4_deg", -5.0, 5.0, (0.1, 1.0), True, (J,), False, "test constant")]

    def apply(self, ctx, x):
        ctx.q[:, J] += math.radians(x[0])


class _Directional(Effect):
    name = "test_direction_offset"
    stage = "joint"
    order = 92
    directional = True

    def parameters(self, hand):
        return [Param("q4_deg", -5.0, 5.0, (0.1, 1.0), True, (J,), True, "test band half-width")]

    def apply(self, ctx, x):
        ctx.q[:, J] += math.radians(x[0]) * ctx.direction[:, 1]


@pytest.fixture(scope="module")
def effects():
    const_a = type("ConstA", (_Const,), {"name": "test_offset_a"})
    const_b = type("ConstB", (_Const,), {"name": "test_offset_b"})
    for cls in (const_a, const_b, _Directional):
        register_effect(cls)
    yield
    for n in ("test_offset_a", "test_offset_b", "test_direction_offset"):
        REGISTRY.pop(n, None)


def data(hand, both_directions: bool, seed=5):
    u, sweep, cj = sweeps(hand)
    keep = np.ones(len(u), dtype=bool)
    if not both_directions:                      # the paper's protocol: every sweep flexes only
        for s in np.unique(sweep):
            rows = np.flatnonzero(sweep == s)
            keep[rows[len(rows) // 2:]] = False
    u, sweep = u[keep], sweep[keep]
    q = analytic(hand, u)
    d = np.sign(np.diff(u[:, 1], prepend=u[0, 1]))
    d[(sweep == 1) & (d == 0)] = 1.0                   # the first row of the flexing sweep
    q[:, J] += math.radians(TRUE["a"]) + math.radians(TRUE["b"]) * np.where(sweep == 1, d, 1.0)
    return measure(hand, u, sweep, cj, q, seed)


def fitted(hand, m, names):
    problem = Problem(hand, m)
    return fit(Model(hand, names, problem), problem)


def test_one_direction_data_cannot_separate_an_offset_from_a_band(hand, effects):
    fr = fitted(hand, data(hand, False), ["test_offset_a", "test_direction_offset"])
    combos = combinations(fr)
    assert len(combos) == 1
    c = combos[0]
    w = c.weights
    assert set(w) == {"test_offset_a.q4_deg", "test_direction_offset.q4_deg"}
    # identical columns: the invisible combination is (1, -1) / sqrt(2), by hand
    assert sorted(abs(v) for v in w.values()) == pytest.approx([1 / math.sqrt(2)] * 2, abs=1e-3)
    assert np.prod(list(w.values())) < 0
    assert c.ratio < 1e-4
    # no uncertainty is claimed for either
    assert np.all(np.isnan(fr.std))
    # the recording that separates them: the index servo, extending (where the band flips sign)
    e = c.experiment
    assert e is not None and e["servo"] == "u2" and e["direction"] == "extending" and e["joint"] == "q4"
    assert "record servo u2 extending" in c.text()


def test_both_directions_identify_both(hand, effects):
    fr = fitted(hand, data(hand, True), ["test_offset_a", "test_direction_offset"])
    assert combinations(fr) == []
    vals, errs = fr.values(), fr.uncertainties()
    assert vals["test_offset_a"]["q4_deg"] == pytest.approx(TRUE["a"], abs=0.05)
    assert vals["test_direction_offset"]["q4_deg"] == pytest.approx(TRUE["b"], abs=0.05)
    assert 0 < errs["test_offset_a"]["q4_deg"] < 0.05


def test_two_offsets_on_one_joint_are_never_separable(hand, effects):
    fr = fitted(hand, data(hand, True), ["test_offset_a", "test_offset_b"])
    (c,) = combinations(fr)
    assert set(c.weights) == {"test_offset_a.q4_deg", "test_offset_b.q4_deg"}
    assert c.experiment is None
    assert "no recording of one servo separates them" in c.text()
    assert np.all(np.isnan(fr.std))


class _Fit:
    """The parts of a FitResult near_duplicate reads: a normal matrix over free parameters owned
    by named effects (a stand-in model: the recording search is stubbed out)."""

    def __init__(self, jtj, owners):
        from types import SimpleNamespace
        self.jtj = np.asarray(jtj, float)
        names = tuple(dict.fromkeys(owners))
        free = [(names.index(o), i, SimpleNamespace(key=f"p{i}")) for i, o in enumerate(owners)]
        self.model = SimpleNamespace(names=names, free=free, p=len(owners))
        self.m = 100


@pytest.mark.parametrize("rho, flagged", [(0.995, True), (0.99, False), (0.0, False)])
def test_near_duplicate_by_hand(monkeypatch, rho, flagged):
    """Two parameters whose Jacobian columns correlate by rho, and a third apart: with both in the
    fit the first's variance is 1 / (1 - rho^2) of what it is alone (the variance inflation factor),
    whatever the columns' norms: 100.25 at rho = 0.995 (flagged: at least NEAR_DUPLICATE), 50.25 at
    0.99 (not)."""
    from phantom_cad.calibration import identify

    monkeypatch.setattr(identify, "_experiment", lambda fr, delta, rms: None)
    D = np.diag([2.0, 30.0, 0.5])                       # column norms: the units do not matter
    C = np.array([[1.0, rho, 0.0], [rho, 1.0, 0.0], [0.0, 0.0, 1.0]])
    fr = _Fit(D @ C @ D, ["hand_a", "camera", "hand_b"])
    near = identify.near_duplicate(fr, "hand_a", "camera")
    if flagged:
        assert near.parameter == "hand_a.p0"
        assert near.inflation == pytest.approx(1.0 / (1.0 - rho ** 2), rel=1e-9)
    else:
        assert near is None
    assert identify.near_duplicate(fr, "hand_b", "camera") is None      # uncorrelated: inflation 1
