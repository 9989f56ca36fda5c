"""The forearm module's servo row: where each of the six servos sits (the iterative row solver),
their bodies, envelopes and the gaps between them, the drives' clearances to the other servos,
the module's width and the limit a human forearm sets, and the palm's back and ulnar faces the row
sets; the two staggered rows that fit within that limit (:func:`staggered_servos`, which the
module is not built from). numpy only; frames as in :mod:`.frames`."""

from __future__ import annotations

import math

import numpy as np

from .dimensions import printed_hole, servo_screw_offset
from .frames import (T_palm_socket, T_palm_thumb_cmc_base, pulley_cavity_margin, servo_radius, socket_tendon_point,
                     socket_x, tendon_height, tendon_relief, trans, wrist_y)
from .hand_params import HandParams
from .memo import memoised
from .thenar import T_cmc_base_pulley, thenar, thenar_axis_point, thenar_points
from .topology import CMC_SERVO, FINGERS, SERVOS, chain


def metacarpal_x(params: HandParams) -> tuple[float, float]:
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


def T_palm_servo(params: HandParams, servo: int) -> np.ndarray:
    """Servo output frame (see module doc) of servo ``servo`` (0-based index, topology.SERVOS), in
    the forearm module's row (:func:`forearm_servos`)."""
    return forearm_servos(params)[servo].copy()


def cmc_loop_direction(params: HandParams) -> float:
    """Polar angle (rad, the CMC pulley's frame at rest, right hand) of the direction from servo
    6's pulley to the CMC pulley (they lie in one plane, :func:`coplanar_servo`): the loop's
    strands reach the CMC pulley at that angle -+ 90 deg."""
    T = T_palm_thumb_cmc_base(params) @ T_cmc_base_pulley(params)
    d = T[:3, 3] - T_palm_servo(params, CMC_SERVO)[:3, 3]
    v = T[:3, :3].T @ d
    return math.atan2(v[1], v[0])


def servo_boxes(params: HandParams) -> dict[str, tuple[np.ndarray, np.ndarray]]:
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


_ENVELOPE: dict = {}


def servo_envelope(params: HandParams, servo: int) -> np.ndarray:
    """Points (m, servo frame) whose hull holds a servo with its clearance: the corners of its body
    and ears and the rim of its pulley's cavity, grown by a hole clearance. Memoised (read-only)."""
    return memoised(_ENVELOPE, (params.digest, servo), lambda: _servo_envelope(params, servo), cap=96)


def _servo_envelope(params: HandParams, servo: int) -> np.ndarray:
    c = params.print.hole_clearance
    pts = [box_corners(lo - c, hi + c) for lo, hi in servo_boxes(params).values()]
    rc = servo_radius(params, servo) + pulley_cavity_margin(params)
    h = params.cad.servo_pulley_width / 2.0 + c
    a = np.linspace(0.0, 2.0 * math.pi, 48, endpoint=False)
    for z in (-h, h):
        pts.append(np.c_[rc * np.cos(a), rc * np.sin(a), np.full_like(a, z)])
    return np.vstack(pts)


def forearm_pitch(params: HandParams, a: int | None = None, b: int | None = None) -> float:
    """Least x spacing (m) of two neighbouring servos ``a`` and ``b`` in the forearm module (by
    default the largest of any two): the wider of their two pulley cavities' radii and a servo body
    with its clearances, and a palm wall (:func:`forearm_servos` widens it where the servos, each
    turned toward its target, would come closer than a wall)."""
    m = pulley_cavity_margin(params)
    r = sorted(servo_radius(params, s.index) for s in SERVOS)
    ra, rb = (r[-1], r[-2]) if a is None else (servo_radius(params, a), servo_radius(params, b))
    body = params.servo.body[1] + 2.0 * params.print.hole_clearance
    return max(ra + rb + 2.0 * m, body) + params.palm.wall


def servo_target(params: HandParams, servo: int) -> np.ndarray:
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


