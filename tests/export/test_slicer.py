"""PrusaSlicer headless: G-code summary parsing (known text) and slicing a cube whose
filament volume is bounded by hand-computed volumes."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.export import slicer
from phantom_cad.export.step_stl import stl_bytes
from phantom_cad.params import load_params

GCODE_TAIL = """G1 X1 Y1
; filament used [mm] = 1940.21
; filament used [cm3] = 4.67
; filament used [g] = 5.79
; filament cost = 0.00
; total filament used [g] = 5.79
; estimated printing time (normal mode) = 1h 16m 43s
; prusaslicer_config = begin
"""


def test_parse_gcode_summary():
    est = slicer.parse_gcode(GCODE_TAIL)
    assert est.time_s == 1 * 3600 + 16 * 60 + 43
    assert est.time_text == "1h 16m 43s"
    assert (est.filament_mm, est.filament_cm3, est.filament_g) == (1940.21, 4.67, 5.79)


def test_parse_gcode_days_and_missing_lines():
    assert slicer.parse_duration("1d 0h 2m 5s") == 86400 + 125
    with pytest.raises(slicer.SlicerError, match=r"no '; estimated printing time \(normal mode\)' line"):
        slicer.parse_gcode("; filament used [mm] = 1\n")


def test_config_from_params():
    ini = slicer.config_ini(load_params().print)
    lines = [line for line in ini.splitlines() if not line.startswith("#")]
    # params/phantom.toml [print]; the layer height is the default 0.2 mm (PrusaSlicer's own is 0.3)
    assert lines == ["fill_density = 40%", "layer_height = 0.2", "first_layer_height = 0.2", "filament_density = 1.24"]


def _cube(a):
    v = np.array([[x, y, z] for x in (0, a) for y in (0, a) for z in (0, a)], dtype=float)
    # faces of the cube on vertices indexed 4x + 2y + z, outward normals
    f = np.array([[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5]])
    return v, f


@pytest.mark.skipif(slicer.find_slicer() is None,
                    reason="prusa-slicer is not installed (bash .ci/sysdeps installs Debian's prusa-slicer)")
def test_slice_cube_headless(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    a = 20.0
    v, f = _cube(a)
    stl = tmp_path / "cube.stl"
    stl.write_bytes(stl_bytes(v, f, "cube"))
    params = load_params()
    # a relative path, as the default cache (.cache/) gives: PrusaSlicer runs in a scratch folder
    monkeypatch.chdir(tmp_path)
    est = slicer.slice_stl(stl.relative_to(tmp_path), slicer.config_ini(params.print))
    cube_cm3 = a ** 3 / 1000.0
    # 40 % infill plus solid shells: more than 40 % of the cube, less than the full cube
    assert 0.4 * cube_cm3 < est.filament_cm3 < cube_cm3
    # grams = cm^3 x density (PrusaSlicer rounds both to 0.01)
    assert est.filament_g == pytest.approx(est.filament_cm3 * 1.24, abs=0.02)
    # 1.75 mm filament: length = volume / (pi d^2 / 4)
    assert est.filament_mm == pytest.approx(est.filament_cm3 * 1000 / (np.pi * 1.75 ** 2 / 4), rel=5e-3)
    assert 60 < est.time_s < 3 * 3600


needs_slicer = pytest.mark.skipif(slicer.find_slicer() is None,
                                  reason="prusa-slicer is not installed (bash .ci/sysdeps installs Debian's prusa-slicer)")


@needs_slicer
def test_support_goes_under_an_overhang_and_nowhere_else(tmp_path):
    """A 10 mm pillar carrying a 30 x 10 x 2 mm shelf at z = 10 (10 mm overhanging on each side,
    built with trimesh), and the pillar alone: PrusaSlicer's automatic supports stand under the
    shelf's two overhangs (|x| > 5 mm, below z = 10), none on the pillar's footprint and none for
    the pillar alone; the points come back in the STL's frame."""
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("manifold3d")
    pillar = trimesh.creation.box((10.0, 10.0, 10.0))
    pillar.apply_translation((7.0, -3.0, 5.0))            # off the origin: the frame must come back
    shelf = trimesh.creation.box((30.0, 10.0, 2.0))
    shelf.apply_translation((7.0, -3.0, 11.0))
    tee = pillar.union(shelf)
    ini = slicer.config_ini(load_params().print)
    for name, mesh in (("tee", tee), ("pillar", pillar)):
        (tmp_path / f"{name}.stl").write_bytes(stl_bytes(np.asarray(mesh.vertices), np.asarray(mesh.faces), name))
    pts = slicer.slice_supports(tmp_path / "tee.stl", ini)
    assert len(pts) > 100
    x, y, z = pts[:, 0] - 7.0, pts[:, 1] + 3.0, pts[:, 2]
    assert np.all(z <= 10.0 + 1e-6)                                  # under the shelf
    # above its first layer (which PrusaSlicer widens by about 5 mm) the support keeps to the
    # shelf's outline within 2.5 mm (2.12 measured at 0.2 mm layers), and keeps off the pillar
    up = z > 0.4
    assert np.all(np.abs(y[up]) <= 5.0 + 2.5) and np.all(np.abs(x[up]) <= 15.0 + 2.5)
    assert not np.any((np.abs(x) < 5.0) & (np.abs(y) < 5.0))        # nothing inside the pillar
    left, right = x < -5.0, x > 5.0
    assert left.sum() > 0.4 * len(pts) and right.sum() > 0.4 * len(pts)
    assert len(slicer.slice_supports(tmp_path / "pillar.stl", ini)) == 0


def test_support_points_read_from_gcode():
    """Known text: a support extrusion of 1 mm is sampled every 0.25 mm at its layer's z; travel
    moves and other roles are not support."""
    text = """M82
;Z:0.6
;TYPE:Perimeter
G1 X0 Y0 E1
G1 X5 Y0 E2
;TYPE:Support material
G1 X10 Y10
G1 X11 Y10 E3.1 ; a comment
G1 X11 Y12 E3.1
G1 E2.3
G1 X12 Y12
G1 E3.1
G92 E0
G1 X13 Y12 E0.5
;TYPE:External perimeter
G1 X20 Y20 E4
"""
    pts = slicer.support_points(text)
    # the X11 Y12 move holds E (a travel), E2.3 retracts, X12 travels, E3.1 un-retracts in place,
    # the move after G92 E0 extrudes
    assert pts.tolist() == [[10.0, 10.0, 0.6], [10.25, 10.0, 0.6], [10.5, 10.0, 0.6], [10.75, 10.0, 0.6],
                            [11.0, 10.0, 0.6], [12.0, 12.0, 0.6], [12.25, 12.0, 0.6], [12.5, 12.0, 0.6],
                            [12.75, 12.0, 0.6], [13.0, 12.0, 0.6]]
