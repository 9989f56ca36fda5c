"""The MJCF of the default hand (description/mjcf), loaded and simulated by MuJoCo (the power grasp
also on the left and the 170 mm hands' MJCF).

Known answers: the URDF read by yourdfpy (tree, forward kinematics, inertials), the cosine law
of eq. (4)-(6) computed here by hand from params/phantom.toml, the radii 5:4:5 and 5:4 by hand,
and MuJoCo itself (tendon lengths along its own wrapping, equilibria, tendon forces, warnings);
never the writer. No joint equality couples the joints: the routed tendons do.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from phantom_cad.kinematics.topology import JOINT_NAMES
from phantom_cad.params.io import load_params
from tests.support.hands import HANDS

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


def _set_q(m, d, q: dict, u: dict | None = None):
    """Joint angles ``q`` by name and tendon servo angles ``u`` by digit (the rest 0), then the
    kinematics and tendon lengths."""
    d.qpos[:] = 0.0
    for name, v in q.items():
        d.qpos[_qadr(m, name)] = v
    for digit, v in (u or {}).items():
        d.qpos[_qadr(m, f"{digit}_flexion")] = v
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
    # 15 joints and the 6 servos' pulleys, each on its hinge; no equality
    assert m.njnt == 21 and m.nu == 6 and m.neq == 0
    for servo, digit in SERVO_DIGIT.items():
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"{digit}_flexion")
        assert _name(m, mujoco.mjtObj.mjOBJ_BODY, m.jnt_bodyid[jid]) == f"servo_pulley_{servo[-1]}"
        assert m.actuator_trnid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, servo)][0] == jid
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
        # MuJoCo's XML keeps 6 significant digits: the slicer's masses have no more, an unsliced
        # export's (volume x density x infill) do
        assert m.body_mass[bid] == pytest.approx(link.inertial.mass, rel=5e-6), link.name
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


def _radii(doc, digit):
    t = doc["thumb"] if digit == "thumb" else doc["fingers"][digit]
    return {k: v / 1000.0 for k, v in t["pulley_radius_mm"].items()}


#: chain joints proximal first, and the loops between them
CHAIN_KEYS = {"thumb": ("mp", "ip"), **{f: ("mcp", "pip", "dip") for f in FINGERS}}


def _length(m, d, name):
    return d.ten_length[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, name)]


def test_tendon_lengths_are_the_mechanism(model, doc):
    """MuJoCo's own lengths of the routed tendons (its wrapping of the sites and pulley cylinders),
    at random joint and servo angles, against the mechanism by hand from the TOML: each strand of
    the loop between joints a and b changes by +-(R_a q_a - R_b q_b) (so it keeps its length
    exactly when eq. (2) holds), the drive by chord(q_ref) - chord(0) + r u (eq. 4-5: winding
    r u onto the servo takes up the chord's shortening), the return cord by sum R_i q_i (eq. 11)."""
    m, d = model, mujoco.MjData(model)
    _set_q(m, d, {}, {})
    rest = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t): d.ten_length[t] for t in range(m.ntendon)}
    rng = np.random.default_rng(7)
    for _ in range(6):
        q = {j: rng.uniform(0.0, 1.2) for j in JOINT_NAMES}
        u = {digit: rng.uniform(0.0, 1.4) for digit in SERVO_DIGIT.values()}
        _set_q(m, d, q, u)
        for digit, keys in CHAIN_KEYS.items():
            R = _radii(doc, digit)
            for a, b in zip(keys, keys[1:]):
                want = R[a] * q[f"{digit}_{a}"] - R[b] * q[f"{digit}_{b}"]
                da = _length(m, d, f"{digit}_{a}_{b}_a") - rest[f"{digit}_{a}_{b}_a"]
                db = _length(m, d, f"{digit}_{a}_{b}_b") - rest[f"{digit}_{a}_{b}_b"]
                assert da == pytest.approx(want, abs=2e-5) and db == pytest.approx(-want, abs=2e-5), (digit, a, b)
            d1, d2, alpha = _guide(doc, digit)
            chord = lambda qr: math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha - qr))  # noqa: E731
            want = chord(q[f"{digit}_{keys[0]}"]) - chord(0.0) + _servo_radius(doc, digit) * u[digit]
            assert _length(m, d, f"{digit}_drive") - rest[f"{digit}_drive"] == pytest.approx(want, abs=2e-5), digit
            want = sum(R[k] * q[f"{digit}_{k}"] for k in keys)
            assert _length(m, d, f"{digit}_return") - rest[f"{digit}_return"] == pytest.approx(want, abs=2e-5), digit