def forearm_servos(params: HandParams) -> dict[int, np.ndarray]:
    """T_palm_servo (m, right hand) of every servo in the forearm module: two staggered rows
    (:func:`staggered_servos`) where :func:`forearm_rows` is 2, one row (:func:`row_servos`)
    otherwise. Read-only."""
    return staggered_servos(params) if forearm_rows(params) == 2 else row_servos(params)


def forearm_rows(params: HandParams) -> int:
    """How many rows the forearm module holds its servos in: one on every hand (:func:`two_rows`
    says where two would fit a human forearm; the module is not built from them, docs/sizing.md)."""
    return 1


def drops_straight(params: HandParams, servo: int) -> bool:
    """Whether a servo's pocket and pulley cavity open straight up the module's z rather than along
    its shaft: servo 6 in the two rows (tilted with the CMC axis: along its shaft its pocket would
    cut into the middle servo's beside it; tilted across its ears, its flange pilots stay whole)."""
    return SERVOS[servo].drive == "loop" and forearm_rows(params) == 2


def row_servos(params: HandParams) -> dict[int, np.ndarray]:
    """T_palm_servo (m, right hand) of the six servos in one row across the
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
    return memoised(_FOREARM, params.digest, lambda: _row_servos(params), cap=16)


def two_rows(params: HandParams) -> bool:
    """Whether two staggered rows (:func:`staggered_servos`) fit within a human forearm: their
    width, measured as :func:`forearm_width` measures the module's, at most
    :func:`forearm_width_limit` (from about 182 mm of hand length: the servo does not scale)."""
    return _width(params, staggered_servos(params)) <= forearm_width_limit(params)


def _row_servos(params: HandParams) -> dict[int, np.ndarray]:
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


def drive_runs(params: HandParams) -> list[tuple[int, float, np.ndarray, np.ndarray]]:
    """Every drive's straight run through the forearm module: (servo, side, start, end), the start
    where it leaves its pulley (servo frame (side r, 0, 0): a tendon servo's drive at -x, the CMC
    loop's strands at -x and +x), the end where it crosses the module's front face
    (:func:`forearm_front`) along the servo's y (m, palm frame, right hand)."""
    return _drive_runs(params, forearm_servos(params))


def _drive_runs(params: HandParams, servos: dict[int, np.ndarray]) -> list[tuple[int, float, np.ndarray, np.ndarray]]:
    out = []
    y1 = forearm_front(params)
    for k, T in sorted(servos.items()):
        for side in ((-1.0, 1.0) if SERVOS[k].drive == "loop" else (-1.0,)):
            p = T[:3, 3] + side * servo_radius(params, k) * T[:3, 0]
            u = T[:3, 1]
            out.append((k, side, p, p + u * (y1 - p[1]) / u[1]))
    return out


def _convex_min(f, rounds: int = 5, n: int = 33) -> float:
    """The least value on [0, 1] of a convex function of one variable, evaluated on arrays: n
    samples, then n again between the least one's neighbours (the least lies between them), ``rounds``
    times (the bracket shrinks to 2 / (n - 1) of itself each time: a millionth of the run)."""
    lo, hi = 0.0, 1.0
    best = math.inf
    for _ in range(rounds):
        t = np.linspace(lo, hi, n)
        v = f(t)
        i = int(np.argmin(v))
        best = min(best, float(v[i]))
        lo, hi = float(t[max(i - 1, 0)]), float(t[min(i + 1, n - 1)])
    return best


def drive_clearances(params: HandParams) -> dict[tuple[int, float, int], float]:
    """The least distance (m) from each drive's run through the module (:func:`drive_runs`) to
    every other servo's envelope: its body and its ears grown by a hole clearance
    (:func:`servo_boxes`) and its pulley's cavity (a cylinder of the pulley's radius and the
    cavity margin, a pulley width and two hole clearances tall), keyed (servo, side, other servo).
    A point's distance to each of the three is convex along the run: each one's least value by
    shrinking brackets (:func:`_convex_min`), the least of the three."""
    return _drive_clearances(params, forearm_servos(params))


def _drive_clearances(params: HandParams, servos: dict[int, np.ndarray],
                      only: int | None = None) -> dict[tuple[int, float, int], float]:
    c = params.print.hole_clearance
    h = params.cad.servo_pulley_width / 2.0 + c
    boxes = [(lo - c, hi + c) for lo, hi in servo_boxes(params).values()]
    out = {}
    for k, side, p0, p1 in _drive_runs(params, servos):
        if only is not None and k != only:
            continue
        for j, T in sorted(servos.items()):
            if j == k:
                continue
            R = T[:3, :3].T
            a, b = R @ (p0 - T[:3, 3]), R @ (p1 - T[:3, 3])
            rc = servo_radius(params, j) + pulley_cavity_margin(params)

            def to_box(t: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
                q = a + (b - a) * t[:, None]
                return np.linalg.norm(np.maximum(np.maximum(lo - q, q - hi), 0.0), axis=1)

            def to_cavity(t: np.ndarray) -> np.ndarray:
                q = a + (b - a) * t[:, None]
                return np.hypot(np.maximum(np.hypot(q[:, 0], q[:, 1]) - rc, 0.0), np.maximum(np.abs(q[:, 2]) - h, 0.0))

            out[(k, side, j)] = min([_convex_min(to_cavity)] +
                                    [_convex_min(lambda t, lo=lo, hi=hi: to_box(t, lo, hi)) for lo, hi in boxes])
    return out


def raised_servo(C: np.ndarray, E: np.ndarray, r: float) -> np.ndarray:
    """Servo frame at pulley centre C turned about its shaft as :func:`aimed_servo` turns it in
    plan, then tilted about its x (kept level) so that the drive, leaving the pulley at (-r, 0, 0)
    along +y, runs straight through E where C and E stand at different heights (the pulley's plane
    holds the drive)."""
    T = aimed_servo(np.array([C[0], C[1], E[2]]), E, r)
    x, h = T[:3, 0], T[:3, 1]
    d = E - (C - r * x)
    a = math.atan2(float(d[2]), float(d[:2] @ h[:2]))
    y = math.cos(a) * h + math.sin(a) * np.array([0.0, 0.0, 1.0])
    T[:3, 1], T[:3, 2], T[:3, 3] = y, np.cross(x, y), C
    return T


def staggered_rows(params: HandParams) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(front, rear): the servos of :func:`staggered_servos`' two rows, each radial to ulnar. In the
    order of their targets (servo 6, thumb, index, middle, ring, pinky) the front row takes the
    first, fourth and sixth (servo 6's loop runs at its own height, in the CMC pulley's plane), the
    raised rear row the others: every rear drive passes over the front row between the front
    drives either side of it, so no two drives cross."""
    targets = {s.index: servo_target(params, s.index) for s in SERVOS}
    order = sorted(targets, key=lambda k: (targets[k][0] + (0.0 if SERVOS[k].drive == "loop" else
                                                              servo_radius(params, k)), k))
    return (order[0], order[3], order[5]), (order[1], order[2], order[4])


def _pocket_points(params: HandParams, T: np.ndarray, k: int) -> np.ndarray:
    """Points (3, n; m, palm frame) whose hull in plan holds servo ``k``'s pocket placed at T: its
    envelope (:func:`servo_envelope`) swept straight up (servo 6), or along its shaft up to the
    module's top (:func:`forearm_top`; a raised servo tilts with its drive and drops in along its
    shaft, which keeps the material under its flange pilots)."""
    P = T[:3, :3] @ servo_envelope(params, k).T + T[:3, 3:4]
    if SERVOS[k].drive == "loop" or T[2, 2] >= 1.0 - 1e-12:
        return P
    a = T[:3, 2:3]
    return np.hstack([P, P + a * ((forearm_top(params) - P[2]) / a[2, 0])])


def _plan_gap(params: HandParams, Ta: np.ndarray, a: int, Tb: np.ndarray, b: int) -> float:
    """The distance (m) between two placed servos' pockets seen from the dorsal side (the convex
    hulls in plan of :func:`_pocket_points`); negative where they overlap (less their overlap along the axis that
    separates them best). For convex sets it is the largest over directions n of
    min(B . n) - max(A . n): the best of 256 directions, then 33 between its neighbours, five times
    (the function has one maximum there)."""
    P, Q = [_pocket_points(params, T, k)[:2] for T, k in ((Ta, a), (Tb, b))]

    def gap(t: np.ndarray) -> np.ndarray:
        n = np.vstack([np.cos(t), np.sin(t)])
        return (n.T @ Q).min(axis=1) - (n.T @ P).max(axis=1)

    step = 2.0 * math.pi / 256
    t = np.arange(256) * step
    best = -math.inf
    for _ in range(6):
        v = gap(t)
        i = int(np.argmax(v))
        best = max(best, float(v[i]))
        t = t[i] + np.linspace(-step, step, 33)
        step = 2.0 * step / 32
    return best


def _envelope_x(params: HandParams, T: np.ndarray, k: int) -> tuple[float, float]:
    x = _pocket_points(params, T, k)[0]
    return float(x.min()), float(x.max())


def _packed(place, left: float, lo: float, hi: float) -> float:
    """The least x in [lo, hi] at which ``place(x)``'s gap to its left neighbour is ``left`` or
    more (bisection: the gap grows with x)."""
    if place(lo) >= left:
        return lo
    for _ in range(26):
        mid = (lo + hi) / 2.0
        lo, hi = (lo, mid) if place(mid) >= left else (mid, hi)
    return hi


_STAGGERED: dict = {}


def staggered_servos(params: HandParams) -> dict[int, np.ndarray]:
    """T_palm_servo (m, right hand) of the six servos in two staggered rows (:func:`staggered_rows`)
    within a forearm's breadth (76.9 mm wide on the default hand, :func:`forearm_width_limit` 80 mm).
    The front row as far forward as the servos' envelopes allow (:func:`forearm_front`, as the one
    row stands): servo 6 behind the CMC pulley (at its x), its shaft parallel to the CMC axis and its
    pulley in the CMC pulley's plane (:func:`coplanar_servo`), then the middle and the pinky servos,
    each a palm wall ulnar of the one before in plan (:func:`_plan_gap`), at their targets' height
    and aimed at them (:func:`aimed_servo`). The rear row's pockets a palm wall behind the front
    row's: the thumb's servo flush with servo 6's radial side, or as little ulnar of it as lets
    its drive clear servo 6's tilted pulley, then the index and the ring servos a wall apart; each
    raised (:func:`raised_servo`: its drive slopes to its target) to the lowest height, its pulley
    inside the module, at which its drive clears every other servo's envelope by half a tendon hole
    and a palm wall (:func:`drive_clearances`), so that it passes over the front row. The gaps in
    plan and between the rows are the pockets' (:func:`_pocket_points`): servo 6, tilted, drops in
    straight along z with its pulley on, a raised servo along its shaft. Memoised (read-only): the
    search takes about a second."""
    return memoised(_STAGGERED, params.digest, lambda: _staggered_servos(params), cap=16)


def _staggered_servos(params: HandParams) -> dict[int, np.ndarray]:
    front_ids, rear_ids = staggered_rows(params)
    targets = {s.index: servo_target(params, s.index) for s in SERVOS}
    radius = {k: servo_radius(params, k) for k in targets}
    axis = T_palm_thumb_cmc_base(params)[:3, 2]
    w = params.palm.wall
    span = 4.0 * params.servo.body[0]           # room enough for any packing search

    def frame(k: int, x: float, y: float, z: float | None = None) -> np.ndarray:
        if SERVOS[k].drive == "loop":
            return coplanar_servo(x, y, targets[k], axis)
        C = np.array([x, y, targets[k][2] if z is None else z])
        return raised_servo(C, targets[k], radius[k])

    def reach(T: np.ndarray, k: int, sign: float) -> float:
        y = _pocket_points(params, T, k)[1] - T[1, 3]
        return float(y.max() if sign > 0 else y.min())

    out: dict[int, np.ndarray] = {}
    # the front row: as far forward as its envelopes allow (a servo's turn depends weakly on y)
    y = forearm_front(params) - w
    x0 = float(targets[front_ids[0]][0])
    for _ in range(6):
        row = {front_ids[0]: frame(front_ids[0], x0, y)}
        prev = front_ids[0]
        for k in front_ids[1:]:
            x = _packed(lambda x: _plan_gap(params, row[prev], prev, frame(k, x, y), k), w,
                        row[prev][0, 3], row[prev][0, 3] + span)
            row[k], prev = frame(k, x, y), k
        y_new = forearm_front(params) - w - max(reach(T, k, 1.0) for k, T in row.items())
        if abs(y_new - y) < 1e-9:
            break
        y = y_new
    out.update(row)
    left = min(_envelope_x(params, T, k)[0] for k, T in row.items())
    back = min(reach(T, k, -1.0) + T[1, 3] for k, T in row.items()) - w
    # the rear row: its radial servo flush with the front row's radial side, or as little ulnar
    # of it as lets its drive clear the front row from the highest its pulley may stand (inside the
    # module); the others packed a wall apart; each raised as little as lets its drive clear every
    # other servo; packed again at those heights (a raised servo's tilt turns its outline a little)
    z_top = forearm_top(params) - params.cad.servo_pulley_width / 2.0 - params.print.hole_clearance
    need = tendon_relief(params) / 2.0 + w
    first = rear_ids[0]
    z = {k: float(targets[k][2]) for k in rear_ids}

    def clears(k: int, T: np.ndarray, others: dict[int, np.ndarray]) -> float:
        return min(_drive_clearances(params, {**others, k: T}, only=k).values())

    def pack(yr: float, x_first: float | None) -> dict[int, np.ndarray]:
        rear: dict[int, np.ndarray] = {}
        if x_first is None:
            x_first = _packed(lambda x: _envelope_x(params, frame(first, x, yr, z[first]), first)[0] - left, 0.0,
                              left - span, left + span)
        if clears(first, frame(first, x_first, yr, z_top), out) < need:
            x_first = _packed(lambda x: clears(first, frame(first, x, yr, z_top), out), need,
                              x_first, x_first + span)
        rear[first] = frame(first, x_first, yr, z[first])
        prev = first
        for k in rear_ids[1:]:
            x = _packed(lambda x: _plan_gap(params, rear[prev], prev, frame(k, x, yr, z[k]), k), w,
                        rear[prev][0, 3], rear[prev][0, 3] + span)
            rear[k], prev = frame(k, x, yr, z[k]), k
        return rear

    yr, x_first = back, None
    for _ in range(2):
        for _ in range(6):
            rear = pack(yr, x_first)
            y_new = back - max(reach(T, k, 1.0) for k, T in rear.items())
            if abs(y_new - yr) < 1e-9:
                break
            yr = y_new
        x_first = float(rear[first][0, 3])
        for k in rear_ids:
            x = float(rear[k][0, 3])
            lo, hi = float(targets[k][2]), max(z_top, float(targets[k][2]))
            if clears(k, frame(k, x, yr, lo), {**out, **rear}) < need:
                for _ in range(22):
                    mid = (lo + hi) / 2.0
                    lo, hi = (lo, mid) if clears(k, frame(k, x, yr, mid), {**out, **rear}) >= need else (mid, hi)
                lo = hi
            z[k] = lo
            rear[k] = frame(k, x, yr, lo)
    # the raised servos' tilts move their fronts a little: the row back to a wall behind the front
    for _ in range(6):
        y_new = back - max(reach(T, k, 1.0) for k, T in rear.items())
        if abs(y_new - yr) < 1e-12:
            break
        yr = y_new
        rear = {k: frame(k, float(T[0, 3]), yr, z[k]) for k, T in rear.items()}
    out.update(rear)
    return out


def _outlines(params: HandParams, T: np.ndarray, servo: int) -> list[np.ndarray]:
    """The xy outlines (palm frame, counter-clockwise) of servo ``servo``'s body, ears and pulley
    cavity, grown by a clearance, placed by T, with the pockets the module cuts for them: open along
    the shaft up to the module's top (a wall above the palm's dorsal face), so a tilted shaft sweeps
    them sideways (the convex hull of the outline at the servo and at the top)."""
    c = params.print.hole_clearance
    z_top = forearm_top(params)
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


def servo_gaps(params: HandParams, servos: dict[int, np.ndarray]) -> list[float]:
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


def heel_box(params: HandParams) -> tuple[np.ndarray, np.ndarray] | None:
    """(lo, hi) (m, palm frame, right hand) of the palm's heel, under the metacarpal block
    (:func:`metacarpal_x`) from the palm's back face (:func:`palm_back`) ``palm.heel_length_mm``
    forward, ``palm.heel_height_mm`` below the palmar face (``cad.parts.palm.Palm.heel`` builds it);
    None for a flat palm."""
    pm = params.palm
    if pm.heel_height <= 0.0:
        return None
    x0, x1 = metacarpal_x(params)
    y0 = palm_back(params)
    return (np.array([x0, y0, -pm.thickness / 2.0 - pm.heel_height]),
            np.array([x1, y0 + pm.heel_length, -pm.thickness / 2.0]))


def heel_gap(params: HandParams) -> float:
    """The least distance (m) from the palm's heel (:func:`heel_box`) to the CMC base at rest (its
    hub: thumb.width_mm across, thumb.thickness_mm thick about the CMC axis; its column up the axis
    to the palm's palmar face; the metacarpal's arm, as wide and thick, out to the MP axis);
    negative where they overlap; inf for a flat palm. Their surfaces are sampled; a point's distance
    to the box is the largest of its distances beyond the box's faces (a lower bound)."""
    box = heel_box(params)
    if box is None:
        return math.inf
    th = params.thumb
    t = thenar(params)
    W, T, L = th.width, th.thickness, th.metacarpal
    a = np.linspace(0.0, 2.0 * math.pi, 48, endpoint=False)
    pts = [np.c_[r * np.cos(a), r * np.sin(a), np.full_like(a, s)]
           for r, s0, s1 in ((W / 2.0, -T / 2.0, T / 2.0), (t["column_r"], T / 2.0, max(t["face"], T / 2.0)))
           for s in np.linspace(s0, s1, 9)]
    u = np.linspace(0.0, 1.0, 13)
    g = np.array([(x, y, z) for x in -W / 2.0 + W * u for y in L * u for z in (-T / 2.0, T / 2.0)] +
                 [(x, y, z) for x in (-W / 2.0, W / 2.0) for y in L * u for z in -T / 2.0 + T * u])
    local = np.vstack(pts + [g])
    T0 = T_palm_thumb_cmc_base(params)
    P = local @ T0[:3, :3].T + T0[:3, 3]
    lo, hi = box
    return float(np.maximum(lo - P, P - hi).max(axis=1).min())


