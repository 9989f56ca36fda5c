"""The closed hand holding a cylinder, simulated by MuJoCo on an export's MJCF scene (docs/parts.md,
"Power grasp").

The procedure, as a user would run it on the printed hand: a free solid cylinder lies where
``cad.grasp.power_grasp`` puts it (its axis along the palm frame's x); the thumb turns to its
commands there (the cylinder's contacts off, gravity off, 1 s); every finger servo is commanded to
the end of its travel (2 s); then gravity comes on toward the palm's palmar side (the scene's -z:
the palm facing down, 3 s). :func:`hold_cylinder` reports what MuJoCo did; what counts as held is
the caller's (tests/export/test_mjcf.py). MuJoCo is imported inside.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import units
from ..kinematics.topology import CMC_SERVO, JOINTS, SERVOS, THUMB_CHAIN, chain, FINGERS

#: the simulated phases (s): the thumb turning, the fingers closing, the palm facing down
THUMB_S, CLOSE_S, HOLD_S = 1.0, 2.0, 3.0


@dataclass(frozen=True)
class Hold:
    """What MuJoCo did with a cylinder in the closing hand (palm frame: mm, rad)."""
    diameter_mm: float
    mass_kg: float
    start_mm: np.ndarray            # the cylinder's centre when the fingers start closing
    closed_mm: np.ndarray           # ... when gravity comes on
    end_mm: np.ndarray              # ... at the end
    speed_mm_s: float               # its linear speed at the end
    warnings: dict                  # MuJoCo's warnings raised during the run: {name: count}
    palm_contacts_y_mm: tuple       # y of every contact between the palm and the cylinder at the end
    servo_torques: np.ndarray       # N m, one per servo (topology order)
    q: np.ndarray                   # the 15 joint angles at the end (topology order)
    T_start: np.ndarray             # 4x4 pose of the cylinder where it was put (its axis along its z)
    T_cylinder: np.ndarray          # ... at the end
    gravity: np.ndarray             # the scene's gravity in the hold phase (m/s^2)

    @property
    def squeezed_mm(self) -> float:
        """How far the closing fingers moved the cylinder."""
        return float(np.linalg.norm(self.closed_mm - self.start_mm))

    @property
    def moved_mm(self) -> float:
        """How far it moved with the palm facing down."""
        return float(np.linalg.norm(self.end_mm - self.closed_mm))


def hold_cylinder(scene: str | Path, grasp, mass_kg: float = 0.1) -> Hold:
    """Simulate the closed hand of ``scene`` (an export's ``description/mjcf/scene.xml``) on the
    cylinder of ``grasp`` (``cad.grasp.CylinderGrasp``), a solid of ``mass_kg``."""
    import mujoco

    g = grasp
    spec = mujoco.MjSpec.from_file(str(scene))
    r, length = units.m(g.diameter_mm / 2.0), units.m(g.x_mm[1] - g.x_mm[0])
    body = spec.worldbody.add_body(name="cylinder", pos=[units.m((g.x_mm[0] + g.x_mm[1]) / 2.0), units.m(g.axis_y_mm),
                                                         units.m(g.axis_z_mm)],
                                   quat=[math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0])   # z -> x
    body.add_freejoint(name="cylinder")
    body.add_geom(name="cylinder", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[r, length / 2, 0.0])
    # a solid cylinder: I_axis = m r^2 / 2, across it m (3 r^2 + l^2) / 12
    body.mass, body.explicitinertial = mass_kg, True
    body.inertia = [mass_kg * (3 * r * r + length * length) / 12] * 2 + [mass_kg * r * r / 2]
    m = spec.compile()
    d = mujoco.MjData(m)

    def pose(b: int) -> np.ndarray:
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = d.xmat[b].reshape(3, 3), units.mm(d.xpos[b])
        return T

    gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "cylinder")
    bid = int(m.geom_bodyid[gid])
    contype, conaffinity = int(m.geom_contype[gid]), int(m.geom_conaffinity[gid])
    gravity = m.opt.gravity.copy()
    act = {s.index: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, s.actuator) for s in SERVOS}
    fingers = [act[chain(f).servo] for f in FINGERS]

    def run(seconds: float) -> None:
        for _ in range(int(seconds / m.opt.timestep)):
            mujoco.mj_step(m, d)

    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_kinematics(m, d)
    T_start = pose(bid)
    d.ctrl[:] = 0.0
    m.geom_contype[gid] = m.geom_conaffinity[gid] = 0
    m.opt.gravity[:] = 0.0
    for k in (THUMB_CHAIN.servo, CMC_SERVO):
        d.ctrl[act[k]] = g.u[k]
    run(THUMB_S)
    start = d.xpos[bid].copy()
    m.geom_contype[gid], m.geom_conaffinity[gid] = contype, conaffinity
    d.ctrl[fingers] = m.actuator_ctrlrange[fingers, 1]
    run(CLOSE_S)
    closed = d.xpos[bid].copy()
    m.opt.gravity[:] = gravity
    run(HOLD_S)
    free = m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "cylinder")]
    palm = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "palm")
    contacts = tuple(units.mm(float(c.pos[1])) for c in d.contact[:d.ncon]
                     if gid in (c.geom1, c.geom2) and palm in (m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2]))
    q = np.array([d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j.name)]] for j in JOINTS])
    return Hold(diameter_mm=g.diameter_mm, mass_kg=mass_kg, start_mm=units.mm(start), closed_mm=units.mm(closed),
                end_mm=units.mm(d.xpos[bid]), speed_mm_s=units.mm(float(np.linalg.norm(d.qvel[free:free + 3]))),
                warnings={mujoco.mjtWarning(i).name: int(d.warning[i].number) for i in range(len(d.warning))
                          if d.warning[i].number},
                palm_contacts_y_mm=contacts,
                servo_torques=np.array([d.actuator_force[act[s.index]] for s in SERVOS]),
                q=q, T_start=T_start, T_cylinder=pose(bid), gravity=gravity)
