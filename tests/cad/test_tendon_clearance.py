"""No tendon passes through material: points sampled every 0.25 mm along every strand of the routing
model, with the hand posed at 0, 25, 50, 75 and 100 % of every travel, classified by OpenCascade
against the built solids (cad.clearance). Default hand, left hand, slender.toml.

Known answers: nothing inside any solid; and the check sees a tendon in material when a part is
built without the channels cut for it (the check can fail).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.cad import assembly, clearance, registry
from phantom_cad.params import parse
from tests.support.hands import hand_source


@pytest.fixture(scope="module")
def right_solids(built, params):
    """The default hand's right-handed solids in their link frames (as the parts build them)."""
    assert params.side == "right"
    return {n: b.shape for n, b in built.items()}


def _fmt(hits):
    return [f"{h.strand} at {h.fraction:.0%} in {h.part} ({h.n_points} points, first at {h.point_mm} mm)" for h in hits]


def test_no_tendon_passes_through_material(params, right_solids):
    assert _fmt(clearance.tendon_hits(params, right_solids)) == []


def test_left_hand_tendons_pass_through_no_material(document, right_solids):
    """A left hand's parts are the right hand's mirrored (test_parts checks that): its routes,
    mirrored back into the parts' frames, must clear the same solids."""
    doc = dict(document)
    doc["hand"] = {**document["hand"], "side": "left"}
    left = parse(doc)
    assert left.side == "left"
    assert _fmt(clearance.tendon_hits(left, right_solids)) == []


def test_slender_hand_tendons_pass_through_no_material(hand_parts):
    """params/examples/slender.toml, on its export's solids."""
    p, solids = hand_parts("slender")
    assert sorted(solids) == sorted(assembly.part_names(p))
    assert _fmt(clearance.tendon_hits(p, solids)) == []


def test_a_part_without_its_channels_is_caught(params, monkeypatch):
    """Build the index proximal phalanx without the loop and return channels the routing model asks
    for: the check finds those strands inside it."""
    from phantom_cad.cad.parts import phalanx
    monkeypatch.setattr(phalanx, "channel_tools", lambda lt, extend=None, faces=(), up=None: [])
    shape = registry.part(params, "index_proximal").build()
    hits = clearance.tendon_hits(params, {"index_proximal": shape}, fractions=(0.0,))
    assert {h.strand for h in hits} >= {"index_mcp_pip_a", "index_mcp_pip_b", "index_return"}
    assert all(h.part == "index_proximal" for h in hits)
    # phantom-cad check's row fails on it, naming the part
    from phantom_cad.export.check import tendon_rows

    (row,) = tendon_rows(params, {"index_proximal": shape})
    assert row.ok is False and row.item.endswith(" in index_proximal at 0%"), row


def _classify(shape, points_mm):
    """OpenCascade's state of each point against a solid: True where it is inside material."""
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN

    cl = BRepClass3d_SolidClassifier(shape.wrapped)
    out = []
    for p in points_mm:
        cl.Perform(gp_Pnt(*map(float, p)), 1e-6)
        out.append(cl.State() == TopAbs_IN)
    return np.array(out)


def _envelope(exit_mm, u, s_from, s_to, radius, step=0.25, n=16):
    """Points on the surface and the axis of a cylinder along u from s_from to s_to (mm)."""
    e1 = np.cross(u, [0.0, 0.0, 1.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    pts = []
    for s in np.arange(s_from, s_to + 1e-9, step):
        c = exit_mm + s * u
        pts.append(c)
        pts += [c + radius * (math.cos(a) * e1 + math.sin(a) * e2)
                for a in np.linspace(0, 2 * math.pi, n, endpoint=False)]
    return np.array(pts)


def test_the_drive_couplers_travel_in_the_palms_bore(params, document, right_solids):
    _couplers_travel_in_the_bore(params, document, right_solids["palm"])


def test_slender_hand_couplers_travel_in_the_palms_bore(hand_parts):
    from phantom_cad.params import load_document
    p, solids = hand_parts("slender")
    doc = load_document(hand_source("slender")[0])
    doc["hardware"].setdefault("tendon_stop", {"diameter_mm": 2.0, "length_mm": 3.0})
    _couplers_travel_in_the_bore(p, doc, solids["palm"])


def _couplers_travel_in_the_bore(params, document, palm):
    """Each finger drive's coupler (the crimp stop with the loop on it, docs/transmission.md): its
    envelope, a cylinder of stop + 2 cords by 1 + stop + 3 cords (worked out here from the file),
    from 2 clearances inside the socket face at u = 0 to r u_max deeper at full travel, lies in no
    material of the palm (measured on the solid). At the service angle it lies wholly outside the
    palm, beyond the socket face. The bore is no wider than it must be: a ring 0.2 mm outside it
    is in material."""
    from phantom_cad.kinematics import forearm_layout as FL
    from phantom_cad.kinematics import frames as Fr
    from phantom_cad.kinematics.topology import chain

    hw, pr = document["hardware"], document["print"]
    d, c = hw["tendon_diameter_mm"], pr["hole_clearance_mm"]
    D = hw["tendon_stop"]["diameter_mm"] + 2 * d
    L = d + hw["tendon_stop"]["length_mm"] + 3 * d
    s0 = 2 * c
    for f in ("index", "middle", "ring", "pinky"):
        src = document["fingers"][f]
        r, travel = src["servo_pulley_radius_mm"], src["servo_travel_deg"][1]
        k = chain(f).servo
        exit_ = Fr.socket_tendon_point(params, f) * 1e3
        tangent = (FL.T_palm_servo(params, k) @ np.array([-r * 1e-3, 0.0, 0.0, 1.0]))[:3] * 1e3
        u = (tangent - exit_) / np.linalg.norm(tangent - exit_)
        sweep = r * math.radians(travel)
        inside = _classify(palm, _envelope(exit_, u, s0, s0 + sweep + L, D / 2 - 0.01))
        assert not inside.any(), f"{f}: the coupler meets the palm at {int(inside.sum())} points"
        payout = r * math.radians(180 - 2 * 8 - travel)
        out = _envelope(exit_, u, s0 - payout, s0 - payout + L, D / 2)
        assert not _classify(palm, out).any() and np.all((out - exit_) @ u < 0.0), f
        bore = D + 2 * c
        ring = _envelope(exit_, u, s0 + sweep / 2, s0 + sweep / 2, bore / 2 + 0.2, n=32)[1:]
        assert _classify(palm, ring).all(), f
