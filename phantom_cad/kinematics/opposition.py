"""Thumb opposition: can the thumb's pad reach the fingertips' pads? numpy only
(docs/opposition.md). Where the thumb should sit for them to is :mod:`.thumb_placement`'s.

Each fingertip is modelled by the capsule inside its printed tip: the tip is a half cylinder about
the distal link's x (``frames.fingertip``: length L, radius r, half width w); the capsule's segment
runs along x over |x| <= max(w - r, 0) at y = L - r, with radius r. The capsule lies inside the
printed tip, so a capsule gap is never smaller than the solids' gap.

For the thumb at commands (u1, u6) and a finger at its command u_k, the two capsules' closest
points give the *gap* (distance between the segments minus the two radii: negative when they
overlap) and the contact direction v (thumb to finger). The contact is *pad to pad* when v lies
within ``PAD_CONE`` of the thumb pad's outward normal and -v within it of the finger pad's
(``frames.T_distal_pad``: 45 deg from the palmar face toward the tip; a 45 deg cone spans the
palmar face to the very tip). The joint angles are the model's at the commands
(``hand.forward(u, compensated=True)``: the hand's compensation, the routed statics unless the file
carries fitted effects), over a grid of each servo's travel.

* ``reach(hand)``: per finger, the smallest pad-to-pad gap over the commands (<= 0: the pads meet
  at some command; by continuity the contact gap 0 is passed on the way from rest) and how
  squarely they meet: the *margin*, ``PAD_CONE`` less the smallest facing angle of the command
  pairs in contact (overlapping by at most ``CONTACT_BAND``). A positive margin means the pads meet
  with the contact direction that far inside the pad cone: a margin for build error.
* ``pad_facing(params, q)``: how far the two pads' normals are from facing each other. The cones
  alone let them be up to 90 deg apart; ``reach`` and ``thumb_placement.solve`` hold them within
  ``oppose`` (e.g. ``PAD_OPPOSE``) on request.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .. import units
from . import frames as F
from . import link_frames as LF
from .hand_params import HandParams
from .topology import CMC_Q, CMC_SERVO, FINGERS, N_SERVOS, OPPOSED_FINGERS, THUMB_CHAIN, chain, digit_links, joint, link


#: the half angle (rad) of the cone around a pad's normal in which a contact counts as pad to pad
PAD_CONE = units.rad(45.0)
#: how far (rad) from facing each other (antiparallel) two pads' normals may be for a pinch: the
#: ``oppose`` the placement search and the reach take on request (docs/opposition.md, "Pad to pad")
PAD_OPPOSE = units.rad(30.0)
#: the fingers the thumb opposes (the paper's postures 1-3); the pinky is reported, not required
OPPOSED = OPPOSED_FINGERS
THUMB = THUMB_CHAIN.digit
#: a pair of commands counts as *in contact* when its capsules overlap by at most this (m): the
#: pads have met on the way there and press by less than a grid step
CONTACT_BAND = 3e-3
#: how many of the model's contacts (distinct thumb commands, squarest first) a pinch on the printed
#: tips or the solids tries (:func:`contact_commands`)
CANDIDATES = 8


@dataclass(frozen=True)
class Tips:
    """Fingertip capsules at a batch of commands, in the palm frame (right hand, metres)."""
    a: np.ndarray        # (n, 3) one end of the capsule's segment
    b: np.ndarray        # (n, 3) the other end
    normal: np.ndarray   # (n, 3) the pad's outward normal
    radius: float
    u: np.ndarray        # (n, k) the commands (rad) of the servos that move it

    @cached_property
    def axis(self) -> tuple:
        """The capsule's segment for :func:`segment_closest`: its start a and direction b - a as (x, y, z)
        components (n,) each, and the direction's squared length (n,)."""
        d = self.b - self.a
        d = (d[:, 0], d[:, 1], d[:, 2])
        return xyz(self.a), d, _dot(d, d)


def xyz(p: np.ndarray) -> tuple:
    """The (x, y, z) components of points p (..., 3)."""
    return p[..., 0], p[..., 1], p[..., 2]


def _dot(u, v):
    """u . v of vectors given as (x, y, z) components, summed in the order numpy's einsum sums three
    products, (x + z) + y: the search's numbers are einsum's bit for bit."""
    return (u[0] * v[0] + u[2] * v[2]) + u[1] * v[1]


