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
from .dimensions import finger_columns, slot_back
from .memo import memoised
from .topology import CMC_Q, CMC_SERVO, FINGERS, JOINTS, LINKS, N_JOINTS, SERVOS, chain, joint, link

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


def socket_x(params) -> tuple[float, float]:
    """x extent (m, palm frame, right hand) of the palm's finger sockets: the outer sides of the
    index's and the pinky's (the columns converge toward the wrist, so their faces are widest)."""
    xs = []
    for f in FINGERS:
        T = T_palm_socket(params, f)
        w = params.fingers[f].width / 2.0
        xs += [float((T @ np.array([sx, 0.0, 0.0, 1.0]))[0]) for sx in (-w, w)]
    return min(xs), max(xs)


def metacarpal_x(params) -> tuple[float, float]:
    """x extent (m, palm frame, right hand) of the palm's metacarpal block: across the sockets
    (:func:`socket_x`), and ulnar far enough that every finger drive's channel keeps a wall to the
    block's ulnar face where the drive runs ulnar toward its servo (from its exit under the socket
    to the palm's back face). The palm's ulnar face; its radial side is the thenar's."""
    x0, x1 = socket_x(params)
    y0 = palm_back(params)
    half = tendon_relief(params) / 2.0 + params.palm.wall     # half a tendon hole and a wall
    for f in FINGERS:
        s = chain(f).servo
        tangent = T_palm_servo(params, s) @ np.array([-servo_radius(params, s), 0.0, 0.0, 1.0])
        exit_ = T_palm_socket(params, f) @ np.array([0.0, 0.0, tendon_height(params), 1.0])
        at_back = exit_ + (tangent - exit_) * (y0 - exit_[1]) / (tangent[1] - exit_[1])
        x1 = max(x1, float(max(exit_[0], at_back[0])) + half)
    return x0, x1


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
    """Radius (m) of a servo's pulley: the chain's r_j for a tendon servo, the CMC loop's pulley
    radius (thumb.cmc_pulley_radius, the same on the CMC column: q15 = u6) for servo 6."""
    s = SERVOS[servo]
    if s.drive == "loop":
        return params.thumb.cmc_pulley_radius
    return params.digit(s.digit).chain.servo_radius


def cmc_pulley_radius(params) -> float:
    """Radius (m) of the CMC pulley: servo 6's (thumb.cmc_pulley_radius) over thumb.cmc_gain, so
    that the loop holds q15 = cmc_gain u6 (eq. 9; equal radii at the paper's gain of 1)."""
    return params.thumb.cmc_pulley_radius / params.thumb.cmc_gain


def T_palm_servo(params, servo: int) -> np.ndarray:
    """Servo output frame (see module doc) of servo ``servo`` (0-based index, topology.SERVOS), in
    the forearm module's row (:func:`forearm_servos`)."""
    return forearm_servos(params)[servo].copy()


def tendon_relief(params) -> float:
    """Radius (m) of the sphere that rounds a tendon channel's bend: a tendon hole (the tendon
    and two clearances) wide."""
    return params.hardware.tendon_diameter + 2.0 * params.print.hole_clearance


_THENAR: dict = {}


def thenar(params) -> dict[str, float]:
    """The palm's hold on the thumb (CMC base frame at rest, distances s along the CMC axis from
    the CMC centre, metres; memoised, read-only):

    * ``face``: where the axis crosses the palm's palmar face (the column enters the journal);
    * ``column_r``: the column's radius (cad.cmc_column_radius); ``journal_r`` the palm's bore;
    * ``pulley``: the CMC pulley's mid-plane: as low in the palm as its cavity allows (the cavity's
      rim a palm wall above the palmar face); ``cavity_r``, ``cavity_h``: the cavity's radius and
      half height along the axis (the pulley's flanges, running room and a clearance);
    * ``top``: the column's top, flush with the pulley's upper flange;
    * ``ceiling``: the cavity's top; ``turn``: where the thumb drive turns down onto the CMC axis,
      a palm wall and a relief above it (the drive reaches the CMC along its axis, so turning the
      CMC leaves its length alone).

    The palm cuts a slot from the cavity toward servo 6 (the loop runs in it; the pulley slides in
    through it, then the column up through the journal into it)."""
    return memoised(_THENAR, params.digest, lambda: thenar_layout(params, T_palm_thumb_cmc_base(params)), cap=16)


