"""The support blockers of the digit parts' tendon features (``cad.parts.tendons.feature_blockers``):
their meshes against closed forms, and where they lie on the built solids of both hands (manifold3d).
What they cover once printed is measured on the export (tests/export/test_project3mf.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.cad.parts import tendons

trimesh = pytest.importorskip("trimesh")
manifold3d = pytest.importorskip("manifold3d")


def polygon_area(R: float, n: int, turn: float = 2.0 * math.pi) -> float:
    """Area of n isosceles triangles of legs R filling the angle ``turn`` (a regular polygon)."""
    return 0.5 * n * R * R * math.sin(turn / n)


def test_ring_and_cylinder_meshes_against_closed_forms():
    # a full ring: 72 steps of 5 deg; the outer polygon's chords outside r1, the inner inside r0
    V, F = tendons.sector_ring_mesh(2.0, -1.0, 0.5, 1.5, 2.0, 6.0)
    m = trimesh.Trimesh(V, F)
    half = math.pi / 72
    known = (polygon_area(6.0 / math.cos(half), 72) - polygon_area(2.0 * math.cos(half), 72)) * 1.0
    assert m.is_watertight and m.is_winding_consistent and m.volume == pytest.approx(known, rel=1e-9)
    assert np.allclose(m.center_mass[1:], (2.0, -1.0), atol=1e-9)
    # a quarter sector: 18 steps
    V, F = tendons.sector_ring_mesh(0.0, 0.0, 0.0, 2.0, 1.0, 4.0, (0.0, math.pi / 2))
    m = trimesh.Trimesh(V, F)
    half = math.pi / 72
    known = (polygon_area(4.0 / math.cos(half), 18, math.pi / 2) - polygon_area(math.cos(half), 18, math.pi / 2)) * 2.0
    assert m.is_watertight and m.is_winding_consistent and m.volume == pytest.approx(known, rel=1e-9)
    # a cylinder of 24 sides along (1, 1, 1)
    p0, p1 = np.zeros(3), np.ones(3)
    V, F = tendons.cylinder_mesh(p0, p1, 0.8)
    m = trimesh.Trimesh(V, F)
    known = polygon_area(0.8 / math.cos(math.pi / 24), 24) * math.sqrt(3.0)
    assert m.is_watertight and m.is_winding_consistent and m.volume == pytest.approx(known, rel=1e-9)


def test_which_blockers_hold_in_an_orientation():
    from phantom_cad.cad import registry
    from phantom_cad.params import load_params

    params = load_params()
    b = registry.part(params, "index_proximal").support_blockers()
    labels = [x.label for x in b]
    assert sum(lab.startswith("groove") for lab in labels) == 2 and sum(lab.startswith("set-screw") for lab in labels) == 1
    # dorsal face down (the joint axes flat): all hold; side down (axes upright): the channels only
    assert all(x.holds((0.0, 0.0, -1.0)) for x in b)
    assert [x.label for x in b if x.holds((1.0, 0.0, 0.0))] == [lab for lab in labels if lab.startswith("channel")]


def _manifold(V, F):
    return manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(V, np.float32),
                                               tri_verts=np.asarray(F, np.uint32)))


@pytest.mark.parametrize("name", ["index_proximal", "index_base"])
def test_left_hand_blockers_lie_on_its_mirrored_features(name, built, hand_parts, hand_meshes):
    """A left hand's part is the right's mirror; so are its blockers: each holds as much of the
    part, and as much air, as the right hand's (manifold3d), and the air is there (the feature)."""
    from phantom_cad.cad import assembly

    p, shapes = hand_parts("left")
    assert p.side == "left"
    left = assembly.build_part(p, name, shape=shapes[name]).blockers
    right = built[name].blockers
    assert [b.label for b in left] == [b.label for b in right]
    solids = {side: _manifold(*hand_meshes(kind)[name]) for side, kind in (("right", "default"), ("left", "left"))}
    for bl, br in zip(left, right):
        vol = {}
        for side, b in (("left", bl), ("right", br)):
            m = _manifold(b.vertices, b.faces)
            assert m.status() == manifold3d.Error.NoError
            vol[side] = (m.volume(), (m ^ solids[side]).volume())
        assert vol["left"][0] == pytest.approx(vol["right"][0], rel=1e-9)
        assert vol["left"][1] == pytest.approx(vol["right"][1], rel=1e-3, abs=1e-3)
        assert vol["right"][0] - vol["right"][1] > 0.2, br.label     # the feature's air
