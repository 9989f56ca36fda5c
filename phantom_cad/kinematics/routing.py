"""The routing model: every tendon of the hand as path elements in link frames (the records and
the routes built from the parameters). numpy only.

One model, derived from the parameters, from which the MJCF's spatial tendons, the tendon
lengths of the BOM, ``routing.json`` and the checks come (and, in the CAD layer, the channels and
grooves cut into the parts). docs/transmission.md describes the mechanism and the file format.
The rules a route must keep (its clamps' wraps over the travel) are :mod:`.routing_rules`'s; the
strands posed, measured and swept :mod:`.routing_paths`'; the split drives :mod:`.couplers`'; the
file :mod:`.routing_json`'s.

A tendon (a ``topology.Tendon``) is one or two *strands*; a strand is a sequence of elements,
each in the frame of the link it is fixed to (metres, mirrored for a left hand):

* :class:`Point`: an ``anchor`` (a knot, a clamp: the strand ends there) or a ``via`` point
  (an eyelet, a channel bend, the crossing of a figure-eight loop);
* :class:`Pulley`: a circle the strand wraps (a hub, a groove, the servo pulley): centre, axis and
  radius of the tendon's *centreline* (the pulley radius R_i of the paper is the moment arm, so the
  groove floor lies half a tendon diameter inside it). The strand turns positively (right-hand
  rule) about ``axis`` from where it arrives to where it leaves. A pulley always lies between two
  points (as MuJoCo's spatial tendons require).

The mechanism (right hand; x ulnar, y along the link, z dorsal in every link frame):

* **Drive** (one per tendon servo): clamped on the servo pulley (radius r_j) and wound on it by
  the servo's angle u, through the palm to the digit's interface (the magnet face, where the drive
  is split by a coupler), through the metacarpal-side guide G1 (d1) to the phalanx-side guide G2
  (d2) on the proximal phalanx, where it is anchored. Its length is
  const + chord(q_ref) - r_j u: the free chord G1-G2 is the L of eq. (4)-(6).
* **Coupling loops** (one per pair of adjacent joints a, b, carried by the link C between them):
  a closed cord clamped on a hub fixed to the link *before* a (radius R_a) and on the groove of
  the link *after* b (radius R_b), crossed once between them (figure eight). Each of its two
  strands has length const +- (R_a q_a - R_b q_b): the loop holds R_a q_a = R_b q_b (eq. 2).
  Loops alternate sides: the MCP-PIP loop in the ulnar half of the slot, the PIP-DIP loop in the
  radial half, each in one plane.
* **CMC loop** (servo 6 to the CMC pulley on the CMC base's column, :func:`_cmc_loop`): a closed
  cord with two strands between two pulleys in one plane; it holds q15 = cmc_gain u6.
* **Return** (the dorsal cable-spring): anchored on the digit's first link, over the dorsal side
  of every chain joint at its radius R_i, anchored on the distal phalanx. Via points on each link
  hold it tangent to every groove even at rest, so its length is const + sum R_i q_i exactly and
  its tension k_s sum R_i q_i (eq. 11).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import forearm_layout as FL
from . import frames as F
from . import link_frames as LF
from . import servo_geometry as SG
from . import thenar as TH
from .dimensions import FLANK, slot_back
from .hand_params import HandParams
from .memo import memoised
from .routing_rules import (WRAP_MARGIN, clamp_angle, cmc_loop_clamps, joint_travel, limit_field, loop_travel_rule,
                            servo_clamp_wrap)
from .topology import (CHAINS, CMC_PULLEY, CMC_Q, CMC_SERVO, JOINTS, SERVOS, TENDONS, Tendon, chain, digit_links,
                       joint, link)


#: a clamp sits this far outside its pulley's centreline circle (m): a simulator's wrapping needs the
#: strand's end outside the cylinder; the length this changes is of order (2 rho e)^1.5 / rho, < 1 nm
CLAMP_OFFSET = 1e-6


@dataclass(frozen=True)
class Point:
    kind: str                    # "anchor" or "via"
    link: str
    pos: tuple[float, float, float]
    role: str                    # "clamp", "interface", "guide", "crossing", "channel", "knot", ...


@dataclass(frozen=True)
class Pulley:
    link: str
    centre: tuple[float, float, float]
    axis: tuple[float, float, float]      # the strand turns positively about it
    radius: float                          # of the tendon centreline (the moment arm)
    width: float                           # the groove's width along the axis
    role: str                              # "servo", "hub", "groove", "return"
    joint: str | None = None               # the joint (or servo) it sits on


@dataclass(frozen=True)
class Strand:
    name: str
    elements: tuple[Point | Pulley, ...]


@dataclass(frozen=True)
class Route:
    """One tendon of the topology, routed: its strands, and what it is made of."""
    tendon: Tendon
    strands: tuple[Strand, ...]
    diameter: float              # the cord's diameter (m)
    stiffness: str               # "EA" (a tendon) or "k_s" (the elastic return cord)

    @property
    def name(self) -> str:
        return self.tendon.name


@dataclass(frozen=True)
class Layout:
    """Where a digit's tendons run across its joints (x in every link frame of the digit,
    right hand, metres)."""
    slot_half: float             # half the clevis slot (between the cheeks)
    groove: float                # width of a tendon groove (tendon + two clearances)
    return_groove: float         # width of the return cord's groove
    loop_x: tuple[float, ...]    # plane of each coupling loop, chain order
    return_x: float              # plane of the return cord
    hub_width: float             # a hub beside the cheek: from the cheek face to its inner flank


def layout(params: HandParams, digit: str) -> Layout:
    """The planes: loop k in the slot's half of sign (-1)^k (ulnar first), its groove one flank
    and one clearance inside the slot's edge; its hub on the cheek of that side, one flank wider
    than the groove; the return cord one flank inside the tongue that the second hub leaves."""
    d = params.digit(digit)
    c = params.print.hole_clearance
    g = params.hardware.tendon_diameter + 2.0 * c
    gr = params.cad.spring_diameter + 2.0 * c
    s = (d.width - 2.0 * params.cad.cheek) / 2.0
    x_loop = s - c - FLANK - g / 2.0
    hub = c + 2.0 * FLANK + g
    n_loops = len(chain(digit).keys) - 1
    loops = tuple((1.0 if k % 2 == 0 else -1.0) * x_loop for k in range(n_loops))
    x_ret = -(s - hub - c - FLANK - gr / 2.0)
    return Layout(s, g, gr, loops, x_ret, hub)


def _yz(angle: float, r: float) -> np.ndarray:
    return np.array([r * math.cos(angle), r * math.sin(angle)])


def _child_origin(rest: dict[str, np.ndarray], jname: str) -> np.ndarray:
    """The joint's axis point (its child's origin) in its parent's frame, from the rest transforms."""
    j = joint(jname)
    return rest[f"T_{j.parent}_{j.child}"][:3, 3].copy()


