"""Link frames of the hand: where every part sits, at rest and posed. numpy only.

Units: metres (SI, like the parameter object). The CAD layer converts to millimetres once
(:func:`to_mm`, through :mod:`phantom_cad.units`). Every link, joint and servo comes from
:mod:`phantom_cad.kinematics.topology`. Conventions (docs/frames.md):

* Palm (hand) frame, right hand: origin on the index MCP axis, centre of the index finger;
  x toward the ulnar side (index -> pinky), y distal (wrist -> fingers), z = x cross y,
  dorsal (back of the hand).
* A finger link frame has its origin on the link's proximal joint axis, centre of the
  finger's width; at rest its axes are those of the finger column: x along the joint
  axes (ulnar), y along the link (distal), z dorsal. Flexion q >= 0 is a rotation by q
  about -x (URDF axis "-1 0 0"): the distal end moves palmar (-z).
* A finger base has no proximal joint (it is fixed to the palm by magnets); its origin is
  on its distal (MCP) axis, so T_index_base_index_proximal(0) is the identity.
* Finger columns fan out on an arc: finger i (index 0 .. pinky 3) points along
  Rz(-phi_i) y with phi_i = (i - 1.5) arc_offset; adjacent columns are finger_pitch apart
  on the arc of radius palm.arc_radius whose centre lies proximal of the MCPs.
* The metacarpal heads are stepped (the paper's stepped knuckle line): each MCP sits
  metacarpal_i - metacarpal_index further along its column than the arc, as if the
  metacarpals' bases sat on the arc and their heads ended at their own lengths
  (fingers.<f>.length_fraction.metacarpal). The index MCP stays at the origin.
* Thumb: the CMC base frame sits at palm.thumb_cmc_offset (from the index MCP, palm
  frame) turned by R = Rz(yaw) Ry(pitch) Rx(roll) of palm.thumb_cmc_axis; the CMC joint
  axis is its z (q15 rotates about +z: abduction toward opposition); MP and IP flex about
  -x like the fingers.
* Servo frames: origin on the output shaft at the pulley mid-plane, z along the shaft
  from the servo body toward the pulley, y along the body length (the body lies toward
  -y of the shaft by cad.servo_shaft_offset).
* Left hand: every transform is conjugated by the mirror S = diag(-1, 1, 1): the left
  hand is the mirror image of the right in the palm's y-z plane, and each link's shape is
  mirrored in its own y-z plane, so T stays a proper rigid transform.
"""

from __future__ import annotations

import math

import numpy as np

from .. import units
from ..params.rules import finger_columns, slot_back
from .topology import CMC_Q, FINGERS, JOINTS, LINKS, N_JOINTS, SERVOS, chain, joint, link, servo_joints

MIRROR = np.diag([-1.0, 1.0, 1.0, 1.0])


# ---------------------------------------------------------------------------
# elementary transforms
# ---------------------------------------------------------------------------

def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]], float)


def rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1]], float)


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], float)


def trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def flex(q: float) -> np.ndarray:
    """A flexion joint: rotation by q about -x."""
    return rot_x(-q)


def to_mm(T: np.ndarray) -> np.ndarray:
    """The same rigid transform with its translation in millimetres."""
    out = np.array(T, float)
    out[:3, 3] = units.mm(out[:3, 3])
    return out


def from_mm(T: np.ndarray) -> np.ndarray:
    """The same rigid transform with its translation in metres (from millimetres)."""
    out = np.array(T, float)
    out[:3, 3] = units.m(out[:3, 3])
    return out


def mirror(T: np.ndarray) -> np.ndarray:
    """The left-hand counterpart of a right-hand transform (S T S)."""
    return MIRROR @ T @ MIRROR


# ---------------------------------------------------------------------------
# the hand's frames
# ---------------------------------------------------------------------------

def finger_angle(params, i: int) -> float:
    """phi_i: rotation of finger column i (0 = index) about -z, symmetric about the middle of the arc."""
    return (i - (len(FINGERS) - 1) / 2.0) * params.palm.arc_offset


def finger_direction(params, i: int) -> np.ndarray:
    phi = finger_angle(params, i)
    return np.array([math.sin(phi), math.cos(phi), 0.0])


def mcp_position(params, i: int) -> np.ndarray:
    """MCP axis centre of finger i in the palm frame (index at the origin): on the palm arc,
    stepped along its column by its metacarpal's length less the index's
    (``params.rules.finger_columns``)."""
    x, y, _ = finger_columns(params.palm.finger_pitch, params.palm.arc_offset,
                             [params.fingers[f].metacarpal for f in FINGERS])[i]
    return np.array([x, y, 0.0])


