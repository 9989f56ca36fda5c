"""The format-neutral robot model between the parts and the description writers (URDF, ...).

One ``RobotModel`` per build: links with their inertials and meshes, joints with origins, axes,
limits, efforts, velocities and mimic couplings, and the massless fingertip frames. It is made
from the topology (``kinematics.topology``), the frames the parts were modelled in
(``kinematics.frames``), each part's mass properties measured on its solid (the part cache's
meta) and, where known, the slicer's mass estimate. The writers only format it.

Conventions (SI, link frames as in docs/frames.md):
* the 15 revolute joints keep the names of the topology (``index_mcp``, ..., ``thumb_cmc``);
  fixed mounts are ``<child>_joint``;
* a coupled joint (PIP, DIP, thumb IP) mimics its chain's reference joint (MCP, thumb MP) with
  the analytic multiplier of eq. (2), R_ref / R_i; never a mimic of a mimic;
* effort: the servo's stall torque through the tendon (tension tau / r_j times the joint's
  pulley radius R_i), or tau / g for the directly driven CMC; velocity: the servo's no-load
  speed times the largest dq/du over the travel (eq. 6; times the multiplier for a coupled joint),
  or g times the speed for the CMC;
* inertials: mass from the slicer estimate when the build sliced the part, else volume x density
  x infill; the tensor is the solid's (uniform density) scaled to that mass, about the centre of
  mass, in the link frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from ..kinematics import closed_form as cf
from ..kinematics import link_frames as LF
from ..kinematics import routing
from ..kinematics import routing_paths
from ..kinematics.hand_params import ChainParams, HandParams, Print
from ..kinematics.topology import CHAINS, CMC_PULLEY, CMC_Q, JOINTS, LINK_NAMES, LINKS, SERVOS
from .manifest import mass_g

#: dense grid of the servo travel on which the largest joint rate is taken
RATE_SAMPLES = 2001


@dataclass(frozen=True)
class Inertial:
    mass: float                  # kg
    com: tuple[float, float, float]          # m, link frame
    inertia: tuple[float, ...]   # ixx, ixy, ixz, iyy, iyz, izz about the centre of mass, kg m^2
    source: str                  # "slicer" or "volume x density x infill"


@dataclass(frozen=True)
class RobotLink:
    name: str
    inertial: Inertial | None    # None: a massless frame
    mesh: str | None             # visual mesh file stem (the part name), None for a frame
    color: tuple[float, float, float] = (0.7, 0.7, 0.7)
    collision: tuple[str, ...] = ()          # collision mesh file stems (convex pieces)


def collision_stems(stem: str, n: int) -> tuple[str, ...]:
    """File stems of a link's collision meshes: ``palm`` for one hull, ``palm_0``.. for pieces."""
    return (stem,) if n == 1 else tuple(f"{stem}_{k}" for k in range(n))


@dataclass(frozen=True)
class Mimic:
    joint: str
    multiplier: float
    offset: float = 0.0


@dataclass(frozen=True)
class RobotJoint:
    name: str
    type: str                    # "revolute" or "fixed"
    parent: str
    child: str
    origin: np.ndarray           # 4x4 T_parent_child at q = 0, metres
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    lower: float = 0.0
    upper: float = 0.0
    effort: float = 0.0          # N m
    velocity: float = 0.0        # rad/s
    mimic: Mimic | None = None


@dataclass(frozen=True)
class ServoDrive:
    """A tendon servo: its pulley (link ``link``) turns on a hinge ``joint`` about ``axis`` (its own
    frame); the angle u winds the digit's drive tendon (``kinematics.routing``) onto it."""
    actuator: str                # "servo1", ...
    servo: str                   # topology name ("index_flexion", ...): also the hinge's name
    link: str                    # the servo pulley link
    axis: tuple[float, float, float]
    travel: tuple[float, float]  # servo travel, rad
    torque: float                # stall torque, N m
    stiffness: float             # position gain, N m / rad of servo angle
    damping: float               # N m s / rad: stall torque / no-load speed (the motor's line)
    armature: float              # inertia on the hinge, kg m^2: kv^2 / (4 kp), the position loop
                                 # critically damped (a hobby servo does not ring after a step)

    @property
    def joint(self) -> str:
        return self.servo