def thenar_layout(params, T0: np.ndarray) -> dict[str, float]:
    """:func:`thenar` for the CMC placement T0 (T_palm_cmc_base at rest) instead of the file's."""
    a, C = T0[:3, 2], T0[:3, 3]
    c, w = params.print.hole_clearance, params.palm.wall
    Tp = params.palm.thickness
    az = max(float(a[2]), 1e-9)
    R = cmc_pulley_radius(params) + pulley_cavity_margin(params)
    h = params.cad.servo_pulley_width / 2.0 + c
    tilt = math.sqrt(max(1.0 - az * az, 0.0))
    face = (-Tp / 2.0 - C[2]) / az
    z_q = -Tp / 2.0 + w + R * tilt + h * az             # the cavity's lowest rim a wall above the face
    pulley = (z_q - C[2]) / az
    ceiling = pulley + h
    return {"face": face, "column_r": params.cad.cmc_column_radius,
            "journal_r": params.cad.cmc_column_radius + c, "pulley": pulley, "cavity_r": R,
            "cavity_h": h, "top": pulley + params.cad.servo_pulley_width / 2.0, "ceiling": ceiling,
            "turn": ceiling + w + tendon_relief(params)}


#: the CMC axis's largest tilt from the palm's normal (rad): the column along it climbs into the palm
MAX_CMC_TILT = math.radians(60.0)


def thenar_margins(params, T0: np.ndarray) -> dict[str, float]:
    """How well the palm's thenar holds the CMC placed at T0 (T_palm_cmc_base at rest): each
    margin >= 0 where it fits. ``tilt`` (rad): the CMC axis within MAX_CMC_TILT of the palm's
    normal; ``base`` (m): the CMC base (a hub of half the thumb's width, the thumb's thickness,
    turning with the thumb) a clearance below the palm's palmar face; ``turn`` (m): the thumb
    drive's turn above the CMC pulley's cavity a relief and a wall under the dorsal face. The
    file's are checked before a build (``cad.preflight``); the placement search keeps to them."""
    a, C = T0[:3, 2], T0[:3, 3]
    th, c, w, Tp = params.thumb, params.print.hole_clearance, params.palm.wall, params.palm.thickness
    az = float(np.clip(a[2], -1.0, 1.0))
    out = {"tilt": MAX_CMC_TILT - math.acos(az)}
    top = C[2] + th.thickness / 2.0 * az + th.width / 2.0 * math.sqrt(max(1.0 - az * az, 0.0))
    out["base"] = -Tp / 2.0 - c - top
    if az <= 0.0:
        out["turn"] = -Tp
        return out
    t = thenar_layout(params, T0)
    D = T0 @ np.array([0.0, 0.0, t["turn"], 1.0])
    out["turn"] = Tp / 2.0 - (tendon_relief(params) + w) - float(D[2])
    return out


def T_cmc_base_pulley(params) -> np.ndarray:
    """The CMC pulley's frame in the CMC base's (fixed): on the CMC axis at the pulley's mid-plane,
    the CMC base's axes (its key's flat on +y)."""
    return trans(0.0, 0.0, thenar(params)["pulley"])


def cmc_loop_direction(params) -> float:
    """Polar angle (rad, the CMC pulley's frame at rest, right hand) of the direction from servo
    6's pulley to the CMC pulley (they lie in one plane, :func:`coplanar_servo`): the loop's
    strands reach the CMC pulley at that angle -+ 90 deg."""
    T = T_palm_thumb_cmc_base(params) @ T_cmc_base_pulley(params)
    d = T[:3, 3] - T_palm_servo(params, CMC_SERVO)[:3, 3]
    v = T[:3, :3].T @ d
    return math.atan2(v[1], v[0])


def thenar_axis_point(params, s: float) -> np.ndarray:
    """The palm-frame point (m, right hand) s along the CMC axis from the CMC centre, at rest."""
    return (T_palm_thumb_cmc_base(params) @ np.array([0.0, 0.0, s, 1.0]))[:3]


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


