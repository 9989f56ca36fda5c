"""The routes posed: every strand's path and length at joint angles q and servo angles u, its
straight runs and the links that hold them, the poses over the travel and the sector each pulley
is in contact, and MuJoCo's side sites. numpy only; the routes are :mod:`.routing`'s."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import units
from . import frames as F
from . import link_frames as LF
from .hand_params import HandParams
from .memo import memoised
from .routing import Point, Pulley, Strand, routes
from .routing_rules import joint_travel
from .topology import CMC_Q, JOINTS, N_JOINTS, SERVOS
from .vectors import clipped_acos, cross3


def servo_axis(params: HandParams) -> np.ndarray:
    """A tendon servo's axis in its own (mirrored) frame: positive u winds its drive."""
    return np.array([0.0, 0.0, 1.0 if params.side == "right" else -1.0])


def _rotation(axis, angle: float) -> np.ndarray:
    a = np.asarray(axis, float)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    R = np.eye(4)
    R[:3, :3] = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    return R


def pose(params: HandParams, q=None, u=None) -> dict[str, np.ndarray]:
    """T_palm_link of every link at joint angles q (15) and servo angles u (6): every servo's
    pulley turned by u about :func:`servo_axis` (servo 6's by u6: its loop holds q15 = cmc_gain u6
    when both are given so)."""
    Ts = LF.link_transforms(params, q)
    if u is not None:
        ax = servo_axis(params)
        for s in SERVOS:
            Ts[s.link] = Ts[s.link] @ _rotation(ax, float(u[s.index]))
    return Ts


def _world(Ts, link_name, v, w=1.0) -> np.ndarray:
    return (Ts[link_name] @ np.array([*v, w]))[:3]


