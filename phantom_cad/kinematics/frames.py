"""Link frames of the hand: where every part sits, at rest and posed. numpy only.

Units: metres (SI, like the parameter object). The CAD layer converts to millimetres once
(:func:`to_mm`). Conventions (docs/frames.md):

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
  Rz(-phi_i) y with phi_i = (i - 1.5) arc_offset; adjacent MCPs are finger_pitch apart
  on the arc of radius palm.arc_radius whose centre lies proximal of the MCPs.
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

from .topology import CMC_Q, FINGERS, N_JOINTS, joint_index

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
    out[:3, 3] *= 1000.0
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
    """MCP axis centre of finger i in the palm frame (index at the origin), on the palm arc."""
    R = params.palm.arc_radius
    centre = -R * finger_direction(params, 0)
    return centre + R * finger_direction(params, i)


def T_palm_finger_base(params, finger: str) -> np.ndarray:
    i = FINGERS.index(finger)
    T = rot_z(-finger_angle(params, i))
    T[:3, 3] = mcp_position(params, i)
    return T


def T_palm_socket(params, finger: str) -> np.ndarray:
    """The palm's finger socket: origin at the centre of the magnet face, y its outward normal."""
    return T_palm_finger_base(params, finger) @ trans(0.0, -params.cad.finger_base_length, 0.0)


def T_palm_thumb_cmc_base(params, q15: float = 0.0) -> np.ndarray:
    roll, pitch, yaw = params.palm.thumb_cmc_axis
    T = rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)
    T[:3, 3] = params.palm.thumb_cmc_offset
    return T @ rot_z(q15)


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
    """Column of servo (0-based): servo 0 (thumb flexion) uses a virtual column -1 radial of
    the index; servos 1..4 their finger's column. Even columns use row A, odd ones row B."""
    return servo - 1


def T_palm_servo(params, servo: int) -> np.ndarray:
    """Servo output frame (see module doc) of servo 0..4 (tendon servos) and 5 (thumb CMC)."""
    if servo == 5:
        th = params.thumb
        pw = params.cad.servo_pulley_width
        c = params.print.hole_clearance
        # the CMC hub (servo pulley 6) sits under the CMC base, coaxial with the CMC axis
        return T_palm_thumb_cmc_base(params) @ trans(0.0, 0.0, -(th.thickness / 2.0 + c + pw / 2.0))
    col = servo_column(params, servo)
    d_a, d_b = servo_row_depths(params)
    depth = d_a if col % 2 == 0 else d_b
    r = params.chains[servo].servo_radius
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


def socket_tendon_point(params, finger: str) -> np.ndarray:
    """Where the finger's tendon crosses the magnet face (palm frame, metres)."""
    return (T_palm_socket(params, finger) @ np.array([0.0, 0.0, tendon_height(params), 1.0]))[:3]


def rest_transforms(params) -> dict[str, np.ndarray]:
    """Joint origins T_parent_child at rest, named after their frames (right hand, metres)."""
    return joint_transforms(params, np.zeros(N_JOINTS))


def _q_of(q, digit: str, joint: str) -> float:
    return float(q[joint_index(digit, joint)])


def joint_transforms(params, q) -> dict[str, np.ndarray]:
    """T_parent_child for every joint at joint angles q (15,), right hand, metres."""
    q = np.zeros(N_JOINTS) if q is None else np.asarray(q, float)
    if q.shape != (N_JOINTS,):
        raise ValueError(f"q must have shape ({N_JOINTS},), got {q.shape}")
    out = {}
    for f in FINGERS:
        fp = params.fingers[f]
        out[f"T_palm_{f}_base"] = T_palm_finger_base(params, f)
        out[f"T_{f}_base_{f}_proximal"] = flex(_q_of(q, f, "mcp"))
        out[f"T_{f}_proximal_{f}_middle"] = trans(0, fp.proximal, 0) @ flex(_q_of(q, f, "pip"))
        out[f"T_{f}_middle_{f}_distal"] = trans(0, fp.middle, 0) @ flex(_q_of(q, f, "dip"))
    th = params.thumb
    out["T_palm_thumb_cmc_base"] = T_palm_thumb_cmc_base(params, float(q[CMC_Q]))
    out["T_thumb_cmc_base_thumb_proximal"] = trans(0, th.metacarpal, 0) @ flex(_q_of(q, "thumb", "mp"))
    out["T_thumb_proximal_thumb_distal"] = trans(0, th.proximal, 0) @ flex(_q_of(q, "thumb", "ip"))
    for k in range(6):
        T = T_palm_servo(params, k)
        if k == 5:   # direct drive: the CMC hub turns with q15 about the CMC axis (its z)
            T = T @ rot_z(float(q[CMC_Q]))
        out[f"T_palm_servo_pulley_{k + 1}"] = T
    return out