def test_loops_hold_the_coupling_and_only_it(model, doc):
    """Along the coupled motion (eq. 2 by hand) every loop strand keeps its length within 0.02 mm
    over the whole travel; one joint leaving the coupling by 1 degree changes it by >= 0.05 mm."""
    m, d = model, mujoco.MjData(model)
    _set_q(m, d, {}, {})
    rest = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t): d.ten_length[t] for t in range(m.ntendon)}
    loops = [n for n in rest if n.endswith(("_a", "_b")) and not n.startswith("thumb_cmc_loop")]
    assert len(loops) == 2 * (1 + 2 * len(FINGERS))
    for ref in np.linspace(0.0, 1.2, 13):
        q = {j: ref for j in SERVO_JOINT.values() if j != "thumb_cmc"}
        q.update({f: k * q[r] for f, (r, k) in MIMIC.items()})
        _set_q(m, d, q, {})
        assert max(abs(_length(m, d, n) - rest[n]) for n in loops) < 2e-5
        for j in MIMIC:
            _set_q(m, d, {**q, j: q[j] + math.radians(1.0)}, {})
            moved = [n for n in loops if abs(_length(m, d, n) - rest[n]) >= 5e-5]
            digit = j.split("_")[0]
            assert moved and all(n.startswith(digit) for n in moved), j


def _settle(m, d, u, seconds=2.0):
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "home"))
    d.ctrl[:] = u
    for _ in range(int(seconds / m.opt.timestep)):
        mujoco.mj_step(m, d)


def test_near_rigid_twin_is_the_cosine_law(pkg, doc):
    """The tendons made near-rigid (every strand but the return cord 200x stiffer, the step
    shortened to stay stable), contacts and gravity off: at 20 commands over each servo's travel
    the joints settle where the cosine law puts them at the angle the servo reached, q_ref =
    alpha - arccos((d1^2 + d2^2 - (L0 - r u)^2) / (2 d1 d2)) by hand, the others at the radius
    ratios (eq. 2), the CMC at cmc_gain u: within 0.1 degree, and hand.forward agrees."""
    from phantom_cad.kinematics.model import Hand

    m = mujoco.MjModel.from_xml_path(str(pkg / "mjcf" / "scene.xml"))
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    for t in range(m.ntendon):
        if not mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t).endswith("_return"):
            m.tendon_stiffness[t] *= 200.0
            m.tendon_damping[t] *= 200.0
    m.opt.timestep = 2e-5
    d = mujoco.MjData(m)
    hand = Hand(load_params(PARAMS))
    lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
    worst = 0.0
    for frac in np.linspace(0.0, 1.0, 20):
        u = lo + frac * (hi - lo)
        _settle(m, d, u, seconds=1.0)
        assert np.abs(d.qvel).max() < 1e-2
        reached = u.copy()
        by_hand = {}
        for k, (act, jn) in enumerate(SERVO_JOINT.items()):
            if act in SERVO_DIGIT:
                digit = SERVO_DIGIT[act]
                reached[k] = d.qpos[_qadr(m, f"{digit}_flexion")]
                d1, d2, alpha = _guide(doc, digit)
                r = _servo_radius(doc, digit)
                L0 = math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha))
                by_hand[jn] = alpha - math.acos((d1 * d1 + d2 * d2 - (L0 - r * reached[k]) ** 2) / (2 * d1 * d2))
            else:                   # the CMC loop: q15 = cmc_gain times the angle servo 6 reached
                reached[k] = d.qpos[_qadr(m, "thumb_abduction")]
                by_hand[jn] = doc["thumb"]["cmc_gain"] * reached[k]
        by_hand.update({f: k * by_hand[r] for f, (r, k) in MIMIC.items()})
        analytic = hand.forward(reached)
        for i, name in enumerate(JOINT_NAMES):
            q = d.qpos[_qadr(m, name)]
            worst = max(worst, abs(q - by_hand[name]))
            assert abs(q - by_hand[name]) < math.radians(0.1), (frac, name, math.degrees(q - by_hand[name]))
            assert abs(q - analytic[i]) < math.radians(0.1), (frac, name)
    assert worst > 0.0


