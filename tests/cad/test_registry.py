"""The part registry and the part protocol: one part per topology link, no more, no less."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.cad import assembly, registry
from phantom_cad.cad.parts.base import Part
from phantom_cad.kinematics import topology


def test_registry_covers_exactly_the_topology_links(params):
    assert set(registry.PART_NAMES) == set(topology.LINK_NAMES)
    assert len(registry.PART_NAMES) == len(topology.LINK_NAMES)
    assert list(registry.PART_NAMES) == [n for n in topology.LINK_NAMES if n in registry.PART_NAMES]
    assert assembly.part_names(params) == list(topology.LINK_NAMES)
    # every link is claimed by exactly one family
    claims = [ln.name for fam in registry.FAMILIES for ln in fam.links()]
    assert sorted(claims) == sorted(topology.LINK_NAMES)


def test_each_part_declares_an_existing_link(params):
    for name in registry.PART_NAMES:
        part = registry.part(params, name)
        assert isinstance(part, Part)
        assert part.link == topology.link(part.link.name)
        assert part.name == part.link.name == name
        assert part.digit == part.link.digit
        assert part.link.segment in type(part).SEGMENTS
        assert len(part.color) == 3 and all(0.0 <= c <= 1.0 for c in part.color)
        R = np.asarray(part.print_rotation)
        assert R.shape == (3, 3) and np.allclose(R @ R.T, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
        assert part.inputs() == assembly.part_inputs(params, name)


def test_unknown_part_is_refused_by_the_registry(params):
    with pytest.raises(KeyError, match="unknown part 'index_claw'"):
        registry.part(params, "index_claw")
