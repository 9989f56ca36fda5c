"""Power grasp, its first-contact half: the hand's cylinder (35 mm at 189 mm, scaled with the
hand) across the palm, laid against its heel, every finger flexing onto it touches it past its
equator; default hand, left hand and the 170 mm hand (params/examples/small.toml). Whether the
closing hand then holds it is simulated in MuJoCo (tests/export/test_mjcf.py: it does, against the
palm's heel).

``cad.grasp.power_grasp`` lays the cylinder on the palm's palmar face against the heel, axis along
the knuckle line (``kinematics.power_grasp.laid_axis_y``), flexes each finger from rest until it
comes within 1 mm of it and turns the thumb out of the way. What it returns is measured again here,
each with a tool of its own: the cylinder rebuilt from the parameter file's palm thickness and the
finger bases' measured extents, half a millimetre off the heel (a box of the file's heel
dimensions); the commands within the travel; OpenCascade's distances from the palm and from each
finger's phalanges to it, in (0, 1] mm; the wrap angle of each finger's closest point about the
cylinder's axis, from the point's coordinates, over 90 deg (at first contact the finger presses it
toward the palm); and manifold3d: no part of the hand overlaps the cylinder (a 256-sided prism of
its own), and no two parts of the hand interpenetrate (a joint's parent and child and the designed
contacts may touch).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.cad import assembly, grasp
from phantom_cad.cad import measure
from phantom_cad.export.interference import interference, may_touch
from phantom_cad.kinematics.topology import FINGERS

from tests.support.hands import HANDS

#: the distance (mm) the grasp's contacts must come within
REACH_MM = 1.0
#: manifold3d's overlap (mm^3) that counts as interpenetration: the command sweep's bar
OVERLAP_MM3 = 0.01


@pytest.fixture(scope="module", params=HANDS)
def hand(request, hand_parts, hand_meshes, power_grasps):
    """The power grasp of one reference hand, on its export's solids (``power_grasps``: the
    session's, shared with the MuJoCo hold test)."""
    p, shapes = hand_parts(request.param)
    h, g, tried = power_grasps(request.param)
    assert h.params is p
    return request.param, p, h, shapes, hand_meshes(request.param), g, tried


def _cylinder(p, shapes, diameter: float, y: float):
    """The test's own cylinder: build123d's Cylinder along x, half a millimetre under the palm's
    palmar face (-thickness_mm / 2 in the parameter file), over the finger bases' x extent at rest
    (their solids' boxes); (the cylinder, its axis's z, that extent, the heel: a box from the palm
    solid's back face heel_length_mm forward, heel_height_mm under the palmar face, across the palm)."""
    from build123d import Box, Cylinder, Pos, Rot

    T0 = assembly.pose_transforms(p)
    palm = p.document["palm"]
    bb = measure.placed(shapes["palm"], T0["palm"]).bounding_box()
    T, H, L = palm["thickness_mm"], palm["heel_height_mm"], palm["heel_length_mm"]
    heel = Pos((bb.min.X + bb.max.X) / 2, bb.min.Y + L / 2, -T / 2 - H / 2) * Box(bb.max.X - bb.min.X, L, H)
    z = -T / 2 - 0.5 - diameter / 2
    boxes = [measure.placed(shapes[f"{f}_base"], T0[f"{f}_base"]).bounding_box() for f in FINGERS]
    x0, x1 = min(b.min.X for b in boxes), max(b.max.X for b in boxes)
    return Pos((x0 + x1) / 2, y, z) * Rot(0, 90, 0) * Cylinder(diameter / 2, x1 - x0), z, (x0, x1), heel


def test_the_cylinder_is_found(hand):
    """The hand's own cylinder (35 mm at 189 mm: 35 x 170 / 189 mm on the 170 mm hand), laid against
    the heel: its axis half a millimetre plus its radius from the heel's lower front edge (the heel's
    front at the palm's back face plus heel_length_mm, its face heel_height_mm under the palmar
    face), and OpenCascade's distance from the heel to it half a millimetre."""
    kind, p, h, shapes, meshes, g, tried = hand
    report = [(round(t.axis_y_mm, 1), {f: c and round(c.wrap_deg) for f, c in t.fingers.items()}) for t in tried]
    assert g is not None, f"{kind}: the fingers do not all reach past its equator against the heel: {report}"
    assert len(tried) == 1
    D = 35.0 * p.document["hand"]["hand_length_mm"] / 189.0
    assert g.diameter_mm == pytest.approx(D, abs=1e-9)
    cyl, z, x, heel = _cylinder(p, shapes, D, g.axis_y_mm)
    assert g.axis_z_mm == pytest.approx(z, abs=1e-9) and g.x_mm == pytest.approx(x, abs=1e-9)
    assert abs(g.solid().volume - cyl.volume) < 1e-6 * cyl.volume
    # the cylinder's volume by hand: pi r^2 l
    assert cyl.volume == pytest.approx(math.pi * (D / 2) ** 2 * (x[1] - x[0]), rel=1e-6)
    edge = (heel.bounding_box().max.Y, heel.bounding_box().min.Z)
    assert math.hypot(g.axis_y_mm - edge[0], z - edge[1]) == pytest.approx(D / 2 + 0.5, abs=1e-6)
    assert heel.distance_to(cyl) == pytest.approx(0.5, abs=1e-6)