def test_twin_compliance_is_the_statics_of_the_routing(model, doc):
    """With the file's EA and k_s the twin leaves the cosine law by the stretch of its strands,
    and by exactly what the statics of the printed routing say, computed here by hand from the
    settled angles: the return cord pulls with T = k_s sum R_i q_i on every joint (eq. 11); the
    last loop carries T, each loop before it T more (it also holds every joint beyond it), the
    drive (3 T R_MCP + ...) / its moment arm d1 d2 sin(alpha - q) / L; each strand stretches by its
    tension times rest length / EA, which the joints give up: R_a q_a - R_b q_b = stretch and
    L(q_ref) = L0 - r u + stretch. Within 0.05 degree for every chain at 4 commands
    (docs/transmission.md: why this is not the paper's eq. 12-13)."""
    m = model
    off = mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    m.opt.disableflags |= off
    try:
        d = mujoco.MjData(m)
        EA, k_s = doc["mechanics"]["tendon_EA_N"], doc["mechanics"]["spring_k_N_per_m"]
        lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
        rest = lambda name: m.tendon_lengthspring[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, name)][1]  # noqa: E731
        for frac in (0.25, 0.5, 0.75, 1.0):
            _settle(m, d, lo + frac * (hi - lo))
            for act, digit in SERVO_DIGIT.items():
                keys = CHAIN_KEYS[digit]
                R = _radii(doc, digit)
                q = {k: d.qpos[_qadr(m, f"{digit}_{k}")] for k in keys}
                T = k_s * sum(R[k] * q[k] for k in keys)
                n = len(keys)
                # loop k (between keys[k] and keys[k+1]) holds the return on joints k+1..n-1
                for k in range(n - 1):
                    F = T * (n - 1 - k)
                    loop = f"{digit}_{keys[k]}_{keys[k + 1]}"
                    taut = max("ab", key=lambda x: _length(m, d, f"{loop}_{x}") - rest(f"{loop}_{x}"))
                    stretch = F * rest(f"{loop}_{taut}") / EA
                    give = R[keys[k]] * q[keys[k]] - R[keys[k + 1]] * q[keys[k + 1]]
                    assert math.degrees(abs(give - stretch) / R[keys[k + 1]]) < 0.05, (frac, digit, keys[k])
                d1, d2, alpha = _guide(doc, digit)
                r = _servo_radius(doc, digit)
                L = math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha - q[keys[0]]))
                arm = d1 * d2 * math.sin(alpha - q[keys[0]]) / L
                F_drive = T * n * R[keys[0]] / arm
                u = d.qpos[_qadr(m, f"{digit}_flexion")]
                L0 = math.sqrt(d1 * d1 + d2 * d2 - 2 * d1 * d2 * math.cos(alpha))
                want = L0 - r * u + F_drive * rest(f"{digit}_drive") / EA
                assert math.degrees(abs(L - want) / arm) < 0.05, (frac, digit, L, want)
    finally:
        m.opt.disableflags &= ~off


