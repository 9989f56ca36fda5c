"""Files ``phantom-cad size`` wrote for the population study (bench/population.py) that validated and
did not build, kept as regression tests: each builds."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from phantom_cad.cad.registry import part
from phantom_cad.cad.verify import solid_problems
from phantom_cad.params import load_params

pytest.importorskip("build123d")


@pytest.mark.slow
def test_a_213_x_85_mm_palm_builds(tmp_path):
    """The palm of ``size --hand-length 213 --hand-breadth 85``: the thumb drive turns at a 1 mm
    sphere onto the CMC axis, and with the sphere's pole and seam where OpenCascade put them the cut
    left no solid at all."""
    out = tmp_path / "h213.toml"
    run = subprocess.run([sys.executable, "-m", "phantom_cad", "size", "--hand-length", "213",
                          "--hand-breadth", "85", "--out", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    pt = part(load_params(out), "palm")
    shape = pt.build()
    assert not solid_problems("palm", shape)
    assert pt.verify(shape) == []


@pytest.mark.parametrize("into, out", [((0.1, 0.99, 0.0), (-0.5, -0.05, -0.87)), ((0, 0, 1), (1, 0, 0)),
                                       ((0, 0, -1), (0, 0, -1)), ((1, 0, 0), (-1, 0.001, 0))])
def test_a_turn_spheres_poles_and_seam_lie_off_its_channels(into, out):
    """Both openings of the turn lie on the sphere's equator, and its seam (the edge between the
    poles) opposite them: every point of the seam and both poles at least 90 degrees from each."""
    from phantom_cad.cad.parts.common import turn_sphere

    c = np.array([3.0, -2.0, 1.0])
    s = turn_sphere(c, 1.0, into, out)
    openings = [-np.asarray(into, float) / np.linalg.norm(into), np.asarray(out, float) / np.linalg.norm(out)]
    seam = s.edges()                    # a sphere's one edge: the half circle from pole to pole
    assert len(seam) == 1
    pts = [np.array(tuple(v)) - c for v in s.vertices()]
    pts += [np.array(tuple(e.position_at(t))) - c for e in seam for t in np.linspace(0, 1, 21)]
    for p in pts:
        p = p / np.linalg.norm(p)
        for o in openings:
            assert p @ o <= 1e-6, (p, o)
    assert s.volume == pytest.approx(4.0 / 3.0 * np.pi, rel=1e-6)
