"""The placement search's arithmetic (kinematics/opposition.py, kinematics/thumb_placement.py,
kinematics/thenar.py) against straightforward versions written here: the closest points of segments
with einsum over (..., 3) arrays, the thumb turned by its CMC angle and then placed, the box distance
with np.linalg.norm, the facing angle of every pair. The search keeps its answers only if every
number is the same, so each comparison is bit for bit (np.array_equal, ==), on random inputs and on
the default hand's grids."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.kinematics import opposition as O, thumb_placement as TP
from phantom_cad.kinematics import thenar as TH
from phantom_cad.kinematics.model import Hand
from phantom_cad.params.io import load_params


@pytest.fixture(scope="module")
def hand():
    return Hand(load_params(None))


def ref_segment_distance(p1, q1, p2, q2):
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a = np.einsum("...i,...i", d1, d1)
    e = np.einsum("...i,...i", d2, d2)
    f = np.einsum("...i,...i", d2, r)
    c = np.einsum("...i,...i", d1, r)
    b = np.einsum("...i,...i", d1, d2)
    eps = 1e-18
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > eps, np.clip((b * f - c * e) / np.where(denom > eps, denom, 1.0), 0.0, 1.0), 0.0)
        s = np.where(a > eps, s, 0.0)
        t = np.where(e > eps, (b * s + f) / np.where(e > eps, e, 1.0), 0.0)
        s = np.where(t < 0.0, np.where(a > eps, np.clip(-c / np.where(a > eps, a, 1.0), 0.0, 1.0), 0.0), s)
        s = np.where(t > 1.0, np.where(a > eps, np.clip((b - c) / np.where(a > eps, a, 1.0), 0.0, 1.0), 0.0), s)
        t = np.clip(t, 0.0, 1.0)
    c1 = p1 + s[..., None] * d1
    c2 = p2 + t[..., None] * d2
    return np.linalg.norm(c1 - c2, axis=-1), c1, c2


def ref_contacts(T, Fg):
    dist, c1, c2 = ref_segment_distance(T.a[:, None], T.b[:, None], Fg.a[None], Fg.b[None])
    gap = dist - T.radius - Fg.radius
    v = c2 - c1
    with np.errstate(divide="ignore", invalid="ignore"):
        v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    cos = np.minimum(np.einsum("tfi,ti->tf", v, T.normal), np.einsum("tfi,fi->tf", -v, Fg.normal))
    return gap, np.arccos(np.clip(np.nan_to_num(cos, nan=-1.0), -1.0, 1.0))


def ref_box_distance(p, lo, hi):
    c, h = (lo + hi) / 2.0, (hi - lo) / 2.0
    d = np.abs(p - c) - h
    return np.linalg.norm(np.maximum(d, 0.0), axis=-1) + np.minimum(d.max(axis=-1), 0.0)


def ref_turn_and_place(thumb, T0, p, w=1.0):
    """Rz(q15) of each command's points, then T0."""
    c, s = np.cos(thumb.q15), np.sin(thumb.q15)
    if p.ndim == 3:
        c, s = c[:, None], s[:, None]
    out = np.empty_like(p)
    out[..., 0] = c * p[..., 0] - s * p[..., 1]
    out[..., 1] = s * p[..., 0] + c * p[..., 1]
    out[..., 2] = p[..., 2]
    return out @ T0[:3, :3].T + (T0[:3, 3] if w else 0.0)


def ref_margin(thumb, fingers, x):
    T0 = TP._placement(x)
    tt = O.Tips(ref_turn_and_place(thumb, T0, thumb.a), ref_turn_and_place(thumb, T0, thumb.b),
                ref_turn_and_place(thumb, T0, thumb.normal, 0.0), thumb.radius, thumb.u)
    worst = math.inf
    for f in O.OPPOSED:
        gap, angle = ref_contacts(tt, fingers[f])
        band = (gap <= 0.0) & (gap >= -O.CONTACT_BAND)
        if band.any():
            m = O.PAD_CONE - float(angle[band].min())
        else:
            miss = float(np.min(np.where(gap > 0.0, gap, -O.CONTACT_BAND - gap)))
            m = -(math.pi - O.PAD_CONE) - miss / (tt.radius + fingers[f].radius)
        worst = min(worst, m)
    return worst


def _segments(rng, shape):
    """Random segment ends (shape + (3,)) over six decades of scale, some of them points."""
    p = rng.normal(size=(*shape, 3)) * 10.0 ** rng.integers(-3, 3, size=(*shape, 1))
    q = p + rng.normal(size=(*shape, 3)) * 10.0 ** rng.integers(-3, 3, size=(*shape, 1))
    point = rng.random(shape) < 0.05
    q[point] = p[point]
    return p, q


def test_segment_distance_is_the_einsum_version_bit_for_bit():
    rng = np.random.default_rng(11)
    for s1, s2 in [((200,), (200,)), ((30, 1), (1, 17)), ((5, 7), (7,)), ((), ())]:
        (p1, q1), (p2, q2) = _segments(rng, s1), _segments(rng, s2)
        got, want = O.segment_distance(p1, q1, p2, q2), ref_segment_distance(p1, q1, p2, q2)
        for g, w in zip(got, want):
            assert g.shape == w.shape and np.array_equal(g, w)
    # parallel, collinear-overlapping, crossing, a point, and both points
    for case in ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 0, 0], [2, 0, 0], [1, 0, 0], [3, 0, 0]],
                 [[-1, 0, 0], [1, 0, 0], [0, -1, 0.5], [0, 1, 0.5]], [[0.3, 0.2, 0.1], [0.3, 0.2, 0.1], [0, 0, 0], [1, 0, 0]],
                 [[0.3, 0.2, 0.1], [0.3, 0.2, 0.1], [1, 0, 0], [1, 0, 0]]):
        case = np.array(case, float)
        for g, w in zip(O.segment_distance(*case), ref_segment_distance(*case)):
            assert np.array_equal(g, w)