class _Wrap:
    """A strand's composite path P -> tangent -> arc (positive about the pulley's axis) -> tangent
    -> N, in the pulley's plane frame (e1, e2, axis). The cord lifts off (straight P-N) when the
    arc would exceed 180 degrees (a wrap the routes never ask for) or vanish: ``lifted``."""

    def __init__(self, P, N, centre, axis, rho):
        a = axis / np.linalg.norm(axis)
        # not vectors.perpendicular_frame: another frame in the pulley's plane moves the tangent
        # points by rounding, and with them the grooves cut into the parts
        e1 = cross3(a, [1.0, 0.0, 0.0])
        if np.linalg.norm(e1) < 1e-6:
            e1 = cross3(a, [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = cross3(a, e1)
        loc = lambda p: np.array([np.dot(p - centre, e1), np.dot(p - centre, e2), np.dot(p - centre, a)])  # noqa: E731
        p, n = loc(P), loc(N)
        dp, dn = math.hypot(p[0], p[1]), math.hypot(n[0], n[1])
        if dp < rho * (1.0 - 1e-9) or dn < rho * (1.0 - 1e-9):
            raise ValueError("a route point lies inside its pulley")
        t_in = math.atan2(p[1], p[0]) + clipped_acos(rho / dp)
        t_out = math.atan2(n[1], n[0]) - clipped_acos(rho / dn)
        arc = (t_out - t_in) % (2.0 * math.pi)
        if arc > 2.0 * math.pi - 1e-9:      # a tangent run (no wrap) that rounding put a turn away
            arc = 0.0
        self.P, self.N, self.lifted = P, N, arc > math.pi
        if self.lifted:
            self.length = float(np.linalg.norm(N - P))
            return
        self.l1 = math.sqrt(max(0.0, dp * dp - rho * rho))
        l3 = math.sqrt(max(0.0, dn * dn - rho * rho))
        self.planar = self.l1 + rho * arc + l3
        self.dz = n[2] - p[2]
        self.length = math.hypot(self.planar, self.dz)
        self.t_in, self.arc, self.z_in = t_in, arc, p[2]
        self.centre, self.rho, self.e1, self.e2, self.a = centre, rho, e1, e2, a

    def _angles(self) -> np.ndarray:
        return np.linspace(self.t_in, self.t_in + self.arc, max(2, int(self.arc / units.rad(5.0)) + 1))

    def _on_arc(self, t) -> np.ndarray:
        """The arc's point at angle t, its height interpolated along the planar length."""
        s = (self.l1 + self.rho * (t - self.t_in)) / self.planar if self.planar > 0 else 0.0
        h = self.z_in + s * self.dz
        return self.centre + self.rho * math.cos(t) * self.e1 + self.rho * math.sin(t) * self.e2 + h * self.a

    def points(self) -> list[np.ndarray]:
        """P, the arc's points every 5 degrees or less (its two tangent points included), N."""
        if self.lifted:
            return [self.P, self.N]
        return [self.P, *(self._on_arc(t) for t in self._angles()), self.N]

    def tangent_points(self) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
        """The arc's first and last point (:meth:`points`' second and second to last), or None
        twice where the cord lifts off."""
        if self.lifted:
            return None, None
        t = self._angles()
        return self._on_arc(t[0]), self._on_arc(t[-1])


def _wrap(P, N, centre, axis, rho):
    """(length, points along it) of :class:`_Wrap`'s path."""
    w = _Wrap(P, N, centre, axis, rho)
    return w.length, w.points()


def strand_path(params: HandParams, strand: Strand, Ts) -> tuple[float, np.ndarray]:
    """Length (m) and polyline (palm frame, metres) of a strand with the links at ``Ts``."""
    els = strand.elements
    total, pts = 0.0, []
    cur = None
    i = 0
    while i < len(els):
        e = els[i]
        if isinstance(e, Point):
            p = _world(Ts, e.link, e.pos)
            if cur is not None:
                total += float(np.linalg.norm(p - cur))
            pts.append(p)
            cur = p
            i += 1
            continue
        nxt = els[i + 1]
        N = _world(Ts, nxt.link, nxt.pos)
        length, wp = _wrap(cur, N, _world(Ts, e.link, e.centre), _world(Ts, e.link, e.axis, 0.0), e.radius)
        total += length
        pts.extend(wp[1:])
        cur = N
        i += 2
    return total, np.array(pts)


def strand_nodes(strand: Strand, Ts) -> list[tuple[np.ndarray | None, np.ndarray | None]]:
    """(arrival, departure) point of every element, palm frame: a point's own position; a pulley's
    two tangent points (None where the strand lifts off it)."""
    els = strand.elements
    out: list = [None] * len(els)
    for i, e in enumerate(els):
        if isinstance(e, Point):
            p = _world(Ts, e.link, e.pos)
            out[i] = (p, p)
    for i, e in enumerate(els):
        if isinstance(e, Pulley):
            out[i] = _Wrap(out[i - 1][1], out[i + 1][0], _world(Ts, e.link, e.centre),
                           _world(Ts, e.link, e.axis, 0.0), e.radius).tangent_points()
    return out


@dataclass(frozen=True)
class Run:
    """A straight stretch of a strand between two consecutive elements (a point, or where it leaves
    or reaches a pulley), at rest, in the frame of every link it is fixed to (``links``): the
    channel a part must leave open for it. ``links`` is empty for a free run (a chord across a
    joint, which moves relative to every link)."""
    tendon: str
    strand: str
    index: int                   # between elements index and index + 1 of the strand
    links: tuple[str, ...]
    ends: dict                   # link -> (p0, p1) in that link's frame (m)
    diameter: float              # of the cord (m)


_RUNS: dict = {}


def runs(params: HandParams, right_handed: bool = False) -> tuple[Run, ...]:
    """Every straight run of every strand, with the links it is fixed to. A run is fixed to a link
    when both its ends stay put in that link's frame at rest, at mid travel and at full travel
    (found by evaluating them there, not by case analysis: a tangent point is fixed to the link
    that holds both the pulley's axis and the point it comes from). ``right_handed`` as for
    :func:`routes`."""
    return memoised(_RUNS, (params.digest, right_handed), lambda: _runs(params, right_handed), cap=16)


def _runs(params: HandParams, right_handed: bool) -> tuple[Run, ...]:
    q_full = np.zeros(N_JOINTS)
    for j in JOINTS:
        if j.key != "cmc":
            q_full[j.index] = joint_travel(params, j.name)
    # the loop's pulleys turn too
    q_full[CMC_Q] = params.thumb.cmc_gain * params.thumb.cmc_travel[1]
    u_full = np.array([params.digit(s.digit).chain.travel[1] if s.drive == "tendon" else params.thumb.cmc_travel[1]
                       for s in SERVOS])
    poses = [pose(params, None, np.zeros(len(SERVOS))), mid_travel_pose(params), pose(params, q_full, u_full)]
    unmirror = F.MIRROR[:3, :3] if (right_handed and params.side == "left") else np.eye(3)
    inverses: list[dict] = [{} for _ in poses]      # T_link_palm of each pose, each inverted once

    def inverse(k: int, ln: str) -> np.ndarray:
        if ln not in inverses[k]:
            inverses[k][ln] = np.linalg.inv(poses[k][ln])
        return inverses[k][ln]
    out = []
    for r in routes(params):
        for st in r.strands:
            nodes = [strand_nodes(st, Ts) for Ts in poses]
            els = st.elements
            for i in range(len(els) - 1):
                ends = [(n[i][1], n[i + 1][0]) for n in nodes]
                if any(a is None or b is None for a, b in ends):
                    continue
                if any(isinstance(e, Point) and e.role == "clamp" for e in (els[i], els[i + 1])):
                    continue                  # a clamp sits on its pulley's circle: no straight run
                cands = dict.fromkeys(e.link for e in (els[i], els[i + 1]))
                fixed = {}
                for ln in cands:
                    loc = [tuple((inverse(k, ln) @ np.array([*p, 1.0]))[:3] for p in pair)
                           for k, pair in enumerate(ends)]
                    if all(np.linalg.norm(a - b) < 1e-9 for pr in loc[1:] for a, b in zip(pr, loc[0])):
                        fixed[ln] = tuple(tuple(float(v) for v in unmirror @ p) for p in loc[0])
                out.append(Run(r.name, st.name, i, tuple(fixed), fixed, r.diameter))
    return tuple(out)


_POSES: dict = {}


_TRAVEL_NODES: dict = {}


def travel_poses(params: HandParams, fractions) -> tuple[dict[str, np.ndarray], ...]:
    """T_palm_link with every flexion joint and tendon servo at each fraction of its travel (the
    joints to the clamps' design travel, :func:`joint_travel`; the CMC at rest). Memoised by
    the parameters' digest and the fractions (read-only)."""
    fr = tuple(float(f) for f in fractions)
    return memoised(_POSES, (params.digest, fr), lambda: _travel_poses(params, fr), cap=16)


def travel_nodes(params: HandParams, strand: Strand, fractions) -> tuple[list, ...]:
    """:func:`strand_nodes` of ``strand`` at each of :func:`travel_poses` (memoised, read-only)."""
    fr = tuple(float(f) for f in fractions)
    return memoised(_TRAVEL_NODES, (params.digest, strand, fr),
                    lambda: tuple(strand_nodes(strand, Ts) for Ts in travel_poses(params, fr)), cap=512)


def _travel_poses(params: HandParams, fractions) -> tuple[dict[str, np.ndarray], ...]:
    out = []
    for f in fractions:
        q = np.zeros(N_JOINTS)
        for j in JOINTS:
            if j.key != "cmc":
                q[j.index] = f * joint_travel(params, j.name)
        u = np.array([f * params.digit(s.digit).chain.travel[1] if s.drive == "tendon" else 0.0 for s in SERVOS])
        out.append(pose(params, q, u))
    return tuple(out)


def arc_range(params: HandParams, strand: Strand, index: int,
              fractions=tuple(np.linspace(0.0, 1.0, 11))) -> tuple[float, float]:
    """The polar angles (rad, about the pulley's centre in its link's (y, z) plane, from +y toward
    +z) between which strand element ``index`` (a pulley) is ever in contact over the travel: the
    sector its groove must span. Mirror-invariant (a left hand mirrors x only)."""
    e = strand.elements[index]
    angles = []
    for Ts, nodes in zip(travel_poses(params, fractions), travel_nodes(params, strand, fractions)):
        tin, tout = nodes[index]
        if tin is None:
            continue
        inv = np.linalg.inv(Ts[e.link])
        for p in (tin, tout):
            v = (inv @ np.array([*p, 1.0]))[:3] - np.asarray(e.centre)
            angles.append(math.atan2(v[2], v[1]))
        # the arc between them, on the side the strand turns
        a0, a1 = angles[-2], angles[-1]
        turn = (a1 - a0) % (2 * math.pi) if e.axis[0] > 0 else -((a0 - a1) % (2 * math.pi))
        angles.append(a0 + turn / 2.0)
    ref = angles[0]
    rel = [((a - ref + math.pi) % (2 * math.pi)) - math.pi for a in angles]
    return ref + min(rel), ref + max(rel)


def run_sweep(params: HandParams, run: Run, link_name: str, fractions=tuple(np.linspace(0.0, 1.0, 21)),
              right_handed: bool = False) -> list[tuple[np.ndarray, np.ndarray]]:
    """The ends of a run (m) in ``link_name``'s frame at each fraction of the travel
    (:func:`travel_poses`): the region a free run (a chord across a joint) sweeps through a part."""
    st = next(s for r in routes(params) for s in r.strands if s.name == run.strand)
    S = F.MIRROR[:3, :3] if (right_handed and params.side == "left") else np.eye(3)
    out = []
    for Ts, n in zip(travel_poses(params, fractions), travel_nodes(params, st, fractions)):
        inv = np.linalg.inv(Ts[link_name])
        a, b = n[run.index][1], n[run.index + 1][0]
        if a is None or b is None:
            continue
        out.append(tuple(S @ (inv @ np.array([*p, 1.0]))[:3] for p in (a, b)))
    return out


def lengths(params: HandParams, q=None, u=None, which=None) -> dict[str, float]:
    """Every strand's length (m) at joint angles q and servo angles u."""
    Ts = pose(params, q, np.zeros(len(SERVOS)) if u is None else u)
    out = {}
    for r in which or routes(params):
        for s in r.strands:
            out[s.name] = strand_path(params, s, Ts)[0]
    return out


def mid_travel_pose(params: HandParams) -> dict[str, np.ndarray]:
    """T_palm_link with every flexion joint at half its travel (as the clamps are placed) and every
    tendon servo at the middle of its travel: where :func:`side_sites` places the side sites."""
    q = np.zeros(N_JOINTS)
    for j in JOINTS:
        if j.key != "cmc":
            q[j.index] = joint_travel(params, j.name) / 2.0
    u = np.array([sum(params.digit(s.digit).chain.travel) / 2.0 if s.drive == "tendon" else 0.0 for s in SERVOS])
    return pose(params, q, u)


def side_sites(params: HandParams, strand: Strand, Ts=None) -> list[tuple[str, tuple[float, float, float]] | None]:
    """For each element of ``strand``: None for a point; for a pulley, a point on the side its
    strand wraps (MuJoCo's ``sidesite``), fixed to the link that carries the strand's straight
    runs beside it, half a radius outside the arc's middle at the middle of every travel
    (``Ts``: :func:`mid_travel_pose`, computed when not given)."""
    Ts = mid_travel_pose(params) if Ts is None else Ts
    els = strand.elements
    out: list = []
    for i, e in enumerate(els):
        if isinstance(e, Point):
            out.append(None)
            continue
        prev, nxt = els[i - 1], els[i + 1]
        carrier = nxt.link if nxt.link != e.link else prev.link
        P, N = _world(Ts, prev.link, prev.pos), _world(Ts, nxt.link, nxt.pos)
        c = _world(Ts, e.link, e.centre)
        _, pts = _wrap(P, N, c, _world(Ts, e.link, e.axis, 0.0), e.radius)
        arc = pts[1:-1]
        mid = arc[len(arc) // 2] if len(arc) else (P + N) / 2.0
        a = _world(Ts, e.link, e.axis, 0.0)
        radial = (mid - c) - np.dot(mid - c, a) * a
        if np.linalg.norm(radial) < 1e-12:
            radial = np.cross(a, N - P)
        s = c + np.dot(mid - c, a) * a + 1.5 * e.radius * radial / np.linalg.norm(radial)
        local = np.linalg.inv(Ts[carrier]) @ np.array([*s, 1.0])
        out.append((carrier, tuple(float(v) for v in local[:3])))
    return out
