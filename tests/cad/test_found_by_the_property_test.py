"""Files the property test (tests/export/test_validation_builds.py) found validating and not
building, kept as regression tests: each builds, or is refused by a rule (tests/test_params.py)."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.cad.registry import part
from phantom_cad.cad.verify import solid_problems

pytest.importorskip("build123d")


def _build(p, name):
    pt = part(p, name)
    shape = pt.build()
    assert not solid_problems(name, shape)
    return pt, shape


@pytest.mark.slow
def test_small_mcp_pulley_keeps_one_guide_eyelet(variant):
    """A small MCP pulley (found at R_MCP = 2.51 mm): the figure-eight channels leave tendon-hole
    faces near the MCP almost as long as an eyelet, which the guide measurement took for eyelets;
    the eyelet is the one face of exactly eyelet_length, at d2. 2.56 mm is the smallest radius the
    rule accepts today (the return groove's floor, R - 0.75 mm, outside the 3.6 mm compensated
    axle bore)."""
    p = variant(lambda d: d["fingers"]["pinky"]["pulley_radius_mm"].__setitem__("mcp", 2.56))
    pt, shape = _build(p, "pinky_proximal")
    assert pt.verify(shape) == []


def test_parallel_fingers_palm(variant):
    """arc_offset_deg = 0: the palm builds with four parallel sockets (normals 0 degrees apart).
    Without the arc the ring's drive run shortens (its channel 16.6 mm): the default 3 mm crimp
    stop's coupler would need 17.1 mm there and is refused (couplers.couplers), a 2.4 mm stop fits."""
    def edit(d):
        d["palm"]["arc_offset_deg"] = 0.0
        d["hardware"]["tendon_stop"] = {"diameter_mm": 2.0, "length_mm": 2.4}
    p = variant(edit)
    pt, shape = _build(p, "palm")
    assert pt.verify(shape) == []
    from phantom_cad.cad.measure import circular_pockets

    facing = {tuple(np.round(p["facing"], 9)) for p in circular_pockets(shape, pt.tol.magnet_pocket_d / 2.0)}
    assert facing == {(0.0, 1.0, 0.0)}


@pytest.mark.slow
def test_the_cmc_base_clears_the_palm_where_the_rule_accepts(variant):
    """The CMC axis along the palm's normal and the CMC base's top 0.01 mm inside what the thenar
    rule accepts (a clearance below the palmar face: centre at -12 - 0.2 - 7.5 - 0.01 mm): the
    palm and the CMC base, where the assembly places them, stay at least a clearance apart
    (OpenCascade's distance: the base's top under the palmar face, the column in the journal): a
    placement the rule accepts is one the build makes. (The placement moves the palm's back face,
    and with it the servos the coupler bores run toward: the magnet pockets are lifted as
    ``phantom-cad size`` lifts them.)"""
    from phantom_cad.cad import preflight
    from phantom_cad.cad.assembly import pose_transforms
    from phantom_cad.cad.measure import placed
    from phantom_cad.kinematics.topology import JOINTS
    from phantom_cad.sizing import magnet_lift

    def change(d):
        d["palm"]["thumb_cmc_axis_deg"] = [0.0, 0.0, 0.0]
        d["palm"]["thumb_cmc_offset_mm"] = [-25.0, -70.0, -12.0 - 0.2 - 7.5 - 0.01]
        magnet_lift(d)

    p = variant(change)
    preflight.check(p)
    rest = pose_transforms(p, np.zeros(len(JOINTS)))        # where the assembly places the parts (mm)
    _, palm = _build(p, "palm")
    base_part, base = _build(p, "thumb_cmc_base")
    gap = placed(palm, rest["palm"]).distance_to(placed(base, rest["thumb_cmc_base"]))
    assert gap >= base_part.sec.tol.clearance - 1e-6


@pytest.mark.slow
def test_the_longest_servo_body_the_rule_accepts_builds(variant):
    """A 24.69 mm servo body under the 32.3 mm flange, 0.01 mm inside what the flange-screw rule
    accepts (tests/test_params.py): the forearm module is one valid solid and its check finds the
    12 flange pilot holes, each a wall from its servo's pocket."""
    p = variant(lambda d: d["servo"].__setitem__("body_mm", [24.69, 12.1, 25.3]))
    pt, shape = _build(p, "forearm")
    assert pt.verify(shape) == []


