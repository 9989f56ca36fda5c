"""The thumb's twist (``thumb.twist_deg``: its MP turned about the metacarpal's length), against
answers worked by hand from the frames' conventions (docs/frames.md) and against the robot
descriptions as other readers pose them (yourdfpy for the URDF, MuJoCo for the MJCF). No part is
built: the descriptions are the kinematic tree alone (``export.robot.kinematic_model``)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from phantom_cad.kinematics import frames as F, link_frames as LF, opposition as O
from phantom_cad.kinematics.topology import JOINTS, LINK_NAMES
from phantom_cad.params import ParamError, parse
from phantom_cad.params.io import DEFAULT_PARAMS, load_document, load_params
from tests.support.joint_angles import q_deg


def _twisted(params, deg: float, side: str | None = None):
    """The default file with ``thumb.twist_deg = deg`` (and ``hand.side``), parsed: its digest,
    which the memoised routes and models are keyed on, is the file's."""
    doc = load_document(DEFAULT_PARAMS)
    doc["thumb"]["twist_deg"] = deg
    if side is not None:
        doc["hand"]["side"] = side
    return parse(doc, str(DEFAULT_PARAMS))


@pytest.fixture(scope="module")
def params():
    return load_params(None)


def test_twist_deg_is_read_in_degrees_and_defaults_to_0(document):
    assert parse(document).thumb.twist == 0.0
    document["thumb"]["twist_deg"] = 80.0
    assert parse(document).thumb.twist == pytest.approx(math.radians(80.0))
    document["thumb"]["twist_deg"] = 95.0
    with pytest.raises(ParamError) as info:
        parse(document)
    assert str(info.value) == "thumb.twist_deg = 95.0: must be <= 90"


def test_the_mp_origin_by_hand(params):
    """Twisted by 90 deg (Ry(90): x -> -z, z -> x), the proximal phalanx's frame at rest sits at the
    metacarpal's end with its flexion axis x along the CMC base's -z and its nail side z along the
    CMC base's x; its y, the metacarpal's length, stays."""
    p = _twisted(params, 90.0)
    T = LF.rest_transforms(p)["T_thumb_cmc_base_thumb_proximal"]
    assert T[:3, 3] == pytest.approx([0.0, p.thumb.metacarpal, 0.0], abs=1e-15)
    assert T[:3, 0] == pytest.approx([0.0, 0.0, -1.0], abs=1e-15)
    assert T[:3, 1] == pytest.approx([0.0, 1.0, 0.0], abs=1e-15)
    assert T[:3, 2] == pytest.approx([1.0, 0.0, 0.0], abs=1e-15)
    # the joint a description writes: that origin, the same axis in the child frame
    mp = next(j for j in LF.joints(p) if j["name"] == "thumb_mp")
    assert np.allclose(mp["origin"], T) and tuple(mp["axis"]) == (-1.0, 0.0, 0.0)
    # 0 leaves the fingers' and the thumb's origins what they were: no turn
    rest = LF.rest_transforms(_twisted(params, 0.0))
    assert np.array_equal(rest["T_thumb_cmc_base_thumb_proximal"][:3, :3], np.eye(3))


def test_the_pad_normal_from_the_cmc_axis_is_the_closed_form(params):
    """The pad normal, n(s) = (0, sin(45 - s), -cos(45 - s)) after flexion s = q_MP + q_IP, turned by
    Ry(psi): its z component, the cosine to the CMC axis, is -cos psi cos(45 - s). At psi = 90 it
    lies across the CMC axis whatever the flexion, q15 and placement."""
    rng = np.random.default_rng(11)
    for psi in (30.0, 70.0, 90.0, -45.0):
        for _ in range(8):
            offset, axis = rng.normal(scale=0.03, size=3), rng.uniform(-1.5, 1.5, size=3)
            p = _twisted(params, psi)
            p = replace(p, palm=replace(p.palm, thumb_cmc_offset=tuple(offset), thumb_cmc_axis=tuple(axis)))
            mp, ip, cmc = rng.uniform(0, 70), rng.uniform(0, 55), rng.uniform(0, 90)
            T = LF.link_transforms(p, q_deg(thumb_mp=mp, thumb_ip=ip, thumb_cmc=cmc))
            n = (T["thumb_distal"] @ F.T_distal_pad(p, "thumb"))[:3, 2]
            z = F.thumb_cmc_placement(offset, axis)[:3, 2]
            want = math.acos(-math.cos(math.radians(psi)) * math.cos(math.radians(45.0 - mp - ip)))
            assert math.acos(n @ z) == pytest.approx(want, abs=1e-9)
            if psi == 90.0:
                assert math.degrees(math.acos(n @ z)) == pytest.approx(90.0, abs=1e-9)


