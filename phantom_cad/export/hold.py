"""A closing hand and a free object, simulated by MuJoCo on an export's MJCF scene: the one
procedure behind the power grasp's hold (:func:`hold_cylinder`; docs/parts.md, "Power grasp") and
the grasp library (``export.grasps``; docs/grasps.md).

The procedure, as a user would run it on the printed hand (:class:`Trial`): a free object is put
where the grasp says (a pose in the palm frame, which is the scene's world frame); the hand takes
its approach commands with the object's contacts off and gravity off (the hand moves into place
around it); the object's contacts come on and the hand takes its closing commands; then gravity
comes on. The object is rigid: its contacts with the hand take the stiffest time constant the
integrator resolves (:data:`OBJECT_SOLREF_STEPS`). MuJoCo is imported inside.

:func:`hold_cylinder`: a solid cylinder is presented where ``cad.grasp.power_grasp`` puts it (its
axis along the palm frame's x), as a user hands it over and as the grasp library presents its
objects; the thumb turns to its commands there (1 s); every finger servo is commanded to the end
of its travel (2 s); the cylinder is let go (gravity off, 0.5 s: where the closed fingers and the
palm put it); then gravity comes on toward the palm's palmar side (the scene's -z: the palm facing
down, 3 s). It reports what MuJoCo did; what counts as held is :meth:`Hold.problems`
(tests/export/test_mjcf.py, ``export.check``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import units
from ..kinematics.topology import CMC_SERVO, JOINTS, SERVOS, THUMB_CHAIN, chain, FINGERS

#: the simulated phases (s): the thumb turning, the fingers closing, the cylinder let go, the palm
#: facing down
THUMB_S, CLOSE_S, RELEASE_S, HOLD_S = 1.0, 2.0, 0.5, 3.0
#: the weld that holds a presented object: a time constant of four steps, critically damped (MuJoCo's
#: default, 20 ms, lets a closing digit knock it centimetres away)
PRESENTED_SOLREF = (0.002, 1.0)
#: the free object's contacts with the hand (MuJoCo's solref, in the scene's time steps): a rigid
#: object, as stiff as the integrator resolves (a time constant of two steps, critically damped).
#: Its geoms take priority over the hand's, so this governs. MuJoCo's default time constant, 20 ms,
#: lets a digit closing at servo speed sink up to 12 mm into an object and pass through a 2 mm plate
#: (docs/grasps.md, "Contacts").
OBJECT_SOLREF_STEPS = 2.0
#: the free object's body, joint and (first) geom name in the scene
OBJECT = "object"
#: the cylinder the closed hand holds palm down (kg), and what counts as held: let go, the closed
#: fingers move it less than RELEASED_MM (the palm's heel holds it on its wrist side), palm down it
#: moves less than MOVED_MM and ends slower than RESTING_MM_S, no warning, the palm touching it
HOLD_KG = 0.1
RELEASED_MM, MOVED_MM, RESTING_MM_S = 5.0, 5.0, 10.0


class Trial:
    """The scene of ``scene`` (an export's ``description/mjcf/scene.xml``) with a free body at
    ``T_object`` (4x4, metres, the world = palm frame) whose geoms ``build(mujoco, spec, body)`` adds,
    stepped phase by phase; ``presented``: the object is held where it was put (as a user hands it
    over) until :meth:`release`. The servos are addressed in servo (topology) order."""

    def __init__(self, scene: str | Path, T_object: np.ndarray, build, presented: bool = False):
        import mujoco

        self.mj = mujoco
        spec = mujoco.MjSpec.from_file(str(scene))
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(T_object[:3, :3]).reshape(9))
        body = spec.worldbody.add_body(name=OBJECT, pos=list(T_object[:3, 3]), quat=list(quat))
        body.add_freejoint(name=OBJECT)
        build(mujoco, spec, body)
        for g in body.geoms:
            g.priority = 1
            g.solref = [OBJECT_SOLREF_STEPS * spec.option.timestep, 1.0]
        if presented:       # held where it was put (welded to the world) until :meth:`release`
            spec.add_equality(name=OBJECT, type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_BODY,
                              name1=OBJECT, data=[0.0] * 10 + [1.0, 0.0],   # anchor 0; relpose from the start
                              solref=list(PRESENTED_SOLREF))
        m = self.m = spec.compile()
        self.d = mujoco.MjData(m)
        self.body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, OBJECT)
        self.geoms = np.flatnonzero(m.geom_bodyid == self.body)
        self.contype = m.geom_contype[self.geoms].copy()
        self.conaffinity = m.geom_conaffinity[self.geoms].copy()
        self.gravity = m.opt.gravity.copy()
        self.act = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, s.actuator) for s in SERVOS]
        self.free = int(m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, OBJECT)])
        mujoco.mj_resetDataKeyframe(m, self.d, 0)
        mujoco.mj_kinematics(m, self.d)
        self.T_start = self.pose()

    def run(self, seconds: float) -> None:
        for _ in range(int(seconds / self.m.opt.timestep)):
            self.mj.mj_step(self.m, self.d)

    def command(self, u: dict) -> None:
        """Servo commands {servo index: rad}; the others' stay as they are."""
        for k, v in u.items():
            self.d.ctrl[self.act[k]] = v

    def top(self, servos) -> dict:
        """{servo: the end of its travel} for the servos given (their actuators' upper control limit)."""
        return {k: float(self.m.actuator_ctrlrange[self.act[k], 1]) for k in servos}

    def approach(self, u: dict, seconds: float) -> None:
        """Every other servo at 0, these at their commands, the object's contacts and gravity off."""
        self.d.ctrl[:] = 0.0
        self.m.geom_contype[self.geoms] = 0
        self.m.geom_conaffinity[self.geoms] = 0
        self.m.opt.gravity[:] = 0.0
        self.command(u)
        self.run(seconds)

    def close(self, u: dict, seconds: float) -> None:
        """The object's contacts on, then the closing commands."""
        self.m.geom_contype[self.geoms] = self.contype
        self.m.geom_conaffinity[self.geoms] = self.conaffinity
        self.command(u)
        self.run(seconds)

    def release(self) -> None:
        """Let go of a presented object."""
        self.d.eq_active[self.mj.mj_name2id(self.m, self.mj.mjtObj.mjOBJ_EQUALITY, OBJECT)] = 0

    def hold(self, gravity, seconds: float) -> None:
        self.m.opt.gravity[:] = gravity
        self.run(seconds)

    def save(self):
        d = self.mj.MjData(self.m)
        self.mj.mj_copyData(d, self.m, self.d)
        return d

    def restore(self, saved) -> None:
        self.mj.mj_copyData(self.d, self.m, saved)

    # -- what the scene is doing ---------------------------------------------------------------
    def pose(self) -> np.ndarray:
        """The object's pose (4x4, mm)."""
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = self.d.xmat[self.body].reshape(3, 3), units.mm(self.d.xpos[self.body])
        return T

    def position_mm(self) -> np.ndarray:
        return units.mm(self.d.xpos[self.body].copy())

    def speed_mm_s(self) -> float:
        return units.mm(float(np.linalg.norm(self.d.qvel[self.free:self.free + 3])))

    def touching(self) -> list[tuple[int, np.ndarray]]:
        """(the hand's body, contact point in mm) of every contact of the object with the hand."""
        m, out = self.m, []
        mine = set(int(g) for g in self.geoms)
        for c in self.d.contact[:self.d.ncon]:
            g1, g2 = int(c.geom1), int(c.geom2)
            if (g1 in mine) == (g2 in mine):
                continue
            other = int(m.geom_bodyid[g2 if g1 in mine else g1])
            if other != 0:                       # the world's geoms (the floor) are not the hand
                out.append((other, units.mm(c.pos.copy())))
        return out

    def warnings(self) -> dict:
        return {self.mj.mjtWarning(i).name: int(self.d.warning[i].number) for i in range(len(self.d.warning))
                if self.d.warning[i].number}

    def servo_torques(self) -> np.ndarray:
        """N m, one per servo (topology order)."""
        return np.array([self.d.actuator_force[a] for a in self.act])

    def stall_torques(self) -> np.ndarray:
        """Each servo's stall torque (its actuator's force limit), N m."""
        return np.array([self.m.actuator_forcerange[a, 1] for a in self.act])

    def q(self) -> np.ndarray:
        m, mj = self.m, self.mj
        return np.array([self.d.qpos[m.jnt_qposadr[mj.mj_name2id(m, mj.mjtObj.mjOBJ_JOINT, j.name)]] for j in JOINTS])


@dataclass(frozen=True)
class Hold:
    """What MuJoCo did with a cylinder in the closing hand (palm frame: mm, rad)."""
    diameter_mm: float
    mass_kg: float
    start_mm: np.ndarray            # the cylinder's centre where it was presented
    closed_mm: np.ndarray           # ... let go in the closed hand, when gravity comes on
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
    def released_mm(self) -> float:
        """How far the closed fingers moved the cylinder when it was let go."""
        return float(np.linalg.norm(self.closed_mm - self.start_mm))

    @property
    def moved_mm(self) -> float:
        """How far it moved with the palm facing down."""
        return float(np.linalg.norm(self.end_mm - self.closed_mm))

    def problems(self) -> list[str]:
        """Why the cylinder does not count as held (empty: held; the limits above)."""
        out = [f"{k} x{n}" for k, n in self.warnings.items()]
        if self.released_mm >= RELEASED_MM:
            out.append(f"let go, moved {self.released_mm:.1f} mm >= {RELEASED_MM:g}")
        if self.moved_mm >= MOVED_MM:
            out.append(f"moved {self.moved_mm:.1f} mm >= {MOVED_MM:g} palm down")
        if self.speed_mm_s >= RESTING_MM_S:
            out.append(f"still moving at {self.speed_mm_s:.1f} mm/s")
        if not self.palm_contacts_y_mm:
            out.append("the palm does not touch it")
        return out


def hold_cylinder(scene: str | Path, grasp, mass_kg: float = HOLD_KG) -> Hold:
    """Simulate the closed hand of ``scene`` (an export's ``description/mjcf/scene.xml``) on the
    cylinder of ``grasp`` (``cad.grasp.CylinderGrasp``), a solid of ``mass_kg``."""
    g = grasp
    r, length = units.m(g.diameter_mm / 2.0), units.m(g.x_mm[1] - g.x_mm[0])
    T = np.eye(4)
    T[:3, :3] = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]          # its axis (z) along x
    T[:3, 3] = units.m((g.x_mm[0] + g.x_mm[1]) / 2.0), units.m(g.axis_y_mm), units.m(g.axis_z_mm)

    def build(mujoco, spec, body):
        body.add_geom(name=OBJECT, type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[r, length / 2, 0.0])
        # a solid cylinder: I_axis = m r^2 / 2, across it m (3 r^2 + l^2) / 12
        body.mass, body.explicitinertial = mass_kg, True
        body.inertia = [mass_kg * (3 * r * r + length * length) / 12] * 2 + [mass_kg * r * r / 2]

    t = Trial(scene, T, build, presented=True)
    t.approach({k: g.u[k] for k in (THUMB_CHAIN.servo, CMC_SERVO)}, THUMB_S)
    start = t.position_mm()
    t.close(t.top([chain(f).servo for f in FINGERS]), CLOSE_S)
    t.release()
    t.run(RELEASE_S)
    closed = t.position_mm()
    t.hold(t.gravity, HOLD_S)
    palm = t.mj.mj_name2id(t.m, t.mj.mjtObj.mjOBJ_BODY, "palm")
    return Hold(diameter_mm=g.diameter_mm, mass_kg=mass_kg, start_mm=start, closed_mm=closed,
                end_mm=t.position_mm(), speed_mm_s=t.speed_mm_s(), warnings=t.warnings(),
                palm_contacts_y_mm=tuple(float(p[1]) for b, p in t.touching() if b == palm),
                servo_torques=t.servo_torques(), q=t.q(), T_start=t.T_start, T_cylinder=t.pose(),
                gravity=t.gravity)