def test_the_loops_carry_a_fingertip_load(model, doc):
    """A torque against flexion on the index DIP, with the file's EA: only the loops couple the
    joints, so the PIP-DIP loop's taut strand carries it. Measured in MuJoCo: its stretch is the
    coupling's give, R_PIP q_PIP - R_DIP q_DIP (by hand), and its tension times R_DIP balances the
    load plus the return cord's pull on the DIP, k_s sum R_i q_i times R_DIP (statics by hand, 2 %)."""
    m = model
    off = mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    m.opt.disableflags |= off
    try:
        d = mujoco.MjData(m)
        aid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "servo2")
        mujoco.mj_resetDataKeyframe(m, d, 0)
        d.ctrl[aid] = float(m.actuator_ctrlrange[aid].mean())
        dip = m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "index_dip")]
        load = 0.02                                                    # N m
        for _ in range(int(2.0 / m.opt.timestep)):
            d.qfrc_applied[dip] = -load
            mujoco.mj_step(m, d)
        assert np.abs(d.qvel).max() < 1e-3
        assert 0.0 < d.actuator_force[aid] < 0.226                    # the servo holds the finger
        R = _radii(doc, "index")
        q = {k: d.qpos[_qadr(m, f"index_{k}")] for k in ("mcp", "pip", "dip")}
        give = R["pip"] * q["pip"] - R["dip"] * q["dip"]
        tid = {s: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, f"index_pip_dip_{s}") for s in "ab"}
        stretch = {s: d.ten_length[t] - m.tendon_lengthspring[t][1] for s, t in tid.items()}
        taut = max(stretch, key=lambda s: stretch[s])
        assert stretch[taut] > 0.0 and min(stretch.values()) < 0.0      # one strand pulls, one is slack
        assert abs(give) == pytest.approx(stretch[taut], rel=1e-3)
        tension = m.tendon_stiffness[tid[taut]] * stretch[taut]
        k_s = doc["mechanics"]["spring_k_N_per_m"]
        T = k_s * sum(R[k] * q[k] for k in R)
        assert tension * R["dip"] == pytest.approx(load + T * R["dip"], rel=0.02)
        assert tension == pytest.approx(doc["mechanics"]["tendon_EA_N"] / m.tendon_lengthspring[tid[taut]][1]
                                        * stretch[taut], rel=1e-5)     # the XML keeps 6-7 digits
    finally:
        m.opt.disableflags &= ~off


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
    # the session's cache holds the other hands' entries too (hand_export): the default hand's has its text
    entries = [e for e in sorted((cache / "mjcf").glob("*.json"))
               if json.loads(e.read_text())["xml"].encode() == written]
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


#: the mass (kg) of the cylinder the closed hand must hold with the palm facing down
CYLINDER_KG = 0.1


@pytest.fixture(scope="module", params=HANDS)
def cylinder_grasp(request, hand_export, power_grasps):
    """(``cad.grasp.power_grasp`` of a reference hand on the power grasp's cylinder (35 mm at
    189 mm, scaled with the hand; tests/conftest.py), laid against the palm's heel, where the solids
    say every finger reaches past its equator, and the thumb's commands that clear it; the hand's
    MJCF scene), on the solids of the hand's export (each part's BREP from the cache entry its
    manifest names: tests/conftest.py). The palm's heel holds the cylinder: without it the
    fingertips would squeeze it toward the wrist and it would fall out palm down (docs/parts.md)."""
    kind = request.param
    _, g, _ = power_grasps(kind)
    assert g is not None
    return g, hand_export(kind).out_dir / "description" / "mjcf" / "scene.xml"


