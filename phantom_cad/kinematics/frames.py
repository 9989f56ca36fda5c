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
* Forearm module: behind the wrist crease (the index metacarpal's length behind the index
  MCP), palm axes; it carries the five tendon servos in one row, shafts dorsal.
* Left hand: every transform is conjugated by the mirror S = diag(-1, 1, 1): the left
  hand is the mirror image of the right in the palm's y-z plane, and each link's shape is
  mirrored in its own y-z plane, so T stays a proper rigid transform.
"""

from __future__ import annotations

import math

import numpy as np

from .. import units
from .dimensions import finger_columns, slot_back
from .memo import memoised
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
    (``dimensions.finger_columns``)."""
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


def servo_radius(params, servo: int) -> float:
    """Radius (m) of a servo's output: the chain's pulley radius r_j for a tendon servo, the
    CMC hub radius for the direct drive."""
    s = SERVOS[servo]
    if s.drive == "direct":
        return params.thumb.cmc_horn_radius
    return params.digit(s.digit).chain.servo_radius


def T_palm_servo(params, servo: int) -> np.ndarray:
    """Servo output frame (see module doc) of servo ``servo`` (0-based index, topology.SERVOS):
    a tendon servo in the forearm module (:func:`forearm_servos`), or the direct-drive CMC servo
    under the CMC base."""
    if SERVOS[servo].drive == "direct":
        th = params.thumb
        pw = params.cad.servo_pulley_width
        c = params.print.hole_clearance
        # the CMC hub (servo pulley 6) sits under the CMC base, coaxial with the CMC axis
        return T_palm_thumb_cmc_base(params) @ trans(0.0, 0.0, -(th.thickness / 2.0 + c + pw / 2.0))
    return forearm_servos(params)[servo].copy()


def thumb_arch(params) -> dict[str, float]:
    """The post and arch on the palm that carry the thumb's drive onto the CMC axis above the CMC
    base (CMC base frame at rest, metres), so that turning the CMC leaves its length alone. The
    post stands on the end wall of servo 6's housing, on the side the thumb never sweeps (q15
    turns the thumb from +y toward -x); the arch clears the CMC base by one clearance."""
    c, w = params.print.hole_clearance, params.palm.wall
    relief = 2.0 * (params.hardware.tendon_diameter + 2.0 * c)
    T = params.thumb.thickness
    r_hub = params.thumb.cmc_horn_radius
    r_post = w
    y_post = -max(params.cad.servo_shaft_offset + params.servo.flange_span / 2.0 + 2.0 * c + r_post,
                  r_hub + c + r_post)
    z_floor = -(T / 2.0 + 2.0 * c + params.cad.servo_pulley_width)   # servo 6 housing top
    z_lo = T / 2.0 + c                                               # arch underside
    z_hi = z_lo + 2.0 * w
    return {"r_post": r_post, "y_post": y_post, "z_floor": z_floor, "z_lo": z_lo, "z_hi": z_hi,
            "z_mid": (z_lo + z_hi) / 2.0, "z_entry": z_floor + relief + w}


def wrist_y(params) -> float:
    """y (m, palm frame) of the wrist crease: the index metacarpal's length behind the index MCP.
    The palm lies between it and the knuckles, the forearm module behind it."""
    return -params.fingers[FINGERS[0]].metacarpal


def servo_boxes(params) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """(lo, hi) corners (m, servo frame) of a servo's body and of its flange ears (both ears as
    one slab across the body): the body's output face one hole clearance below the pulley's
    lower flange, the body toward -y of the shaft by cad.servo_shaft_offset."""
    sv, cad = params.servo, params.cad
    L, W, H = sv.body
    z_top = -(cad.servo_pulley_width / 2.0 + params.print.hole_clearance)
    z1 = z_top - cad.servo_ear_offset
    z0 = z1 - cad.servo_ear_thickness
    y0 = -cad.servo_shaft_offset
    return {"body": (np.array([-W / 2.0, y0 - L / 2.0, z_top - H]), np.array([W / 2.0, y0 + L / 2.0, z_top])),
            "ears": (np.array([-W / 2.0, y0 - sv.flange_span / 2.0, z0]),
                     np.array([W / 2.0, y0 + sv.flange_span / 2.0, z1]))}


def box_corners(lo, hi) -> np.ndarray:
    """The eight corners (8, 3) of the axis-aligned box [lo, hi]."""
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])], float)


