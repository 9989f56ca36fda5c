"""The hand's frame conventions and its fixed frames: the elementary transforms, the finger
columns, sockets and CMC placement, the sizes they derive from. numpy only.

The servo row is :mod:`.forearm_layout`'s, the palm's hold on the thumb :mod:`.thenar`'s, every link's
frame at joint angles q :mod:`.link_frames`'s.

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
* Forearm module: behind the wrist crease (the index metacarpal's length behind the index
  MCP, or behind the thenar where that reaches further back), palm axes; it carries the six
  servos in one row, shafts dorsal.
* Thenar: the CMC base carries a column along the CMC axis up into the palm, which holds it in a
  journal; on the column, inside the palm, the CMC pulley (link ``thumb_cmc_pulley``, fixed to the
  CMC base: origin on the CMC axis at its mid-plane, z the CMC axis, y the palm's y turned into
  the pulley's plane at rest) that servo 6's closed cable loop turns (:func:`thenar`).
* Left hand: every transform is conjugated by the mirror S = diag(-1, 1, 1): the left
  hand is the mirror image of the right in the palm's y-z plane, and each link's shape is
  mirrored in its own y-z plane, so T stays a proper rigid transform.
"""

from __future__ import annotations

import math

import numpy as np

from .. import units
from . import dimensions
from .dimensions import finger_columns, slot_back
from .hand_params import Guide, HandParams
from .topology import FINGERS, SERVOS, chain, joint, link


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

def finger_angle(params: HandParams, i: int) -> float:
    """phi_i: rotation of finger column i (0 = index) about -z, symmetric about the middle of the arc."""
    return (i - (len(FINGERS) - 1) / 2.0) * params.palm.arc_offset


def finger_direction(params: HandParams, i: int) -> np.ndarray:
    phi = finger_angle(params, i)
    return np.array([math.sin(phi), math.cos(phi), 0.0])


def mcp_position(params: HandParams, i: int) -> np.ndarray:
    """MCP axis centre of finger i in the palm frame (index at the origin): on the palm arc,
    stepped along its column by its metacarpal's length less the index's
    (``dimensions.finger_columns``)."""
    x, y, _ = finger_columns(params.palm.finger_pitch, params.palm.arc_offset,
                             [params.fingers[f].metacarpal for f in FINGERS])[i]
    return np.array([x, y, 0.0])


def T_palm_finger_base(params: HandParams, finger: str) -> np.ndarray:
    i = FINGERS.index(finger)
    T = rot_z(-finger_angle(params, i))
    T[:3, 3] = mcp_position(params, i)
    return T


def T_palm_socket(params: HandParams, finger: str) -> np.ndarray:
    """The palm's finger socket: origin at the centre of the magnet face, y its outward normal."""
    return T_palm_finger_base(params, finger) @ trans(0.0, -params.cad.finger_base_length, 0.0)


def limiter_outline(params: HandParams, finger: str) -> list[tuple[float, float]]:
    """(y, z) outline (m), in the finger base frame (MCP axis at the origin), of the palm's
    flexion limiter rails: from a wall inside the socket block to the plane the proximal phalanx's
    palmar face (z_child = -thickness/2) reaches at the MCP upper limit (Table I), between that
    face, a clearance below it, and the palm's palmar face. The rails span x from the guide
    eyelet's boss to the finger's sides (+-width/2)."""
    d = params.digit(finger)
    q = d.chain.limits[0][1]
    s, c = math.sin(q), math.cos(q)
    rb = d.thickness / 2.0
    back = -params.cad.finger_base_length - params.palm.wall
    z_top = -d.thickness / 2.0 - params.print.hole_clearance
    z_bot = -params.palm.thickness / 2.0
    y_at = lambda z: (-rb - z * c) / s  # noqa: E731
    return [(back, z_bot), (y_at(z_bot), z_bot), (y_at(z_top), z_top), (back, z_top)]


def limiter_x_extent(params: HandParams, finger: str) -> tuple[float, float]:
    """x extent (m, palm frame, right hand) of the finger's two limiter rails
    (:func:`limiter_outline`, +-width/2 across)."""
    T = T_palm_finger_base(params, finger)
    w = params.fingers[finger].width / 2.0
    xs = [float((T @ np.array([sx, y, z, 1.0]))[0]) for y, z in limiter_outline(params, finger) for sx in (-w, w)]
    return min(xs), max(xs)


def socket_x(params: HandParams) -> tuple[float, float]:
    """x extent (m, palm frame, right hand) of the palm's finger sockets: the outer sides of the
    index's and the pinky's (the columns converge toward the wrist, so their faces are widest)."""
    xs = []
    for f in FINGERS:
        T = T_palm_socket(params, f)
        w = params.fingers[f].width / 2.0
        xs += [float((T @ np.array([sx, 0.0, 0.0, 1.0]))[0]) for sx in (-w, w)]
    return min(xs), max(xs)


