"""A convex solid swept along a vector (``common.swept_along``) and the many-sided prism that
holds a cylinder (``common.polygon_cylinder``): the forearm module's pockets where a tilted servo
drops in along ``Forearm.drop_vector``.

Known answers by hand: a convex body K swept by a vector v (K plus the segment [0, 1] v) has the
volume vol(K) + |v| x the area of K's outline seen along v; a box a x b x c turned t about x has
the outline a x (b cos t + c sin t) in plan; an upright box a x b x c swept by (0, s, H) has the
outline a x (b H + c s) / |v| seen along it (a sheared prism); a prism of n sides whose flats
stand r from its axis has the section n r^2 tan(pi / n).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("build123d")

from phantom_cad.cad.parts.common import box, polygon_cylinder, swept_along, transform  # noqa: E402
from phantom_cad.kinematics.frames import rot_x  # noqa: E402


def _volume(tools) -> float:
    return tools[0].fuse(*tools[1:]).volume


@pytest.mark.parametrize("t_deg", [0.0, 6.4, 30.0])
def test_a_turned_box_swept_up(t_deg):
    a, b, c, H, t = 10.0, 20.0, 5.0, 7.0, math.radians(t_deg)
    T = rot_x(t)
    T[:3, 3] = (1.0, -2.0, 3.0)
    tools = swept_along(transform(box(0.0, a, 0.0, b, 0.0, c), T), (0.0, 0.0, H))
    assert _volume(tools) == pytest.approx(a * b * c + H * a * (b * math.cos(t) + c * math.sin(t)), rel=1e-9)
    top = max(s.bounding_box().max.Z for s in tools)
    assert top == pytest.approx(3.0 + b * math.sin(t) + c * math.cos(t) + H, abs=1e-9)


@pytest.mark.parametrize("s", [0.0, 0.9, -3.0])
def test_a_box_swept_aslant(s):
    a, b, c, H = 10.0, 20.0, 5.0, 7.0
    tools = swept_along(box(0.0, a, 0.0, b, 0.0, c), (0.0, s, H))
    assert _volume(tools) == pytest.approx(a * b * c + a * (b * H + c * abs(s)), rel=1e-9)
    lo = min(t.bounding_box().min.Y for t in tools)
    hi = max(t.bounding_box().max.Y for t in tools)
    assert (lo, hi) == (pytest.approx(min(0.0, s), abs=1e-9), pytest.approx(b + max(0.0, s), abs=1e-9))


def test_a_polygon_cylinder_holds_its_cylinder_and_sweeps_up():
    r, L, H, n = 4.0, 6.0, 5.0, 32
    p = polygon_cylinder((0.0, 0.0, 0.0), (0.0, 0.0, L), r, n)
    section = n * r * r * math.tan(math.pi / n)
    assert p.volume == pytest.approx(section * L, rel=1e-9)
    assert _volume(swept_along(p, (0.0, 0.0, H))) == pytest.approx(section * (L + H), rel=1e-9)
    # every flat r from the axis: the cylinder of radius r inside, touching each flat
    for f in p.faces():
        n_ = np.array(tuple(f.normal_at()))
        if abs(n_[2]) < 1e-9:
            assert np.array(tuple(f.center()))[:2] @ n_[:2] == pytest.approx(r, abs=1e-9)