def servo_envelope(params, servo: int) -> np.ndarray:
    """Points (m, servo frame) whose hull holds a servo with its clearance: the corners of its body
    and ears and the rim of its pulley's cavity, grown by a hole clearance."""
    c = params.print.hole_clearance
    pts = [box_corners(lo - c, hi + c) for lo, hi in servo_boxes(params).values()]
    rc = servo_radius(params, servo) + pulley_cavity_margin(params)
    h = params.cad.servo_pulley_width / 2.0 + c
    a = np.linspace(0.0, 2.0 * math.pi, 48, endpoint=False)
    for z in (-h, h):
        pts.append(np.c_[rc * np.cos(a), rc * np.sin(a), np.full_like(a, z)])
    return np.vstack(pts)


def forearm_pitch(params) -> float:
    """Least x spacing (m) of the forearm module's servos: the wider of two pulley cavities' radii
    and a servo body with its clearances, and a palm wall (:func:`forearm_servos` widens it where
    the servos, each turned toward its target, would come closer than a wall)."""
    rc = max(c.servo_radius for c in params.chains) + pulley_cavity_margin(params)
    body = params.servo.body[1] + 2.0 * params.print.hole_clearance
    return max(2.0 * rc, body) + params.palm.wall


def servo_target(params, servo: int) -> np.ndarray:
    """The palm-frame point (m, right hand) a tendon servo's drive heads for as it leaves its
    pulley: the finger's tendon exit at its socket; for the thumb, the CMC centre (the drive climbs
    the CMC post from there, kinematics.routing)."""
    digit = SERVOS[servo].digit
    if digit in FINGERS:
        return socket_tendon_point(params, digit)
    return T_palm_thumb_cmc_base(params)[:3, 3].copy()


def aimed_servo(C: np.ndarray, E: np.ndarray, r: float) -> np.ndarray:
    """Servo frame at pulley centre C with its shaft along +z, turned about it so that the drive,
    leaving the pulley (radius r) at (-r, 0, 0) along +y, passes over E's (x, y)."""
    d = E[:2] - C[:2]
    n2 = float(d @ d)
    t = math.sqrt(n2 - r * r)
    # E - C = -r x_s + t y_s with x_s = y_s cross z = (y_s.y, -y_s.x): solved for y_s = (a, b)
    a, b = (t * d[0] + r * d[1]) / n2, (-r * d[0] + t * d[1]) / n2
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2] = (b, -a, 0.0), (a, b, 0.0), (0.0, 0.0, 1.0)
    T[:3, 3] = C
    return T


def spaced(want, pitch: float) -> list[float]:
    """The x_k nearest ``want`` in least squares with x_k+1 - x_k >= pitch: with z_k = x_k - k
    pitch it is the isotonic regression of want_k - k pitch (pool adjacent violators)."""
    blocks: list[list[float]] = []          # [mean, count]
    for k, w in enumerate(want):
        blocks.append([w - k * pitch, 1.0])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            (m1, n1), (m2, n2) = blocks[-2], blocks.pop()
            blocks[-1] = [(m1 * n1 + m2 * n2) / (n1 + n2), n1 + n2]
    z = [m for m, n in blocks for _ in range(int(n))]
    return [zk + k * pitch for k, zk in enumerate(z)]


_FOREARM: dict = {}


def forearm_servos(params) -> dict[int, np.ndarray]:
    """T_palm_servo (m, right hand) of every tendon servo in the forearm module: one row across the
    forearm, thumb servo radial to pinky servo ulnar (the order of their targets, so no two drives
    cross), each as near (least squares, :func:`spaced`) to where its drive leaves straight ahead
    as at least forearm_pitch apart allows, widened until the turned servos stand a palm wall apart
    (:func:`servo_gaps`); shafts dorsal, every pulley's mid-plane at the fingers' tendon height, so
    that a finger drive runs level from its pulley to its socket; each servo turned about its shaft
    so that its drive leaves straight toward its target (:func:`servo_target`); the row as far
    forward as the servos' envelopes (:func:`servo_envelope`) allow, one palm wall behind the
    module's front face (:func:`forearm_front`). Memoised (read-only)."""
    return memoised(_FOREARM, params.digest, lambda: _forearm_servos(params), cap=16)


def _forearm_servos(params) -> dict[int, np.ndarray]:
    tendon = [s.index for s in SERVOS if s.drive == "tendon"]
    targets = {k: servo_target(params, k) for k in tendon}
    # each pulley as near as the pitch allows to where its drive leaves straight ahead toward its
    # target (its centre r ulnar of the target's x): least squares with x_k+1 - x_k >= pitch
    radius = {k: servo_radius(params, k) for k in tendon}
    envelope = {k: servo_envelope(params, k) for k in tendon}
    want = [targets[k][0] + radius[k] for k in tendon]
    z = tendon_height(params)
    front = forearm_front(params) - params.palm.wall
    pitch, w = forearm_pitch(params), params.palm.wall
    out: dict[int, np.ndarray] = {}
    for _ in range(12):         # widen the pitch until the turned servos stand a wall apart
        xs = spaced(want, pitch)
        y = front
        for _ in range(6):      # a servo's turn depends (weakly) on the row's depth: settle it
            out = {k: aimed_servo(np.array([xs[i], y, z]), targets[k], radius[k]) for i, k in enumerate(tendon)}
            reach = max(float((out[k][:3, :3] @ envelope[k].T)[1].max()) for k in tendon)
            y = front - reach
        short = w - min(servo_gaps(params, out))
        if short <= 1e-9:
            break
        pitch += short + 1e-6
    return out


