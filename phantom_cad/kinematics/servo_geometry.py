"""The geometry of the forearm module's servos, whatever layout places them: a servo's body, ears
and envelope, the pitch two neighbours need, the point its cable heads for and the frames that aim
a servo at it, the drives' runs and clearances and the gaps between servos for servos placed as
given, the module's front face, top and width limit, and the palm's back face the module stands
behind. Places no servo. numpy only; frames as in :mod:`.frames`."""

from __future__ import annotations

import math

import numpy as np

from .frames import pulley_cavity_margin, servo_radius, socket_tendon_point, wrist_y
from .hand_params import HandParams
from .memo import memoised
from .thenar import thenar, thenar_axis_point, thenar_points
from .topology import FINGERS, SERVOS


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
    with its clearances, and a palm wall (:func:`.forearm_layout.forearm_servos` widens it where
    the servos, each turned toward its target, would come closer than a wall)."""
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


def drive_runs_of(params: HandParams, servos: dict[int, np.ndarray]) -> list[tuple[int, float, np.ndarray, np.ndarray]]:
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


def drive_clearances_of(params: HandParams, servos: dict[int, np.ndarray],
                      only: int | None = None) -> dict[tuple[int, float, int], float]:
    c = params.print.hole_clearance
    h = params.cad.servo_pulley_width / 2.0 + c
    boxes = [(lo - c, hi + c) for lo, hi in servo_boxes(params).values()]
    out = {}
    for k, side, p0, p1 in drive_runs_of(params, servos):
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


#: the breadth (m) of a human forearm near the wrist (55-65 mm) with room for a shell, which the
#: forearm module should stay within at the reference hand (:data:`REFERENCE_HAND_LENGTH`), scaled
#: with the hand length (docs/sizing.md)
FOREARM_BREADTH = 0.080


#: the hand length (m) :data:`FOREARM_BREADTH` is given at: the default hand's (the paper's)
REFERENCE_HAND_LENGTH = 0.189


def envelope_points(params: HandParams, servos: dict[int, np.ndarray]) -> np.ndarray:
    pts = []
    for k, T in servos.items():
        env = servo_envelope(params, k)
        pts.append((T[:3, :3] @ env.T).T + T[:3, 3])
    return np.vstack(pts)


def envelope_width(params: HandParams, servos: dict[int, np.ndarray]) -> float:
    x = envelope_points(params, servos)[:, 0]
    return float(x.max() - x.min()) + 2.0 * params.palm.wall


def forearm_width_limit(params: HandParams) -> float:
    """The widest (m) a forearm module within a human forearm may be for this hand:
    :data:`FOREARM_BREADTH` scaled with the hand length."""
    return FOREARM_BREADTH * params.hand_length / REFERENCE_HAND_LENGTH


def forearm_top(params: HandParams) -> float:
    """z (m, palm frame) of the forearm module's top: a palm wall above the palm's dorsal face
    (flush with the tab that screws it onto the palm)."""
    return params.palm.thickness / 2.0 + params.palm.wall


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