def norm3(u):
    """|u| of vectors given as (x, y, z) components, summed in np.linalg.norm's order."""
    return np.sqrt((u[0] * u[0] + u[1] * u[1]) + u[2] * u[2])


def _servo(digit: str) -> int:
    return chain(digit).servo


def _chain(params: HandParams, digit: str, q: np.ndarray):
    """The distal link of ``digit`` in its chain's root frame (the finger base; the thumb's CMC
    base), for joint angles q (n, 15): flexion turns about -x, so every link after the reference
    joint stays in that joint's y-z plane, which ``link_frames.joint_origin`` places in the root
    (the thumb's MP turned by its twist about the root's y). Returns the tip segment's ends (n, 3)
    x2, the pad normal (n, 3), the tip radius, and the joint centres (n, 3) in chain order (the
    reference joint first), then the tip's centre."""
    ch = chain(digit)
    d = params.digit(digit)
    lengths = [getattr(d, seg) for seg in ch.segments[1:]]     # the links after each joint
    origin = LF.joint_origin(params, link(joint(ch.joint_names[0]).child))
    theta = np.zeros(len(q))
    yz = np.zeros((len(q), 2))
    # the origin lies on the root's y, the axis its turn is about: the chain is laid out in the
    # plane from the origin's y and the plane turned about the root's y as a whole
    yz[:, 0] = 0.0 if origin is None else origin[1, 3]
    centres = []
    for k, qi in enumerate(ch.q_index):
        centres.append(yz.copy())
        theta = theta + q[:, qi]
        if k < len(ch.q_index) - 1:
            yz += lengths[k] * np.stack([np.cos(theta), -np.sin(theta)], axis=1)
    ey = np.stack([np.cos(theta), -np.sin(theta)], axis=1)
    ez = np.stack([np.sin(theta), np.cos(theta)], axis=1)
    L, r, w = F.fingertip(params, digit)
    c = yz + (L - r) * ey
    half = max(w - r, 0.0)
    n = math.sin(F.PAD_ANGLE) * ey - math.cos(F.PAD_ANGLE) * ez
    zeros = np.zeros((len(q), 1))
    a = np.hstack([zeros - half, c])
    b = np.hstack([zeros + half, c])
    centres = [np.hstack([zeros, v]) for v in (*centres, c)]
    n = np.hstack([zeros, n])
    if origin is not None and not np.array_equal(origin[:3, :3], np.eye(3)):
        R = origin[:3, :3].T
        a, b, n, centres = a @ R, b @ R, n @ R, [v @ R for v in centres]
    return a, b, n, r, centres


def _rz(q15: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Rz(q15) of each command's points (the CMC's own rotation)."""
    c, s = np.cos(q15), np.sin(q15)
    if p.ndim == 3:
        c, s = c[:, None], s[:, None]
    out = np.empty_like(p)
    out[..., 0] = c * p[..., 0] - s * p[..., 1]
    out[..., 1] = s * p[..., 0] + c * p[..., 1]
    out[..., 2] = p[..., 2]
    return out


def _apply(T: np.ndarray, p: np.ndarray, w: float = 1.0) -> np.ndarray:
    return p @ T[:3, :3].T + (T[:3, 3] if w else 0.0)


def _travel(hand, servo: int, n: int) -> np.ndarray:
    return np.linspace(hand.u_min[servo], hand.u_max[servo], n)


def finger_tips(hand, finger: str, n: int = 41) -> Tips:
    """The fingertip capsule of ``finger`` at n commands over its servo's travel."""
    s = _servo(finger)
    u = np.zeros((n, N_SERVOS))
    u[:, s] = _travel(hand, s, n)
    q = hand.forward(u, compensated=True)
    a, b, nrm, r, _ = _chain(hand.params, finger, q)
    T = F.T_palm_finger_base(hand.params, finger)
    return Tips(_apply(T, a), _apply(T, b), _apply(T, nrm, 0.0), r, u[:, [s]])