def test_every_finger_wraps_the_cylinder(hand):
    kind, p, h, shapes, meshes, g, tried = hand
    assert g is not None
    assert np.all(g.u >= h.u_min - 1e-12) and np.all(g.u <= h.u_max + 1e-12)
    cyl, z, _, _ = _cylinder(p, shapes, g.diameter_mm, g.axis_y_mm)
    T = assembly.pose_transforms(p, h.forward(g.u, compensated=True))
    palm = measure.placed(shapes["palm"], T["palm"]).distance_to(cyl)
    assert 0.0 < palm <= REACH_MM
    for f in FINGERS:
        d, point = min(((*measure.placed(shapes[n], T[n]).distance_to_with_closest_points(cyl)[:2],)
                        for n in (f"{f}_proximal", f"{f}_middle", f"{f}_distal")), key=lambda r: r[0])
        assert 0.0 < d <= REACH_MM, (kind, f, d)
        # the angle about the axis from the palm's side (+z) toward the fingertips (+y)
        wrap = math.degrees(math.atan2(point.Y - g.axis_y_mm, point.Z - z)) % 360.0
        assert wrap > 90.0, (kind, f, wrap)
        assert wrap == pytest.approx(g.fingers[f].wrap_deg, abs=1e-6)


def test_nothing_interpenetrates_at_the_grasp(hand):
    import manifold3d

    kind, p, h, shapes, meshes, g, tried = hand
    assert g is not None
    T = assembly.pose_transforms(p, h.forward(g.u, compensated=True))
    R = g.diameter_mm / 2
    c = manifold3d.Manifold.cylinder(g.x_mm[1] - g.x_mm[0], R, R, 256)
    c = c.rotate((0.0, 90.0, 0.0)).translate((g.x_mm[0], g.axis_y_mm, g.axis_z_mm))
    lo, hi = np.array(c.bounding_box()[:3]), np.array(c.bounding_box()[3:])
    assert lo == pytest.approx([g.x_mm[0], g.axis_y_mm - R, g.axis_z_mm - R], abs=1e-3)
    assert hi == pytest.approx([g.x_mm[1], g.axis_y_mm + R, g.axis_z_mm + R], abs=1e-3)
    # the cylinder as one more part, in the hand frame: it may touch nothing
    mesh = c.to_mesh()
    r = interference({**meshes, "cylinder": (np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts))},
                     {**T, "cylinder": np.eye(4)}, may_touch(assembly.designed_contacts(p)), tol_mm3=OVERLAP_MM3)
    assert r["collisions"] == [], (kind, r["collisions"])


def test_a_cylinder_reaching_over_the_heel_rests_on_its_edge(hand_parts):
    """``grasp.resting_axis_z`` by hand (default hand, the file's palm): a 35 mm cylinder in front of
    the heel lies half a millimetre under the palmar face, its axis at -T/2 - 0.5 - R; a 45 mm one
    whose back reaches 3.5 mm over the heel's front is held off by the heel's lower front edge (at the
    heel's front y_f and its face z_h = -T/2 - heel_height): its axis lies R + 0.5 from that edge,
    z = z_h - sqrt((R + 0.5)^2 - (y - y_f)^2), 0.96 mm lower than the face alone would put it."""
    p, shapes = hand_parts("default")
    doc = p.document["palm"]
    T, H, L = doc["thickness_mm"], doc["heel_height_mm"], doc["heel_length_mm"]
    palm = measure.placed(shapes["palm"], assembly.pose_transforms(p)["palm"])
    bb = palm.bounding_box()
    y_f, z_h = bb.min.Y + L, -T / 2 - H
    x = (bb.min.X + 20.0, bb.max.X - 5.0)           # under the metacarpal block, across the heel
    y = y_f + 17.5 + 1.0
    assert grasp.resting_axis_z(palm, 35.0, y, x) == pytest.approx(-T / 2 - 0.5 - 17.5, abs=1e-6)
    R = 22.5
    y = y_f + R - 3.5
    want = z_h - math.sqrt((R + 0.5) ** 2 - (y - y_f) ** 2)
    assert want < -T / 2 - 0.5 - R - 0.5                # the edge, not the face, holds it off
    assert grasp.resting_axis_z(palm, 2 * R, y, x) == pytest.approx(want, abs=1e-6)