def T_palm_finger_base(params, finger: str) -> np.ndarray:
    i = FINGERS.index(finger)
    T = rot_z(-finger_angle(params, i))
    T[:3, 3] = mcp_position(params, i)
    return T


def T_palm_socket(params, finger: str) -> np.ndarray:
    """The palm's finger socket: origin at the centre of the magnet face, y its outward normal."""
    return T_palm_finger_base(params, finger) @ trans(0.0, -params.cad.finger_base_length, 0.0)


def thumb_cmc_placement(offset, axis) -> np.ndarray:
    """T_palm_cmc_base at q15 = 0 for a CMC centre ``offset`` (m, palm frame) and ``axis`` =
    (roll, pitch, yaw) (rad): R = Rz(yaw) Ry(pitch) Rx(roll); the CMC axis is the frame's z."""
    roll, pitch, yaw = axis
    T = rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)
    T[:3, 3] = offset
    return T


def T_palm_thumb_cmc_base(params, q15: float = 0.0) -> np.ndarray:
    return thumb_cmc_placement(params.palm.thumb_cmc_offset, params.palm.thumb_cmc_axis) @ rot_z(q15)


def tendon_height(params) -> float:
    """z of every finger tendon where it crosses the magnet face (palm and finger base):
    one wall above the palmar face of the thinnest finger."""
    return -min(f.thickness for f in params.fingers.values()) / 2.0 + params.palm.wall


def servo_pulley_lip(params) -> float:
    """Flange height of a tendon servo pulley above its groove bottom: two tendon diameters."""
    return 2.0 * params.hardware.tendon_diameter


def pulley_cavity_margin(params) -> float:
    """The palm's cavity around a servo pulley is this much larger than the pulley's groove radius:
    the pulley's flanges, one tendon diameter of running room and a hole clearance."""
    return servo_pulley_lip(params) + params.hardware.tendon_diameter + params.print.hole_clearance


def servo_row_depths(params) -> tuple[float, float]:
    """Depth (behind the socket face, along the column) of the two staggered servo rows' shafts:
    one palm wall between a socket's magnet pockets and the pulley cavity behind it."""
    hw, pr, cad, sv = params.hardware, params.print, params.cad, params.servo
    cavity = max(c.servo_radius for c in params.chains) + pulley_cavity_margin(params)
    d_a = hw.magnet_thickness + pr.magnet_clearance + params.palm.wall + cavity
    d_b = d_a + cad.servo_shaft_offset + sv.flange_span / 2.0 + params.palm.wall + cavity
    return d_a, d_b


def servo_column(params, servo: int) -> int:
    """Palm column of a tendon servo (0-based index): its finger's column on the arc; the thumb
    flexion servo uses a virtual column -1 radial of the index. Even columns use row A, odd
    ones row B."""
    digit = SERVOS[servo].digit
    return FINGERS.index(digit) if digit in FINGERS else -1


def servo_radius(params, servo: int) -> float:
    """Radius (m) of a servo's output: the chain's pulley radius r_j for a tendon servo, the
    CMC hub radius for the direct drive."""
    s = SERVOS[servo]
    if s.drive == "direct":
        return params.thumb.cmc_horn_radius
    return params.digit(s.digit).chain.servo_radius


def T_palm_servo(params, servo: int) -> np.ndarray:
    """Servo output frame (see module doc) of servo ``servo`` (0-based index, topology.SERVOS):
    a tendon servo in the palm's servo bay, or the direct-drive CMC servo under the CMC base."""
    if SERVOS[servo].drive == "direct":
        th = params.thumb
        pw = params.cad.servo_pulley_width
        c = params.print.hole_clearance
        # the CMC hub (servo pulley 6) sits under the CMC base, coaxial with the CMC axis
        return T_palm_thumb_cmc_base(params) @ trans(0.0, 0.0, -(th.thickness / 2.0 + c + pw / 2.0))
    col = servo_column(params, servo)
    d_a, d_b = servo_row_depths(params)
    depth = d_a if col % 2 == 0 else d_b
    r = servo_radius(params, servo)
    # servos lie along the palm's y axis, in two staggered rows, each pulley straight behind
    # its finger's socket centre (the virtual column -1 of the thumb-flexion servo one
    # finger_pitch radial of the index socket)
    if col >= 0:
        sock = T_palm_socket(params, FINGERS[col])[:3, 3]
    else:
        sock = T_palm_socket(params, FINGERS[0])[:3, 3] - np.array([params.palm.finger_pitch, 0.0, 0.0])
    y_front = min(T_palm_socket(params, f)[1, 3] for f in FINGERS)
    # servo frame: z = -palm x (shaft toward the radial side, body on the ulnar side of its
    # pulley, above the next column's tendon), y = palm y, x = y cross z = palm z
    T = np.array([[0, 0, -1, 0], [0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1]], float)
    T[:3, 3] = (sock[0], y_front - depth, tendon_height(params) + r)
    return T


