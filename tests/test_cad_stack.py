"""build123d and cadquery both ship the OCP module; the pins in pyproject.toml keep them on one
OCP. If a future install breaks that, `import build123d` fails while pip reports no conflict:
this test imports both in one process and builds a solid with each."""

from __future__ import annotations

import math

import pytest


def test_build123d_and_cadquery_share_one_ocp():
    import build123d as bd
    import cadquery as cq
    import OCP

    box = bd.Box(10, 20, 30)
    assert box.is_valid
    assert box.volume == pytest.approx(10 * 20 * 30)
    cyl = cq.Workplane("XY").cylinder(5.0, 2.0).val()
    assert cyl.isValid()
    assert cyl.Volume() == pytest.approx(math.pi * 2.0 ** 2 * 5.0, rel=1e-9)
    # the two libraries hand shapes to each other through the same OCP classes
    as_cq = cq.Shape.cast(box.wrapped)
    assert as_cq.Volume() == pytest.approx(6000.0)
    assert type(box.wrapped).__module__.split(".")[0] == OCP.__name__
