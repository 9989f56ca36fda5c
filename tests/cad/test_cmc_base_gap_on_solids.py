"""The CMC base's distance to the forearm module's block (``kinematics.cmc_base_gap``, which the
pre-build check and the placement search keep to) against OpenCascade's distance from the built
CMC base, placed at rest, to the same box. (The heel's: the palm and the CMC base built,
tests/cad/test_found_by_the_property_test.py.)"""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad import units
from phantom_cad.cad import preflight
from phantom_cad.cad.assembly import pose_transforms
from phantom_cad.cad.measure import placed
from phantom_cad.cad.registry import part
from phantom_cad.kinematics import forearm_layout as FL

pytest.importorskip("build123d")


def _base(p):
    return placed(part(p, "thumb_cmc_base").build(), pose_transforms(p)["thumb_cmc_base"])


def _box(lo, hi):
    from phantom_cad.cad.parts.common import box

    lo, hi = units.mm(np.asarray(lo)), units.mm(np.asarray(hi))
    return box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])


@pytest.mark.parametrize("turn_deg", [0.0, 8.0, 10.0])
def test_the_cmc_bases_gap_to_the_forearm_module_is_opencascades(variant, turn_deg):
    """The default CMC axis turned about its third angle: 2.75 mm from the module's block, 0.50 mm
    at 8 deg, and at 10 deg the hub reaches into it (the pre-build check refuses that file). The
    measure agrees with OpenCascade within 5 micrometres, the floor under the hub included (the MP
    guide's boss reaches 1.9 mm below the thumb's palmar face; the part's hub goes down with it)."""
    p = variant(lambda d: d["palm"]["thumb_cmc_axis_deg"].__setitem__(2, d["palm"]["thumb_cmc_axis_deg"][2] + turn_deg))
    floor = preflight.cmc_base_floor(p)
    assert floor < -p.thumb.thickness / 2.0 - 1e-3
    gap = FL.forearm_gap(p, floor=floor)
    base, block = _base(p), _box(*FL.forearm_box(p))
    if gap > 0.0:
        assert units.mm(gap) == pytest.approx(base.distance_to(block), abs=0.005)
    else:
        assert units.mm(gap) < -0.05
        assert sum(s.volume for s in base.intersect(block).solids()) > 0.1          # mm^3

