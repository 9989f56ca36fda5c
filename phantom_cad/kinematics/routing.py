"""The routing model: every tendon of the hand as path elements in link frames. numpy only.

One model, derived from the parameters, from which the MJCF's spatial tendons, the tendon
lengths of the BOM, ``routing.json`` and the checks come (and, in the CAD layer, the channels and
grooves cut into the parts). docs/transmission.md describes the mechanism and the file format.

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

from ..errors import ParamError
from .dimensions import FLANK, digit_field, slot_back
from . import frames as F
from .memo import memoised
from .topology import (CHAINS, CMC_PULLEY, CMC_Q, CMC_SERVO, JOINTS, N_JOINTS, SERVOS, TENDONS, Tendon, chain,
                       digit_links, joint, link)

#: every wrap stays this far inside (0, 180 deg) over the joint's whole travel (rad)
WRAP_MARGIN = math.radians(8.0)
#: a clamp sits this far outside its pulley's centreline circle (m): a simulator's wrapping needs the
#: strand's end outside the cylinder; the length this changes is of order (2 rho e)^1.5 / rho, < 1 nm
CLAMP_OFFSET = 1e-6
#: a loop's clamps are placed for a travel this far past the joint's upper limit (rad)
TRAVEL_MARGIN = math.radians(3.0)


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


# ---------------------------------------------------------------------------
# layout: the planes of the loops and the return cord in a digit's slot
# ---------------------------------------------------------------------------

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


def layout(params, digit: str) -> Layout:
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


# ---------------------------------------------------------------------------
# plane geometry
# ---------------------------------------------------------------------------

def _yz(angle: float, r: float) -> np.ndarray:
    return np.array([r * math.cos(angle), r * math.sin(angle)])


def _clamp_angle(lo: float, hi: float, what: str, params, field: str, value, why: str) -> float:
    """The middle of [lo, hi]; a ParamError naming ``field`` (its ``value``) when it is empty: no
    clamp keeps every wrap of ``what`` inside (WRAP_MARGIN, 180 deg - WRAP_MARGIN) over the travel
    (``why``: what that asks of the parameters, in their words)."""
    if hi - lo < 0.0:
        raise ParamError(field, value, f"no clamp position on the {what} keeps every wrap inside "
                         f"({math.degrees(WRAP_MARGIN):g}, {180 - math.degrees(WRAP_MARGIN):g} deg) over the "
                         f"travel: {why}", params.source)
    return (lo + hi) / 2.0


def _joint_travel(params, jname: str) -> float:
    j = joint(jname)
    lim = dict(zip(params.digit(j.digit).chain.joints, params.digit(j.digit).chain.limits))[j.key]
    return lim[1] + TRAVEL_MARGIN + (params.cad.module_stop_margin if link(j.parent).segment == "base" else 0.0)


def _child_origin(rest: dict[str, np.ndarray], jname: str) -> np.ndarray:
    """The joint's axis point (its child's origin) in its parent's frame, from the rest transforms."""
    j = joint(jname)
    return rest[f"T_{j.parent}_{j.child}"][:3, 3].copy()


def _segment(params, link_name: str) -> float:
    return float(F.segment_length(params, link(link_name)))


# ---------------------------------------------------------------------------
# the routes
# ---------------------------------------------------------------------------

X = np.array([1.0, 0.0, 0.0])


def _p(x: float, yz) -> tuple[float, float, float]:
    return (float(x), float(yz[0]), float(yz[1]))


def _limit_field(params, digit: str, jname: str) -> tuple[str, list[float]]:
    """The parameter field (and its value) a loop's clamp rule names: the joint's limits."""
    ch = params.digit(digit).chain
    key = joint(jname).key
    return f"{digit_field(digit)}.limits_rad.{key}", [round(v, 6) for v in dict(zip(ch.joints, ch.limits))[key]]


