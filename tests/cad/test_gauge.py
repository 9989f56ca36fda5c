"""The angle gauge (phantom_cad.cad.gauge), measured on the solid.

Known answers by hand from the parameter document: the outline's corners lie on a circle of the
longest finger's length beyond its MCP (hand_length_mm x the proximal, middle and distal fractions
of the middle finger), one corner every 15 degrees, and two radii close it; so the plate is n
triangles of the circle's centre, 0.5 R^2 n sin 15, two palm walls thick, less one dimple per step
on every face but the datum (n (n - 1) / 2 in all).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from phantom_cad.cad import measure
from phantom_cad.errors import ParamError

pytest.importorskip("build123d")


def _expected(doc):
    """(angles, R, thickness, volume) by hand from the document (mm, degrees)."""
    hl = doc["hand"]["hand_length_mm"]
    R = max(hl * (f["length_fraction"]["proximal"] + f["length_fraction"]["middle"] + f["length_fraction"]["distal"])
            for f in doc["fingers"].values())
    top = max([hi for f in doc["fingers"].values() for _, hi in f["limits_rad"].values()]
              + [hi for _, hi in doc["thumb"]["limits_rad"].values()])
    n = math.ceil(math.degrees(top) / 15.0)             # faces beyond the datum
    angles = [15.0 * k for k in range(n + 1)]
    faces = n + 1
    t = 2.0 * doc["palm"]["wall_mm"]
    area = 0.5 * R * R * faces * math.sin(math.radians(15.0))
    dimples = faces * (faces - 1) // 2
    return angles, R, t, area * t - dimples * math.pi * 0.75 ** 2 * 0.6


@pytest.fixture(scope="module")
def gauge(params):
    from phantom_cad.cad.gauge import AngleGauge

    g = AngleGauge(params)
    return g, g.build()


def test_gauge_dimensions_and_volume_by_hand(gauge, document):
    g, shape = gauge
    angles, R, t, volume = _expected(document)
    # params/phantom.toml: the PIPs reach 1.61 rad (92.2 deg), so the faces run to 105 degrees
    assert list(g.angles_deg) == angles == [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0, 105.0]
    assert g.radius == pytest.approx(R, rel=1e-12)
    assert g.face_length == pytest.approx(2 * R * math.sin(math.radians(7.5)), rel=1e-12)
    assert g.thickness == pytest.approx(t)
    assert g.volume() == pytest.approx(volume, rel=1e-12)
    rep = measure.solid_report(shape)
    assert rep["n_solids"] == 1 and rep["valid"]
    assert shape.volume == pytest.approx(volume, rel=1e-9)
    assert rep["bbox_min"][2] == pytest.approx(0.0, abs=1e-9) and rep["bbox_max"][2] == pytest.approx(t, abs=1e-9)


def test_reference_faces_measured_on_the_solid(gauge, document):
    """Every side face's normal, read from the solid's planar faces: the datum's is -y, each
    reference face's is it turned by its nominal angle, and the face is as long as the chord."""
    g, shape = gauge
    angles, R, t, _ = _expected(document)
    sides = [f for f in measure.planar_faces(shape) if abs(f["normal"][2]) < 1e-9]
    measured = {}
    for f in sides:
        n = f["normal"]
        measured[round(math.degrees(math.atan2(n[0], -n[1])) % 360.0, 6)] = f["area"]
    for a in angles:
        assert a in measured, (a, sorted(measured))
        assert measured[a] == pytest.approx(2 * R * math.sin(math.radians(7.5)) * t, rel=1e-9)
    assert len(sides) == len(angles) + 2            # and the two closing radii
    assert g.verify(shape) == []


def test_gauge_of_the_170_mm_hand():
    """params/examples/small.toml: shorter fingers, shorter faces; every dimple stays inside."""
    from phantom_cad import load_params
    from phantom_cad.canon import plain
    from phantom_cad.cad.gauge import AngleGauge
    from phantom_cad.params import DEFAULT_PARAMS

    small = load_params(DEFAULT_PARAMS.parent / "examples" / "small.toml")
    g = AngleGauge(small)
    angles, R, t, volume = _expected(plain(small.document))
    assert R == pytest.approx(170.0 * (0.266 + 0.170 + 0.108)) and list(g.angles_deg) == angles
    assert g.mark_clearance() > 1.0
    shape = g.build()
    assert shape.volume == pytest.approx(volume, rel=1e-9)
    assert g.verify(shape) == []