def _segment(params: HandParams, link_name: str) -> float:
    return float(F.segment_length(params, link(link_name)))


X = np.array([1.0, 0.0, 0.0])


def _p(x: float, yz) -> tuple[float, float, float]:
    return (float(x), float(yz[0]), float(yz[1]))


def _loop(params: HandParams, digit: str, k: int, lay: Layout, rest) -> tuple[Strand, Strand]:
    """The figure-eight loop between chain joints k and k+1 (see the module doc)."""
    ch = params.digit(digit).chain
    spec = chain(digit)
    ja, jb = spec.joint_names[k], spec.joint_names[k + 1]
    A, C, B = joint(ja).parent, joint(ja).child, joint(jb).child
    Ra, Rb = ch.radii[k], ch.radii[k + 1]
    L = _segment(params, C)
    x = lay.loop_x[k]
    gamma = math.acos((Ra + Rb) / L)                  # tangent points' polar angle (from X)
    Xc = np.array([L * Ra / (Ra + Rb), 0.0])          # the crossing, on the carrier
    # clamp on the hub (fixed to A), polar angle in C at rest phi: strand a wraps phi - gamma + q_a,
    # strand b 2 pi - gamma - phi - q_a; both inside (margin, pi - margin) over the travel
    qa, qb, m = joint_travel(params, ja), joint_travel(params, jb), WRAP_MARGIN
    loop = f"{digit} {joint(ja).key.upper()}-{joint(jb).key.upper()}"
    phi = clamp_angle(max(gamma + m, math.pi - gamma + m), min(math.pi + gamma - qa - m, 2 * math.pi - gamma - qa - m),
                       f"{loop} loop's hub", params, *limit_field(params, digit, ja),
                       loop_travel_rule(ja, jb, C, ja, qa, gamma, L, Ra, Rb))
    # clamp on the groove (fixed to B, centre at y = L of C), polar angle psi about B's centre:
    # strand a wraps psi - pi - gamma - q_b, strand b 2 pi - 2 gamma minus that
    wa = clamp_angle(math.pi - 2 * gamma + qb + m, math.pi - m, f"{loop} loop's groove",
                      params, *limit_field(params, digit, jb),
                      loop_travel_rule(ja, jb, C, jb, qb, gamma, L, Ra, Rb))
    psi = wa + math.pi + gamma
    hub_c = _child_origin(rest, ja)                   # joint a's axis in A's frame
    cA = hub_c + np.array([x, 0.0, 0.0])
    clamp_A = cA + np.array([0.0, *_yz(phi, Ra + CLAMP_OFFSET)])   # A's frame = C's frame at rest
    clamp_B = np.array([x, *_yz(psi, Rb + CLAMP_OFFSET)])
    hub = lambda axis: Pulley(A, _p(x, cA[1:]), axis, Ra, lay.groove, "hub", ja)  # noqa: E731
    groove = lambda axis: Pulley(B, (float(x), 0.0, 0.0), axis, Rb, lay.groove, "groove", jb)  # noqa: E731
    cross = Point("via", C, _p(x, Xc), "crossing")
    name = f"{digit}_{spec.keys[k]}_{spec.keys[k + 1]}"
    # strand a: clamp on the hub, over its dorsal side (turning clockwise in (y, z): about -x),
    # across, under the groove (about -x again: from pi + gamma on to psi)
    a = Strand(f"{name}_a", (Point("anchor", A, _p(x, clamp_A[1:]), "clamp"), hub(tuple(-X)), cross,
                             groove(tuple(X)), Point("anchor", B, _p(x, clamp_B[1:]), "clamp")))
    b = Strand(f"{name}_b", (Point("anchor", A, _p(x, clamp_A[1:]), "clamp"), hub(tuple(X)), cross,
                             groove(tuple(-X)), Point("anchor", B, _p(x, clamp_B[1:]), "clamp")))
    return a, b


