"""The forearm module's servos as placed: the one row the module is built from (the iterative row
solver), the switch between it and the two staggered rows (:mod:`.forearm_stagger`), each servo's
frame, and what the placed servos set: the palm's ulnar face, the CMC loop's direction, the drives'
runs and clearances, the palm's heel, the module's points, block, width, flange pilots' headroom
and frame, and the gaps from the heel and the block to the CMC base. The servo geometry both
layouts share is :mod:`.servo_geometry`'s. numpy only; frames as in :mod:`.frames`."""

from __future__ import annotations

import math

import numpy as np

from .cmc_base_gap import cmc_base_gap
from .dimensions import printed_hole, servo_screw_offset
from .forearm_stagger import staggered_servos, two_rows
from .frames import (T_palm_socket, T_palm_thumb_cmc_base, limiter_x_extent, servo_radius, socket_x, tendon_height, tendon_relief, trans,
                     wrist_y)
from .hand_params import HandParams
from .memo import memoised
from .servo_geometry import (drive_clearances_of, drive_runs_of, envelope_points, envelope_width, aimed_servo, coplanar_servo,
                             forearm_front, forearm_pitch, forearm_top, palm_back, servo_boxes, servo_envelope,
                             servo_gaps, servo_target, spaced)
from .thenar import T_cmc_base_pulley, thenar_points
from .topology import CMC_SERVO, FINGERS, SERVOS, chain


def metacarpal_x(params: HandParams) -> tuple[float, float]:
    """x extent (m, palm frame, right hand) of the palm's metacarpal block: across the sockets
    (:func:`socket_x`), ulnar over the flexion limiter rails (:func:`limiter_x_extent`: the arc
    turns the pinky's rails ulnar past its socket), and far enough that every finger drive's
    channel keeps a wall to the block's ulnar face where the drive runs ulnar toward its servo
    (from its exit under the socket to the palm's back face). The palm's ulnar face; its radial
    side is the thenar's."""
    x0, x1 = socket_x(params)
    x1 = max(x1, *(limiter_x_extent(params, f)[1] for f in FINGERS))
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


def forearm_servos(params: HandParams) -> dict[int, np.ndarray]:
    """T_palm_servo (m, right hand) of every servo in the forearm module: two staggered rows
    (:func:`staggered_servos`) where :func:`forearm_rows` is 2, one row (:func:`row_servos`)
    otherwise. Read-only."""
    return staggered_servos(params) if forearm_rows(params) == 2 else row_servos(params)


def forearm_rows(params: HandParams) -> int:
    """How many rows the forearm module holds its servos in: two staggered rows where they fit
    within a human forearm (:func:`.forearm_stagger.two_rows`), one otherwise."""
    return 2 if two_rows(params) else 1


def drops_straight(params: HandParams, servo: int) -> bool:
    """Whether a servo's pocket and pulley cavity open straight up the module's z rather than along
    its shaft: servo 6 in the two rows (tilted with the CMC axis: along its shaft its pocket would
    cut into the middle servo's beside it; tilted across its ears, its flange pilots stay whole)."""
    return SERVOS[servo].drive == "loop" and forearm_rows(params) == 2


_FOREARM: dict = {}


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
    return drive_runs_of(params, forearm_servos(params))


def drive_clearances(params: HandParams) -> dict[tuple[int, float, int], float]:
    """The least distance (m) from each drive's run through the module (:func:`drive_runs`) to
    every other servo's envelope: its body and its ears grown by a hole clearance
    (:func:`servo_boxes`) and its pulley's cavity (a cylinder of the pulley's radius and the
    cavity margin, a pulley width and two hole clearances tall), keyed (servo, side, other servo).
    A point's distance to each of the three is convex along the run: each one's least value by
    shrinking brackets (:func:`.servo_geometry._convex_min`), the least of the three."""
    return drive_clearances_of(params, forearm_servos(params))


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


def heel_clear_y(params: HandParams, z: float, r: float) -> float:
    """The least y (m) of the centre of a circle of radius ``r`` at height ``z`` (m, palm frame)
    moving along y that keeps it clear of the heel (:func:`heel_box`): ``r`` in front of its front
    face where the circle's centre lies at its height, else off its lower front edge, and at its
    front where the circle passes under it. The heel must exist."""
    front = float(heel_box(params)[1][1])
    bottom = -params.palm.thickness / 2.0 - params.palm.heel_height
    if z >= bottom:
        return front + r
    return front + (math.sqrt(r * r - (z - bottom) ** 2) if r > bottom - z else 0.0)


def heel_gap(params: HandParams, T0: np.ndarray | None = None, floor: float | None = None) -> float:
    """The distance (m) from the palm's heel (:func:`heel_box`) to the CMC base at rest
    (``cmc_base_gap.cmc_base_gap``; ``T0``: another CMC placement than the file's, ``floor`` the
    base's lowest face as there); negative where they overlap; inf for a flat palm."""
    box = heel_box(params)
    if box is None:
        return math.inf
    return cmc_base_gap(params, *box, T0, floor)


def forearm_box(params: HandParams, T0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (m, palm frame, right hand) of the forearm module's block: one palm wall around
    every one of its servos' envelopes (:func:`forearm_points`), its front face
    (:func:`forearm_front`), its top a wall above the palm's dorsal face (:func:`forearm_top`, flush
    with the tab). ``T0``: another CMC placement than the file's; the block moves along y with the
    palm's back face it stands behind (the back of that placement's thenar where it reaches
    further back than the wrist crease), its servos where the file's row holds them."""
    w = params.palm.wall
    pts = forearm_points(params)
    lo = np.array([pts[:, 0].min() - w, pts[:, 1].min() - w, pts[:, 2].min() - w])
    hi = np.array([pts[:, 0].max() + w, forearm_front(params), forearm_top(params)])
    if T0 is not None:
        back = min(float(v[:, 1].min()) for v in thenar_points(params, T0).values())
        shift = min(wrist_y(params), back) - palm_back(params)
        lo[1] += shift
        hi[1] += shift
    return lo, hi


def forearm_gap(params: HandParams, T0: np.ndarray | None = None, floor: float | None = None) -> float:
    """The distance (m) from the forearm module's block (:func:`forearm_box`, moved with ``T0``) to
    the CMC base at rest (``cmc_base_gap.cmc_base_gap``; ``T0`` and ``floor`` as there); negative
    where they overlap. The module stands behind the palm's back face; the CMC's hub hangs below
    the palm, and where its axis leans back as it goes down, the hub reaches behind the thenar's
    cuts that set that face."""
    return cmc_base_gap(params, *forearm_box(params, T0), T0, floor)


def forearm_points(params: HandParams) -> np.ndarray:
    """Every servo's envelope (:func:`servo_envelope`) placed in the forearm module (m, palm frame,
    right hand), stacked (n, 3): the module's block is one palm wall around them."""
    return envelope_points(params, forearm_servos(params))


def forearm_width(params: HandParams) -> float:
    """The forearm module's width (m, across the forearm, palm x): its servos' envelopes
    (:func:`forearm_points`) across and a palm wall each side (``cad.parts.wrist.forearm_block``)."""
    return envelope_width(params, forearm_servos(params))


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


def T_palm_forearm(params: HandParams) -> np.ndarray:
    """The forearm module's frame: the palm's axes, origin on the wrist crease at the middle of the
    servo row, in the palm's mid-plane."""
    xs = [T[0, 3] for T in forearm_servos(params).values()]
    return trans((min(xs) + max(xs)) / 2.0, wrist_y(params), 0.0)