def test_the_closed_hand_holds_a_cylinder_palm_down(cylinder_grasp):
    """MuJoCo, contacts on (``export.hold.hold_cylinder``): a cylinder (100 g, solid) presented where
    ``cad.grasp`` puts it, the thumb at its commands there (the cylinder's contacts off while the
    thumb turns, gravity off); then every finger servo commanded to the end of its travel for 2 s;
    the cylinder let go (gravity off): the closed fingers move it less than 5 mm (the palm's heel
    holds it on its wrist side); then gravity toward the palm's palmar side (the palm facing down)
    for 3 s: it moves less than 5 mm and has come to rest, no warning, and the palm touches it
    (each hand's figures: docs/parts.md, "Power grasp")."""
    from phantom_cad.export.hold import hold_cylinder
    from phantom_cad.kinematics.topology import SERVOS

    g, scene = cylinder_grasp
    m = mujoco.MjModel.from_xml_path(str(scene))
    # the actuators in u order (each drives its servo's joint), as g.u; gravity along the palm's -z
    assert [_name(m, mujoco.mjtObj.mjOBJ_JOINT, m.actuator_trnid[a, 0]) for a in range(m.nu)] == [s.name for s in SERVOS]
    assert m.opt.gravity == pytest.approx([0.0, 0.0, -9.81])          # the palm frame's -z: palmar
    h = hold_cylinder(scene, g, mass_kg=CYLINDER_KG)
    what = (f"let go, moved {h.released_mm:.1f} mm; then moved {h.moved_mm:.1f} mm palm down; "
            f"servo torques {h.servo_torques.round(3).tolist()}")
    assert h.warnings == {}, what
    assert h.released_mm < 5.0, what              # the closed fingers hold it against the heel
    assert h.moved_mm < 5.0, what
    assert h.speed_mm_s < 10.0, what              # it has come to rest
    assert h.palm_contacts_y_mm, what             # against the palm


def test_a_presented_plate_stops_a_finger_closing_at_servo_speed(hand_export):
    """A rigid object: a 2 mm steel plate presented (welded) 1 mm off the index's pad at 30 % of its
    travel, the index servo then commanded to the end of its travel at its own speed for 1 s. The
    plate stops the finger: touching it, the servo at its stall torque, the finger 20 deg or more
    short of its full-travel MCP angle, no contact deeper than 0.1 mm. (With MuJoCo's default
    contact, a 20 ms time constant, the finger passes through the plate to the end of its travel.)"""
    from phantom_cad import load_hand
    from phantom_cad.export.hold import OBJECT, Trial
    from phantom_cad.kinematics import frames
    from phantom_cad.kinematics.link_frames import link_transforms
    from phantom_cad.kinematics.topology import chain, joint_index

    hand = load_hand()
    p, k, mcp = hand.params, chain("index").servo, joint_index("index", "mcp")
    u = np.zeros(len(hand.u_max))
    u[k] = hand.u_min[k] + 0.3 * (hand.u_max[k] - hand.u_min[k])
    T = link_transforms(p, hand.forward(u, compensated=True))
    pad = T["index_distal"] @ frames.T_distal_pad(p, "index")
    half, side, rho = 0.001, 0.015, 7800.0                       # m, m, kg/m^3
    T_plate = pad.copy()
    T_plate[:3, 3] += pad[:3, 2] * (0.001 + half)                 # its near face 1 mm off the pad

    def build(mj, spec, body):
        body.add_geom(name=OBJECT, type=mj.mjtGeom.mjGEOM_BOX, size=[side, side, half])
        mass = rho * (2 * side) ** 2 * 2 * half
        body.mass, body.explicitinertial = mass, True
        body.inertia = [mass * ((2 * side) ** 2 + (2 * half) ** 2) / 12] * 2 + [mass * 2 * (2 * side) ** 2 / 12]

    t = Trial(hand_export("default").out_dir / "description" / "mjcf" / "scene.xml", T_plate, build, presented=True)
    t.approach({}, 0.2)
    t.close(t.top([k]), 1.0)
    mine = set(int(g) for g in t.geoms)
    depth = max((-c.dist for c in t.d.contact[:t.d.ncon] if (int(c.geom1) in mine) != (int(c.geom2) in mine)),
                default=0.0)
    full = hand.forward(hand.u_max, compensated=True)[mcp]
    what = (f"MCP {math.degrees(t.q()[mcp]):.1f} deg (full travel {math.degrees(full):.1f}), torque "
            f"{t.servo_torques()[k]:.3f} N m, deepest contact {depth * 1000:.2f} mm")
    assert t.touching(), what
    assert t.q()[mcp] < full - math.radians(20.0), what
    assert t.servo_torques()[k] == pytest.approx(t.stall_torques()[k], rel=0.01), what
    assert depth < 1e-4, what
