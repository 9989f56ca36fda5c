"""The forearm module and the palm built for the two staggered rows (``kinematics.forearm_stagger``)
on the default hand: each one solid, the module with its twelve pilot holes, and every wall two
perimeters. The rear row's index and ring drives run beside a front servo's pocket (servo 6's,
swept straight up the module; the little finger's, open along its shaft) and then through it: each
is opened into the pocket along the run where the wall between them is under two perimeters
(``common.channel_slots``), up to where it enters. In the palm, the CMC pulley cavity's sweep
toward servo 6, behind it, runs straight back 0.43-0.46 mm inside the thenar block's radial face,
tilted 28.5 deg to it: the lip is cut away (``Palm.cavity_face_openings``)."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest

pytest.importorskip("build123d")


@contextlib.contextmanager
def _rows_2(monkeypatch):
    """The default hand's parts laid out in two rows; what was memoised for its digest with one row
    (the routes, the couplers, the links' tendons) is dropped on the way in and out."""
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics import memo

    memo.clear()
    monkeypatch.setattr(FL, "forearm_rows", lambda params: 2)
    try:
        yield
    finally:
        monkeypatch.undo()
        memo.clear()


@pytest.fixture
def two_rows(monkeypatch):
    with _rows_2(monkeypatch):
        yield


def _palm_strands(params) -> np.ndarray:
    """Each finger drive's strand in the palm (m, ``couplers.couplers``, memoised): from its socket
    to its servo's pulley, which the rows move."""
    from phantom_cad.kinematics import couplers

    return np.array([c.palm_strand for c in couplers.couplers(params).values()], float)


def test_the_two_rows_leave_nothing_memoised(monkeypatch):
    """The couplers made for two rows are not served once the one row is back (the default file's
    digest is the same)."""
    from phantom_cad.params import load_params

    p = load_params(None)
    before = _palm_strands(p)
    with _rows_2(monkeypatch):
        during = _palm_strands(p)
    after = _palm_strands(p)
    assert during.shape != before.shape or np.abs(during - before).max() > 1e-3
    assert np.array_equal(after, before)


def test_the_swept_pocket_is_measured_as_cut(two_rows):
    """Servo 6's pocket and cavity are swept straight up the module's z (``Forearm.pocket_gap``, as
    ``Forearm.build`` cuts them): 30 mm straight above its body's centre is in the cut (along its
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


@pytest.mark.slow
@pytest.mark.parametrize("name", ["forearm", "palm"])
def test_the_two_rows_parts_build_with_walls_of_two_perimeters(two_rows, name):
    from phantom_cad import units
    from phantom_cad.cad.registry import part
    from phantom_cad.cad.verify import solid_problems
    from phantom_cad.export import step_stl
    from phantom_cad.export.walls import thin_walls, wall_bar_mm
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.params import load_params

    p = load_params(None)
    assert FL.forearm_width(p) < 80.0e-3                  # the two rows, not the one
    pt = part(p, name)
    shape = pt.build()
    assert not solid_problems(name, shape)
    assert pt.verify(shape) == []
    mesh = step_stl.tessellate(shape, units.mm(p.print.stl_tolerance))
    v, f = mesh if isinstance(mesh, tuple) else (mesh.vertices, mesh.faces)
    walls = thin_walls(np.asarray(v), np.asarray(f), wall_bar_mm(p), samples=100_000)
    assert walls["wall_thinnest"] >= wall_bar_mm(p), walls