def wrist_y(params) -> float:
    """y (m, palm frame) of the wrist crease: the index metacarpal's length behind the index MCP.
    The palm (in the anthropometric sense) lies between it and the knuckles."""
    return -params.fingers[FINGERS[0]].metacarpal


def servo_boxes(params) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """(lo, hi) corners (m, servo frame) of a servo's body and of its flange ears (both ears as
    one slab across the body): the body's output face one hole clearance below the pulley's
    lower flange, the body toward -y of the shaft by cad.servo_shaft_offset, the ears'
    top face cad.servo_ear_offset below the output face."""
    sv, cad = params.servo, params.cad
    L, W, H = sv.body
    z_top = -(cad.servo_pulley_width / 2.0 + params.print.hole_clearance)
    z1 = z_top - cad.servo_ear_offset
    z0 = z1 - cad.servo_ear_thickness
    y0 = -cad.servo_shaft_offset
    return {"body": (np.array([-W / 2.0, y0 - L / 2.0, z_top - H]), np.array([W / 2.0, y0 + L / 2.0, z_top])),
            "ears": (np.array([-W / 2.0, y0 - sv.flange_span / 2.0, z0]),
                     np.array([W / 2.0, y0 + sv.flange_span / 2.0, z1]))}


def socket_tendon_point(params, finger: str) -> np.ndarray:
    """Where the finger's tendon crosses the magnet face (palm frame, metres)."""
    return (T_palm_socket(params, finger) @ np.array([0.0, 0.0, tendon_height(params), 1.0]))[:3]


def guide_offsets(guide) -> tuple[np.ndarray, np.ndarray]:
    """The drive tendon's guide eyelets G1 and G2 as (y, z) from the reference joint's (MCP /
    thumb MP) axis at rest, metres: G1 on the metacarpal side at d1, G2 on the phalanx at d2,
    symmetric about the palmar direction (-z) and alpha apart, so that their chord at rest is
    L0 (eq. 4) and flexion by q closes the angle between them to alpha - q (eq. 5)."""
    h = guide.alpha / 2.0
    G1 = guide.d1 * np.array([-math.sin(h), -math.cos(h)])
    G2 = guide.d2 * np.array([math.sin(h), -math.cos(h)])
    return G1, G2


def guide_sites(params, digit: str) -> tuple[tuple[str, np.ndarray], tuple[str, np.ndarray]]:
    """(link, point) of G1 and G2 of a digit's drive tendon, each in its own link frame (metres,
    mirrored for a left hand): G1 on the reference joint's parent link, G2 on its child. The
    straight line between them is the chord of eq. (4)-(5) in every pose."""
    ch = chain(digit)
    ref = joint(ch.joint_names[0])
    G1, G2 = guide_offsets(params.digit(digit).chain.guide)
    L = segment_length(params, link(ref.parent))
    p1 = np.array([0.0, L + G1[0], G1[1]])
    p2 = np.array([0.0, G2[0], G2[1]])
    if params.side == "left":
        p1, p2 = MIRROR[:3, :3] @ p1, MIRROR[:3, :3] @ p2
    return (ref.parent, p1), (ref.child, p2)


#: where a fingertip's pad centre sits on the tip's half cylinder: this far (rad) from the palmar
#: face toward the tip (the flat palmar face carries the tendon's knot well)
PAD_ANGLE = math.pi / 4.0


def fingertip(params, digit: str) -> tuple[float, float, float]:
    """(length, tip radius, half width), metres, of a digit's distal phalanx: its tip is a half
    cylinder about the link's x at y = length - radius, of radius half the thickness (or less, when
    the phalanx is shorter than the clevis slot behind it needs), across the digit's width."""
    d = params.digit(digit)
    L = d.distal
    return L, min(d.thickness / 2.0, L - slot_back(d.thickness, params.print.hole_clearance)), d.width / 2.0


