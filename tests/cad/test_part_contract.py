"""The part protocol as a contract: every family implements what the assembly and the export
pipeline call on a part, and a part's cache key (``inputs()``) covers every parameter it reads."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from phantom_cad.cad import assembly, registry
from phantom_cad.cad.parts.base import Part
from phantom_cad.kinematics import topology

#: what the assembly (``cad.assembly``, ``cad.verify``) and the export pipeline call on a part
CALLED = ("for_link", "build", "inputs", "verify", "collision_solids", "support_blockers", "print_rotation",
          "color", "digit", "name")


def test_the_part_base_is_abstract_in_what_every_family_must_make():
    assert inspect.isabstract(Part)
    assert Part.__abstractmethods__ == {"for_link", "build", "inputs"}
    with pytest.raises(TypeError):
        Part()


@pytest.mark.parametrize("family", registry.FAMILIES, ids=lambda f: f.__name__)
def test_every_family_implements_the_protocol(family):
    assert issubclass(family, Part)
    assert not inspect.isabstract(family), f"{family.__name__} lacks {sorted(family.__abstractmethods__)}"
    for method in ("for_link", "build", "inputs"):
        assert getattr(family, method) is not getattr(Part, method), f"{family.__name__}.{method}"


def test_every_part_of_the_default_hand_is_made_through_the_registry(params):
    for name in registry.PART_NAMES:
        part = registry.part(params, name)
        assert type(part) is registry.FAMILY[name]
        for what in CALLED:
            assert hasattr(part, what), f"{name} has no {what}"
        assert isinstance(part.inputs(), dict)


def test_the_fingertip_pads_the_assembly_asks_for_are_implemented(params):
    """``assembly.tip_frames`` asks each digit's last link for its pad: its family has one of its
    own (the base's refuses), and it is a rigid transform."""
    for digit in topology.DIGITS:
        distal = topology.digit_links(digit)[-1]
        part = registry.part(params, distal.name)
        assert type(part).pad is not Part.pad, f"{type(part).__name__} makes the fingertip {distal.name} without pad()"
        T = np.asarray(part.pad(), float)
        assert T.shape == (4, 4)
        assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3)) and np.allclose(T[3], [0, 0, 0, 1])
    assert set(assembly.tip_frames(params)) == {f"{d}_tip" for d in topology.DIGITS}


def test_a_part_without_a_fingertip_refuses_a_pad(params):
    tips = {topology.digit_links(d)[-1].name for d in topology.DIGITS}
    for name in registry.PART_NAMES:
        if name not in tips:
            with pytest.raises(ValueError, match=f"{name} is not a fingertip"):
                registry.part(params, name).pad()