def test_the_opposition_chain_is_the_link_frames(params):
    """opposition's batched thumb (tip capsule, pad normal, joint centres) is where link_frames
    puts the twisted thumb's links, pose by pose."""
    from phantom_cad.kinematics.model import Hand

    p = _twisted(params, 75.0)
    hand = Hand(p)
    thumb = O.thumb_tips(hand, 4, 3)
    placed = thumb.placed(F.thumb_cmc_placement(p.palm.thumb_cmc_offset, p.palm.thumb_cmc_axis))
    u = np.zeros((len(thumb.u), 6))
    u[:, 0], u[:, 5] = thumb.u[:, 0], thumb.u[:, 1]
    d = p.thumb
    r = min(d.thickness / 2.0, d.distal - d.thickness / 2.0 - p.print.hole_clearance)
    for k, q in enumerate(hand.forward(u, compensated=True)):
        T = LF.link_transforms(p, q)
        tip = T["thumb_distal"]
        centre = (tip @ np.array([0.0, d.distal - r, 0.0, 1.0]))[:3]
        assert np.allclose((placed.a[k] + placed.b[k]) / 2.0, centre, atol=1e-12)
        assert np.allclose(placed.normal[k], (tip @ F.T_distal_pad(p, "thumb"))[:3, 2], atol=1e-12)
        # the body's points: the last of the metacarpal's run is the MP, of the phalanx's the IP
        body = thumb.body_placed(F.thumb_cmc_placement(p.palm.thumb_cmc_offset, p.palm.thumb_cmc_axis))
        pts = body.T.reshape(len(thumb.u), -1, 3)[k]
        assert np.allclose(pts[7], T["thumb_proximal"][:3, 3], atol=1e-12)
        assert np.allclose(pts[15], T["thumb_distal"][:3, 3], atol=1e-12)


def _kinematic_model(p):
    from phantom_cad.cad.assembly import tip_frames
    from phantom_cad.export.robot import kinematic_model
    return kinematic_model(p, tip_frames(p))


@pytest.mark.parametrize("side", ["right", "left"])
def test_the_urdf_of_a_twisted_thumb_poses_its_links_where_link_frames_does(params, side, tmp_path):
    yourdfpy = pytest.importorskip("yourdfpy")
    from phantom_cad.export.urdf import urdf_bytes

    p = _twisted(params, 80.0, side)
    path = tmp_path / "hand.urdf"
    path.write_bytes(urdf_bytes(_kinematic_model(p), lambda kind, stem: f"{stem}.stl"))
    robot = yourdfpy.URDF.load(str(path), load_meshes=False, build_collision_scene_graph=False)
    rng = np.random.default_rng(3)
    for _ in range(4):
        q = rng.uniform(0.0, 0.9, len(JOINTS))
        robot.update_cfg({j.name: q[j.index] for j in JOINTS if j.name in robot.actuated_joint_names})
        # the mimic joints follow their reference in the URDF: read back what it posed
        q = np.array([robot.cfg[robot.actuated_joint_names.index(j.name)] if j.name in robot.actuated_joint_names
                      else q[j.index] for j in JOINTS])
        want = LF.link_transforms(p, _poseq_deg(robot, q))
        for link in LINK_NAMES:
            assert np.allclose(robot.get_transform(link, "palm"), want[link], atol=1e-12), link


def _poseq_deg(robot, q):
    """The joint angles the URDF posed: mimic joints from their reference joints' multipliers."""
    out = q.copy()
    for j in JOINTS:
        joint = robot.joint_map[j.name]
        if joint.mimic is not None:
            ref = next(k for k in JOINTS if k.name == joint.mimic.joint)
            out[j.index] = joint.mimic.multiplier * q[ref.index] + (joint.mimic.offset or 0.0)
    return out