@dataclass(frozen=True)
class Strand:
    """One strand of a routed tendon (``kinematics.routing``) as the simulator models it: a cord
    through its path elements that pulls (never pushes) with ``stiffness`` once longer than
    ``spring_length``: its ``rest_length``, or for a coupling loop's strand tied with the file's
    loop preload P, rest_length (1 - P / EA), so that it pulls with P at rest."""
    name: str
    tendon: str                  # the topology tendon ("index_mcp_pip", ...)
    kind: str                    # "drive", "coupling", "return"
    elements: tuple              # routing.Point / routing.Pulley, link frames (mirrored for a left hand)
    sides: tuple                 # per element: None, or (link, pos) of the pulley's side site
    rest_length: float           # m: the routed length at rest (q = 0, u = 0)
    stiffness: float             # N/m: EA / rest length for a tendon, k_s for the return cord
    damping: float               # N s/m
    spring_length: float | None = None     # m: where it starts to pull, when not rest_length

    @property
    def slack_length(self) -> float:
        """Where the strand starts to pull (m)."""
        return self.rest_length if self.spring_length is None else self.spring_length


@dataclass(frozen=True)
class RobotModel:
    name: str                    # the hand's name (the robot's name in the descriptions)
    side: str
    links: tuple[RobotLink, ...]
    joints: tuple[RobotJoint, ...]
    drives: tuple[ServoDrive, ...] = ()     # servo order
    strands: tuple[Strand, ...] = ()                     # every routed tendon strand
    #: pairs of links in contact by design (a joint, a mount): no collision between them
    adjacent: tuple[tuple[str, str], ...] = ()


def inertial(meta: dict, printing: Print, estimate: dict | None = None) -> Inertial:
    """The inertial of a part from its measured mass properties (``meta["mass_properties"]``:
    volume mm^3, centre of mass mm, tensor about it in mm^5 at unit density)."""
    mp = meta["mass_properties"]
    volume = float(mp["volume_mm3"])
    if estimate and estimate.get("filament_g"):
        grams, source = float(estimate["filament_g"]), "slicer"
    else:
        grams, source = mass_g(volume, printing), "volume x density x infill"
    mass = grams * units.KG_PER_G
    density = mass / volume                                  # kg / mm^3
    I = np.asarray(mp["inertia_mm5"], float) * density * units.MM ** 2     # kg m^2
    I = (I + I.T) / 2.0
    com = tuple(float(v) * units.MM for v in mp["com_mm"])
    return Inertial(mass, com, (I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2]), source)


def _max_rate(chain: ChainParams) -> float:
    """The largest dq_ref/du over the chain's servo travel (eq. 6), on a dense grid."""
    u = np.linspace(chain.travel[0], chain.travel[1], RATE_SAMPLES)
    g = chain.guide
    return float(np.max(np.abs(cf.reference_angle_rate(u, g.d1, g.d2, g.alpha, chain.servo_radius))))


def _drives(params: HandParams) -> dict[str, tuple[float, float, Mimic | None]]:
    """joint name -> (effort N m, velocity rad/s, mimic) of the 15 actuated joints."""
    tau, speed = params.servo.stall_torque, params.servo.speed
    out = {}
    for spec, chain in zip(CHAINS, params.chains):
        tension = tau / chain.servo_radius
        rate = _max_rate(chain)
        A = cf.ideal_coupling(chain.radii)
        ref = spec.joint_names[0]
        for k, (name, R) in enumerate(zip(spec.joint_names, chain.radii)):
            mimic = None if k == 0 else Mimic(ref, float(A[k]))
            out[name] = (tension * R, speed * rate * float(A[k]), mimic)
    g = params.thumb.cmc_gain
    out[JOINTS[CMC_Q].name] = (tau / g, speed * g, None)
    return out


#: a strand's damping is its stiffness times this time constant (s): a few simulation steps
STRAND_TAU = 0.002