def _return(params: HandParams, digit: str, lay: Layout, rest) -> Strand:
    """The dorsal cable-spring: tangent to every joint's groove at its radius, on both sides."""
    spec = chain(digit)
    ch = params.digit(digit).chain
    d = params.digit(digit)
    links = [ln.name for ln in digit_links(digit) if ln.segment != "servo_pulley"]
    x = lay.return_x
    first = links[0]
    # anchored on the first link, half way between its start and the first joint's clevis slot
    # (the slot's back wall, dimensions.slot_back: the knot's well must be cut in material)
    ja0 = _child_origin(rest, spec.joint_names[0])
    start = _segment(params, first) if _segment(params, first) > 0 else params.cad.finger_base_length
    y0 = ja0[1] - (start + slot_back(d.thickness, params.print.hole_clearance)) / 2.0
    els: list = [Point("anchor", first, (float(x), float(y0), float(ch.radii[0])), "knot")]
    e = lay.return_groove      # the cord leaves / reaches each groove tangentially over this run
    for k, jn in enumerate(spec.joint_names):
        j = joint(jn)
        R = ch.radii[k]
        c = _child_origin(rest, jn)
        # tangent on the parent's side, then the groove on the child (the cord slides on it)
        els.append(Point("via", j.parent, (float(x), float(c[1] - e), float(R)), "channel"))
        els.append(Pulley(j.child, (float(x), 0.0, 0.0), tuple(-X), R, lay.return_groove, "return", jn))
        els.append(Point("via", j.child, (float(x), float(e), float(R)), "channel"))
    last = links[-1]
    y_end = max(2.0 * e, _segment(params, last) - d.thickness / 2.0)
    els.append(Point("anchor", last, (float(x), float(y_end), float(ch.radii[-1])), "knot"))
    return Strand(f"{digit}_return", tuple(els))