def test_the_mjcf_of_a_twisted_thumb_poses_its_bodies_where_link_frames_does(params):
    mujoco = pytest.importorskip("mujoco")
    from phantom_cad.export.mjcf import mjcf_spec
    from phantom_cad.export.robot import Inertial, RobotLink

    p = _twisted(params, 80.0)
    model = _kinematic_model(p)
    # a small mass on every link, so that MuJoCo compiles the tree (the kinematics does not see it)
    mass = Inertial(0.01, (0.0, 0.0, 0.0), (1e-6, 0.0, 0.0, 1e-6, 0.0, 1e-6), "test")
    model = replace(model, links=tuple(RobotLink(ln.name, mass if ln.name in LINK_NAMES else None, None)
                                       for ln in model.links))
    m = mjcf_spec(model).compile()
    d = mujoco.MjData(m)
    rng = np.random.default_rng(5)
    q = rng.uniform(0.0, 0.9, len(JOINTS))
    for j in JOINTS:
        d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j.name)]] = q[j.index]
    mujoco.mj_kinematics(m, d)
    want = LF.link_transforms(p, q)
    palm = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "palm")
    R0, p0 = d.xmat[palm].reshape(3, 3), d.xpos[palm]
    for link in LINK_NAMES:
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, link)
        assert np.allclose(R0.T @ d.xmat[b].reshape(3, 3), want[link][:3, :3], atol=1e-9), link
        assert np.allclose(R0.T @ (d.xpos[b] - p0), want[link][:3, 3], atol=1e-9), link


@pytest.mark.parametrize("side", ["right", "left"])
def test_the_twisted_thumbs_tendons_are_the_mechanism(params, side):
    """The routing model of a twisted thumb (its guide G1, MP-IP loop hub and return channel on the
    metacarpal turned with the MP) keeps the mechanism's lengths, worked from the file's numbers:
    the loop's strands +-(R_MP q_MP - R_IP q_IP) (eq. 2), the drive chord(q_MP) - chord(0) + r u1
    (eq. 4-5), whatever q15 (the drive enters down the CMC axis), the return R_MP q_MP + R_IP q_IP
    (eq. 11)."""
    from phantom_cad.kinematics import routing_paths
    from phantom_cad.kinematics.topology import SERVOS

    p = _twisted(params, 80.0, side)
    t = p.thumb
    R_mp, R_ip = t.chain.radii
    g = t.chain.guide
    chord = lambda x: math.sqrt(g.d1 ** 2 + g.d2 ** 2 - 2.0 * g.d1 * g.d2 * math.cos(g.alpha - x))  # noqa: E731
    rest = routing_paths.lengths(p)
    rng = np.random.default_rng(13)
    for _ in range(6):
        mp, ip, cmc = rng.uniform(0.0, 1.2), rng.uniform(0.0, 0.95), rng.uniform(0.0, 1.5)
        u = np.zeros(len(SERVOS))
        u[0], u[5] = rng.uniform(0.0, 1.4), cmc
        got = routing_paths.lengths(p, q_deg(thumb_mp=math.degrees(mp), thumb_ip=math.degrees(ip),
                                          thumb_cmc=math.degrees(cmc)), u)
        want = R_mp * mp - R_ip * ip
        assert got["thumb_mp_ip_a"] - rest["thumb_mp_ip_a"] == pytest.approx(want, abs=1e-9)
        assert got["thumb_mp_ip_b"] - rest["thumb_mp_ip_b"] == pytest.approx(-want, abs=1e-9)
        r = t.chain.servo_radius
        assert got["thumb_drive"] - rest["thumb_drive"] == pytest.approx(chord(mp) - chord(0.0) + r * u[0], abs=1e-9)
        assert got["thumb_return"] - rest["thumb_return"] == pytest.approx(R_mp * mp + R_ip * ip, abs=1e-9)


