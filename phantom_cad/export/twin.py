"""The MJCF twin brought to rest: the one settling loop and the one servo sweep that
``phantom-cad check``, the twin-vs-model tests and the twin benchmarks share. ``mujoco`` is passed
in: the caller imports it (only commands that simulate do)."""

from __future__ import annotations

import numpy as np

from ..kinematics.topology import JOINTS, SERVOS

#: the twin is at rest when no joint moves faster than its threshold at this many checks in a row,
#: CHECK_S apart: one sample can fall on a swing's turning point
STILL_CHECKS, CHECK_S = 4, 0.05


def settle(mujoco, m, d, rest: float, seconds: float) -> bool:
    """Step ``d`` until every joint is slower than ``rest`` (rad/s) at :data:`STILL_CHECKS` checks
    :data:`CHECK_S` apart, or for ``seconds`` of simulated time; whether it came to rest."""
    check = max(1, int(CHECK_S / m.opt.timestep))
    still = 0
    for i in range(1, int(seconds / m.opt.timestep)):
        mujoco.mj_step(m, d)
        if i % check == 0:
            still = still + 1 if np.abs(d.qvel).max() < rest else 0
            if still == STILL_CHECKS:
                return True
    return False


def sweep(lo, hi, fractions, together) -> list[np.ndarray]:
    """Servo commands between the ranges' ends ``lo`` and ``hi``: each servo alone at each of
    ``fractions`` of its range (the others at ``lo``), then all of them together at ``together``."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    out = []
    for k in range(len(lo)):
        for f in fractions:
            u = lo.copy()
            u[k] += f * (hi[k] - lo[k])
            out.append(u)
    return out + [lo + f * (hi - lo) for f in together]


def addresses(mujoco, m) -> tuple[list[int], list[int]]:
    """qpos addresses of the 15 joints (topology order) and of the six servo hinges (servo order)."""
    def adr(name: str) -> int:
        return int(m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)])
    return [adr(j.name) for j in JOINTS], [adr(s.name) for s in SERVOS]


#: the plates' contact: a time constant of two simulation steps, critically damped, and an
#: impedance near 1 (as the joint limits', export.mjcf), so a pad sinks into its plate by a fraction
#: of a millimetre at the stall force, not by MuJoCo's default millimetres
PLATE_SOLREF = (0.001, 1.0)
PLATE_SOLIMP = (0.99, 0.999, 0.0005, 0.5, 2.0)
#: the plates' half size (m): a 24 mm square, 4 mm thick
PLATE_HALF = (0.012, 0.012, 0.002)


def press(mujoco, scene: str, u, rest: float = 2e-4, seconds: float = 20.0) -> dict:
    """Each fingertip pressing a plate, as a force gauge would measure it: the twin of ``scene``
    (gravity and every contact off) settled at servo commands ``u`` (6, rad); a box welded to the
    world at each pad (``<digit>_tip``), its face tangent there, that touches only that digit's
    distal link (frictionless: the gauge reads the normal force); then the five tendon servos
    commanded to the end of their travel, servo 6 held, and the twin settled again.

    Returns ``force`` (digit -> the plate's normal force, N, summed over its contacts), ``torque``
    (the six servos' torques, N m), ``stall`` (their stall torques: each actuator's force limit),
    ``q0`` / ``q`` and ``u0`` / ``u`` (the joints and the servo hinges at contact and pressing, topology
    and servo order) and ``rested``."""
    spec = mujoco.MjSpec.from_file(str(scene))
    spec.option.gravity = [0.0, 0.0, 0.0]
    m = spec.compile()
    collides = (m.geom_contype != 0) | (m.geom_conaffinity != 0)
    for g in spec.geoms:
        g.contype, g.conaffinity = 0, 0
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    d.ctrl[:] = u
    rested = settle(mujoco, m, d, rest, seconds)
    q_adr, u_adr = addresses(mujoco, m)
    q0, u0 = d.qpos[q_adr].copy(), d.qpos[u_adr].copy()
    digits = [s.digit for s in SERVOS if s.drive == "tendon"]
    for bit, digit in enumerate(digits):
        site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, f"{digit}_tip")
        R = d.site_xmat[site].reshape(3, 3)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, R.reshape(9))
        spec.worldbody.add_geom(name=f"{digit}_plate", type=mujoco.mjtGeom.mjGEOM_BOX, size=list(PLATE_HALF),
                                pos=list(d.site_xpos[site] + R[:, 2] * PLATE_HALF[2]), quat=list(quat),
                                contype=1 << bit, conaffinity=0, condim=1, solref=list(PLATE_SOLREF),
                                solimp=list(PLATE_SOLIMP))
        body = m.site_bodyid[site]
        for g in np.flatnonzero((m.geom_bodyid == body) & collides):
            geom = spec.geom(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, int(g)))
            geom.contype, geom.conaffinity, geom.condim = 0, 1 << bit, 1
    qpos, qvel = d.qpos.copy(), d.qvel.copy()
    m = spec.compile()
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = qpos, qvel
    push = np.array(u, dtype=float)
    tendon = [s.index for s in SERVOS if s.drive == "tendon"]
    push[tendon] = m.actuator_ctrlrange[tendon, 1]
    d.ctrl[:] = push
    rested = settle(mujoco, m, d, rest, seconds) and rested
    plates = {mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"{digit}_plate"): digit for digit in digits}
    force = dict.fromkeys(digits, 0.0)
    f6 = np.zeros(6)
    for i in range(d.ncon):
        c = d.contact[i]
        digit = plates.get(int(c.geom1), plates.get(int(c.geom2)))
        if digit is not None:
            mujoco.mj_contactForce(m, d, i, f6)
            force[digit] += float(f6[0])
    return {"force": force, "torque": d.actuator_force.copy(), "stall": m.actuator_forcerange[:, 1].copy(),
            "q0": q0, "q": d.qpos[q_adr].copy(), "u0": u0, "u": d.qpos[u_adr].copy(), "rested": rested}