def _drive(params: HandParams, digit: str) -> Strand:
    spec = chain(digit)
    servo = SERVOS[spec.servo]
    r = F.servo_radius(params, servo.index)
    w0 = servo_clamp_wrap(params, servo.index)
    # servo frame: the tendon leaves the pulley at (-r, 0, 0) along +y, so it winds clockwise in
    # (x, y) seen from +z: from the clamp at polar angle pi + w0 (x toward y) down to pi
    rc = r + CLAMP_OFFSET
    clamp = (rc * math.cos(math.pi + w0), rc * math.sin(math.pi + w0), 0.0)
    els: list = [Point("anchor", servo.link, clamp, "clamp"),
                 Pulley(servo.link, (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), r,
                        params.cad.servo_pulley_width, "servo", servo.name)]
    (l1, g1), (l2, g2) = F.guide_sites(params, digit)
    if params.side == "left":        # guide_sites mirrors; the routes are right-handed until the end
        g1, g2 = F.MIRROR[:3, :3] @ g1, F.MIRROR[:3, :3] @ g2
    first = spec.joint_names[0]
    base = joint(first).parent
    if digit == "thumb":
        t = TH.thenar(params)
        P = lambda s: tuple(float(v) for v in TH.thenar_axis_point(params, s))  # noqa: E731
        # the drive runs level from its pulley (aimed at the turn, at its height) to its turn onto
        # the CMC axis above the CMC pulley's cavity, and down the axis into the CMC base's column
        els += [Point("via", "palm", P(t["turn"]), "over the CMC axis"),
                Point("via", "palm", P(t["ceiling"]), "CMC axis")]
        # down the column into the CMC base, and along it to G1
        els.append(Point("via", base, (0.0, 0.0, float(g1[2])), "interface"))
    else:
        z = F.tendon_height(params)
        els.append(Point("via", base, (0.0, -params.cad.finger_base_length, float(z)), "interface"))
    els += [Point("via", base, tuple(float(v) for v in g1), "guide G1"),
            Point("anchor", l2, tuple(float(v) for v in g2), "guide G2")]
    return Strand(f"{digit}_drive", tuple(els))


def _cmc_loop(params: HandParams) -> tuple[Strand, Strand]:
    """The closed loop from servo 6's pulley to the CMC pulley (equal radii r6: q15 = u6): strand a
    leaves servo 6's pulley at its -x along its y, strand b at its +x; both reach the CMC pulley
    on the same sides (an open loop: both pulleys turn the same way) and end at one clamp on each
    pulley (:func:`cmc_loop_clamps`). Turning servo 6's pulley by u6 (:func:`pose`) changes strand
    a's path by + r6 u6 and b's by - r6 u6, turning the CMC by q15 by - r6 q15 / cmc_gain and + r6
    q15 / cmc_gain: both paths keep their lengths exactly when q15 = cmc_gain u6. A via point where each strand crosses the gap
    between the palm and the forearm module holds it between the two wraps (servo 6's pulley lies in
    the CMC pulley's plane, ``servo_geometry.coplanar_servo``: the strands are straight and in both planes)."""
    s = SERVOS[CMC_SERVO]
    r, rq = F.servo_radius(params, s.index), F.cmc_pulley_radius(params)
    w = params.cad.servo_pulley_width
    Ts = FL.T_palm_servo(params, s.index)
    # the CMC pulley's frame turned so that its y points away from servo 6 (the strands reach it
    # at its -x and +x, as they leave servo 6's pulley)
    turn = FL.cmc_loop_direction(params) - math.pi / 2.0
    Tq = F.T_palm_thumb_cmc_base(params) @ TH.T_cmc_base_pulley(params) @ F.rot_z(turn)
    (sa, sb), (qa, qb) = cmc_loop_clamps(params)
    clamps = {"a": (sa, qa + turn), "b": (sb, qb + turn)}
    y_gap = SG.forearm_front(params) + params.print.hole_clearance / 2.0
    out = []
    for name, side, axis in (("a", -1.0, -1.0), ("b", 1.0, 1.0)):
        cs, cq = clamps[name]
        p0 = (Ts @ np.array([side * r, 0.0, 0.0, 1.0]))[:3]
        p1 = (Tq @ np.array([side * rq, 0.0, 0.0, 1.0]))[:3]
        t = (y_gap - p0[1]) / (p1[1] - p0[1])
        via = p0 + t * (p1 - p0)
        out.append(Strand(f"thumb_cmc_loop_{name}", (
            Point("anchor", s.link, ((r + CLAMP_OFFSET) * math.cos(cs), (r + CLAMP_OFFSET) * math.sin(cs), 0.0),
                  "clamp"),
            Pulley(s.link, (0.0, 0.0, 0.0), (0.0, 0.0, axis), r, w, "servo", s.name),
            Point("via", "palm", tuple(float(v) for v in via), "channel"),
            Pulley(CMC_PULLEY, (0.0, 0.0, 0.0), (0.0, 0.0, axis), rq, w, "loop", JOINTS[CMC_Q].name),
            Point("anchor", CMC_PULLEY, ((rq + CLAMP_OFFSET) * math.cos(cq), (rq + CLAMP_OFFSET) * math.sin(cq), 0.0),
                  "clamp"))))
    return tuple(out)