def T_distal_pad(params, digit: str) -> np.ndarray:
    """T_link_pad (metres, right hand) of a fingertip: the centre of its contact pad on the tip's
    half cylinder, PAD_ANGLE from the palmar face toward the tip; z the outward surface normal
    there, x the link's x."""
    L, r, _ = fingertip(params, digit)
    n = np.array([0.0, math.sin(PAD_ANGLE), -math.cos(PAD_ANGLE)])
    T = np.eye(4)
    T[:3, 0], T[:3, 2] = (1.0, 0.0, 0.0), n
    T[:3, 1] = np.cross(n, T[:3, 0])
    T[:3, 3] = np.array([0.0, L - r, 0.0]) + r * n
    return T


def rest_transforms(params) -> dict[str, np.ndarray]:
    """Joint origins T_parent_child at rest, named after their frames (right hand, metres)."""
    return joint_transforms(params, np.zeros(N_JOINTS))


def segment_length(params, ln) -> float:
    """Length (m) of link ``ln`` from its proximal joint to its distal one (0 for a finger base,
    whose origin is its distal joint)."""
    key = ln.length_key
    return 0.0 if key is None else getattr(params.digit(ln.digit), key)


def _joint_transform(params, ln, q) -> np.ndarray:
    """T_parent_child of link ``ln`` at joint angles q: a fixed mount on the palm (finger base,
    servo pulley), the CMC (about the CMC base's z) or a flexion joint behind the parent's
    segment."""
    if ln.parent_joint is None:
        if ln.segment == "servo_pulley":
            T = T_palm_servo(params, ln.servo)
            if SERVOS[ln.servo].drive == "direct":   # the hub turns with its joint about its z
                (qi,) = servo_joints(ln.servo)
                T = T @ rot_z(float(q[qi]))
            return T
        return T_palm_finger_base(params, ln.digit)
    j = joint(ln.parent_joint)
    if j.index == CMC_Q:
        return T_palm_thumb_cmc_base(params, float(q[j.index]))
    L = segment_length(params, link(ln.parent))
    return flex(float(q[j.index])) if L == 0.0 else trans(0, L, 0) @ flex(float(q[j.index]))


def joint_transforms(params, q) -> dict[str, np.ndarray]:
    """T_parent_child (named ``T_<parent>_<child>``) for every link but the palm at joint angles
    q (15,), right hand, metres."""
    q = np.zeros(N_JOINTS) if q is None else np.asarray(q, float)
    if q.shape != (N_JOINTS,):
        raise ValueError(f"q must have shape ({N_JOINTS},), got {q.shape}")
    return {_transform_name(ln): _joint_transform(params, ln, q) for ln in LINKS if ln.parent is not None}


def _transform_name(ln) -> str:
    return f"T_{ln.parent}_{ln.name}"


#: link -> (parent link, joint transform name), from the topology; palm is the root
LINK_PARENTS: dict[str, tuple[str, str]] = {ln.name: (ln.parent, _transform_name(ln))
                                            for ln in LINKS if ln.parent is not None}


def link_transforms(params, q=None) -> dict[str, np.ndarray]:
    """T_palm_link (metres) of every link at joint angles q (None = rest), mirrored for a left hand."""
    joints = joint_transforms(params, q)
    out = {"palm": np.eye(4)}
    for name, (parent, jname) in LINK_PARENTS.items():   # topology order: parents first
        out[name] = out[parent] @ joints[jname]
    if params.side == "left":
        out = {k: mirror(v) for k, v in out.items()}
    return out


def joints(params) -> list[dict]:
    """The 15 actuated joints, in q order (Table I), as a robot-description writer would use
    them: name (``index_dip``, ...), parent and child link, ``origin`` = T_parent_child at rest
    (metres, mirrored for a left hand), ``axis`` (unit vector in the child frame; q turns the
    child about it by +q), ``q_index`` and ``limits`` (rad) from the parameters."""
    rest = joint_transforms(params, None)
    left = params.side == "left"
    out = []
    for j in JOINTS:
        T = rest[_transform_name(link(j.child))]
        digit = params.digit(j.digit)
        if j.index == CMC_Q:
            # the CMC's own rotation Rz(q15) is the joint, not part of its origin
            axis = np.array([0.0, 0.0, -1.0 if left else 1.0])
            limits = params.thumb.cmc_limits
        else:
            axis = np.array([-1.0, 0.0, 0.0])
            limits = dict(zip(digit.chain.joints, digit.chain.limits))[j.key]
        out.append({"name": j.name, "parent": j.parent, "child": j.child,
                    "origin": mirror(T) if left else T, "axis": axis, "q_index": j.index,
                    "limits": tuple(float(v) for v in limits)})
    return out
