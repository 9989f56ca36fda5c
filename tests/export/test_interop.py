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