def _tips(rng, n, radius):
    a, b = _segments(rng, (n,))
    a, b = a * 1e-2, b * 1e-2                                      # metres: within a hand's reach
    normal = rng.normal(size=(n, 3))
    return O.Tips(a, b, normal / np.linalg.norm(normal, axis=1, keepdims=True), radius, np.zeros((n, 1)))


def test_contacts_are_the_einsum_version_bit_for_bit():
    rng = np.random.default_rng(12)
    for _ in range(20):
        T, Fg = _tips(rng, 37, 0.006), _tips(rng, 13, 0.005)
        for g, w in zip(O.contacts(T, Fg), ref_contacts(T, Fg)):
            assert np.array_equal(g, w)
    # axes that meet: the contact direction is undefined and the facing angle pi
    T = O.Tips(np.zeros((1, 3)), np.array([[1.0, 0, 0]]), np.array([[0, 0, 1.0]]), 0.1, np.zeros((1, 1)))
    Fg = O.Tips(np.array([[0.5, -1, 0]]), np.array([[0.5, 1, 0]]), np.array([[0, 0, -1.0]]), 0.1, np.zeros((1, 1)))
    gap, angle = O.contacts(T, Fg)
    assert gap[0, 0] == -0.2 and angle[0, 0] == math.pi
    assert all(np.array_equal(g, w) for g, w in zip((gap, angle), ref_contacts(T, Fg)))


def test_box_distance_is_the_norm_version_bit_for_bit():
    rng = np.random.default_rng(13)
    lo, hi = np.array([-0.02, -0.07, -0.01]), np.array([0.06, 0.01, 0.012])
    for shape in [(500,), (40, 24), ()]:
        p = rng.normal(scale=0.05, size=(*shape, 3))
        got = TP.box_distance(p, lo, hi)
        assert got.shape == shape and np.array_equal(got, ref_box_distance(p, lo, hi))


@pytest.fixture(scope="module")
def grids(hand):
    return (O.thumb_tips(hand, 11, 11), O.thumb_tips(hand, 7, 5),
            {f: O.finger_tips(hand, f, 21) for f in O.FINGERS})


def _placements(hand, n, seed):
    b = TP.default_bounds(hand.params).array()
    rng = np.random.default_rng(seed)
    return b[:, 0] + (b[:, 1] - b[:, 0]) * rng.random((n, 6))


def test_the_placed_thumb_is_turned_then_placed_bit_for_bit(hand, grids):
    thumb, small, _ = grids
    for x in _placements(hand, 20, 14):
        T0 = TP._placement(x)
        for th in (thumb, small):
            tt = th.placed(T0)
            assert np.array_equal(tt.a, ref_turn_and_place(th, T0, th.a))
            assert np.array_equal(tt.b, ref_turn_and_place(th, T0, th.b))
            assert np.array_equal(tt.normal, ref_turn_and_place(th, T0, th.normal, 0.0))
            body = ref_turn_and_place(th, T0, th.body)
            assert np.array_equal(th.body_placed(T0), body.reshape(-1, 3).T)
            env = TP.palm_envelope(hand.params)
            assert TP.palm_intrusion(th, T0, env) == float(th.body_radius - ref_box_distance(body, *env).min())


def test_the_search_margin_is_the_reference_bit_for_bit(hand, grids, monkeypatch):
    """Over placements across the bounds (most miss some finger; at one of these the pairs the
    margin keeps cannot settle a finger's miss and it works out all of them) and near the file's
    (in contact)."""
    thumb, _, fingers = grids
    p = hand.params
    file = np.array([*p.palm.thumb_cmc_offset, *p.palm.thumb_cmc_axis])
    rng = np.random.default_rng(15)
    near = file + rng.normal(scale=[2e-3] * 3 + [0.05] * 3, size=(20, 6))
    every, pairs = [0], TP.pad_pairs         # the name the margin calls

    def counted(*args):
        every[0] += 1
        return pairs(*args)

    monkeypatch.setattr(TP, "pad_pairs", counted)
    contact = 0
    for x in [*_placements(hand, 40, 2), *near]:
        m = TP.margin(thumb, fingers, x)
        assert m == ref_margin(thumb, fingers, x)
        contact += m > -O.PAD_CONE
    assert contact >= 10 and every[0] >= 1          # both ways of settling a finger were compared
    tt = thumb.placed(TP._placement(file))
    for f, Fg in fingers.items():
        assert all(np.array_equal(g, w) for g, w in zip(O.contacts(tt, Fg), ref_contacts(tt, Fg)))


def test_the_thenar_rings_are_the_reference_bit_for_bit(hand):
    def ref_ring(T0, s, r, n=24):
        a = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
        pts = np.c_[r * np.cos(a), r * np.sin(a), np.full_like(a, s), np.ones_like(a)]
        return (T0 @ pts.T).T[:, :3]

    rng = np.random.default_rng(17)
    for x in _placements(hand, 20, 18):
        T0 = TP._placement(x)
        s, r = rng.normal(scale=0.02), rng.uniform(0.0, 0.01)
        for n in (24, 7):
            assert np.array_equal(TH._ring(T0, s, r, n), ref_ring(T0, s, r, n))
