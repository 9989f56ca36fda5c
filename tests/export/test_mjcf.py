"""The MJCF of the default hand (description/mjcf), loaded and simulated by MuJoCo.

Known answers: the URDF read by yourdfpy (tree, forward kinematics, inertials), the cosine law
of eq. (4)-(6) computed here by hand from params/phantom.toml, the multipliers 5:4:5 and 5:4 by
hand, and MuJoCo itself (lengths, equilibria, warnings); never the writer.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from phantom_cad.kinematics.topology import JOINT_NAMES
from phantom_cad.params.io import load_params

mujoco = pytest.importorskip("mujoco")

PARAMS = Path(__file__).resolve().parents[2] / "params" / "phantom.toml"
FINGERS = ("index", "middle", "ring", "pinky")
#: by hand from params/phantom.toml: q_i = (R_ref / R_i) q_ref (eq. 2), radii 5:4:5 and 5:4
MIMIC = {f"{f}_{k}": (f"{f}_mcp", m) for f in FINGERS for k, m in (("pip", 5.0 / 4.0), ("dip", 1.0))}
MIMIC["thumb_ip"] = ("thumb_mp", 4.0 / 5.0)
#: servo n drives: the reference joint of a chain, or the CMC
SERVO_JOINT = {"servo1": "thumb_mp", "servo2": "index_mcp", "servo3": "middle_mcp", "servo4": "ring_mcp",
               "servo5": "pinky_mcp", "servo6": "thumb_cmc"}
SERVO_DIGIT = {"servo1": "thumb", "servo2": "index", "servo3": "middle", "servo4": "ring", "servo5": "pinky"}


@pytest.fixture(scope="module")
def model(pkg):
    return mujoco.MjModel.from_xml_path(str(pkg / "mjcf" / "scene.xml"))


@pytest.fixture(scope="module")
def doc():
    """The parameter file as written (TOML), for the by-hand answers."""
    import tomllib

    return tomllib.loads(PARAMS.read_text())


def _guide(doc, digit):
    g = (doc["thumb"] if digit == "thumb" else doc["fingers"][digit])["guide"]
    return g["d1_mm"] / 1000.0, g["d2_mm"] / 1000.0, math.radians(g["alpha_deg"])


def _servo_radius(doc, digit):
    t = doc["thumb"] if digit == "thumb" else doc["fingers"][digit]
    return t["servo_pulley_radius_mm"] / 1000.0


def _name(m, kind, i):
    return mujoco.mj_id2name(m, kind, i)


def _qadr(m, joint):
    return m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, joint)]


def _set_q(m, d, q: dict):
    d.qpos[:] = 0.0
    for name, v in q.items():
        d.qpos[_qadr(m, name)] = v
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    mujoco.mj_tendon(m, d)


def _coupled_q(rng, lo=0.0, hi=0.9):
    """Random reference angles, the followers at their multipliers."""
    ref = {j: rng.uniform(lo, hi) for j in SERVO_JOINT.values()}
    return {**ref, **{f: k * ref[r] for f, (r, k) in MIMIC.items()}}


def test_same_tree_names_and_limits_as_the_urdf(pkg, model):
    yourdfpy = pytest.importorskip("yourdfpy")
    robot = yourdfpy.URDF.load(str(pkg / "urdf" / "phantom.local.urdf"), load_meshes=False,
                               build_collision_scene_graph=False)
    m = model
    bodies = {_name(m, mujoco.mjtObj.mjOBJ_BODY, i) for i in range(1, m.nbody)}
    tips = {f"{d}_tip" for d in ("thumb",) + FINGERS}
    assert bodies == set(robot.link_map) - tips
    sites = {_name(m, mujoco.mjtObj.mjOBJ_SITE, i) for i in range(m.nsite)}
    assert tips <= sites
    for j in robot.robot.joints:
        if j.type != "revolute":
            continue
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j.name)
        assert jid >= 0 and m.jnt_type[jid] == mujoco.mjtJoint.mjJNT_HINGE, j.name
        assert _name(m, mujoco.mjtObj.mjOBJ_BODY, m.jnt_bodyid[jid]) == j.child
        assert np.allclose(m.jnt_axis[jid], j.axis, atol=1e-12)
        assert np.allclose(m.jnt_range[jid], [j.limit.lower, j.limit.upper], atol=1e-12)
    assert m.njnt == 15 and m.nu == 6
    assert [_name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(m.nu)] == list(SERVO_JOINT)


def test_inertials_equal_the_urdf(pkg, model):
    """MuJoCo keeps mass, centre of mass and the full tensor (it stores the principal axes)."""
    robot = pytest.importorskip("yourdfpy").URDF.load(str(pkg / "urdf" / "phantom.local.urdf"),
                                                      load_meshes=False, build_collision_scene_graph=False)
    m = model
    for link in robot.robot.links:
        bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, link.name)
        if link.inertial is None or bid < 0:
            continue
        I_urdf = link.inertial.inertia
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, m.body_iquat[bid])
        R = R.reshape(3, 3)
        I_mj = R @ np.diag(m.body_inertia[bid]) @ R.T
        assert m.body_mass[bid] == pytest.approx(link.inertial.mass, rel=1e-9), link.name
        assert np.allclose(m.body_ipos[bid], link.inertial.origin[:3, 3], atol=1e-12), link.name
        # MuJoCo writes the principal moments with 6 significant digits
        assert np.allclose(I_mj, I_urdf, rtol=1e-5, atol=1e-5 * np.abs(I_urdf).max()), link.name


def test_bodies_where_the_urdf_puts_its_links(pkg, model):
    """At random coupled configurations MuJoCo's forward kinematics equals yourdfpy's on the URDF
    (0.01 mm, 0.01 degree)."""
    yourdfpy = pytest.importorskip("yourdfpy")
    robot = yourdfpy.URDF.load(str(pkg / "urdf" / "phantom.local.urdf"), load_meshes=False,
                               build_collision_scene_graph=False)
    m, d = model, mujoco.MjData(model)
    rng = np.random.default_rng(11)
    palm = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "palm")
    for _ in range(5):
        q = _coupled_q(rng)
        _set_q(m, d, q)
        robot.update_cfg({n: q[n] for n in robot.actuated_joint_names})
        T_w_palm = np.eye(4)
        T_w_palm[:3, :3], T_w_palm[:3, 3] = d.xmat[palm].reshape(3, 3), d.xpos[palm]
        for i in range(1, m.nbody):
            name = _name(m, mujoco.mjtObj.mjOBJ_BODY, i)
            T = np.eye(4)
            T[:3, :3], T[:3, 3] = d.xmat[i].reshape(3, 3), d.xpos[i]
            T = np.linalg.inv(T_w_palm) @ T
            U = robot.get_transform(name, "palm")
            assert np.linalg.norm(T[:3, 3] - U[:3, 3]) <= 1e-5, name
            cos = (np.trace(T[:3, :3].T @ U[:3, :3]) - 1.0) / 2.0
            assert math.degrees(math.acos(min(1.0, cos))) <= 0.01, name


def test_drive_tendon_length_is_the_chord(model, doc):
    """MuJoCo's own length of each drive tendon is the chord of eq. (4)-(5),
    L = sqrt(d1^2 + d2^2 - 2 d1 d2 cos(alpha - q_ref)), computed here by hand."""
    m, d = model, mujoco.MjData(model)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = _coupled_q(rng, 0.0, 1.2)
        _set_q(m, d, q)
        for act, digit in SERVO_DIGIT.items():
            d1, d2, alpha = _guide(doc, digit)
            want = math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha - q[SERVO_JOINT[act]]))
            tid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, f"{digit}_drive")
            assert d.ten_length[tid] == pytest.approx(want, abs=1e-7), digit   # 0.1 um: MJCF's digits


def _settle(m, d, u, seconds=2.0):
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "home"))
    d.ctrl[:] = u
    for _ in range(int(seconds / m.opt.timestep)):
        mujoco.mj_step(m, d)


def test_static_equilibrium_is_the_cosine_law(model, doc):
    """Under the six actuators and the return springs alone (contacts and gravity off: the
    transmission, not the grasp; gravity would flex a finger past a slack tendon), the joints
    settle where the cosine law puts them: q_ref = alpha - arccos((d1^2 + d2^2 - (L0 - r u)^2) /
    (2 d1 d2)) by hand, the followers at their multipliers, the CMC at cmc_gain u; and where
    hand.forward puts them (0.01 rad)."""
    from phantom_cad.kinematics.model import Hand

    m = model
    off = mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    m.opt.disableflags |= off
    try:
        d = mujoco.MjData(m)
        hand = Hand(load_params(PARAMS))
        rng = np.random.default_rng(5)
        lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
        for _ in range(4):
            u = lo + rng.uniform(0.05, 0.95, m.nu) * (hi - lo)
            _settle(m, d, u)
            assert np.abs(d.qvel).max() < 1e-3
            by_hand = {}
            for k, (act, joint) in enumerate(SERVO_JOINT.items()):
                if act in SERVO_DIGIT:
                    d1, d2, alpha = _guide(doc, SERVO_DIGIT[act])
                    r = _servo_radius(doc, SERVO_DIGIT[act])
                    L0 = math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha))
                    by_hand[joint] = alpha - math.acos((d1 * d1 + d2 * d2 - (L0 - r * u[k]) ** 2) / (2 * d1 * d2))
                else:
                    by_hand[joint] = doc["thumb"]["cmc_gain"] * u[k]
            by_hand.update({f: k * by_hand[r] for f, (r, k) in MIMIC.items()})
            analytic = hand.forward(u)
            for i, name in enumerate(JOINT_NAMES):
                q = d.qpos[_qadr(m, name)]
                assert abs(q - by_hand[name]) < 0.01, (name, q, by_hand[name])
                assert abs(q - analytic[i]) < 0.01, (name, q, analytic[i])
    finally:
        m.opt.disableflags &= ~off


def test_coupling_holds_under_servo_load(pkg, doc):
    """A fingertip load (a torque against flexion on the index DIP) of half what the servo holds
    at stall through its tendon: tension 0.226 N m / r times the moment arm of the chord about
    the MCP, d1 d2 sin(phi) / L (by hand). The followers stay on q_f = k q_ref within 0.01 rad
    (measured: about 0.001 rad); with MuJoCo's default solref/solimp the same load tears the
    coupling apart (the drift this test guards)."""
    spec_path = pkg / "mjcf" / "phantom.xml"
    d1, d2, alpha = _guide(doc, "index")
    r = _servo_radius(doc, "index")

    def run(default_constraint: bool):
        spec = mujoco.MjSpec.from_file(str(spec_path))
        if default_constraint:
            for e in spec.equalities:
                e.solref = [0.02, 1.0]
                e.solimp = [0.9, 0.95, 0.001, 0.5, 2.0]
        m = spec.compile()
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
        d = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, d, 0)
        aid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "servo2")
        u = float(m.actuator_ctrlrange[aid].mean())
        d.ctrl[aid] = u
        L0 = math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha))
        L = L0 - r * u
        phi = math.acos((d1 * d1 + d2 * d2 - L * L) / (2 * d1 * d2))
        load = 0.5 * (0.226 / r) * d1 * d2 * math.sin(phi) / L
        dip = m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "index_dip")]
        for _ in range(int(2.0 / m.opt.timestep)):
            d.qfrc_applied[dip] = -load
            mujoco.mj_step(m, d)
        q_ref = d.qpos[_qadr(m, "index_mcp")]
        err = max(abs(d.qpos[_qadr(m, f)] - MIMIC[f][1] * q_ref) for f in ("index_pip", "index_dip"))
        return err, d.actuator_force[aid], q_ref

    err, force, q_ref = run(False)
    assert 0.0 < force < 0.226 and q_ref > 0.3            # the servo holds the loaded finger
    assert err < 0.01
    assert run(True)[0] > 0.01


def test_menagerie_model_test(model):
    """MuJoCo Menagerie's model test: 1 s of random controls across the control range (new
    targets every 0.1 s), contacts on: no warning, finite state."""
    m, d = model, mujoco.MjData(model)
    rng = np.random.default_rng(0)
    lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
    mujoco.mj_resetDataKeyframe(m, d, 0)
    steps = int(1.0 / m.opt.timestep)
    for k in range(steps):
        if k % int(0.1 / m.opt.timestep) == 0:
            d.ctrl[:] = lo + rng.random(m.nu) * (hi - lo)
        mujoco.mj_step(m, d)
        assert np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all()
    assert [d.warning[i].number for i in range(len(d.warning))] == [0] * len(d.warning)


def test_home_keyframe_has_no_contact(model):
    m, d = model, mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "home"))
    mujoco.mj_forward(m, d)
    pairs = [(_name(m, mujoco.mjtObj.mjOBJ_BODY, m.geom_bodyid[c.geom1]),
              _name(m, mujoco.mjtObj.mjOBJ_BODY, m.geom_bodyid[c.geom2])) for c in d.contact[:d.ncon]]
    assert pairs == []


def test_compiled_mjcf_is_served_from_the_cache_only_when_it_matches(hand_build, pkg, tmp_path):
    """A warm rebuild takes the compiled MJCF from the cache (MuJoCo not run again); an entry whose
    text no longer matches its SHA-256 is compiled again, and the package gets the same bytes."""
    import json

    from phantom_cad.export.pipeline import build_hand

    result, cache = hand_build
    written = (pkg / "mjcf" / "phantom.xml").read_bytes()
    entries = sorted((cache / "mjcf").glob("*.json"))
    assert len(entries) == 1
    doc = json.loads(entries[0].read_text())
    assert doc["xml"].encode() == written
    mujoco.MjModel.from_xml_path(str(pkg / "mjcf" / "scene.xml"))      # what was kept compiles

    doc["xml"] = doc["xml"].replace('name="index_mcp"', 'name="corrupted"', 1)
    entries[0].write_text(json.dumps(doc))
    again = build_hand(None, tmp_path / "again", cache_dir=cache, jobs=1, slice=None, render=False)
    assert again.built == []
    assert (tmp_path / "again" / "description" / "mjcf" / "phantom.xml").read_bytes() == written
    assert json.loads(entries[0].read_text())["xml"].encode() == written     # the entry was rewritten