def _loop_travel_rule(ja: str, jb: str, carrier: str, jname: str, q: float, gamma: float, L: float,
                      Ra: float, Rb: float) -> str:
    """Why a loop's clamp cannot be placed: both clamps exist while each joint's travel (limit +
    margins) stays under 2 gamma - 2 WRAP_MARGIN, gamma = acos((R_a + R_b) / L)."""
    m = WRAP_MARGIN
    stop = " + cad.module_stop_margin_deg" if link(joint(jname).parent).segment == "base" else ""
    return (f"the {joint(jname).key.upper()} travel ({math.degrees(q):.2f} deg: the upper limit + "
            f"{math.degrees(TRAVEL_MARGIN):g} deg{stop}) must stay under 2 acos((R_{joint(ja).key} + "
            f"R_{joint(jb).key}) / L_{link(carrier).segment}) - {2 * math.degrees(m):g} deg = "
            f"{math.degrees(2 * gamma - 2 * m):.2f} deg (L = {L * 1e3:.2f} mm, R = {Ra * 1e3:g} and "
            f"{Rb * 1e3:g} mm: smaller pulley radii or a longer phalanx allow more)")


def _loop(params, digit: str, k: int, lay: Layout, rest) -> tuple[Strand, Strand]:
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
    qa, qb, m = _joint_travel(params, ja), _joint_travel(params, jb), WRAP_MARGIN
    loop = f"{digit} {joint(ja).key.upper()}-{joint(jb).key.upper()}"
    phi = _clamp_angle(max(gamma + m, math.pi - gamma + m), min(math.pi + gamma - qa - m, 2 * math.pi - gamma - qa - m),
                       f"{loop} loop's hub", params, *_limit_field(params, digit, ja),
                       _loop_travel_rule(ja, jb, C, ja, qa, gamma, L, Ra, Rb))
    # clamp on the groove (fixed to B, centre at y = L of C), polar angle psi about B's centre:
    # strand a wraps psi - pi - gamma - q_b, strand b 2 pi - 2 gamma minus that
    wa = _clamp_angle(math.pi - 2 * gamma + qb + m, math.pi - m, f"{loop} loop's groove",
                      params, *_limit_field(params, digit, jb),
                      _loop_travel_rule(ja, jb, C, jb, qb, gamma, L, Ra, Rb))
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


def _return(params, digit: str, lay: Layout, rest) -> Strand:
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


def servo_clamp_wrap(params, servo: int) -> float:
    """Wrap (rad) of a drive on its servo pulley at u = 0: the largest that keeps the wrap inside
    (margin, 180 deg - margin) over the servo's travel, so that unwinding below the travel to the
    service angle pays the most cord out (:class:`Coupler`)."""
    digit = SERVOS[servo].digit
    lo, travel = params.digit(digit).chain.travel
    m = math.degrees(WRAP_MARGIN)
    hi = math.pi - WRAP_MARGIN - travel
    _clamp_angle(WRAP_MARGIN, hi, f"servo {servo + 1} pulley", params,
                 f"{digit_field(digit)}.servo_travel_deg", [round(math.degrees(lo), 6), round(math.degrees(travel), 6)],
                 f"the servo's travel must be at most {180 - 2 * m:g} deg (a wrap is modelled up to 180 deg)")
    return hi


def _drive(params, digit: str) -> Strand:
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
        t = F.thenar(params)
        P = lambda s: tuple(float(v) for v in F.thenar_axis_point(params, s))  # noqa: E731
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


#: how far (rad) each of the CMC loop's clamps sits inside the wraps the travel allows
LOOP_CLAMP_MARGIN = math.radians(2.0)


def cmc_loop_clamps(params) -> tuple[tuple[float, float], tuple[float, float]]:
    """Polar angles (rad, right hand, each pulley's frame at rest: servo 6's, and the CMC pulley's
    turned so that its y points away from servo 6) of the CMC loop's clamps, strand a's and strand
    b's, on servo 6's pulley and on the CMC pulley. Each strand winds on one pulley as it unwinds
    from the other; its wrap stays inside (WRAP_MARGIN, 180 deg - WRAP_MARGIN) over a pulley's
    travel T (servo 6's; the CMC's, cmc_gain times it). Each clamp sits LOOP_CLAMP_MARGIN inside its
    strand's allowed wraps, on the side that keeps the two clamps of a pulley furthest apart:
    180 deg - 2 WRAP_MARGIN - T - 2 LOOP_CLAMP_MARGIN (70.1 deg by default), room for two knot
    wells."""
    lo, hi = params.thumb.cmc_travel
    m, d = WRAP_MARGIN, LOOP_CLAMP_MARGIN
    out = []
    for what, travel in (("servo 6's pulley", hi - lo), ("CMC pulley", params.thumb.cmc_gain * (hi - lo))):
        _clamp_angle(m + d, math.pi - m - d - travel, f"CMC loop's {what}", params,
                     "thumb.cmc_servo_travel_deg", [round(math.degrees(lo), 6), round(math.degrees(hi), 6)],
                     f"the pulley's travel must be at most {180 - 2 * math.degrees(m + d):g} deg (a wrap is "
                     f"modelled up to 180 deg, each clamp {math.degrees(d):g} deg inside it)")
        out.append(travel)
    ts, tq = out
    # servo 6: a winds (wrap m + d at rest, clamp at pi + wrap), b unwinds (m + d + T, clamp at -wrap)
    servo = (math.pi + m + d, -(m + d + ts))
    # the CMC pulley: a unwinds (m + d + T, clamp at pi - wrap), b winds (m + d, clamp at wrap)
    cmc = (math.pi - (m + d + tq), m + d)
    return servo, cmc