@dataclass(frozen=True)
class ThumbTips:
    """The thumb's capsule in its CMC base frame at q15 = 0, over a grid of (u1, u6): placed in the
    palm by :meth:`placed` for any CMC placement."""
    a: np.ndarray        # (n1 * n6, 3), CMC base frame before the CMC's own rotation
    b: np.ndarray
    normal: np.ndarray
    q15: np.ndarray      # (n1 * n6,)
    radius: float
    u: np.ndarray        # (n1 * n6, 2): u1, u6
    body: np.ndarray     # (n1 * n6, m, 3): points along the axes of the thumb's links
    body_radius: float   # half the thumb's thickness
    # a, b, normal and body turned by the CMC's own rotation, which no placement changes: done once,
    # so placing is one affine map (body as x, y, z rows of every command's points)
    _turned: tuple = field(init=False, repr=False, compare=False)
    _body_xyz: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "_turned", tuple(_rz(self.q15, p) for p in (self.a, self.b, self.normal)))
        object.__setattr__(self, "_body_xyz", np.ascontiguousarray(_rz(self.q15, self.body).reshape(-1, 3).T))

    def placed(self, T0: np.ndarray) -> Tips:
        a, b, normal = self._turned
        return Tips(_apply(T0, a), _apply(T0, b), _apply(T0, normal, 0.0), self.radius, self.u)

    def body_placed(self, T0: np.ndarray) -> np.ndarray:
        """The body's points placed by T0, as x, y, z rows (3, n1 * n6 * m)."""
        p = T0[:3, :3] @ self._body_xyz
        p += T0[:3, 3:]
        return p


def thumb_tips(hand, n1: int = 21, n6: int = 21) -> ThumbTips:
    s1, s6 = _servo(THUMB), CMC_SERVO
    g1, g6 = np.meshgrid(_travel(hand, s1, n1), _travel(hand, s6, n6), indexing="ij")
    u = np.zeros((n1 * n6, N_SERVOS))
    u[:, s1], u[:, s6] = g1.ravel(), g6.ravel()
    q = hand.forward(u, compensated=True)
    p = hand.params
    a, b, nrm, r, centres = _chain(p, THUMB, q)
    # the links' axes: the metacarpal from its hub's rim (the hub sits on the palm) to the MP, the
    # proximal phalanx to the IP, the distal phalanx to its tip's centre, 8 points each
    hub = np.zeros_like(centres[0])
    hub[:, 1] = min(p.thumb.width / 2.0, p.thumb.metacarpal)
    ends = [hub, *centres]
    t = np.linspace(0.0, 1.0, 8)[None, :, None]
    body = np.concatenate([e0[:, None] + t * (e1 - e0)[:, None] for e0, e1 in zip(ends, ends[1:])], axis=1)
    return ThumbTips(a, b, nrm, q[:, CMC_Q].copy(), r, u[:, [s1, s6]], body, p.thumb.thickness / 2.0)


def tip_gaps(hand, u) -> np.ndarray:
    """(n, 4): the gap (m; < 0 overlapping) between the thumb's tip capsule and each finger's
    (:data:`FINGERS` order) at the commands u (n, 6), the joint angles the model's at them (right-hand
    frames, the file's CMC placement)."""
    u = np.atleast_2d(np.asarray(u, float))
    q = hand.forward(u, compensated=True)
    p = hand.params
    T0 = F.thumb_cmc_placement(p.palm.thumb_cmc_offset, p.palm.thumb_cmc_axis)
    a, b, _, r, _ = _chain(p, THUMB, q)
    a, b = _apply(T0, _rz(q[:, CMC_Q], a)), _apply(T0, _rz(q[:, CMC_Q], b))
    out = np.empty((len(u), len(FINGERS)))
    for k, f in enumerate(FINGERS):
        fa, fb, _, fr, _ = _chain(p, f, q)
        T = F.T_palm_finger_base(p, f)
        out[:, k] = segment_distance(a, b, _apply(T, fa), _apply(T, fb))[0] - r - fr
    return out


def segment_distance(p1, q1, p2, q2):
    """Closest points of segments p1-q1 and p2-q2 (broadcast over leading axes): returns
    (distance, point on the first, point on the second) (:func:`segment_closest`)."""
    d1, d2 = xyz(q1 - p1), xyz(q2 - p2)
    c1, c2 = segment_closest(xyz(p1), d1, _dot(d1, d1), xyz(p2), d2, _dot(d2, d2))
    return norm3(tuple(u - v for u, v in zip(c1, c2))), np.stack(c1, axis=-1), np.stack(c2, axis=-1)


