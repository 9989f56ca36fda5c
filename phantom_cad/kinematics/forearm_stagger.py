"""Two staggered rows of the six servos that fit within a human forearm's breadth
(:func:`staggered_servos`; :func:`two_rows` says whether they fit: where they do, the forearm
module is built from them, ``forearm_layout.forearm_rows``). numpy only; frames as in
:mod:`.frames`."""

from __future__ import annotations

import math

import numpy as np

from .frames import T_palm_thumb_cmc_base, servo_radius, tendon_relief
from .hand_params import HandParams
from .memo import memoised
from .servo_geometry import (drive_clearances_of, envelope_width, aimed_servo, coplanar_servo, forearm_front, forearm_top,
                             forearm_width_limit, servo_envelope, servo_target)
from .topology import SERVOS


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
    and a palm wall (:func:`.forearm_layout.drive_clearances`), so that it passes over the front
    row. The gaps in plan and between the rows are the pockets' (:func:`_pocket_points`): servo 6,
    tilted, drops in straight along z with its pulley on, a raised servo along its shaft. Memoised
    (read-only): the search takes about a second."""
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
        return min(drive_clearances_of(params, {**others, k: T}, only=k).values())

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


def two_rows(params: HandParams) -> bool:
    """Whether two staggered rows (:func:`staggered_servos`) fit within a human forearm: their
    width, measured as :func:`.forearm_layout.forearm_width` measures the module's, at most
    :func:`forearm_width_limit` (from about 182 mm of hand length: the servo does not scale)."""
    return envelope_width(params, staggered_servos(params)) <= forearm_width_limit(params)