def _cmc_loop(params) -> tuple[Strand, Strand]:
    """The closed loop from servo 6's pulley to the CMC pulley (equal radii r6: q15 = u6): strand a
    leaves servo 6's pulley at its -x along its y, strand b at its +x; both reach the CMC pulley
    on the same sides (an open loop: both pulleys turn the same way) and end at one clamp on each
    pulley (:func:`cmc_loop_clamps`). Turning servo 6's pulley by u6 (:func:`pose`) changes strand
    a's path by + r6 u6 and b's by - r6 u6, turning the CMC by q15 by - r6 q15 / cmc_gain and + r6
    q15 / cmc_gain: both paths keep their lengths exactly when q15 = cmc_gain u6. A via point where each strand crosses the gap
    between the palm and the forearm module holds it between the two wraps (servo 6's pulley lies in
    the CMC pulley's plane, ``frames.coplanar_servo``: the strands are straight and in both planes)."""
    s = SERVOS[CMC_SERVO]
    r, rq = F.servo_radius(params, s.index), F.cmc_pulley_radius(params)
    w = params.cad.servo_pulley_width
    Ts = F.T_palm_servo(params, s.index)
    # the CMC pulley's frame turned so that its y points away from servo 6 (the strands reach it
    # at its -x and +x, as they leave servo 6's pulley)
    turn = F.cmc_loop_direction(params) - math.pi / 2.0
    Tq = F.T_palm_thumb_cmc_base(params) @ F.T_cmc_base_pulley(params) @ F.rot_z(turn)
    (sa, sb), (qa, qb) = cmc_loop_clamps(params)
    clamps = {"a": (sa, qa + turn), "b": (sb, qb + turn)}
    y_gap = F.forearm_front(params) + params.print.hole_clearance / 2.0
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


def _mirror_element(e):
    S = F.MIRROR[:3, :3]
    mirror = lambda v: tuple(float(t) for t in S @ np.asarray(v, float))  # noqa: E731
    if isinstance(e, Point):
        return Point(e.kind, e.link, mirror(e.pos), e.role)
    # a reflection turns a positive rotation about a into a positive one about -S a
    return Pulley(e.link, mirror(e.centre), tuple(-v for v in mirror(e.axis)), e.radius, e.width, e.role, e.joint)


_ROUTES: dict = {}


def routes(params, right_handed: bool = False) -> tuple[Route, ...]:
    """Every tendon of the topology (``TENDONS`` order), routed for this hand (memoised by the
    parameters' digest and side: the routes are pure functions of them). ``right_handed``: the
    routes before a left hand's mirroring, in the frames the parts are built in (the CAD layer
    cuts right-handed parts and mirrors them on export)."""
    mirror = params.side == "left" and not right_handed
    return memoised(_ROUTES, (params.digest, mirror), lambda: _routes(params, mirror), cap=16)


def _routes(params, mirror: bool) -> tuple[Route, ...]:
    out = []
    lays = {ch.digit: layout(params, ch.digit) for ch in CHAINS}
    rest = F.rest_transforms(params)
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
        if mirror:
            strands = tuple(Strand(s.name, tuple(_mirror_element(e) for e in s.elements)) for s in strands)
        out.append(Route(t, strands, d, k))
    return tuple(out)


# ---------------------------------------------------------------------------
# posing and lengths
# ---------------------------------------------------------------------------