def forearm_pitch(params, a: int | None = None, b: int | None = None) -> float:
    """Least x spacing (m) of two neighbouring servos ``a`` and ``b`` in the forearm module (by
    default the largest of any two): the wider of their two pulley cavities' radii and a servo body
    with its clearances, and a palm wall (:func:`forearm_servos` widens it where the servos, each
    turned toward its target, would come closer than a wall)."""
    m = pulley_cavity_margin(params)
    r = sorted(servo_radius(params, s.index) for s in SERVOS)
    ra, rb = (r[-1], r[-2]) if a is None else (servo_radius(params, a), servo_radius(params, b))
    body = params.servo.body[1] + 2.0 * params.print.hole_clearance
    return max(ra + rb + 2.0 * m, body) + params.palm.wall


def servo_target(params, servo: int) -> np.ndarray:
    """The palm-frame point (m, right hand) a servo's cable heads for as it leaves its pulley: the
    finger's tendon exit at its socket; for the thumb's drive, its turn onto the CMC axis above the
    CMC pulley (:func:`thenar`); for servo 6, the CMC pulley's centre (its loop's strands run either
    side of the line between the pulleys)."""
    s = SERVOS[servo]
    if s.drive == "loop":
        return thenar_axis_point(params, thenar(params)["pulley"])
    if s.digit in FINGERS:
        return socket_tendon_point(params, s.digit)
    return thenar_axis_point(params, thenar(params)["turn"])


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