def segment_closest(p1, d1, a, p2, d2, e):
    """Closest points of segments p1 + s d1 and p2 + t d2 (s, t in [0, 1]) given as (x, y, z)
    components that broadcast, with a = d1 . d1 and e = d2 . d2: returns the points on the first and
    on the second, as components. Ericson, Real-Time Collision Detection, 5.1.9, with its
    degenerate cases (a segment that is a point, parallel segments)."""
    r = tuple(u - v for u, v in zip(p1, p2))
    f, c, b = _dot(d2, r), _dot(d1, r), _dot(d1, d2)
    eps = 1e-18
    point1, point2 = ~(a > eps), ~(e > eps)
    point1 = point1 if point1.any() else None       # no segment is a point: nothing to mask
    point2 = point2 if point2.any() else None

    def unless(point, v):
        return v if point is None else np.where(point, 0.0, v)

    denom = a * e - b * b
    # a quotient by a (near-)zero denominator is computed and dropped
    with np.errstate(divide="ignore", invalid="ignore"):
        s = unless(point1, np.where(denom > eps, np.clip((b * f - c * e) / denom, 0.0, 1.0), 0.0))
        t = unless(point2, (b * s + f) / e)
        # t outside [0, 1]: clamp it and recompute s for the clamped t
        s = np.where(t < 0.0, unless(point1, np.clip(-c / a, 0.0, 1.0)), s)
        s = np.where(t > 1.0, unless(point1, np.clip((b - c) / a, 0.0, 1.0)), s)
    t = np.clip(t, 0.0, 1.0)
    return tuple(p + s * d for p, d in zip(p1, d1)), tuple(p + t * d for p, d in zip(p2, d2))


def pad_pairs(thumb: Tips, finger: Tips):
    """Every (thumb command, finger command) pair of capsules, (n_thumb, n_finger) each: the gap (m;
    < 0 overlapping), the distance of the axes and the direction (unnormalised) from the thumb's
    closest point to the finger's, as components."""
    (p1, d1, a), (p2, d2, e) = thumb.axis, finger.axis
    down, across = (slice(None), None), (None, slice(None))     # the thumb's commands down, the finger's across
    c1, c2 = segment_closest(tuple(x[down] for x in p1), tuple(x[down] for x in d1), a[down],
                      tuple(x[across] for x in p2), tuple(x[across] for x in d2), e[across])
    v = tuple(y - x for x, y in zip(c1, c2))
    dist = norm3(v)
    return dist - thumb.radius - finger.radius, dist, v


def facing_angle(v, dist, n1, n2, oppose=None):
    """The facing angle (rad) of contact directions v (components, length dist) against the pads'
    normals n1 (the thumb's) and n2 (the finger's), as components: the larger of the two angles; pi
    where the axes meet (dist 0). With ``oppose`` (rad), also the angle between n1 and -n2 less
    ``oppose - PAD_CONE``: the facing angle is within PAD_CONE where the contact direction lies in
    both cones and the normals within ``oppose`` of facing each other."""
    with np.errstate(divide="ignore", invalid="ignore"):
        v = tuple(x / dist for x in v)
    cos = np.minimum(_dot(v, n1), _dot(tuple(-x for x in v), n2))
    angle = np.arccos(np.clip(np.nan_to_num(cos, nan=-1.0), -1.0, 1.0))
    if oppose is None:
        return angle
    normals = np.arccos(np.clip(-_dot(n1, n2), -1.0, 1.0))
    return np.maximum(angle, normals - (oppose - PAD_CONE))


def contacts(thumb: Tips, finger: Tips, oppose=None):
    """(gap, angle) over every (thumb command, finger command) pair, shape (n_thumb, n_finger):
    the capsules' gap (m; < 0 overlapping) and the *facing angle* (rad), the larger of the angles
    between the contact direction and the two pads' normals (pi where the axes meet); with
    ``oppose``, the pads' normals held within it of facing each other too (:func:`facing_angle`)."""
    gap, dist, v = pad_pairs(thumb, finger)
    n1, n2 = xyz(thumb.normal[:, None]), xyz(finger.normal[None, :])
    return gap, facing_angle(v, dist, n1, n2, oppose)


@dataclass(frozen=True)
class Reach:
    """The thumb's pad against one fingertip's pad over the commands."""
    finger: str
    gap: float              # m: the smallest gap of the pairs facing pad to pad (<= 0: the pads meet); inf if none
    u_thumb: tuple          # (u1, u6) rad at that gap
    u_finger: float         # rad
    surface_gap: float      # m: the smallest gap of any contact (pad or not)
    margin: float           # rad: PAD_CONE less the smallest facing angle of the pairs in contact
    #                         (overlap within CONTACT_BAND); -inf if no pair is
    u_contact: tuple        # (u1, u6, u_finger) rad of that pair

    @property
    def reaches(self) -> bool:
        return self.gap <= 0.0