def transmissions(params: HandParams) -> tuple[tuple[ServoDrive, ...], tuple[Strand, ...]]:
    """The six servo drives (servo order) and every routed tendon strand, from the topology's
    servos, the routing model and the parameters."""
    tau, speed = params.servo.stall_torque, params.servo.speed
    kp, kv = tau / params.servo.stall_error, tau / speed
    drives = []
    for servo in SERVOS:
        # every servo turns its pulley: a drive's tendon, or (servo 6) the CMC's closed loop
        travel = params.thumb.cmc_travel if servo.drive == "loop" else params.digit(servo.digit).chain.travel
        drives.append(ServoDrive(servo.actuator, servo.name, servo.link,
                                 tuple(float(v) for v in routing_paths.servo_axis(params)), travel, tau, kp, kv,
                                 kv * kv / (4.0 * kp)))
    rest = routing_paths.lengths(params)
    mid = routing_paths.mid_travel_pose(params)
    strands = []
    for r in routing.routes(params):
        for st in r.strands:
            L = rest[st.name]
            k = params.mechanics.spring_k if r.stiffness == "k_s" else params.mechanics.tendon_EA / L
            P = params.mechanics.loop_preload
            # a preloaded loop's strands are tied short by their stretch under P
            spring = L - P * L / params.mechanics.tendon_EA if (P > 0.0 and r.tendon.kind == "coupling") else None
            strands.append(Strand(st.name, r.name, r.tendon.kind, st.elements,
                                  tuple(routing_paths.side_sites(params, st, mid)), L, k, k * STRAND_TAU, spring))
    return tuple(drives), tuple(strands)


def _joints(params: HandParams, tips: dict[str, tuple[str, np.ndarray]]) -> list[RobotJoint]:
    """The joints of the tree, in the order of its links (topology order, then the fingertip frames):
    the 15 revolute joints with their drives, the fixed mounts and the tip frames' fixed joints."""
    rest = LF.link_transforms(params, None)              # T_palm_link, mirrored for a left hand
    revolute = {j["name"]: j for j in LF.joints(params)}
    drives = _drives(params)
    joints = []
    for ln in LINKS[1:]:
        if ln.parent_joint is not None:
            j = revolute[ln.parent_joint]
            effort, velocity, mimic = drives[j["name"]]
            joints.append(RobotJoint(j["name"], "revolute", j["parent"], j["child"], np.asarray(j["origin"], float),
                                     tuple(float(a) for a in j["axis"]), *j["limits"], effort, velocity, mimic))
        else:
            parent = ln.parent
            origin = np.linalg.inv(rest[parent]) @ rest[ln.name]
            joints.append(RobotJoint(f"{ln.name}_joint", "fixed", parent, ln.name, origin))
    for frame, (parent, T) in tips.items():
        joints.append(RobotJoint(f"{frame}_joint", "fixed", parent, frame, np.asarray(T, float)))
    return joints


def robot_model(params: HandParams, metas: dict[str, dict], tips: dict[str, tuple[str, np.ndarray]],
                estimates: dict[str, dict | None] | None = None) -> RobotModel:
    """The robot model of a built hand: ``metas`` the part metas (by link name), ``tips`` the
    fingertip frames (``assembly.tip_frames``), ``estimates`` the slicer's per-part estimates."""
    estimates = estimates or {}
    links = [RobotLink(ln.name, inertial(metas[ln.name], params.print, estimates.get(ln.name)), ln.name,
                       tuple(float(c) for c in metas[ln.name]["color"]),
                       collision_stems(ln.name, int(metas[ln.name]["collision_pieces"])))
             for ln in LINKS]
    links += [RobotLink(frame, None, None) for frame in tips]
    joints = _joints(params, tips)
    drives, strands = transmissions(params)
    adjacent = [(j.parent, j.child) for j in joints if j.type == "revolute" or j.child in LINK_NAMES]
    # the CMC pulley turns inside the palm's cavity (within the palm's collision solids)
    adjacent.append((JOINTS[CMC_Q].parent, CMC_PULLEY))
    return RobotModel(params.name, params.side, tuple(links), tuple(joints), drives, strands, tuple(adjacent))


def kinematic_model(params: HandParams, tips: dict[str, tuple[str, np.ndarray]]) -> RobotModel:
    """The robot model's kinematic tree alone, made without building a part: the same links,
    joints (origins, axes, limits, mimics) and fingertip frames as :func:`robot_model`'s, no
    inertial, mesh or transmission (what retargeting's URDF needs)."""
    links = tuple(RobotLink(name, None, None) for name in (*LINK_NAMES, *tips))
    return RobotModel(params.name, params.side, links, tuple(_joints(params, tips)))