def _rectangles(params, T: np.ndarray) -> list[np.ndarray]:
    """The xy corners (palm frame) of a servo's body and ears, grown by a clearance, placed by T."""
    c = params.print.hole_clearance
    out = []
    for lo, hi in servo_boxes(params).values():
        pts = np.array([[x, y, 0.0] for x, y in ((lo[0] - c, lo[1] - c), (hi[0] + c, lo[1] - c),
                                                  (hi[0] + c, hi[1] + c), (lo[0] - c, hi[1] + c))])
        out.append((T[:3, :3] @ pts.T).T[:, :2] + T[:2, 3])
    return out


def servo_gaps(params, servos: dict[int, np.ndarray]) -> list[float]:
    """Between each pair of neighbouring servos of a row (T_palm_servo, shafts along z), a lower
    bound (m) of the distance between their bodies and ears with clearance: the largest gap
    between their projections on an edge normal of either (separating axes)."""
    row = sorted(servos.values(), key=lambda T: T[0, 3])
    gaps = []
    for Ta, Tb in zip(row, row[1:]):
        g = np.inf
        for P in _rectangles(params, Ta):
            for Q in _rectangles(params, Tb):
                axes = [np.array([-(R[(i + 1) % 4] - R[i])[1], (R[(i + 1) % 4] - R[i])[0]]) for R in (P, Q)
                        for i in range(2)]
                best = -np.inf
                for n in axes:
                    n = n / np.linalg.norm(n)
                    p, q = P @ n, Q @ n
                    best = max(best, q.min() - p.max(), p.min() - q.max())
                g = min(g, best)
        gaps.append(float(g))
    return gaps


def thenar_housing_box(params) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) corners (m, servo frame) of the palm's housing around the direct-drive CMC servo:
    one box around its body and flange ears grown by a hole clearance and a palm wall, up to its
    output face."""
    boxes = servo_boxes(params)
    g = params.print.hole_clearance + params.palm.wall
    (blo, bhi), (elo, ehi) = boxes["body"], boxes["ears"]
    return (np.array([blo[0] - g, min(blo[1], elo[1]) - g, blo[2] - g]),
            np.array([bhi[0] + g, max(bhi[1], ehi[1]) + g, bhi[2]]))


def thenar_points(params) -> np.ndarray:
    """Points (m, palm frame, right hand) whose hull holds what the palm carries at the thumb's
    CMC: the corners of servo 6's housing (:func:`thenar_housing_box`) and of the post and arch of
    :func:`thumb_arch`."""
    k = next(s.index for s in SERVOS if s.drive == "direct")
    w = params.palm.wall
    lo, hi = thenar_housing_box(params)
    box = box_corners(lo, hi)
    Ts = T_palm_servo(params, k)
    pts = [(Ts[:3, :3] @ box.T).T + Ts[:3, 3]]
    a = thumb_arch(params)
    r = a["r_post"]
    post = box_corners((-r, a["y_post"] - r, a["z_floor"] - w), (r, a["y_post"] + r, a["z_hi"]))
    Tc = T_palm_thumb_cmc_base(params)
    pts.append((Tc[:3, :3] @ post.T).T + Tc[:3, 3])
    return np.vstack(pts)


def forearm_front(params) -> float:
    """y (m, palm frame) of the forearm module's front face: a hole clearance behind the wrist
    crease, or behind the thenar (:func:`thenar_points`) where that reaches further back."""
    c = params.print.hole_clearance
    return min(wrist_y(params), float(thenar_points(params)[:, 1].min())) - c


def T_palm_forearm(params) -> np.ndarray:
    """The forearm module's frame: the palm's axes, origin on the wrist crease at the middle of the
    servo row, in the palm's mid-plane."""
    xs = [T[0, 3] for T in forearm_servos(params).values()]
    return trans((min(xs) + max(xs)) / 2.0, wrist_y(params), 0.0)


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
        if ln.segment == "forearm":
            return T_palm_forearm(params)
        if ln.segment == "servo_pulley":
            T = T_palm_servo(params, ln.servo)
            if ln.parent != "palm":          # mounted on the forearm module
                T = np.linalg.inv(_joint_transform(params, link(ln.parent), q)) @ T
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
