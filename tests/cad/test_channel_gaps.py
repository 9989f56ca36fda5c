"""The distances the parts' slots are placed by (``Forearm.pocket_gap``: a drive's channel to the
other servos' pockets, open up along their shafts; ``Palm.thenar_gap``: a finger drive's channel to
the thenar's cuts) against OpenCascade's distance from the channel's axis to the solids the parts
cut, on the default hand (two staggered rows: servo 6's pocket swept straight up the module) and on
the 160 x 72 mm hand ``size`` makes (one row, whose CMC loop strand passes servo 1's pocket and
whose index drive passes the CMC pulley's cavity less than a flank away)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.kinematics.topology import FINGERS, chain
from phantom_cad.params import parse
from tests.support.sized import sized_document

pytest.importorskip("build123d")


def _axis_gap(gap, p, u, length) -> float:
    s = np.linspace(0.0, length, 4001)
    return float(gap(p + s[:, None] * u)[0].min())


@pytest.mark.parametrize("hand", ["default", "sized_160"])
def test_channel_gaps_are_opencascades_distance(document, tmp_path, hand):
    import build123d as b

    from phantom_cad.cad.parts.common import box, cylinder, polygon_cylinder, swept_along, transform
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.cad.parts.forearm import FOREARM_SERVOS, Forearm
    from phantom_cad.cad.parts.palm import Palm

    p = parse(sized_document(tmp_path, 160.0, 72.0) if hand == "sized_160" else document)
    fa, pa = Forearm(p), Palm(p)
    up = 300.0                                   # through the block's top
    least = {}
    for k in FOREARM_SERVOS:
        for side in fa.strand_sides(k):
            q, u = fa.drive_line(k, side)
            axis = b.Edge.make_line(b.Vector(*q), b.Vector(*(q + 40.0 * u)))
            for j in FOREARM_SERVOS:
                if j == k:
                    continue
                T = fa.T_servo(j)
                zc0, zc1 = fa.cavity_span(j)
                rc = fa.cavity_radius(j)
                if FL.drops_straight(p, j):
                    # swept along its drop as the module cuts it, the cavity a prism holding its cylinder
                    drop = fa.drop_vector(j)
                    solids = [s for lo, hi in fa.open_pockets(j, zc1)
                              for s in swept_along(transform(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]), T), drop)]
                    solids += swept_along(transform(polygon_cylinder((0.0, 0.0, zc0), (0.0, 0.0, zc1), rc), T), drop)
                    prism = rc * (1.0 / math.cos(math.pi / 32) - 1.0)
                else:
                    solids = [transform(box(lo[0], hi[0], lo[1], hi[1], lo[2], up), T) for lo, hi in fa.open_pockets(j, up)]
                    solids.append(transform(cylinder((0.0, 0.0, zc0), (0.0, 0.0, up), rc), T))
                    prism = 0.0
                occ = min(axis.distance_to(s) for s in solids)
                mine = _axis_gap(lambda pts, j=j: fa.pocket_gap(j, pts), q, u, 40.0)
                assert occ - 2e-3 <= mine <= occ + prism + 2e-3, (k, side, j, mine, occ)
                least[("forearm", k, side, j)] = mine
    Tc = pa.T_cmc()
    cuts = [transform(tool, Tc) for tool in pa.thenar_tools()]
    for f in FINGERS:
        T = pa.T_socket(f)
        tangent, _ = pa.drive_line(chain(f).servo)
        exit_ = (T @ np.array([0.0, 0.0, pa.tendon_z, 1.0]))[:3]
        run = float(np.linalg.norm(tangent - exit_))
        u = (tangent - exit_) / run
        axis = b.Edge.make_line(b.Vector(*exit_), b.Vector(*tangent))
        occ = min(axis.distance_to(c) for c in cuts)
        mine = _axis_gap(pa.thenar_gap, exit_, u, run)
        assert mine == pytest.approx(occ, abs=2e-3), f
        least[("palm", f)] = mine
    r = pa.tol.tendon_hole / 2.0
    if hand == "sized_160":      # the two that get slots: walls under 0.8 mm
        assert least[("forearm", 5, 1.0, 0)] - r == pytest.approx(0.27, abs=0.01)
        assert least[("palm", "index")] - r == pytest.approx(0.70, abs=0.01)
    else:
        # the two rows: the rear row's thumb and index drives run into servo 6's pocket and the ring
        # drive into the little finger's (each opened into it by a slot); every other wall is thick
        thin = {key for key, v in least.items() if v - r <= 0.8}
        assert thin == {("forearm", 0, -1.0, 5), ("forearm", 1, -1.0, 5), ("forearm", 3, -1.0, 4)}
        assert all(least[key] == 0.0 for key in thin)