#: link -> (parent link, joint transform name); palm is the root
LINK_PARENTS: dict[str, tuple[str, str]] = {}
for _f in FINGERS:
    LINK_PARENTS[f"{_f}_base"] = ("palm", f"T_palm_{_f}_base")
    LINK_PARENTS[f"{_f}_proximal"] = (f"{_f}_base", f"T_{_f}_base_{_f}_proximal")
    LINK_PARENTS[f"{_f}_middle"] = (f"{_f}_proximal", f"T_{_f}_proximal_{_f}_middle")
    LINK_PARENTS[f"{_f}_distal"] = (f"{_f}_middle", f"T_{_f}_middle_{_f}_distal")
LINK_PARENTS["thumb_cmc_base"] = ("palm", "T_palm_thumb_cmc_base")
LINK_PARENTS["thumb_proximal"] = ("thumb_cmc_base", "T_thumb_cmc_base_thumb_proximal")
LINK_PARENTS["thumb_distal"] = ("thumb_proximal", "T_thumb_proximal_thumb_distal")
for _k in range(6):
    LINK_PARENTS[f"servo_pulley_{_k + 1}"] = ("palm", f"T_palm_servo_pulley_{_k + 1}")

LINKS = ("palm",) + tuple(LINK_PARENTS)


def link_transforms(params, q=None) -> dict[str, np.ndarray]:
    """T_palm_link (metres) of every link at joint angles q (None = rest), mirrored for a left hand."""
    joints = joint_transforms(params, q)
    out = {"palm": np.eye(4)}
    for link in LINKS[1:]:
        parent, jname = LINK_PARENTS[link]
        out[link] = out[parent] @ joints[jname]
    if params.side == "left":
        out = {k: mirror(v) for k, v in out.items()}
    return out


def joints(params) -> list[dict]:
    """The 15 actuated joints for a URDF/MJCF writer, in q order (Table I): name
    (``index_dip``, ...), parent and child link, ``origin`` = T_parent_child at rest (metres,
    mirrored for a left hand), ``axis`` (unit vector in the child frame; q turns the child
    about it by +q), ``q_index`` and ``limits`` (rad) from the parameters."""
    from .topology import JOINT_NAMES

    rest = joint_transforms(params, None)
    left = params.side == "left"
    out = []
    for i, name in enumerate(JOINT_NAMES):
        digit, joint = name.split("_")
        if digit == "thumb":
            chain = {"cmc": ("palm", "thumb_cmc_base"), "mp": ("thumb_cmc_base", "thumb_proximal"),
                     "ip": ("thumb_proximal", "thumb_distal")}[joint]
            limits = params.thumb.cmc_limits if joint == "cmc" else dict(
                zip(params.thumb.chain.joints, params.thumb.chain.limits))[joint]
        else:
            chain = {"mcp": (f"{digit}_base", f"{digit}_proximal"), "pip": (f"{digit}_proximal", f"{digit}_middle"),
                     "dip": (f"{digit}_middle", f"{digit}_distal")}[joint]
            limits = dict(zip(params.fingers[digit].chain.joints, params.fingers[digit].chain.limits))[joint]
        parent, child = chain
        T = rest[f"T_{parent}_{child}"]
        if joint == "cmc":
            # the CMC's own rotation Rz(q15) is the joint, not part of its origin
            axis = np.array([0.0, 0.0, -1.0 if left else 1.0])
        else:
            axis = np.array([-1.0, 0.0, 0.0])
        out.append({"name": name, "parent": parent, "child": child,
                    "origin": mirror(T) if left else T, "axis": axis, "q_index": i,
                    "limits": tuple(float(v) for v in limits)})
    return out