def thumb_cmc_placement(offset, axis) -> np.ndarray:
    """T_palm_cmc_base at q15 = 0 for a CMC centre ``offset`` (m, palm frame) and ``axis`` =
    (roll, pitch, yaw) (rad): R = Rz(yaw) Ry(pitch) Rx(roll); the CMC axis is the frame's z."""
    roll, pitch, yaw = axis
    T = rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)
    T[:3, 3] = offset
    return T


def T_palm_thumb_cmc_base(params: HandParams, q15: float = 0.0) -> np.ndarray:
    return thumb_cmc_placement(params.palm.thumb_cmc_offset, params.palm.thumb_cmc_axis) @ rot_z(q15)


def tendon_height(params: HandParams) -> float:
    """z of every finger tendon where it crosses the magnet face (palm and finger base):
    one wall above the palmar face of the thinnest finger (:func:`.dimensions.tendon_height`)."""
    return dimensions.tendon_height(min(f.thickness for f in params.fingers.values()), params.palm.wall)


def servo_pulley_lip(params: HandParams) -> float:
    """Flange height of a tendon servo pulley above its groove bottom: two tendon diameters."""
    return 2.0 * params.hardware.tendon_diameter


def pulley_cavity_margin(params: HandParams) -> float:
    """The palm's cavity around a servo pulley is this much larger than the pulley's groove radius:
    the pulley's flanges, one tendon diameter of running room and a hole clearance."""
    return servo_pulley_lip(params) + params.hardware.tendon_diameter + params.print.hole_clearance


def servo_radius(params: HandParams, servo: int) -> float:
    """Radius (m) of a servo's pulley: the chain's r_j for a tendon servo, the CMC loop's pulley
    radius (thumb.cmc_pulley_radius, the same on the CMC column: q15 = u6) for servo 6."""
    s = SERVOS[servo]
    if s.drive == "loop":
        return params.thumb.cmc_pulley_radius
    return params.digit(s.digit).chain.servo_radius


def cmc_pulley_radius(params: HandParams) -> float:
    """Radius (m) of the CMC pulley: servo 6's (thumb.cmc_pulley_radius) over thumb.cmc_gain, so
    that the loop holds q15 = cmc_gain u6 (eq. 9; equal radii at the paper's gain of 1)."""
    return params.thumb.cmc_pulley_radius / params.thumb.cmc_gain


def tendon_relief(params: HandParams) -> float:
    """Radius (m) of the sphere that rounds a tendon channel's bend: a tendon hole (the tendon
    and two clearances) wide."""
    return params.hardware.tendon_diameter + 2.0 * params.print.hole_clearance


def wrist_y(params: HandParams) -> float:
    """y (m, palm frame) of the wrist crease: the index metacarpal's length behind the index MCP.
    The palm lies between it and the knuckles, the forearm module behind it."""
    return -params.fingers[FINGERS[0]].metacarpal


def socket_tendon_point(params: HandParams, finger: str) -> np.ndarray:
    """Where the finger's tendon crosses the magnet face (palm frame, metres)."""
    return (T_palm_socket(params, finger) @ np.array([0.0, 0.0, tendon_height(params), 1.0]))[:3]


def guide_offsets(guide: Guide) -> tuple[np.ndarray, np.ndarray]:
    """The drive tendon's guide eyelets G1 and G2 as (y, z) from the reference joint's (MCP /
    thumb MP) axis at rest, metres: G1 on the metacarpal side at d1, G2 on the phalanx at d2,
    symmetric about the palmar direction (-z) and alpha apart, so that their chord at rest is
    L0 (eq. 4) and flexion by q closes the angle between them to alpha - q (eq. 5)."""
    h = guide.alpha / 2.0
    G1 = guide.d1 * np.array([-math.sin(h), -math.cos(h)])
    G2 = guide.d2 * np.array([math.sin(h), -math.cos(h)])
    return G1, G2


def guide_sites(params: HandParams, digit: str) -> tuple[tuple[str, np.ndarray], tuple[str, np.ndarray]]:
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


def fingertip(params: HandParams, digit: str) -> tuple[float, float, float]:
    """(length, tip radius, half width), metres, of a digit's distal phalanx: its tip is a half
    cylinder about the link's x at y = length - radius, of radius half the thickness (or less, when
    the phalanx is shorter than the clevis slot behind it needs), across the digit's width."""
    d = params.digit(digit)
    L = d.distal
    return L, min(d.thickness / 2.0, L - slot_back(d.thickness, params.print.hole_clearance)), d.width / 2.0


def T_distal_pad(params: HandParams, digit: str) -> np.ndarray:
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


def segment_length(params: HandParams, ln) -> float:
    """Length (m) of link ``ln`` from its proximal joint to its distal one (0 for a finger base,
    whose origin is its distal joint)."""
    key = ln.length_key
    return 0.0 if key is None else getattr(params.digit(ln.digit), key)