@pytest.mark.slow
def test_the_cmc_nearest_the_sockets_the_rule_accepts_builds(variant):
    """The CMC 26.99 mm behind the index MCP, where the thenar's cuts come 0.80 mm from the index
    socket's magnet pockets (the least gap the rule accepts, ``thenar.socket_pocket_gap``): the palm is
    one valid solid and its check finds all 8 magnet pockets. The thenar so far forward moves the
    palm's back face forward too, which leaves the heel 41.8 mm of block: its length is 40 mm here."""
    from phantom_cad.cad import preflight
    from phantom_cad.kinematics.thenar import socket_pocket_gap

    def edit(d):
        d["palm"]["thumb_cmc_offset_mm"] = [-25.75, -26.99, -32.81]
        d["palm"]["heel_length_mm"] = 40.0
    p = variant(edit)
    preflight.check(p)
    assert socket_pocket_gap(p)[0] == pytest.approx(0.8e-3, abs=0.02e-3)
    pt, shape = _build(p, "palm")
    assert pt.verify(shape) == []


@pytest.mark.slow
def test_the_widest_servo_body_the_rule_accepts_builds(variant):
    """A 20 mm wide servo body: servo 6's radial flange pilot opens 0.06 mm below the forearm module's
    top (``forearm_layout.pilot_headroom``; 21 mm is refused): the module is one valid solid and its
    check finds all 12 pilots. (The wider row turns the pinky's drive further off its socket's axis:
    its magnet pockets are lifted 0.1 mm to keep two perimeters to its coupler bore.)"""
    from phantom_cad.cad import preflight
    from phantom_cad.kinematics.forearm_layout import pilot_headroom

    def edit(d):
        d["servo"]["body_mm"] = [23.2, 20.0, 25.3]
        d["palm"]["magnet_lift_mm"] = 0.1
    p = variant(edit)
    preflight.check(p)
    assert 0.0 < pilot_headroom(p)[0] < 0.1e-3
    pt, shape = _build(p, "forearm")
    assert pt.verify(shape) == []


@pytest.mark.slow
def test_the_lowest_cmc_the_heel_rule_accepts_builds(variant):
    """The CMC 40.0 mm below the index MCP, 0.242 mm from the palm's heel by the rule's measure
    (``forearm_layout.heel_gap``; 40.4 mm is refused): the palm and the CMC base, where the assembly
    places them, stay at least a clearance apart (OpenCascade's distance; the column in its journal
    is a clearance from the palm by design)."""
    from phantom_cad.cad import preflight
    from phantom_cad.cad.assembly import pose_transforms
    from phantom_cad.cad.measure import placed
    from phantom_cad.kinematics.forearm_layout import heel_gap

    p = variant(lambda d: d["palm"].__setitem__("thumb_cmc_offset_mm", [-25.75, -73.78, -40.0]))
    preflight.check(p)
    assert 0.2e-3 <= heel_gap(p) < 0.25e-3
    rest = pose_transforms(p)
    _, palm = _build(p, "palm")
    base_part, base = _build(p, "thumb_cmc_base")
    gap = placed(palm, rest["palm"]).distance_to(placed(base, rest["thumb_cmc_base"]))
    assert gap >= base_part.sec.tol.clearance - 1e-6


@pytest.mark.slow
def test_sized_205_thumb_cmc_base_is_one_solid(sized_file_205):
    """The file ``phantom-cad size --hand-length 205 --hand-breadth 95`` writes: its thumb CMC
    base's near relief sphere dips 0.03 mm through the palmar face, and with its run (tangent to
    it along a great circle) in one boolean the cut left the sphere's back half standing as a
    second solid. The part is one valid solid that measures as designed."""
    from phantom_cad.params.io import load_params

    path, proc = sized_file_205
    assert proc.returncode == 0, proc.stderr
    p = load_params(path)
    pt, shape = _build(p, "thumb_cmc_base")
    assert pt.verify(shape) == []
