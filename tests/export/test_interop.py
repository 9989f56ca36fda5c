"""phantom_cad.interop.cadquery: the posed hand as a cadquery.Assembly (stand-in parts)."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad import load_hand

cq = pytest.importorskip("cadquery")


def test_hand_assembly_names_colours_locations(standin):
    from phantom_cad.interop.cadquery import hand_assembly

    hand = load_hand()
    assy = hand_assembly(hand)
    assert assy.name == "phantom_right"
    assert [c.name for c in assy.children] == ["palm", "index_proximal", "servo_pulley_2"]
    params = hand.params
    poses = standin.pose_transforms(params)
    for child in assy.children:
        # the location's matrix is the pose
        trsf = child.loc.wrapped.Transformation()
        M = np.array([[trsf.Value(i, j) for j in range(1, 5)] for i in range(1, 4)])
        assert M == pytest.approx(poses[child.name][:3, :], abs=1e-12)
        assert child.color.toTuple()[:3] == pytest.approx(
            standin.build_part(params, child.name).color, abs=1e-6)
    # volumes of the converted shapes: textbook formulas
    for child in assy.children:
        assert child.obj.Volume() == pytest.approx(standin.known_volume(params, child.name), rel=1e-9)
    # the compound is placed: the pulley's lowest point is 1 mm above the palm plate
    d = standin.dims(params)
    pulley = next(c for c in assy.children if c.name == "servo_pulley_2")
    placed = pulley.obj.moved(pulley.loc)
    assert placed.BoundingBox().zmin == pytest.approx(d["palm"][2] / 2 + 1, abs=1e-6)


def test_hand_assembly_unknown_part(standin):
    from phantom_cad.interop.cadquery import hand_assembly

    with pytest.raises(ValueError, match=r"unknown part\(s\) \['thumb'\]"):
        hand_assembly(load_hand(), parts=["palm", "thumb"])


def test_location_rejects_bad_matrix():
    from phantom_cad.interop.cadquery import location

    with pytest.raises(ValueError, match=r"a placement must be a 4x4 matrix, got shape \(3, 3\)"):
        location(np.eye(3))


@pytest.mark.slow
def test_real_parts_posed(tmp_path):
    """Two real parts at a bent pose: the locations are assembly.pose_transforms(q)."""
    # (not ``from conftest import ...``: with tests/cad collected too, "conftest" may be its module)
    assembly = pytest.importorskip("phantom_cad.cad.assembly")
    from phantom_cad.interop.cadquery import hand_assembly
    from phantom_cad.kinematics.topology import joint_index

    hand = load_hand()
    q = np.zeros(15)
    q[joint_index("index", "pip")] = 0.5
    assy = hand_assembly(hand, q, parts=["index_proximal", "index_middle"])
    poses = assembly.pose_transforms(hand.params, q)
    rest = assembly.pose_transforms(hand.params)
    assert [c.name for c in assy.children] == ["index_proximal", "index_middle"]
    for child in assy.children:
        trsf = child.loc.wrapped.Transformation()
        M = np.array([[trsf.Value(i, j) for j in range(1, 5)] for i in range(1, 4)])
        assert M == pytest.approx(poses[child.name][:3, :], abs=1e-9)
    # the middle phalanx turned by the PIP angle relative to the proximal one
    R_rel = rest["index_proximal"][:3, :3].T @ rest["index_middle"][:3, :3]
    R_bent = poses["index_proximal"][:3, :3].T @ poses["index_middle"][:3, :3]
    angle = np.arccos(np.clip((np.trace(R_rel.T @ R_bent) - 1) / 2, -1, 1))
    assert angle == pytest.approx(0.5, abs=1e-9)
    path = tmp_path / "two.step"
    assy.export(str(path))
    assert path.stat().st_size > 10_000