#: the breadth (m) of a human forearm near the wrist (55-65 mm) with room for a shell, which the
#: forearm module should stay within at the reference hand (:data:`REFERENCE_HAND_LENGTH`), scaled
#: with the hand length (docs/sizing.md)
FOREARM_BREADTH = 0.080
#: the hand length (m) :data:`FOREARM_BREADTH` is given at: the default hand's (the paper's)
REFERENCE_HAND_LENGTH = 0.189


def forearm_points(params: HandParams) -> np.ndarray:
    """Every servo's envelope (:func:`servo_envelope`) placed in the forearm module (m, palm frame,
    right hand), stacked (n, 3): the module's block is one palm wall around them."""
    return _points(params, forearm_servos(params))


def _points(params: HandParams, servos: dict[int, np.ndarray]) -> np.ndarray:
    pts = []
    for k, T in servos.items():
        env = servo_envelope(params, k)
        pts.append((T[:3, :3] @ env.T).T + T[:3, 3])
    return np.vstack(pts)


def forearm_width(params: HandParams) -> float:
    """The forearm module's width (m, across the forearm, palm x): its servos' envelopes
    (:func:`forearm_points`) across and a palm wall each side (``cad.parts.wrist.forearm_block``)."""
    return _width(params, forearm_servos(params))


