"""The wall between each finger drive's coupler bore and its socket's magnet pockets
(``kinematics.couplers.pocket_walls``, which ``cad.preflight`` holds to two perimeters) against
OpenCascade's distance between the two solids the palm cuts, placed as the palm places them."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.kinematics.couplers import pocket_walls
from phantom_cad.kinematics.topology import FINGERS, chain
from phantom_cad.params import parse
from tests.support.sized import sized_document

pytest.importorskip("build123d")


def _occ_walls(params) -> dict[str, float]:
    from phantom_cad.cad.parts.common import cylinder, mm
    from phantom_cad.cad.parts.palm import Palm

    pa = Palm(params)
    out = {}
    for f in FINGERS:
        T = pa.T_socket(f)
        n = T[:3, 1]
        tangent, _ = pa.drive_line(chain(f).servo)
        exit_ = (T @ np.array([0.0, 0.0, pa.tendon_z, 1.0]))[:3]
        u = (tangent - exit_) / np.linalg.norm(tangent - exit_)
        cp = pa.couplers[f]
        bore = cylinder(exit_, exit_ + u * mm(cp.bore_end), mm(cp.bore) / 2.0)
        pockets = [cylinder(m, m - n * pa.tol.magnet_pocket_depth, pa.tol.magnet_pocket_d / 2.0)
                   for m in pa.magnet_centres(f)]
        out[f] = min(bore.distance_to(p) for p in pockets)
    return out


@pytest.mark.parametrize("hand", ["default", "sized_160"])
def test_pocket_walls_are_opencascades_distance(document, tmp_path, hand):
    """The default hand (its pinky's wall 0.97 mm), and the 160 x 72 mm hand ``size`` makes with its
    pockets where they were before it lifted them (``palm.magnet_lift_mm`` = 0: centred on the
    magnet face, the tendons one palm wall above the 12.5 mm ring and pinky's palmar face), where the
    pinky's drive, 21 deg off its socket's axis, passes about 0.15 mm from a pocket (a file the rule
    refuses; the palm is still made of the same cuts)."""
    if hand == "sized_160":
        document = sized_document(tmp_path, 160.0, 72.0)
        assert document["palm"].pop("magnet_lift_mm") > 0.0
    p = parse(document)
    walls = {f: w * 1000.0 for f, w in pocket_walls(p).items()}
    occ = _occ_walls(p)
    for f in FINGERS:
        assert walls[f] == pytest.approx(occ[f], abs=1e-3), f
    if hand == "sized_160":
        assert walls["pinky"] < 0.8


def test_a_bore_too_near_its_pockets_is_refused(tmp_path):
    """``params validate`` refuses the 160 x 72 mm hand with its pockets not lifted: one line
    naming palm.magnet_lift_mm, the digit, the wall OpenCascade measures (above) and the rule; the
    file ``size`` wrote, with the lift, validates."""
    import subprocess
    import sys

    import tomli_w

    document = sized_document(tmp_path, 160.0, 72.0)
    lift = document["palm"].pop("magnet_lift_mm")
    path = tmp_path / "unlifted.toml"
    path.write_text(tomli_w.dumps(document), encoding="utf-8")
    run = subprocess.run([sys.executable, "-m", "phantom_cad", "params", "validate", str(path)],
                         capture_output=True, text=True)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"error: {path}: palm.magnet_lift_mm = 0.0: the pinky drive's coupler bore passes 0.1")
    assert lines[0].endswith("the wall must be >= 0.8 mm, two perimeters; a larger palm.magnet_lift_mm (the "
                             "pockets higher) or smaller magnets open it")
    assert pocket_walls(parse(document))["pinky"] < 0.8e-3
    document["palm"]["magnet_lift_mm"] = lift
    assert min(pocket_walls(parse(document)).values()) >= 0.8e-3