def mp_turn(params: HandParams) -> tuple[str, np.ndarray, np.ndarray] | None:
    """(the thumb metacarpal's link, R, o) of the thumb's twist: what is fixed to the metacarpal on
    its MP's side turns by R about the line through o (m, the MP's centre) along the metacarpal's
    length (``link_frames.joint_origin``); None for an untwisted thumb."""
    mp = joint(LF.THUMB_MP)
    T = LF.joint_origin(params, link(mp.child))
    if T is None or np.array_equal(T[:3, :3], np.eye(3)):
        return None
    return mp.parent, T[:3, :3].copy(), T[:3, 3].copy()


def _turned_with_mp(params: HandParams, strands: tuple[Strand, ...]) -> tuple[Strand, ...]:
    """The thumb's strands with what they fix to the metacarpal on its MP's side (the drive's guide
    G1, the MP-IP loop's hub and clamp, the return's knot and channel) turned with the MP by the
    thumb's twist about the metacarpal's length (:func:`mp_turn`: the part is built so). The drive
    enters from the column on the CMC axis, where q15 leaves its length alone, and runs to the
    entry's turned image (where the turned arm's channel starts) before G1."""
    turned = mp_turn(params)
    if turned is None:
        return strands
    base, R, o = turned
    turn = lambda v: tuple(float(t) for t in o + R @ (np.asarray(v, float) - o))  # noqa: E731

    def elements(els):
        for e in els:
            if e.link != base:
                yield e
            elif isinstance(e, Point) and e.role == "interface":
                yield e
                yield Point("via", e.link, turn(e.pos), "channel")
            elif isinstance(e, Point):
                yield Point(e.kind, e.link, turn(e.pos), e.role)
            else:
                yield Pulley(e.link, turn(e.centre), tuple(float(t) for t in R @ np.asarray(e.axis, float)), e.radius,
                             e.width, e.role, e.joint)
    return tuple(Strand(st.name, tuple(elements(st.elements))) for st in strands)


def _mirror_element(e):
    S = F.MIRROR[:3, :3]
    mirror = lambda v: tuple(float(t) for t in S @ np.asarray(v, float))  # noqa: E731
    if isinstance(e, Point):
        return Point(e.kind, e.link, mirror(e.pos), e.role)
    # a reflection turns a positive rotation about a into a positive one about -S a
    return Pulley(e.link, mirror(e.centre), tuple(-v for v in mirror(e.axis)), e.radius, e.width, e.role, e.joint)


_ROUTES: dict = {}


def routes(params: HandParams, right_handed: bool = False) -> tuple[Route, ...]:
    """Every tendon of the topology (``TENDONS`` order), routed for this hand (memoised by the
    parameters' digest and side: the routes are pure functions of them). ``right_handed``: the
    routes before a left hand's mirroring, in the frames the parts are built in (the CAD layer
    cuts right-handed parts and mirrors them on export)."""
    mirror = params.side == "left" and not right_handed
    return memoised(_ROUTES, (params.digest, mirror), lambda: _routes(params, mirror), cap=16)


def _routes(params: HandParams, mirror: bool) -> tuple[Route, ...]:
    out = []
    lays = {ch.digit: layout(params, ch.digit) for ch in CHAINS}
    rest = LF.rest_transforms(params)
    for t in TENDONS:
        lay = lays[t.digit]
        if t.kind == "drive":
            strands, d, k = (_drive(params, t.digit),), params.hardware.tendon_diameter, "EA"
        elif t.kind == "coupling":
            keys = chain(t.digit).keys
            k0 = keys.index(t.joints[0].split("_", 1)[1])
            strands, d, k = _loop(params, t.digit, k0, lay, rest), params.hardware.tendon_diameter, "EA"
        elif t.kind == "loop":
            strands, d, k = _cmc_loop(params), params.hardware.tendon_diameter, "EA"
        else:
            strands, d, k = (_return(params, t.digit, lay, rest),), params.cad.spring_diameter, "k_s"
        if t.digit == JOINTS[CMC_Q].digit:
            strands = _turned_with_mp(params, strands)
        if mirror:
            strands = tuple(Strand(s.name, tuple(_mirror_element(e) for e in s.elements)) for s in strands)
        out.append(Route(t, strands, d, k))
    return tuple(out)