def servo_axis(params) -> np.ndarray:
    """A tendon servo's axis in its own (mirrored) frame: positive u winds its drive."""
    return np.array([0.0, 0.0, 1.0 if params.side == "right" else -1.0])


def _rotation(axis, angle: float) -> np.ndarray:
    a = np.asarray(axis, float)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    R = np.eye(4)
    R[:3, :3] = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    return R


def pose(params, q=None, u=None) -> dict[str, np.ndarray]:
    """T_palm_link of every link at joint angles q (15) and servo angles u (6): every servo's
    pulley turned by u about :func:`servo_axis` (servo 6's by u6: its loop holds q15 = cmc_gain u6
    when both are given so)."""
    Ts = F.link_transforms(params, q)
    if u is not None:
        ax = servo_axis(params)
        for s in SERVOS:
            Ts[s.link] = Ts[s.link] @ _rotation(ax, float(u[s.index]))
    return Ts


def _world(Ts, link_name, v, w=1.0) -> np.ndarray:
    return (Ts[link_name] @ np.array([*v, w]))[:3]


def _wrap(P, N, centre, axis, rho):
    """Composite path P -> tangent -> arc (positive about axis) -> tangent -> N. Returns
    (length, list of points along it). The cord lifts off (straight P-N) when the arc would
    exceed 180 degrees (a wrap the routes never ask for) or vanish."""
    a = axis / np.linalg.norm(axis)
    e1 = np.cross(a, [1.0, 0.0, 0.0])
    if np.linalg.norm(e1) < 1e-6:
        e1 = np.cross(a, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    loc = lambda p: np.array([np.dot(p - centre, e1), np.dot(p - centre, e2), np.dot(p - centre, a)])  # noqa: E731
    p, n = loc(P), loc(N)
    dp, dn = math.hypot(p[0], p[1]), math.hypot(n[0], n[1])
    if dp < rho * (1.0 - 1e-9) or dn < rho * (1.0 - 1e-9):
        raise ValueError("a route point lies inside its pulley")
    t_in = math.atan2(p[1], p[0]) + math.acos(min(1.0, rho / dp))
    t_out = math.atan2(n[1], n[0]) - math.acos(min(1.0, rho / dn))
    arc = (t_out - t_in) % (2.0 * math.pi)
    if arc > 2.0 * math.pi - 1e-9:      # a tangent run (no wrap) that rounding put a turn away
        arc = 0.0
    if arc > math.pi:
        return float(np.linalg.norm(N - P)), [P, N]
    l1 = math.sqrt(max(0.0, dp * dp - rho * rho))
    l3 = math.sqrt(max(0.0, dn * dn - rho * rho))
    planar = l1 + rho * arc + l3
    dz = n[2] - p[2]
    length = math.hypot(planar, dz)
    # points: the two tangent points and the arc, heights interpolated along the planar length
    pts = [P]
    k = max(2, int(arc / math.radians(5.0)) + 1)
    for i, t in enumerate(np.linspace(t_in, t_in + arc, k)):
        s = (l1 + rho * (t - t_in)) / planar if planar > 0 else 0.0
        h = p[2] + s * dz
        pts.append(centre + rho * math.cos(t) * e1 + rho * math.sin(t) * e2 + h * a)
    pts.append(N)
    return length, pts


def strand_path(params, strand: Strand, Ts) -> tuple[float, np.ndarray]:
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


def _nodes(strand: Strand, Ts) -> list[tuple[np.ndarray | None, np.ndarray | None]]:
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
            _, pts = _wrap(out[i - 1][1], out[i + 1][0], _world(Ts, e.link, e.centre),
                           _world(Ts, e.link, e.axis, 0.0), e.radius)
            out[i] = (pts[1], pts[-2]) if len(pts) > 2 else (None, None)
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


def runs(params, right_handed: bool = False) -> tuple[Run, ...]:
    """Every straight run of every strand, with the links it is fixed to. A run is fixed to a link
    when both its ends stay put in that link's frame at rest, at mid travel and at full travel
    (found by evaluating them there, not by case analysis: a tangent point is fixed to the link
    that holds both the pulley's axis and the point it comes from). ``right_handed`` as for
    :func:`routes`."""
    return memoised(_RUNS, (params.digest, right_handed), lambda: _runs(params, right_handed), cap=16)


def _runs(params, right_handed: bool) -> tuple[Run, ...]:
    q_full = np.zeros(N_JOINTS)
    for j in JOINTS:
        if j.key != "cmc":
            q_full[j.index] = _joint_travel(params, j.name)
    # the loop's pulleys turn too
    q_full[CMC_Q] = params.thumb.cmc_gain * params.thumb.cmc_travel[1]
    u_full = np.array([params.digit(s.digit).chain.travel[1] if s.drive == "tendon" else params.thumb.cmc_travel[1]
                       for s in SERVOS])
    poses = [pose(params, None, np.zeros(len(SERVOS))), mid_travel_pose(params), pose(params, q_full, u_full)]
    unmirror = F.MIRROR[:3, :3] if (right_handed and params.side == "left") else np.eye(3)
    out = []
    for r in routes(params):
        for st in r.strands:
            nodes = [_nodes(st, Ts) for Ts in poses]
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
                    loc = [tuple((np.linalg.inv(Ts[ln]) @ np.array([*p, 1.0]))[:3] for p in pair)
                           for Ts, pair in zip(poses, ends)]
                    if all(np.linalg.norm(a - b) < 1e-9 for pr in loc[1:] for a, b in zip(pr, loc[0])):
                        fixed[ln] = tuple(tuple(float(v) for v in unmirror @ p) for p in loc[0])
                out.append(Run(r.name, st.name, i, tuple(fixed), fixed, r.diameter))
    return tuple(out)


_POSES: dict = {}
_TRAVEL_NODES: dict = {}


def travel_poses(params, fractions) -> tuple[dict[str, np.ndarray], ...]:
    """T_palm_link with every flexion joint and tendon servo at each fraction of its travel (the
    joints to the clamps' design travel, :func:`_joint_travel`; the CMC at rest). Memoised by
    the parameters' digest and the fractions (read-only)."""
    fr = tuple(float(f) for f in fractions)
    return memoised(_POSES, (params.digest, fr), lambda: _travel_poses(params, fr), cap=16)


def travel_nodes(params, strand: Strand, fractions) -> tuple[list, ...]:
    """:func:`_nodes` of ``strand`` at each of :func:`travel_poses` (memoised, read-only)."""
    fr = tuple(float(f) for f in fractions)
    return memoised(_TRAVEL_NODES, (params.digest, strand, fr),
                    lambda: tuple(_nodes(strand, Ts) for Ts in travel_poses(params, fr)), cap=512)


def _travel_poses(params, fractions) -> tuple[dict[str, np.ndarray], ...]:
    out = []
    for f in fractions:
        q = np.zeros(N_JOINTS)
        for j in JOINTS:
            if j.key != "cmc":
                q[j.index] = f * _joint_travel(params, j.name)
        u = np.array([f * params.digit(s.digit).chain.travel[1] if s.drive == "tendon" else 0.0 for s in SERVOS])
        out.append(pose(params, q, u))
    return tuple(out)


def arc_range(params, strand: Strand, index: int, fractions=tuple(np.linspace(0.0, 1.0, 11))) -> tuple[float, float]:
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


def run_sweep(params, run: Run, link_name: str, fractions=tuple(np.linspace(0.0, 1.0, 21)),
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


def lengths(params, q=None, u=None, which=None) -> dict[str, float]:
    """Every strand's length (m) at joint angles q and servo angles u."""
    Ts = pose(params, q, np.zeros(len(SERVOS)) if u is None else u)
    out = {}
    for r in which or routes(params):
        for s in r.strands:
            out[s.name] = strand_path(params, s, Ts)[0]
    return out


# ---------------------------------------------------------------------------
# routing.json
# ---------------------------------------------------------------------------

def _element_doc(e) -> dict:
    if isinstance(e, Point):
        return {"type": e.kind, "role": e.role, "link": e.link, "pos_mm": [round(v * 1e3, 6) for v in e.pos]}
    return {"type": "pulley", "role": e.role, "link": e.link, "joint": e.joint,
            "centre_mm": [round(v * 1e3, 6) for v in e.centre], "axis": [round(v, 9) for v in e.axis],
            "radius_mm": round(e.radius * 1e3, 6), "width_mm": round(e.width * 1e3, 6)}


def document(params) -> dict:
    """``routing.json``: per tendon its kind, links, joints, servo, cord and strands (each a list of
    path elements in link frames, millimetres), and the rest length of every strand."""
    rest = lengths(params)
    split = couplers(params)
    tendons = []
    for r in routes(params):
        t = r.tendon
        extra = {}
        if t.kind == "drive" and t.digit in split:
            extra["split"] = coupler_document(params, split[t.digit])
        tendons.append({
            "name": t.name, "kind": t.kind, "digit": t.digit, "links": list(t.links), "joints": list(t.joints),
            "servo": None if t.servo is None else SERVOS[t.servo].name,
            "cord": {"diameter_mm": round(r.diameter * 1e3, 6), "stiffness": r.stiffness},
            "strands": [{"name": s.name, "rest_length_mm": round(rest[s.name] * 1e3, 6),
                         "elements": [_element_doc(e) for e in s.elements]} for s in r.strands],
            **extra,
        })
    return {"format": "phantom_cad routing 1", "hand": params.name, "side": params.side,
            "frames": "link frames of docs/frames.md; millimetres; a pulley's strand turns positively about its axis",
            "tendons": tendons}


def mid_travel_pose(params) -> dict[str, np.ndarray]:
    """T_palm_link with every flexion joint at half its travel (as the clamps are placed) and every
    tendon servo at the middle of its travel: where :func:`side_sites` places the side sites."""
    q = np.zeros(N_JOINTS)
    for j in JOINTS:
        if j.key != "cmc":
            q[j.index] = _joint_travel(params, j.name) / 2.0
    u = np.array([sum(params.digit(s.digit).chain.travel) / 2.0 if s.drive == "tendon" else 0.0 for s in SERVOS])
    return pose(params, q, u)


def side_sites(params, strand: Strand, Ts=None) -> list[tuple[str, tuple[float, float, float]] | None]:
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


# ---------------------------------------------------------------------------
# the drive's split at the magnet face
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Coupler:
    """The drive of a magnet-held finger is split at the socket face into a *palm strand* (servo
    pulley to a crimped stop) and a *finger strand* (a loop round the palm strand behind the stop,
    to G2). Distances ``s`` run from the socket face into the palm along the drive's straight run
    (metres); the coupler is the stop with the loop on it: its knot (3 cord diameters), the stop,
    and the loop's bight behind it (1 cord diameter)."""
    digit: str
    diameter: float          # its envelope: the stop and the loop's two legs beside it
    length: float            # its envelope along the run
    bore: float              # the palm's bore for it (envelope + two clearances)
    run: float               # the straight run from the socket face to the servo pulley's tangent point
    channel: float           # the part of the run outside the pulley's cavity: the bore's room
    rest: tuple[float, float]          # s of its distal and proximal ends at u = 0
    full: tuple[float, float]          # at the end of the travel
    service_angle: float     # rad (< 0): the servo command that pays the palm strand out
    payout: float            # how much it pays out
    bearing: float           # s of the stop's proximal face at rest (where the loop's bight bears)
    palm_strand: float       # working length: from the clamp on the servo pulley to the stop's proximal face
    finger_strand: float     # working length: from the loop's bight to the knot at G2 (the two add up to the drive)

    @property
    def emergence(self) -> float:
        """How far beyond the socket face the coupler's proximal end comes at the service angle."""
        return self.payout - self.rest[1]

    @property
    def bore_end(self) -> float:
        """s where the palm's bore ends: a clearance past the coupler at full travel."""
        return self.full[1] + self.bore / 2.0 - self.diameter / 2.0


def _drive_strand(params, digit: str) -> Strand:
    """The drive's strand as :func:`routes` gives it (mirrored for a left hand), for posing with
    :func:`pose`."""
    return next(r.strands[0] for r in routes(params) if r.tendon.kind == "drive" and r.tendon.digit == digit)


def split_digits() -> tuple[str, ...]:
    """The digits whose drive is split at their magnet face: the magnet-held fingers (the thumb is
    fixed to the palm)."""
    return tuple(ch.digit for ch in CHAINS if link(joint(ch.joint_names[0]).parent).segment == "base")


def couplers(params) -> dict[str, Coupler]:
    """The coupler of every split drive (right-hand frames; the left hand's are their mirror image,
    of the same dimensions). Refuses, naming ``hardware.tendon_stop``, a file whose coupler does not
    stay in its channel over the travel or does not come out of the socket at the service angle."""
    return memoised(_COUPLERS, params.digest, lambda: _couplers(params), cap=16)


_COUPLERS: dict = {}


def _couplers(params) -> dict[str, Coupler]:
    hw, c = params.hardware, params.print.hole_clearance
    d = hw.tendon_diameter
    D = hw.stop_diameter + 2.0 * d
    Lc = d + hw.stop_length + 3.0 * d
    s0 = 2.0 * c
    Ts = pose(params)
    out = {}
    for digit in split_digits():
        spec = chain(digit)
        servo = SERVOS[spec.servo]
        ch = params.digit(digit).chain
        r = ch.servo_radius
        strand = _drive_strand(params, digit)
        nodes = _nodes(strand, Ts)
        k = next(i for i, e in enumerate(strand.elements) if isinstance(e, Point) and e.role == "interface")
        tangent, face = nodes[k - 1][1], nodes[k][0]
        to_face, _ = strand_path(params, Strand(strand.name, strand.elements[:k + 1]), Ts)
        from_face, _ = strand_path(params, Strand(strand.name, strand.elements[k:]), Ts)
        run = float(np.linalg.norm(face - tangent))
        cavity = math.sqrt((r + F.pulley_cavity_margin(params)) ** 2 - r ** 2)
        channel = run - cavity
        travel = r * ch.travel[1]
        full = (s0 + travel, s0 + Lc + travel)
        field = "hardware.tendon_stop.length_mm"
        value = round(hw.stop_length * 1e3, 6)
        if full[1] + c > channel + 1e-12:
            raise ParamError(field, value, f"the {digit} drive's coupler (stop, loop and knot: {Lc * 1e3:.2f} mm) "
                             f"travels {travel * 1e3:.2f} mm into the palm from {s0 * 1e3:.2f} mm behind the socket "
                             "face; "
                             f"with a clearance it needs {(full[1] + c) * 1e3:.2f} mm of channel, it has "
                             f"{channel * 1e3:.2f} mm before servo {servo.index + 1}'s pulley cavity", params.source)
        # the clamp sits for the largest wrap the travel allows (servo_clamp_wrap): unwinding to the
        # smallest (WRAP_MARGIN) pays the palm strand out
        service = WRAP_MARGIN - servo_clamp_wrap(params, servo.index)
        payout = -r * service
        bearing = s0 + 3.0 * d + hw.stop_length
        cp = Coupler(digit, D, Lc, D + 2.0 * c, run, channel, (s0, s0 + Lc), full, service, payout,
                     bearing, to_face - bearing, from_face + bearing)
        if cp.emergence < hw.stop_diameter - 1e-12:
            raise ParamError(field, value, f"at the service angle ({math.degrees(cp.service_angle):.1f} deg) servo "
                             f"{servo.index + 1} pays out {payout * 1e3:.2f} mm: the {digit} coupler "
                             f"({Lc * 1e3:.2f} mm) "
                             f"comes {cp.emergence * 1e3:.2f} mm out of the socket, it must come at least the stop's "
                             f"diameter ({hw.stop_diameter * 1e3:g} mm) out to slip the loop off", params.source)
        out[digit] = cp
    return out


def coupler_document(params, cp: Coupler) -> dict:
    """A split drive in ``routing.json`` (millimetres, degrees; s from the socket face into the palm)."""
    mm = lambda v: round(v * 1e3, 6)  # noqa: E731
    return {"at": "socket face", "coupler": {"stop_diameter_mm": mm(params.hardware.stop_diameter),
                                              "stop_length_mm": mm(params.hardware.stop_length),
                                              "envelope_diameter_mm": mm(cp.diameter),
                                              "envelope_length_mm": mm(cp.length),
                                              "bore_mm": mm(cp.bore)},
            "s_rest_mm": [mm(v) for v in cp.rest], "s_full_travel_mm": [mm(v) for v in cp.full],
            "channel_mm": mm(cp.channel), "run_mm": mm(cp.run),
            "palm_strand_mm": mm(cp.palm_strand), "finger_strand_mm": mm(cp.finger_strand),
            "service_angle_deg": round(math.degrees(cp.service_angle), 6), "service_payout_mm": mm(cp.payout),
            "service_emergence_mm": mm(cp.emergence)}