def test_the_twins_thumb_tendons_are_the_mechanism_when_twisted(params):
    """MuJoCo's own wrapping of a twisted thumb's routed tendons (the MJCF's sites and pulley
    cylinders, written from the routing model), at random joint and servo angles, against the
    mechanism from the file's numbers: the MP-IP loop's strands +-(R_MP q_MP - R_IP q_IP), the
    drive chord(q_MP) - chord(0) + r u1, the return R_MP q_MP + R_IP q_IP."""
    mujoco = pytest.importorskip("mujoco")
    from phantom_cad.export.mjcf import mjcf_spec
    from phantom_cad.export.robot import Inertial, RobotLink, transmissions

    p = _twisted(params, 80.0)
    drives, strands = transmissions(p)
    mass = Inertial(0.01, (0.0, 0.0, 0.0), (1e-6, 0.0, 0.0, 1e-6, 0.0, 1e-6), "test")
    model = _kinematic_model(p)
    model = replace(model, links=tuple(RobotLink(ln.name, mass if ln.name in LINK_NAMES else None, None)
                                       for ln in model.links), drives=drives, strands=strands)
    m = mjcf_spec(model).compile()
    d = mujoco.MjData(m)

    def lengths(q, u1):
        d.qpos[:] = 0.0
        for j in JOINTS:
            d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j.name)]] = q[j.index]
        d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "thumb_flexion")]] = u1
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_tendon(m, d)
        return {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t): d.ten_length[t] for t in range(m.ntendon)}

    t = p.thumb
    R_mp, R_ip = t.chain.radii
    g = t.chain.guide
    chord = lambda x: math.sqrt(g.d1 ** 2 + g.d2 ** 2 - 2.0 * g.d1 * g.d2 * math.cos(g.alpha - x))  # noqa: E731
    rest = lengths(np.zeros(len(JOINTS)), 0.0)
    rng = np.random.default_rng(17)
    for _ in range(5):
        mp, ip, cmc, u1 = rng.uniform(0.0, 1.2), rng.uniform(0.0, 0.95), rng.uniform(0.0, 1.5), rng.uniform(0.0, 1.4)
        got = lengths(q_deg(thumb_mp=math.degrees(mp), thumb_ip=math.degrees(ip), thumb_cmc=math.degrees(cmc)), u1)
        want = R_mp * mp - R_ip * ip
        assert got["thumb_mp_ip_a"] - rest["thumb_mp_ip_a"] == pytest.approx(want, abs=2e-5)
        assert got["thumb_mp_ip_b"] - rest["thumb_mp_ip_b"] == pytest.approx(-want, abs=2e-5)
        assert got["thumb_drive"] - rest["thumb_drive"] == pytest.approx(
            chord(mp) - chord(0.0) + t.chain.servo_radius * u1, abs=2e-5)
        assert got["thumb_return"] - rest["thumb_return"] == pytest.approx(R_mp * mp + R_ip * ip, abs=2e-5)


def test_the_twisted_metacarpal_part_carries_the_models_guide_and_hub(params):
    """The metacarpal part of a file twisted by 80 deg, measured on the solid in its own (the CMC
    base's) frame: its guide eyelet's hole is centred on the routing model's G1 and its MP-IP hub's
    groove lies about the model's hub axis (the MP axis turned by Ry(80 deg): x -> (cos 80, 0,
    -sin 80)), its floor half a cord inside the hub's radius; the MP's axle bore lies on the turned
    axis through the metacarpal's end. Hub and column stay about the CMC axis: the solid's lowest
    point is the part's printing floor."""
    pytest.importorskip("build123d")
    from phantom_cad import units
    from phantom_cad.cad import measure
    from phantom_cad.cad.registry import part as make_part
    from phantom_cad.kinematics import routing

    p = _twisted(params, 80.0)
    part = make_part(p, "thumb_cmc_base")
    shape = part.build()
    assert shape.is_valid and len(shape.solids()) == 1
    faces = measure.cylinders(shape)
    t = part.sec.tol
    axis = np.array([math.cos(math.radians(80.0)), 0.0, -math.sin(math.radians(80.0))])
    drive = next(s for r in routing.routes(p) for s in r.strands if s.name == "thumb_drive")
    g1 = units.mm(np.asarray(next(e.pos for e in drive.elements if getattr(e, "role", "") == "guide G1")))
    eyes = measure.eyelet_centres(shape, t.tendon_hole / 2.0, t.eyelet_length, faces=faces)
    assert len(eyes) == 1 and np.allclose(eyes[0]["centre"], g1, atol=1e-3)
    loop = next(s for r in routing.routes(p) for s in r.strands if s.name == "thumb_mp_ip_a")
    hub = next(e for e in loop.elements if getattr(e, "role", "") == "hub")
    assert np.allclose(hub.axis, -axis, atol=1e-12)
    floor = measure.measure_groove_radius(shape, units.mm(np.asarray(hub.centre)), axis, units.mm(hub.width),
                                          faces=faces)
    assert floor == pytest.approx(units.mm(hub.radius - p.hardware.tendon_diameter / 2.0), abs=1e-3)
    mp = np.array([0.0, units.mm(p.thumb.metacarpal), 0.0])
    assert any(measure.coaxial(c, mp, axis, 1e-6) for c in faces)
    assert shape.bounding_box().min.Z == pytest.approx(part.palmar_floor, abs=1e-3)


def test_the_twisted_metacarpal_verifies_on_both_sides(params):
    """The part's own measurements (its grooves, its guide at d1 from the MP axis, its lowest point)
    pass on the right hand's solid and on the left hand's, which is its mirror image."""
    pytest.importorskip("build123d")
    from phantom_cad.cad import assembly

    for side in ("right", "left"):
        p = _twisted(params, 80.0, side)
        built = assembly.build_part(p, "thumb_cmc_base")
        assert assembly.verify_part(p, "thumb_cmc_base", built.shape) == [], side