def test_marks_are_dimples_on_the_top_face(gauge):
    g, shape = gauge
    assert len(g.marks()) == 28
    floors = [f for f in measure.planar_faces(shape) if f["normal"][2] > 0.5
              and abs(f["centre"][2] - (g.thickness - 0.6)) < 1e-9]
    assert len(floors) == 28


def test_gauge_stl_read_back_is_watertight(gauge):
    import trimesh

    from phantom_cad.export import step_stl

    g, shape = gauge
    v, f = step_stl.tessellate(shape, 0.01)
    mesh = trimesh.load(trimesh.util.wrap_as_stream(step_stl.stl_bytes(v, f, "angle_gauge")), file_type="stl")
    assert mesh.is_watertight and mesh.is_volume
    assert mesh.volume == pytest.approx(shape.volume, rel=1e-3)


def _fake(limit_rad, finger_mm=100.0):
    f = SimpleNamespace(proximal=finger_mm * 0.5e-3, middle=finger_mm * 0.3e-3, distal=finger_mm * 0.2e-3,
                        chain=None)
    thumb = SimpleNamespace(cmc_limits=(0.0, 1.0))
    chain = SimpleNamespace(limits=((0.0, limit_rad),))
    return SimpleNamespace(chains=(chain,), thumb=thumb, digit=lambda n: f, source="hand.toml",
                           palm=SimpleNamespace(wall=2.4e-3), name="fake")


def test_gauge_refuses_what_it_cannot_cover():
    from phantom_cad.cad.gauge import AngleGauge

    assert AngleGauge(_fake(1.0)).angles_deg[-1] == 90.0         # at least 90 degrees
    assert AngleGauge(_fake(math.radians(150.0), 140.0)).angles_deg[-1] == 150.0
    with pytest.raises(ParamError, match="the angle gauge covers joint ranges up to 150 degrees"):
        AngleGauge(_fake(math.radians(151.0), 140.0))
    # 7 faces beyond the datum: a row of 7 marks at the least pitch (2 mm) and a dimple's width beyond
    # each end need 6 x 2 + 3 x 1.5 = 16.5 mm of face; a finger of 60 mm gives 2 x 60 sin 7.5 = 15.7
    with pytest.raises(ParamError, match=r"the angle gauge's faces \(15.7 mm, from the longest finger\) are "
                                         r"shorter than their marks need \(16.5 mm\)"):
        AngleGauge(_fake(1.61, 60.0))
    assert np.isfinite(AngleGauge(_fake(1.61, 90.0)).volume())


def test_a_small_hands_gauge_closes_up_its_marks():
    """Faces too short for the 3 mm pitch (a 150 mm hand's: a finger of 80 mm gives 20.9 mm, where
    7 marks at 3 mm need 22.5): the row of the most marks fills the face less a dimple's width at
    each end, pitch (2 x 80 sin 7.5 - 4.5) / 6; the dimples stay apart and inside, the solid verifies."""
    from phantom_cad.cad.gauge import AngleGauge

    g = AngleGauge(_fake(1.61, 80.0))
    face = 2 * 80.0 * math.sin(math.radians(7.5))
    assert g.face_length == pytest.approx(face, rel=1e-12)
    assert g.mark_pitch == pytest.approx((face - 4.5) / 6.0, rel=1e-12) and 2.0 < g.mark_pitch < 3.0
    assert AngleGauge(_fake(1.61, 100.0)).mark_pitch == 3.0
    marks = np.array(g.marks())
    gaps = np.linalg.norm(marks[:, None] - marks[None, :], axis=-1) + np.eye(len(marks)) * 1e9
    assert gaps.min() == pytest.approx(g.mark_pitch, rel=1e-9) and gaps.min() - 1.5 > 0.5
    assert g.mark_clearance() > 0.75
    shape = g.build()
    assert measure.solid_report(shape)["valid"] and g.verify(shape) == []
    assert shape.volume == pytest.approx(g.volume(), rel=1e-9)
