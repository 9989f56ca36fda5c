"""The default hand's forearm module in two staggered rows (``kinematics.forearm_stagger``, chosen
by ``forearm_layout.forearm_rows`` where they fit a human forearm): servo 6's pocket swept straight
up the module as it is cut, and what the kinematics memoise for a digest made for the layout it
was made with. The parts' walls are the default hand's (tests/cad/test_walls.py)."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

pytest.importorskip("build123d")


@contextlib.contextmanager
def _one_row(monkeypatch):
    """The default hand's servos laid out in one row; what was memoised for its digest with two
    rows (the routes, the couplers, the links' tendons) is dropped on the way in and out."""
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics import memo

    memo.clear()
    monkeypatch.setattr(FL, "forearm_rows", lambda params: 1)
    try:
        yield
    finally:
        monkeypatch.undo()
        memo.clear()


def _palm_strands(params) -> np.ndarray:
    """Each finger drive's strand in the palm (m, ``couplers.couplers``, memoised): from its socket
    to its servo's pulley, which the rows move."""
    from phantom_cad.kinematics import couplers

    return np.array([c.palm_strand for c in couplers.couplers(params).values()], float)


def test_the_default_hand_is_built_from_two_rows_within_a_forearm():
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics import servo_geometry as SG
    from phantom_cad.params import load_params

    p = load_params(None)
    assert FL.forearm_rows(p) == 2
    assert FL.forearm_width(p) <= SG.forearm_width_limit(p)


def test_one_row_leaves_nothing_memoised(monkeypatch):
    """The couplers made for one row are not served once the two rows are back (the default
    file's digest is the same)."""
    from phantom_cad.params import load_params

    p = load_params(None)
    before = _palm_strands(p)
    with _one_row(monkeypatch):
        during = _palm_strands(p)
    after = _palm_strands(p)
    assert during.shape != before.shape or np.abs(during - before).max() > 1e-3
    assert np.array_equal(after, before)


def test_the_swept_pocket_is_measured_as_cut():
    """Servo 6's pocket and cavity are swept up along its drop, 0.3 deg off the module's z
    (``Forearm.drop_vector``; ``Forearm.pocket_gap``, as ``Forearm.build`` cuts them): 30 mm
    straight above its body's centre is in the cut (along its
    shaft, tilted 28.5 deg, the pocket would have passed 14 mm beside it), and 1 mm under the body's
    floor, along the shaft, is 1 mm from it (the sweep goes up, away from it)."""
    from phantom_cad.cad.parts.forearm import Forearm
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics.topology import SERVOS
    from phantom_cad.params import load_params

    p = load_params(None)
    fa = Forearm(p)
    k = next(s.index for s in SERVOS if s.drive == "loop")
    assert FL.drops_straight(p, k)
    T = fa.T_servo(k)
    lo, hi = fa.open_pockets(k, 0.0)[0]
    centre = (T @ np.array([*(lo[:2] + hi[:2]) / 2.0, (lo[2] + hi[2]) / 2.0, 1.0]))[:3]
    under = (T @ np.array([*(lo[:2] + hi[:2]) / 2.0, lo[2] - 1.0, 1.0]))[:3]
    d, near = fa.pocket_gap(k, np.array([centre + [0.0, 0.0, 30.0], under]))
    assert d[0] == pytest.approx(0.0, abs=1e-6)
    assert d[1] == pytest.approx(1.0, abs=1e-6)
    assert np.allclose(near[1], (T @ np.array([*(lo[:2] + hi[:2]) / 2.0, lo[2], 1.0]))[:3], atol=1e-6)