def reach(hand, thumb: ThumbTips | None = None, T0: np.ndarray | None = None, fingers=FINGERS,
          n_finger: int = 41, oppose=None) -> dict[str, Reach]:
    """Per finger, the thumb pad's closest approach to its pad and how squarely they meet (right-hand
    frames; a left hand is the mirror image and reaches the same). ``T0``: a CMC placement
    (default: the file's). ``oppose`` (rad, e.g. :data:`PAD_OPPOSE`): a contact counts as pad to pad
    only where the pads' normals are within it of facing each other too (:func:`contacts`)."""
    p = hand.params
    thumb = thumb_tips(hand) if thumb is None else thumb
    T0 = F.thumb_cmc_placement(p.palm.thumb_cmc_offset, p.palm.thumb_cmc_axis) if T0 is None else T0
    tt = thumb.placed(T0)
    out = {}
    for f in fingers:
        ft = finger_tips(hand, f, n_finger)
        gap, angle = contacts(tt, ft, oppose)
        masked = np.where(angle <= PAD_CONE, gap, np.inf)
        i, j = np.unravel_index(int(np.argmin(masked)), masked.shape)
        touching = np.where((gap <= 0.0) & (gap >= -CONTACT_BAND), angle, np.inf)
        k, m = np.unravel_index(int(np.argmin(touching)), touching.shape)
        out[f] = Reach(f, float(masked[i, j]), tuple(float(v) for v in tt.u[i]), float(ft.u[j, 0]),
                       float(gap.min()), PAD_CONE - float(touching[k, m]),
                       (*(float(v) for v in tt.u[k]), float(ft.u[m, 0])))
    return out


def contact_commands(hand, finger: str, n: int = CANDIDATES) -> list[np.ndarray]:
    """The model's command vectors (6,) where the thumb's tip meets the finger's (capsules
    overlapping by at most :data:`CONTACT_BAND`), squarest first (the facing angle), one per
    distinct thumb command, at most n: where a pinch is tried on the printed tips
    (``printed_tips``) and on the solids (``cad.grasp``)."""
    p = hand.params
    T0 = F.thumb_cmc_placement(p.palm.thumb_cmc_offset, p.palm.thumb_cmc_axis)
    thumb = thumb_tips(hand).placed(T0)
    tips = finger_tips(hand, finger)
    gap, angle = contacts(thumb, tips)
    ok = (gap <= 0.0) & (gap >= -CONTACT_BAND)
    out, seen = [], set()
    for flat in np.argsort(np.where(ok, angle, np.inf), axis=None, kind="stable"):
        i, j = np.unravel_index(int(flat), gap.shape)
        if not ok[i, j] or len(out) == n:
            break
        if i in seen:
            continue
        seen.add(i)
        u = np.zeros(N_SERVOS)
        u[_servo(THUMB)], u[CMC_SERVO] = thumb.u[i]
        u[_servo(finger)] = tips.u[j, 0]
        out.append(u)
    return out


def pad_facing(params: HandParams, q, fingers=FINGERS) -> dict[str, float]:
    """Per finger, the angle (rad) between the thumb's pad normal and the finger's pad normal reversed
    (``frames.T_distal_pad``) at joint angles q (15,): 0 when the pads face each other squarely, pi
    when they face the same way. Right-hand frames (a left hand is the mirror image and faces the
    same).

    Whatever the placement and q15, the thumb's pad normal lies at
    arccos(-cos(twist) cos(PAD_ANGLE - (q_MP + q_IP))) from the CMC axis: untwisted its flexion
    axes are perpendicular to that axis and its pad normal lies in its flexion plane, which
    contains the axis; the twist turns that plane about the metacarpal (docs/opposition.md, "Pad
    to pad")."""
    T = LF.link_transforms(params, q, mirrored=False)

    def normal(digit):
        return (T[digit_links(digit)[-1].name] @ F.T_distal_pad(params, digit))[:3, 2]

    n = normal(THUMB)
    return {f: math.acos(max(-1.0, min(1.0, -float(n @ normal(f))))) for f in fingers}