def coplanar_servo(x: float, y: float, Q: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Servo frame at (x, y) (palm frame) with its shaft along ``a`` and its pulley's mid-plane the
    plane through Q normal to ``a`` (the height z solves (S - Q) . a = 0), turned so that its y
    points at Q: two pulleys of equal radii in one plane, which a closed loop joins with straight
    strands at each one's -x and +x."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    S = np.array([x, y, Q[2] - ((x - Q[0]) * a[0] + (y - Q[1]) * a[1]) / a[2]])
    yv = (Q - S) - ((Q - S) @ a) * a
    yv /= np.linalg.norm(yv)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = np.cross(yv, a), yv, a, S
    return T


def spaced(want, pitch) -> list[float]:
    """The x_k nearest ``want`` in least squares with x_k+1 - x_k >= pitch_k (``pitch`` one number
    or one per gap): with c_k the sum of the gaps before k and z_k = x_k - c_k it is the isotonic
    regression of want_k - c_k (pool adjacent violators)."""
    gaps = [float(pitch)] * max(len(want) - 1, 0) if np.isscalar(pitch) else [float(g) for g in pitch]
    c = np.concatenate([[0.0], np.cumsum(gaps)]) if gaps else np.zeros(len(want))
    blocks: list[list[float]] = []          # [mean, count]
    for k, w in enumerate(want):
        blocks.append([w - c[k], 1.0])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            (m1, n1), (m2, n2) = blocks[-2], blocks.pop()
            blocks[-1] = [(m1 * n1 + m2 * n2) / (n1 + n2), n1 + n2]
    z = [m for m, n in blocks for _ in range(int(n))]
    return [zk + float(c[k]) for k, zk in enumerate(z)]


_FOREARM: dict = {}


def forearm_servos(params) -> dict[int, np.ndarray]:
    """T_palm_servo (m, right hand) of every servo in the forearm module: one row across the
    forearm in the order of their targets (radial to ulnar, so no two cables cross), each as near
    (least squares, :func:`spaced`) to where its cable leaves straight ahead as at least
    forearm_pitch apart allows, widened until the turned servos stand a palm wall apart
    (:func:`servo_gaps`); the tendon servos' shafts dorsal, every pulley's mid-plane at its
    target's height (the fingers' tendon height, the thumb drive's turn), so that every drive runs
    level, each servo turned about its shaft so that its drive leaves straight toward its target
    (:func:`servo_target`); servo 6's shaft parallel to the CMC axis, its pulley in the CMC pulley's
    plane (:func:`coplanar_servo`: the loop's strands run straight and in both pulleys' planes);
    the row as far forward as the servos' envelopes (:func:`servo_envelope`) allow, one palm wall
    behind the module's front face (:func:`forearm_front`). Memoised (read-only)."""
    return memoised(_FOREARM, params.digest, lambda: _forearm_servos(params), cap=16)


def _forearm_servos(params) -> dict[int, np.ndarray]:
    targets = {s.index: servo_target(params, s.index) for s in SERVOS}
    # each pulley as near as the pitch allows to where its drive leaves straight ahead toward its
    # target (its centre r ulnar of the target's x; a loop's centre on it): least squares with
    # x_k+1 - x_k >= pitch, in the order of those x
    radius = {k: servo_radius(params, k) for k in targets}
    aim = {k: (0.0 if SERVOS[k].drive == "loop" else radius[k]) for k in targets}
    envelope = {k: servo_envelope(params, k) for k in targets}
    tendon = sorted(targets, key=lambda k: (targets[k][0] + aim[k], k))
    want = [targets[k][0] + aim[k] for k in tendon]
    front = forearm_front(params) - params.palm.wall
    pitch = [forearm_pitch(params, a, b) for a, b in zip(tendon, tendon[1:])]
    w = params.palm.wall
    axis = T_palm_thumb_cmc_base(params)[:3, 2]
    out: dict[int, np.ndarray] = {}
    for _ in range(12):         # widen each gap until its turned servos stand a wall apart
        xs = spaced(want, pitch)
        y = front
        for _ in range(6):      # a servo's turn depends (weakly) on the row's depth: settle it
            out = {k: (coplanar_servo(xs[i], y, targets[k], axis) if SERVOS[k].drive == "loop" else
                       aimed_servo(np.array([xs[i], y, targets[k][2]]), targets[k], aim[k]))
                   for i, k in enumerate(tendon)}
            reach = max(float((out[k][:3, :3] @ envelope[k].T)[1].max()) for k in tendon)
            y = front - reach
        short = [w - g for g in servo_gaps(params, out)]      # per neighbouring pair, in row order
        if max(short) <= 1e-9:
            break
        pitch = [g + max(s, 0.0) + (1e-6 if s > 1e-9 else 0.0) for g, s in zip(pitch, short)]
    return out


def _outlines(params, T: np.ndarray, servo: int) -> list[np.ndarray]:
    """The xy outlines (palm frame, counter-clockwise) of servo ``servo``'s body, ears and pulley
    cavity, grown by a clearance, placed by T, with the pockets the module cuts for them: open along
    the shaft up to the module's top (a wall above the palm's dorsal face), so a tilted shaft sweeps
    them sideways (the convex hull of the outline at the servo and at the top)."""
    c = params.print.hole_clearance
    z_top = params.palm.thickness / 2.0 + params.palm.wall
    shapes = []
    for lo, hi in servo_boxes(params).values():
        shapes.append([(x, y, lo[2] - c) for x, y in ((lo[0] - c, lo[1] - c), (hi[0] + c, lo[1] - c),
                                                       (hi[0] + c, hi[1] + c), (lo[0] - c, hi[1] + c))])
    rc = servo_radius(params, servo) + pulley_cavity_margin(params)
    a = np.linspace(0.0, 2.0 * math.pi, 24, endpoint=False)
    h = params.cad.servo_pulley_width / 2.0 + c
    shapes.append([(rc * math.cos(t), rc * math.sin(t), -h) for t in a])
    out = []
    for corners in shapes:
        pts = []
        for v in corners:
            p = T[:3, :3] @ np.array(v) + T[:3, 3]
            pts.append(p[:2])
            if T[2, 2] > 1e-9:
                pts.append((p + T[:3, 2] * max((z_top - p[2]) / T[2, 2], 0.0))[:2])
        pts = np.array(pts)
        out.append(pts[convex_hull_2d(pts)])
    return out


def convex_hull_2d(points) -> np.ndarray:
    """The indices of the vertices of the convex hull of 2-D points (n, 2), counter-clockwise from
    the lowest x (then y); points on its edges left out (Andrew's monotone chain). numpy only: the
    forearm's servo row is laid out on every build, and scipy.spatial costs 0.6 s to import.
    ValueError when the points span no area."""
    P = np.asarray(points, dtype=float)

    def turn(o: int, a: int, b: int) -> float:     # > 0: o -> a -> b turns counter-clockwise
        return float((P[a, 0] - P[o, 0]) * (P[b, 1] - P[o, 1]) - (P[a, 1] - P[o, 1]) * (P[b, 0] - P[o, 0]))

    order = [int(i) for i in np.lexsort((P[:, 1], P[:, 0]))]
    chains = []
    for seq in (order, order[::-1]):                # the lower chain, then the upper one
        chain_: list[int] = []
        for i in seq:
            while len(chain_) >= 2 and turn(chain_[-2], chain_[-1], i) <= 0.0:
                chain_.pop()
            chain_.append(i)
        chains.append(chain_[:-1])
    hull = chains[0] + chains[1]
    if len(hull) < 3:
        raise ValueError(f"convex_hull_2d: {len(P)} points span no area")
    return np.array(hull)


def servo_gaps(params, servos: dict[int, np.ndarray]) -> list[float]:
    """Between each pair of neighbouring servos of a row (T_palm_servo), a lower bound (m) of the
    distance between their outlines (:func:`_outlines`: body, ears and pulley cavity with clearance,
    swept along the shaft to the module's top): the largest gap between their projections on an
    edge normal of either (separating axes)."""
    row = sorted(servos.items(), key=lambda kT: kT[1][0, 3])
    outlines = [[(P, _edge_normals(P)) for P in _outlines(params, T, k)] for k, T in row]
    gaps = []
    for A, B in zip(outlines, outlines[1:]):
        g = np.inf
        for P, nP in A:
            for Q, nQ in B:
                n = np.vstack([nP, nQ])             # every edge normal of either: the axes
                p, q = P @ n.T, Q @ n.T             # projections, one column per axis
                best = np.maximum(q.min(axis=0) - p.max(axis=0), p.min(axis=0) - q.max(axis=0)).max()
                g = min(g, float(best))
        gaps.append(float(g))
    return gaps


def _edge_normals(R: np.ndarray) -> np.ndarray:
    """The unit normals (k, 2) of a closed polygon's k edges (its vertices in order)."""
    e = np.roll(R, -1, axis=0) - R
    n = np.c_[-e[:, 1], e[:, 0]]
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def _ring(T0: np.ndarray, s: float, r: float, n: int = 24) -> np.ndarray:
    """Points (n, 3) of the circle of radius r about the CMC axis, s along it (palm frame)."""
    a = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    pts = np.c_[r * np.cos(a), r * np.sin(a), np.full_like(a, s), np.ones_like(a)]
    return (T0 @ pts.T).T[:, :3]


def thenar_points(params, T0: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Points (m, palm frame, right hand) of what the palm's thenar holds round the CMC axis
    (:func:`thenar`), each grown by a palm wall: ``journal`` (the column's bore from the palmar face
    to the pulley's cavity), ``cavity`` (the CMC pulley's cavity) and ``turn`` (the thumb drive's
    turn onto the axis). The palm's thenar block is their bounding box, clipped to the palm's faces;
    only the journal and the turn set how far radial it reaches (the cavity is cut where it reaches
    past that: open, as its slot toward servo 6 is).
    ``T0``: another CMC placement than the file's (T_palm_cmc_base at rest)."""
    if T0 is None:
        T0, t = T_palm_thumb_cmc_base(params), thenar(params)
    else:
        t = thenar_layout(params, T0)
    w = params.palm.wall
    rj = t["journal_r"] + w
    return {"journal": np.vstack([_ring(T0, s, rj) for s in (t["face"], t["pulley"] - t["cavity_h"])]),
            "cavity": np.vstack([_ring(T0, s, t["cavity_r"] + w) for s in (t["pulley"] - t["cavity_h"] - w,
                                                                          t["ceiling"] + w)]),
            "turn": np.vstack([_ring(T0, s, tendon_relief(params) + w) for s in (t["turn"] - tendon_relief(params) - w,
                                                                                  t["turn"] + tendon_relief(params) + w)])}


def palm_back(params) -> float:
    """y (m, palm frame) of the palm's back face: the wrist crease, or the back of the thenar
    (:func:`thenar_points`) where that reaches further back (the palm's metacarpal block reaches
    back as far, so that the finger drives stay in channels up to the forearm module)."""
    back = min(float(v[:, 1].min()) for v in thenar_points(params).values())
    return min(wrist_y(params), back)


def forearm_front(params) -> float:
    """y (m, palm frame) of the forearm module's front face: a hole clearance behind the palm's
    back face (:func:`palm_back`)."""
    return palm_back(params) - params.print.hole_clearance


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
            return T
        if ln.segment == "cmc_pulley":
            return T_cmc_base_pulley(params)
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
