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
    assert lines == ["fill_density = 40%", "filament_density = 1.24"]   # params/phantom.toml [print]


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
