"""build123d and cadquery both ship the OCP module; the pins in pyproject.toml keep them on one
OCP (an unpinned pair overwrites it and `import build123d` fails while pip reports no conflict).
Both must import in one process and build solids whose volumes match textbook formulas."""

import math

import pytest


@pytest.mark.slow
def test_build123d_and_cadquery_share_ocp_and_build_solids():
    import build123d
    import cadquery as cq
    import OCP

    # build123d: box minus a through hole
    a, b, c, r = 30.0, 20.0, 10.0, 4.0
    part = build123d.Box(a, b, c) - build123d.Cylinder(r, 2 * c)
    assert part.volume == pytest.approx(a * b * c - math.pi * r * r * c, rel=1e-9)
    # cadquery: sphere
    R = 7.0
    sphere = cq.Workplane("XY").sphere(R).val()
    assert sphere.Volume() == pytest.approx(4.0 / 3.0 * math.pi * R ** 3, rel=1e-6)
    # both wrap the same OCP classes: a build123d shape converts to cadquery and back
    shape = cq.Shape.cast(part.wrapped)
    assert shape.Volume() == pytest.approx(part.volume, rel=1e-12)
    assert type(shape.wrapped).__module__ == type(part.wrapped).__module__
    assert OCP.__file__
