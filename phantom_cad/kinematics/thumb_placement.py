"""Where the thumb should sit: the search for the CMC placement (``palm.thumb_cmc_offset_mm``,
``palm.thumb_cmc_axis_deg``) whose thumb opposes best. numpy, and scipy for the search
(docs/opposition.md).

* ``solve(hand)``: the thumb's CMC centre and axis within bounds that maximize the *opposition
  margin*, the smallest margin (:attr:`.opposition.Reach.margin`) of index, middle and ring, with
  the thumb's links kept out of the palm a human-scale hand has (``palm_envelope``); ``oppose``
  (e.g. ``opposition.PAD_OPPOSE``) holds the pads' normals within it of facing each other too.
* ``thenar_constraint(params)``: the search's constraint for the palm's thenar (``thenar.thenar``),
  the pre-build rules a placement can break (the heel, the finger sockets' magnet pockets) and a
  palm of human breadth.

The capsules, their contacts and the reach are :mod:`.opposition`'s; the search works its margin out
on the capsule pairs that can matter only.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import units
from . import forearm_layout as FL
from . import frames as F
from . import thenar as TH
from .dimensions import FLANK
from .hand_params import HandParams
from .opposition import (CONTACT_BAND, OPPOSED, PAD_CONE, ThumbTips, Tips, segment_closest, facing_angle, norm3, pad_pairs, xyz,
                         finger_tips, reach, thumb_tips)
from .topology import FINGERS


#: the search's price (rad of margin) of a metre of the thumb inside the palm envelope
INTRUSION_WEIGHT = 100.0
#: what :func:`thenar_constraint` keeps its rules by (m, rad): a placement on a rule's edge, written
#: to a file with four decimals (``sizing``, ``params opposition --solve``), still keeps it
SLACK, SLACK_RAD = 1e-6, 1e-5


@dataclass(frozen=True)
class Bounds:
    """Where the thumb's CMC may sit: its centre (m, palm frame, index MCP at the origin, right
    hand) and its axis angles (rad), each as (low, high)."""
    offset: tuple[tuple[float, float], ...]
    axis: tuple[tuple[float, float], ...]

    def array(self) -> np.ndarray:
        return np.array([*self.offset, *self.axis], float)


def default_bounds(params: HandParams) -> Bounds:
    """The thenar region of a palm of human breadth, scaled with the hand length (189 mm: the
    reference hand): the CMC centre up to 35 mm radial of the palm's radial edge
    (:func:`palm_envelope`), 20-75 mm proximal of the index MCP and 35 mm palmar to 10 mm dorsal
    of it (the CMC base hangs below the palm, its column climbing into it: ``thenar.thenar``; the
    search keeps the thumb's links out of :func:`palm_envelope`); the axis angles within
    +-90 deg roll, -90..30 deg pitch and +-90 deg yaw (docs/opposition.md)."""
    k = params.hand_length / 0.189
    scaled_mm = units.m(k)          # one millimetre of the reference hand, scaled (m)
    rad = units.rad
    x_edge = palm_envelope(params)[0][0]
    return Bounds(offset=((x_edge - 35 * scaled_mm, x_edge), (-75 * scaled_mm, -20 * scaled_mm),
                          (-35 * scaled_mm, 10 * scaled_mm)),
                  axis=((rad(-90), rad(90)), (rad(-90), rad(30)), (rad(-90), rad(90))))


def palm_envelope(params: HandParams) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) corners (m, palm frame, right hand) of the palm a human-scale hand has behind its
    knuckles: across the four fingers' sockets from the index's radial edge to the pinky's ulnar
    edge, one palm wall beyond each; from the most distal socket face back to the index
    metacarpal's length behind the index MCP (the wrist crease); the palm's thickness about the
    MCP axes' plane. The thumb's links
    stay outside it (the thenar side of a human palm is the thumb's own metacarpal)."""
    w = params.palm.wall
    first, last = FINGERS[0], FINGERS[-1]
    x0 = F.mcp_position(params, 0)[0] - params.fingers[first].width / 2.0 - w
    x1 = F.mcp_position(params, len(FINGERS) - 1)[0] + params.fingers[last].width / 2.0 + w
    y1 = max(F.T_palm_socket(params, f)[1, 3] for f in FINGERS)
    y0 = F.wrist_y(params)
    T = params.palm.thickness / 2.0
    return np.array([x0, y0, -T]), np.array([x1, y1, T])


def box_distance(p: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Signed distance (m) of points p (..., 3) to the box [lo, hi]: negative inside."""
    p = np.asarray(p, float)
    return _box_distance(np.array(np.moveaxis(p, -1, 0), order="C"), lo, hi).reshape(p.shape[:-1])


def _box_distance(p: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """:func:`box_distance` of points given as x, y, z rows (3, ...), worked out in p's memory (p
    is overwritten): a search calls it on ten thousand points at a time."""
    c, h = ((lo + hi) / 2.0)[:, None], ((hi - lo) / 2.0)[:, None]
    p = p.reshape(3, -1)
    p -= c
    np.abs(p, out=p)
    p -= h                                                  # d, per axis
    inside = np.maximum(p[0], p[1])
    np.maximum(inside, p[2], out=inside)
    np.minimum(inside, 0.0, out=inside)
    np.maximum(p, 0.0, out=p)
    p *= p
    out = p[0]                                              # |max(d, 0)|, in np.linalg.norm's order
    out += p[1]
    out += p[2]
    np.sqrt(out, out=out)
    out += inside
    return out


def palm_intrusion(thumb: ThumbTips, T0: np.ndarray, envelope) -> float:
    """How far (m) the thumb's links reach into the palm envelope over its commands (<= 0: they
    stay out, by that much)."""
    sd = _box_distance(thumb.body_placed(T0), *envelope)
    return float(thumb.body_radius - sd.min())


#: the 95th-percentile adult palm's breadth at hand length 189 mm (m), scaled with the hand length
HUMAN_BREADTH = 0.095


def human_edge(params: HandParams) -> float:
    """x (m, palm frame, right hand) of the radial edge of a palm of human breadth
    (:data:`HUMAN_BREADTH`, scaled with the hand length) that ends at the palm's ulnar face
    (``forearm_layout.metacarpal_x``: the pinky socket's outer side, or a wall ulnar of a drive's channel
    where the file's servo row draws one further)."""
    return FL.metacarpal_x(params)[1] - HUMAN_BREADTH * params.hand_length / 0.189


def carpus(params: HandParams) -> float:
    """Length (m) of the carpus, between the metacarpals' bases (``frames.wrist_y``) and the wrist
    crease the hand length is measured from: the hand length less the middle finger's metacarpal
    and phalanges (15.7 mm at the default's fractions). A human thenar reaches that far back; the
    palm's back face, and the forearm module behind it, move back with it."""
    m = params.fingers["middle"]
    return params.hand_length - (m.metacarpal + m.proximal + m.middle + m.distal)


def thenar_constraint(params: HandParams, human: bool = True, floor: float | None = None):
    """The placement search's ``constraint`` for the palm's thenar (``thenar.thenar``): metres by
    which a placement T0 misses ``frames.thenar_margins`` (the CMC axis's tilt priced at the thumb's
    half width per radian), the print's hole clearance off the palm's heel
    (``forearm_layout.heel_gap``) and off the forearm module's block (``forearm_layout.forearm_gap``:
    the file's servo row, moved along y with the placement's thenar), and two perimeters off the
    finger sockets' magnet pockets (``thenar.socket_pocket_gap``; the rules ``cad.preflight``
    checks), and, with ``human``, by which
    the journal's and the turn's walls reach radial of a palm of human breadth (:func:`human_edge`;
    the pulley's cavity may open there) and the thenar reaches behind the carpus (:func:`carpus`).
    ``floor``: the CMC base's lowest face (``cad.preflight.cmc_base_floor``; by default its hub's
    palmar face, which the part's MP guide boss can reach below)."""
    edge = human_edge(params)
    back = F.wrist_y(params) - carpus(params)
    lever = params.thumb.width / 2.0
    clearance = params.print.hole_clearance

    def violation(T0: np.ndarray) -> float:
        m = TH.thenar_margins(params, T0)
        v = max(SLACK_RAD - m["tilt"], 0.0) * lever + max(SLACK - m["base"], 0.0) + max(SLACK - m["turn"], 0.0)
        if T0[2, 2] > 0.0:              # the axis climbs into the palm: the thenar's cuts exist
            v += (max(clearance + SLACK - FL.heel_gap(params, T0, floor), 0.0)
                  + max(clearance + SLACK - FL.forearm_gap(params, T0, floor), 0.0)
                  + max(FLANK + SLACK - TH.socket_pocket_gap(params, T0)[0], 0.0))
        if m["tilt"] < 0.0 or not human:
            return v
        pts = TH.thenar_points(params, T0)
        x = min(float(pts["journal"][:, 0].min()), float(pts["turn"][:, 0].min()))
        y = min(float(p[:, 1].min()) for p in pts.values())
        return v + max(edge - x, 0.0) + max(back - y, 0.0)

    return violation


def _placement(x: np.ndarray) -> np.ndarray:
    return F.thumb_cmc_placement(x[:3], x[3:])


def margin(thumb: ThumbTips, fingers: dict[str, Tips], x: np.ndarray, oppose=None) -> float:
    """The search's opposition margin (rad) of placement x = (offset, axis): min over the opposed
    fingers of :attr:`.opposition.Reach.margin` on these grids. A finger no pair of which is in
    contact scores below every finger that has one: -(pi - PAD_CONE) less its distance to the
    contact band over the two radii (so the search moves toward contact)."""
    return _margin(thumb, _opposed(fingers), _placement(x), oppose)


#: the margin leaves a pair out only where its bound clears what matters by this much (m): far above
#: the bounds' rounding (1e-17 m at a hand's size)
_CLEAR = 1e-9


@dataclass(frozen=True)
class _Opposed:
    """The opposed fingers' capsules for :func:`_margin`: stacked, one row per (finger, command)."""
    fingers: dict            # finger -> Tips
    tips: Tips               # the rows (its radius unused)
    radius: np.ndarray       # (n,) each row's capsule radius
    start: np.ndarray        # the row each finger's block starts at, then the end
    centre: tuple            # the segments' bounding spheres (:func:`_sphere`)
    half: np.ndarray


def _sphere(t: Tips):
    """Each capsule segment's midpoint (x, y, z) and half length: the segment lies within the half
    length of the midpoint."""
    return xyz((t.a + t.b) / 2.0), np.sqrt(t.axis[2]) / 2.0


def _opposed(fingers: dict[str, Tips]) -> _Opposed:
    tips = [fingers[f] for f in OPPOSED]
    stacked = Tips(*(np.concatenate([getattr(t, k) for t in tips]) for k in ("a", "b", "normal")), 0.0,
                   np.concatenate([t.u for t in tips]))
    return _Opposed(dict(fingers), stacked, np.concatenate([np.full(len(t.a), t.radius) for t in tips]),
                    np.cumsum([0, *(len(t.a) for t in tips)]), *_sphere(stacked))


def _margin(thumb: ThumbTips, opposed: _Opposed, T0: np.ndarray, oppose=None) -> float:
    """:func:`margin` at the placement T0, worked out on the pairs that can matter. Two capsule
    axes are no nearer than their midpoints' distance less the two half lengths (:func:`_sphere`)
    and no further than the midpoints: a finger's pairs whose lower bound exceeds its least upper
    bound (or 0) are neither in contact nor its nearest, and are left out; where the pairs kept do
    not settle a miss, every pair is worked out. Each pair kept is worked out as
    :func:`.opposition.contacts` does, so the margin is the same number."""
    tt = thumb.placed(T0)
    fo = opposed
    centre, half = _sphere(tt)
    # the fingers' rows down, the thumb's commands across: np.nonzero lists each finger's pairs in a run
    mid = norm3(tuple(y[:, None] - x[None, :] for x, y in zip(centre, fo.centre)))
    r = tt.radius + fo.radius
    upper = np.minimum.reduceat(mid.min(axis=1) - r, fo.start[:-1])
    cut = np.maximum(upper, 0.0) + 2.0 * _CLEAR                       # per finger
    lower = mid - half[None, :]
    lower -= (fo.half + r)[:, None]
    j, i = np.nonzero(lower <= np.repeat(cut, np.diff(fo.start))[:, None])
    (p1, d1, a), (p2, d2, e) = tt.axis, fo.tips.axis
    c1, c2 = segment_closest(tuple(x[i] for x in p1), tuple(x[i] for x in d1), a[i],
                      tuple(x[j] for x in p2), tuple(x[j] for x in d2), e[j])
    v = tuple(y - x for x, y in zip(c1, c2))
    dist = norm3(v)
    gap = dist - tt.radius - fo.radius[j]
    # the facing angle of the pairs in contact only
    k = np.flatnonzero((gap <= 0.0) & (gap >= -CONTACT_BAND))
    angle = facing_angle(tuple(x[k] for x in v), dist[k], xyz(tt.normal[i[k]]), xyz(fo.tips.normal[j[k]]), oppose)
    run, band = np.searchsorted(j, fo.start), np.searchsorted(j[k], fo.start)
    worst = math.inf
    for n, f in enumerate(OPPOSED):
        if band[n + 1] > band[n]:
            m = PAD_CONE - float(angle[band[n]:band[n + 1]].min())
        else:
            g = gap[run[n]:run[n + 1]]
            miss = float(np.min(np.where(g > 0.0, g, -CONTACT_BAND - g))) if len(g) else math.inf
            if not miss <= cut[n] - _CLEAR:         # a pair left out may be nearer: every pair
                g = pad_pairs(tt, fo.fingers[f])[0]
                miss = float(np.min(np.where(g > 0.0, g, -CONTACT_BAND - g)))
            m = -(math.pi - PAD_CONE) - miss / (tt.radius + fo.fingers[f].radius)
        worst = min(worst, m)
    return worst


@dataclass(frozen=True)
class Solution:
    offset: tuple[float, float, float]     # m
    axis: tuple[float, float, float]       # rad
    margin: float                          # rad: the smallest Reach.margin of the opposed fingers
    reach: dict                            # finger -> Reach at the solution (fine grid)
    evaluations: int
    intrusion: float                       # m: the thumb's reach into the palm envelope (<= 0: clear)
    violation: float = 0.0                 # m: ``constraint`` at the solution (<= 0: met; 0 without one)


def solve(hand, bounds: Bounds | None = None, seed: int = 0, coarse=(11, 11, 21), generations: int = 60,
          population: int = 8, iterations: int = 300,
          constraint: Callable[[np.ndarray], float] | None = None, oppose=None) -> Solution:
    """Maximize the opposition margin over the CMC placement within ``bounds``, with the thumb's
    links kept out of the palm envelope (a penalty of ``INTRUSION_WEIGHT`` per metre inside, on the
    fine thumb grid; if the optimum still reaches inside, the best placement seen that does not).
    ``constraint``, if given, maps a placement (T_palm_cmc_base at rest, 4 x 4, metres) to how far
    (m) it violates what the caller requires of it (<= 0: met); it is priced and fallen back on as
    the intrusion is (a design's own reach, e.g. what holds the CMC fitting the palm).
    Method: differential evolution (scipy, seeded: deterministic) on a coarse command grid (``coarse``: n1,
    n6, n_finger), the file's placement in its first population, then Nelder-Mead from the best.
    The result is judged on :func:`.opposition.reach`'s fine grid (21 x 21 x 41), which contains
    the coarse one, so the fine margin is at least the searched one; where it misses a pad and the
    file's placement keeps the rules and meets every pad, the file's is returned. ``oppose`` (rad):
    the pads' normals held within it of facing each other too (:func:`.opposition.reach`)."""
    from scipy.optimize import differential_evolution, minimize

    p = hand.params
    bounds = default_bounds(p) if bounds is None else bounds
    box = bounds.array()
    lo, hi = box[:, 0], box[:, 1]
    env = palm_envelope(p)
    thumb = thumb_tips(hand, coarse[0], coarse[1])
    fine_thumb = thumb_tips(hand)
    fingers = _opposed({f: finger_tips(hand, f, coarse[2]) for f in OPPOSED})
    count = [0]
    clear: list = [math.inf, None]      # the best placement seen that meets both
    _violation = (lambda T0: 0.0) if constraint is None else (lambda T0: float(constraint(T0)))

    def cost(z):
        count[0] += 1
        x = np.clip(z, lo, hi)
        T0 = _placement(x)
        m = _margin(thumb, fingers, T0, oppose)
        # the palm envelope on the fine grid: between the coarse grid's commands the thumb can
        # pass through it
        inside = max(palm_intrusion(fine_thumb, T0, env), 0.0) + max(_violation(T0), 0.0)
        if inside <= 0.0 and -m < clear[0]:
            clear[:] = [-m, x.copy()]
        return -m + INTRUSION_WEIGHT * inside

    rng = np.random.default_rng(seed)
    n = population * len(lo)
    init = lo + (hi - lo) * rng.random((n, len(lo)))
    init[0] = np.clip(np.array([*p.palm.thumb_cmc_offset, *p.palm.thumb_cmc_axis]), lo, hi)
    de = differential_evolution(cost, list(zip(lo, hi)), init=init, maxiter=generations, tol=0.0,
                                seed=seed, polish=False)
    res = minimize(cost, de.x, method="Nelder-Mead",
                   options={"maxiter": iterations, "xatol": 1e-6, "fatol": 1e-7})
    x = np.clip(res.x if res.fun <= de.fun else de.x, lo, hi)
    if (palm_intrusion(fine_thumb, _placement(x), env) > 0.0 or _violation(_placement(x)) > 0.0) \
            and clear[1] is not None:
        x = clear[1]                    # the penalty was not enough: the best clear placement
    fine = reach(hand, thumb=fine_thumb, T0=_placement(x), oppose=oppose)
    start = init[0]
    if min(fine[f].margin for f in OPPOSED) < 0.0 and palm_intrusion(fine_thumb, _placement(start), env) <= 0.0 \
            and _violation(_placement(start)) <= 0.0:
        # the search ended where a pad is missed: the placement it started from, if it keeps the
        # rules and meets every pad, is the better answer
        at_start = reach(hand, thumb=fine_thumb, T0=_placement(start), oppose=oppose)
        if min(at_start[f].margin for f in OPPOSED) >= 0.0:
            x, fine = start, at_start
    return Solution(tuple(float(v) for v in x[:3]), tuple(float(v) for v in x[3:]),
                    min(fine[f].margin for f in OPPOSED), fine, count[0],
                    palm_intrusion(fine_thumb, _placement(x), env),
                    _violation(_placement(x)) if constraint is not None else 0.0)