def _width(params: HandParams, servos: dict[int, np.ndarray]) -> float:
    x = _points(params, servos)[:, 0]
    return float(x.max() - x.min()) + 2.0 * params.palm.wall


def forearm_width_limit(params: HandParams) -> float:
    """The widest (m) a forearm module within a human forearm may be for this hand:
    :data:`FOREARM_BREADTH` scaled with the hand length."""
    return FOREARM_BREADTH * params.hand_length / REFERENCE_HAND_LENGTH


def forearm_top(params: HandParams) -> float:
    """z (m, palm frame) of the forearm module's top: a palm wall above the palm's dorsal face
    (flush with the tab that screws it onto the palm)."""
    return params.palm.thickness / 2.0 + params.palm.wall


def pilot_headroom(params: HandParams) -> tuple[float, int]:
    """(headroom (m), servo index): the least height of the module's top (:func:`forearm_top`) above
    the highest point of a flange screw pilot's opening (mid-ear, ``dimensions.servo_screw_offset``,
    on the ears' underside, a circle tilted with its servo's shaft), and whose. Negative: the pilot
    starts above the module and its screw does not get its thread's full depth in the module (servo
    6 is tilted with the CMC axis and set as high as its pulley's plane: a wide body moves it radial
    and up)."""
    sv, pr = params.servo, params.print
    e = servo_screw_offset(sv.body[0], sv.flange_span)
    z = servo_boxes(params)["ears"][0][2]
    y0 = -params.cad.servo_shaft_offset
    r = printed_hole(pr.screw_pilot_ratio * params.hardware.screw_diameter, pr.hole_compensation) / 2.0
    top = forearm_top(params)
    best = (math.inf, -1)
    for k, T in forearm_servos(params).items():
        rim = r * math.sqrt(max(1.0 - float(T[2, 2]) ** 2, 0.0))
        for side in (-1.0, 1.0):
            h = top - (float((T @ np.array([0.0, y0 + side * e, z, 1.0]))[2]) + rim)
            if h < best[0]:
                best = (h, k)
    return best


def palm_back(params: HandParams) -> float:
    """y (m, palm frame) of the palm's back face: the wrist crease, or the back of the thenar
    (:func:`thenar_points`) where that reaches further back (the palm's metacarpal block reaches
    back as far, so that the finger drives stay in channels up to the forearm module)."""
    back = min(float(v[:, 1].min()) for v in thenar_points(params).values())
    return min(wrist_y(params), back)


def forearm_front(params: HandParams) -> float:
    """y (m, palm frame) of the forearm module's front face: a hole clearance behind the palm's
    back face (:func:`palm_back`)."""
    return palm_back(params) - params.print.hole_clearance


def T_palm_forearm(params: HandParams) -> np.ndarray:
    """The forearm module's frame: the palm's axes, origin on the wrist crease at the middle of the
    servo row, in the palm's mid-plane."""
    xs = [T[0, 3] for T in forearm_servos(params).values()]
    return trans((min(xs) + max(xs)) / 2.0, wrist_y(params), 0.0)
