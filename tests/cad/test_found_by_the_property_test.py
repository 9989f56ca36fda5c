"""Files the property test (tests/export/test_validation_builds.py) found validating and not
building, kept as regressions: each builds now, or is refused by a rule (tests/test_params.py)."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.cad.registry import part
from phantom_cad.cad.verify import solid_problems

pytest.importorskip("build123d")


def _build(p, name):
    pt = part(p, name)
    shape = pt.build()
    assert not solid_problems(name, shape)
    return pt, shape


def test_small_mcp_pulley_keeps_one_guide_eyelet(variant):
    """R_MCP = 2.51 mm: the figure-eight channels leave 1.96 mm long tendon-hole faces near the
    MCP, which the guide measurement took for eyelets (2 mm long); the eyelet is the one face of
    exactly eyelet_length, at d2."""
    p = variant(lambda d: d["fingers"]["pinky"]["pulley_radius_mm"].__setitem__("mcp", 2.51))
    pt, shape = _build(p, "pinky_proximal")
    assert pt.verify(shape) == []


def test_parallel_fingers_palm(variant):
    """arc_offset_deg = 0: the palm builds with four parallel sockets (normals 0 degrees apart)."""
    p = variant(lambda d: d["palm"].__setitem__("arc_offset_deg", 0.0))
    pt, shape = _build(p, "palm")
    assert pt.verify(shape) == []
    from phantom_cad.cad.measure import circular_pockets

    facing = {tuple(np.round(p["facing"], 9)) for p in circular_pockets(shape, pt.tol.magnet_pocket_d / 2.0)}
    assert facing == {(0.0, 1.0, 0.0)}
