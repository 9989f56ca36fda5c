"""Tendon channels that print without support: a teardrop's roof (``common.teardrop``) at
the angle the layer height allows (``cad.print_rules.roof_angle``).

Known answers by hand: the cross-section of a teardrop of radius r whose roof leans a from the
vertical is the circle less the sector the roof spans (2 phi, phi = 90 deg - a) plus the two right
triangles of legs r and r tan(phi) under the roof: r^2 (pi - phi + tan phi); its apex lies
r / sin(a) above the axis. PrusaSlicer (its automatic supports) is the other tool: round holes in a
block take support, the teardrops at the roof angle take none, level or climbing, at 0.2 and 0.3 mm
layers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.cad.print_rules import roof_angle

pytest.importorskip("build123d")

from phantom_cad.cad.parts.common import box, cylinder, teardrop  # noqa: E402


def test_roof_angle_by_hand():
    # atan(0.45 / (2 h)) - 8 deg, at most 40 deg: 0.2 mm -> min(48.37 - 8, 40); 0.3 mm -> 36.87 - 8
    assert math.degrees(roof_angle(0.2e-3)) == pytest.approx(40.0)
    assert math.degrees(roof_angle(0.3e-3)) == pytest.approx(28.8699, abs=1e-3)
    assert math.degrees(roof_angle(0.25e-3)) == pytest.approx(math.degrees(math.atan(0.9)) - 8.0)


@pytest.mark.parametrize("a_deg", [45.0, 40.0, 28.87])
def test_teardrop_section_and_apex(a_deg):
    r, L, a = 0.95, 12.0, math.radians(a_deg)
    phi = math.pi / 2.0 - a
    t = teardrop((0.0, 0.0, 0.0), (L, 0.0, 0.0), r, up=(0.0, 0.0, 1.0), roof=a)
    assert t.is_valid
    assert t.volume == pytest.approx(L * r * r * (math.pi - phi + math.tan(phi)), rel=1e-9)
    bb = t.bounding_box()
    assert bb.max.Z == pytest.approx(r / math.sin(a), abs=1e-9)
    assert bb.min.Z == pytest.approx(-r, abs=1e-9) and bb.max.Y == pytest.approx(r, abs=1e-9)


def test_teardrop_points_up_and_leaves_steep_holes_round():
    r = 0.5
    down = teardrop((0.0, 0.0, 0.0), (10.0, 0.0, 0.0), r, up=(0.0, 0.0, -1.0))
    assert down.bounding_box().min.Z == pytest.approx(-r * math.sqrt(2.0), abs=1e-9)
    # 50 deg from the horizontal: its round wall looks down 50 deg from the vertical at most
    d = np.array([math.cos(math.radians(50.0)), 0.0, math.sin(math.radians(50.0))])
    steep = teardrop((0.0, 0.0, 0.0), 10.0 * d, r, up=(0.0, 0.0, 1.0))
    assert steep.volume == pytest.approx(math.pi * r * r * 10.0, rel=1e-9)
    # 30 deg from the horizontal: a roof; the section across the axis is the teardrop's
    d = np.array([math.cos(math.radians(30.0)), 0.0, math.sin(math.radians(30.0))])
    flat = teardrop((0.0, 0.0, 0.0), 10.0 * d, r, up=(0.0, 0.0, 1.0))
    assert flat.volume == pytest.approx(10.0 * r * r * (math.pi - math.pi / 4 + 1.0), rel=1e-9)
    assert teardrop((0, 0, 0), (10, 0, 0), r).volume == pytest.approx(math.pi * r * r * 10.0, rel=1e-9)


#: (y, radius) of the block's channels, mm
CHANNELS = ((-3.0, 1.5), (2.5, 0.95))

needs_slicer = pytest.mark.skipif(
    __import__("phantom_cad.export.slicer", fromlist=["find_slicer"]).find_slicer() is None,
    reason="prusa-slicer is not installed (bash .ci/sysdeps installs Debian's prusa-slicer)")


@needs_slicer
@pytest.mark.parametrize("layer_mm", [0.2, 0.3])
@pytest.mark.slow
def test_prusaslicer_supports_round_channels_not_teardrops(tmp_path, layer_mm):
    """A 40 x 12 x 12 mm block with a 3 mm and a 1.9 mm channel along it, level and climbing 5 deg
    (a roof's ridge crossing layers): PrusaSlicer's automatic supports fill the round channels and
    leave the teardrop channels empty. (PrusaSlicer 2.x leaves a round 1 mm channel, and a level
    1.9 mm one at 0.3 mm layers, without support: the test's channels are the ones it does fill.)"""
    import trimesh

    from phantom_cad.export import slicer, step_stl

    ini = f"layer_height = {layer_mm:g}\nfirst_layer_height = {layer_mm:g}\n"
    a = roof_angle(layer_mm * 1e-3)
    for climb in (0.0, 5.0):
        dz = 40.0 * math.tan(math.radians(climb))
        found = {}
        for kind in ("round", "teardrop"):
            tools = []
            for y, r in CHANNELS:
                p0, p1 = (-1.0, y, 3.0), (41.0, y, 3.0 + dz)
                tools.append(cylinder(p0, p1, r) if kind == "round" else teardrop(p0, p1, r, (0.0, 0.0, 1.0), a))
            v, f = step_stl.tessellate(box(0.0, 40.0, -6.0, 6.0, 0.0, 12.0).cut(*tools), 0.01)
            path = tmp_path / f"{kind}.stl"
            trimesh.Trimesh(v, f).export(path)
            pts = slicer.slice_supports(path, ini)
            # support inside a channel's circle (the block's two channels), mm of path
            inside = np.zeros(len(pts), bool)
            for y, r in CHANNELS:
                zc = 3.0 + dz * np.clip(pts[:, 0], 0.0, 40.0) / 40.0
                inside |= np.hypot(pts[:, 1] - y, pts[:, 2] - zc) <= r / math.sin(a) + 0.3   # the whole teardrop
            found[kind] = float(inside.sum()) * slicer.SUPPORT_SPACING
        assert found["round"] > 100.0 and found["teardrop"] == 0.0, (climb, found)


@needs_slicer
def test_prusaslicer_bridges_a_flat_roof_across_a_slot_but_supports_a_round_floor(tmp_path):
    """Why the tendon grooves still take support (docs/parts.md): in a 40 x 20 x 10 mm block, a
    1.9 mm slot 6 mm high with a flat roof is bridged (no support); the same slot cut down from
    the top around a 4.25 mm floor (a groove round a hub whose axis lies flat, its lowest point 4 mm
    above the bed) takes support under the floor, though each layer of the floor spans the same
    1.9 mm between the flanks."""
    import trimesh

    from phantom_cad.cad.parts.common import cyl_x
    from phantom_cad.export import slicer, step_stl

    ini = "layer_height = 0.2\nfirst_layer_height = 0.2\n"
    block = box(0.0, 20.0, -10.0, 10.0, 0.0, 10.0)
    flat = block.cut(box(9.05, 10.95, -10.0, 10.0, 0.0, 6.0))
    groove = block.cut(box(9.05, 10.95, -10.0, 10.0, 0.0, 10.0).cut(cyl_x(4.25, 8.0, 12.0, 0.0, 8.25)))
    found = {}
    for name, shape in (("flat", flat), ("groove", groove)):
        v, f = step_stl.tessellate(shape, 0.01)
        trimesh.Trimesh(v, f).export(tmp_path / f"{name}.stl")
        pts = slicer.slice_supports(tmp_path / f"{name}.stl", ini)
        in_slot = (np.abs(pts[:, 0] - 10.0) <= 0.95) if len(pts) else np.zeros(0, bool)
        found[name] = float(in_slot.sum()) * slicer.SUPPORT_SPACING
    assert found["flat"] == 0.0 and found["groove"] > 100.0, found
