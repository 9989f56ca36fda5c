"""The tendon features of a digit link's part, cut from the routing model (``kinematics.routing``).

Nothing here retypes a tendon's path: every groove, channel, clamp and knot well is read from the
right-handed routes (``routing.routes(params, right_handed=True)``) and their straight runs
(``routing_paths.runs``), in the link's frame, in mm. docs/transmission.md describes the mechanism and
docs/parts.md the features:

* a **pulley** element on this link is a groove whose floor lies half a cord inside the pulley's
  centreline radius (the moment arm R): a full ring for a loop's hub and groove (their strands
  touch nearly all the way round over the travel), a sector for the return cord (the arc it ever
  touches, ``routing_paths.arc_range``, plus ``SECTOR_MARGIN``);
* a **hub** (a loop's pulley on the link before its first joint) is material the clevis slot
  leaves standing beside that side's cheek (``routing.Layout.hub_width``); the child's tongue is
  cut back there;
* a **run** fixed to this link is a channel of the cord's clearance diameter along it;
* an **anchor**: a loop's clamp on its hub is an M2 set-screw pilot along the axis from the
  cheek's outer face across the groove (the screw pinches both cord ends against the inner flank:
  the loop is tensioned there); a loop's clamp on its groove is a knot pocket in the groove floor
  (the cord's middle, knotted); the return cord's knots are wells up to the dorsal face.

numpy only; the solids are made by ``common``'s helpers (build123d imported lazily).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ... import units
from ...kinematics import routing
from ...kinematics import routing_paths
from ...kinematics.dimensions import FLANK, HUB_GROOVE_PAST_BOSS
from ...kinematics.hand_params import HandParams
from ...kinematics.link_frames import THUMB_MP
from ...kinematics.memo import memoised
from ...kinematics.topology import TENDONS, joint
from ...kinematics.vectors import clipped_acos, perpendicular_frame
from ..print_rules import roof_angle


#: a return groove's sector reaches this far beyond the arc its cord ever touches (rad)
SECTOR_MARGIN = units.rad(15.0)
#: the widest gap (mm) a support blocker may cover: an overhang between walls no further apart
#: prints as a bridge (the widest groove is 1.9 mm; tests/export/test_project3mf.py measures it)
BRIDGE_MM = 2.0
#: how far (mm) a blocker reaches past its feature: past where a groove is cut, around a pilot's
#: and a channel's wall (at 0.05 mm PrusaSlicer left 0.75-1.0 mm of support path in the hub
#: grooves, by their set-screw pilots)
BLOCKER_MARGIN = 0.3
#: how far (mm) a groove's blocker reaches past its flanks (at 0.3 mm it reached the boss's own
#: rounded underside beside a hub's groove, which is no bridge)
FLANK_MARGIN = 0.05
#: the joint axes' direction in a digit link's frame
AXIS = (1.0, 0.0, 0.0)
#: the loop and return tendons: the ones whose features this module cuts (the drive's eyelets and
#: channels are the guide features of the parts themselves)
KINDS = ("coupling", "return")
_KIND = {t.name: t.kind for t in TENDONS}


def _mm(v) -> np.ndarray:
    return np.asarray(units.mm(np.asarray(v, float)), float)


@dataclass(frozen=True)
class Groove:
    """A groove about an axis parallel to x through (y, z): floor radius, width, plane x, and the
    sector of polar angles it spans (None: all round). mm, rad."""
    role: str
    joint: str
    y: float
    z: float
    x: float
    floor: float
    width: float
    sector: tuple[float, float] | None
    radius: float                # the cord's centreline radius (the moment arm)


@dataclass(frozen=True)
class Anchor:
    role: str                    # "hub clamp", "groove clamp", "knot"
    pos: np.ndarray              # mm, link frame
    centre: np.ndarray | None    # the pulley's centre (mm) for a clamp
    radius: float | None         # the pulley's centreline radius (mm) for a clamp
    cord: float                  # mm


class LinkTendons:
    """What the routing model asks of one link's part (right hand, mm)."""

    def __init__(self, params: HandParams, link_name: str):
        self.params, self.link = params, link_name
        cl = units.mm(params.print.hole_clearance)
        # a twisted thumb's metacarpal: its features are read in its MP's frame before the twist
        # (the part cuts them there and turns them with the MP), where they lie in planes x = const;
        # the twist is asked for on that link only: no other part reads it
        turned = routing.mp_turn(params) if link_name == joint(THUMB_MP).parent else None
        if turned is not None:
            _, turn_R, turn_o = turned
            flat = lambda v: turn_o + turn_R.T @ (np.asarray(v, float) - turn_o)  # noqa: E731
        else:
            flat = lambda v: np.asarray(v, float)  # noqa: E731
        _mm = lambda v: np.asarray(units.mm(flat(v)), float)  # noqa: E731
        self.grooves: list[Groove] = []
        self.anchors: list[Anchor] = []
        seen = set()
        # the arcs are measured over the hand's travel poses (a left hand's mirrored), which the
        # right-handed strands fit while every pulley turns about x (the mirror flips x only); a
        # twisted thumb's do not, so they are measured on the hand's own strands
        sided = ({st.name: st for r in routing.routes(params) for st in r.strands} if turned is not None
                 else {st.name: st for r in routing.routes(params, right_handed=True) for st in r.strands})
        for r in routing.routes(params, right_handed=True):
            if _KIND[r.name] not in KINDS:
                continue
            cord = float(units.mm(r.diameter))
            for st in r.strands:
                els = st.elements
                for i, e in enumerate(els):
                    if e.link != link_name:
                        continue
                    if isinstance(e, routing.Pulley):
                        c, R = _mm(e.centre), float(units.mm(e.radius))
                        key = (e.role, e.joint, round(c[0], 6))
                        sector = None
                        if e.role == "return":
                            # the arc it touches, and behind it the parent's run, which turns into
                            # this link's frame as the joint flexes (up to a quarter turn beyond)
                            a0, a1 = routing_paths.arc_range(params, sided[st.name], i)
                            sector = (a0 - SECTOR_MARGIN, a1 + math.pi / 2.0)
                        if key in seen:
                            continue
                        seen.add(key)
                        self.grooves.append(Groove(e.role, e.joint, float(c[1]), float(c[2]), float(c[0]),
                                                   R - cord / 2.0, float(units.mm(e.width)), sector, R))
                    elif e.kind == "anchor":
                        key = ("anchor", tuple(np.round(_mm(e.pos), 6)))
                        if key in seen:
                            continue
                        seen.add(key)
                        nb = els[i + 1] if i == 0 else els[i - 1]
                        if isinstance(nb, routing.Pulley) and e.role == "clamp":
                            role = "hub clamp" if nb.role == "hub" else "groove clamp"
                            self.anchors.append(Anchor(role, _mm(e.pos), _mm(nb.centre),
                                                       float(units.mm(nb.radius)), cord))
                        else:
                            self.anchors.append(Anchor("knot", _mm(e.pos), None, None, cord))
        #: (p0, p1, channel diameter) of every loop and return run fixed to this link, mm
        self.channels = []
        for run in routing_paths.runs(params, right_handed=True):
            if _KIND[run.tendon] in KINDS and link_name in run.links:
                p0, p1 = run.ends[link_name]
                self.channels.append((_mm(p0), _mm(p1), float(units.mm(run.diameter)) + 2.0 * cl))

        #: drive chords (free runs across the reference joint) with an end on this link: (the end
        #: fixed here, the other end's positions over the travel), mm
        self.drive_sweeps = []
        strands = {st.name: st for r in routing.routes(params, right_handed=True) for st in r.strands}
        for run in routing_paths.runs(params, right_handed=True):
            if _KIND[run.tendon] != "drive" or run.links:
                continue
            els = strands[run.strand].elements
            ends = (els[run.index].link, els[run.index + 1].link)
            if link_name not in ends:
                continue
            sweep = routing_paths.run_sweep(params, run, link_name, right_handed=True)
            k = ends.index(link_name)
            self.drive_sweeps.append((_mm(sweep[0][k]), [_mm(pr[1 - k]) for pr in sweep]))

    @property
    def roof(self) -> float:
        """The roof angle (rad) of this hand's teardrop channels: ``print_rules.roof_angle`` of its
        layer height."""
        return roof_angle(self.params.print.layer_height)

    def eyelet_toward(self, centre_yz) -> np.ndarray:
        """A point (y, z) the drive's guide eyelet at ``centre_yz`` points toward: along the
        bisector of the directions its chord takes over the travel, so the chord swings least
        off the eyelet's axis (at G2 it turns through about 60 deg)."""
        c = np.asarray(centre_yz, float)
        for fixed, moving in self.drive_sweeps:
            if np.linalg.norm(fixed[1:] - c) < 1e-6:
                dirs = [(m - fixed)[1:] / np.linalg.norm((m - fixed)[1:]) for m in moving]
                ang = [math.atan2(d[1], d[0]) for d in dirs]
                rel = [((a - ang[0] + math.pi) % (2 * math.pi)) - math.pi for a in ang]
                mid = ang[0] + (min(rel) + max(rel)) / 2.0
                return c + np.array([math.cos(mid), math.sin(mid)])
        raise ValueError(f"{self.link}: no drive chord ends at {tuple(c)}")

    def hubs(self) -> dict[str, float]:
        """{joint name: x of the hub's groove plane} of the hubs this link carries."""
        return {g.joint: g.x for g in self.grooves if g.role == "hub"}

    def tongue_grooves(self, joint_name: str) -> list[Groove]:
        """The grooves on this link's tongue at its proximal joint (loop grooves, return)."""
        return [g for g in self.grooves if g.joint == joint_name and g.role in ("groove", "return")]


def verify_grooves(part, shape, lt: LinkTendons, out: list[str], faces: list[dict] | None = None) -> None:
    """Every groove the routing model puts on this link (hub, loop groove, return groove), measured
    on the solid: its floor, half a cord inside the pulley radius, about the pulley's axis.
    ``faces``: ``measure.cylinders(shape)``, when the caller has them."""
    from ..measure import cylinders, measure_groove_radius
    if faces is None:
        faces = cylinders(shape) if lt.grooves else []
    for g in lt.grooves:
        try:
            r = measure_groove_radius(shape, (g.x, g.y, g.z), (1, 0, 0), g.width, faces=faces)
        except ValueError:
            r = None
        label = {"hub": "loop hub", "groove": "loop groove", "return": "return groove"}[g.role]
        part.expect(out, f"{g.joint.split('_', 1)[1]} {label} floor", r, g.floor)


_LINK_TENDONS: dict = {}


def link_tendons(params: HandParams, link_name: str) -> LinkTendons:
    """The :class:`LinkTendons` of one link, made once per hand (memoised by the parameters'
    digest: the routes are pure functions of them; a part's build, its verification, its
    child's tongue and the bill of materials all read the same one)."""
    return memoised(_LINK_TENDONS, (params.digest, link_name), lambda: LinkTendons(params, link_name))


def parent_hub_x(params: HandParams, joint_name: str) -> float | None:
    """x of the hub on a joint's parent link (the loop plane that joint's tongue must leave free),
    or None."""
    j = joint(joint_name)
    return link_tendons(params, j.parent).hubs().get(joint_name)


# ---------------------------------------------------------------------------
# geometry (build123d through common's helpers)
# ---------------------------------------------------------------------------

def sector_prism(g: Groove, outer: float):
    """The wedge of the groove's sector about its axis (out past ``outer``, two groove widths long
    in x); None for a groove all round."""
    from .common import prism_x
    if g.sector is None:
        return None
    a0, a1 = g.sector
    n = max(2, int(math.ceil((a1 - a0) / units.rad(10.0))))
    big = outer / math.cos(math.pi / (2 * n)) + 1.0     # the polygon's chords stay outside the ring
    poly = [(g.y, g.z)] + [(g.y + big * math.cos(a), g.z + big * math.sin(a)) for a in np.linspace(a0, a1, n + 1)]
    return prism_x(poly, g.x - g.width, g.x + g.width)


def groove_outer(sec, g: Groove) -> float:
    """How far (mm) from its axis a groove is cut: a millimetre past the boss (a hub's groove, in
    the parent's cheek), or past the tongue's corners (a groove in the child's tongue: the strands
    beyond the arc belong to the parent, and sweep through the tongue's plane as the joint turns)."""
    if g.role == "hub":
        return sec.boss_radius + units.mm(HUB_GROOVE_PAST_BOSS)
    return math.hypot(sec.slot_back, sec.thickness / 2.0) + 1.0


def groove_tool(g: Groove, outer: float):
    """The cutter of a groove: from its floor out to ``outer`` (mm), over its sector."""
    from .common import ring_x
    ring = ring_x(g.floor, outer, g.width, g.y, g.z).moved(_loc_x(g.x))
    if g.sector is None:
        return ring
    sector = ring.intersect(sector_prism(g, outer))
    return cutter(sector)


def cutter(shape):
    """A boolean's result (a shape or a list of them) as one cutting tool: its one solid, or a
    compound of its solids."""
    solids = shape.solids() if hasattr(shape, "solids") else [s for c in shape for s in c.solids()]
    if len(solids) == 1:
        return solids[0]
    from .common import bd
    return bd().Compound(list(solids))


def _loc_x(x: float):
    from .common import bd
    b = bd()
    return b.Location((float(x), 0.0, 0.0))


def channel_tools(lt: LinkTendons, extend: float | None = None, faces=(), up=None):
    """A channel along every loop and return run fixed to the link, a clearance diameter wide,
    reaching half a diameter past each end (into the groove or well it meets); and where two
    strands cross (a figure-eight), the reliefs of :func:`crossing_tools` (``faces`` passed on).
    ``up``: the printer's +z in the link frame (the part's ``print_up``): a channel that lies
    flatter than its round wall prints gets a teardrop's roof at ``print_rules.roof_angle`` of the
    layer height (``common.teardrop``), which prints without support; the cord runs on its round
    floor, so its path does not change."""
    from .common import teardrop
    out = []
    for p0, p1, d in lt.channels:
        u = (p1 - p0) / np.linalg.norm(p1 - p0)
        e = d / 2.0 if extend is None else extend
        out.append(teardrop(p0 - e * u, p1 + e * u, d / 2.0, up, lt.roof))
    return out + crossing_tools(lt, faces, up)


def crossing_tools(lt: LinkTendons, faces=(), up=None) -> list:
    """Where a figure-eight's two strands cross (four channel legs from one point, in one plane
    x = const), the two channels meet at a shallow angle (22 deg on a finger's proximal phalanx) and
    the web between them ends in a knife edge (0.04-0.07 mm). Between each pair of legs less than
    90 deg apart the web is cut away, a channel wide, out to where the channels' walls lie a flank
    (``dimensions.FLANK``) apart: the web then ends square and at least that thick. ``faces``: y
    (mm) of the link's faces square to y (a phalanx's shoulders); a cut that would end less than a
    flank short of one goes through it instead (0.61 mm was left on the pinky's middle phalanx).
    With ``up`` (teardrop channels), the lower leg's roof reaches r / sin(roof) above its axis into
    the web: the cut reaches that much further."""
    from .common import prism_x
    wall = units.mm(FLANK)
    apex = 1.0 / math.sin(lt.roof) - 1.0 if up is not None else 0.0
    legs: dict[tuple, list] = {}
    for p0, p1, d in lt.channels:
        a, b = np.asarray(p0, float), np.asarray(p1, float)
        legs.setdefault(tuple(np.round(a, 6)), []).append((b - a, d))
        legs.setdefault(tuple(np.round(b, 6)), []).append((a - b, d))
    out = []
    for key, ls in sorted(legs.items()):
        if len(ls) < 4:
            continue
        c = np.asarray(key)
        for i in range(len(ls)):
            for j in range(i + 1, len(ls)):
                (va, da), (vb, db) = ls[i], ls[j]
                la, lb = float(np.linalg.norm(va)), float(np.linalg.norm(vb))
                ua, ub = va / la, vb / lb
                if abs(ua[0]) > 1e-9 or abs(ub[0]) > 1e-9:
                    continue
                theta = clipped_acos(float(ua @ ub))
                if not 1e-6 < theta < math.pi / 2.0:
                    continue
                d = max(da, db)
                reach = (d + apex * d / 2.0 + wall) / (2.0 * math.sin(theta / 2.0))
                # a face square to y the relief would stop short of by less than a flank: through it
                for yf in faces:
                    toward = min(ua[1] * (yf - c[1]), ub[1] * (yf - c[1]))
                    if toward <= 0.0:
                        continue
                    cos = min(abs(ua[1]), abs(ub[1]))
                    short = abs(yf - c[1]) - reach * cos
                    if 0.0 <= short < wall:
                        reach = (abs(yf - c[1]) + d / 2.0) / cos
                reach = min(reach, la, lb)
                pa, pb = c + reach * ua, c + reach * ub
                out.append(prism_x([(c[1], c[2]), (pa[1], pa[2]), (pb[1], pb[2])], c[0] - d / 2.0, c[0] + d / 2.0))
    return out


def anchor_tools(lt: LinkTendons, sec, up=None) -> list:
    """Clamps and knot wells (see the module doc). ``up`` as for :func:`channel_tools`: a knot well
    that lies flat as printed (a finger base's, on its magnet face) gets a teardrop's roof."""
    from .common import cylinder, teardrop
    t = sec.tol
    out = []
    for a in lt.anchors:
        p = a.pos
        if a.role == "hub clamp":            # set-screw pilot from the cheek's outer face across the groove
            out.append(cylinder(*pilot_axis(a, sec), t.screw_pilot / 2.0))
        elif a.role == "groove clamp":       # knot pocket in the groove floor
            v = (p - a.centre)[1:]
            v = v / np.linalg.norm(v)
            floor = a.radius - a.cord / 2.0
            depth = knot_pocket_depth(sec, floor, a.cord)
            c0 = np.array([p[0], *(a.centre[1:] + (floor - depth) * v)])
            c1 = np.array([p[0], *(a.centre[1:] + a.radius * v)])
            # a clearance narrower than the groove: a pocket as wide as the groove is tangent to
            # both its walls, and a left hand's mirror of that face is unorientable (BRepCheck)
            out.append(cylinder(c0, c1, (sec.layout.groove - t.clearance) / 2.0))
        else:                                # a knot well up to the dorsal face, one clearance wider
            d = a.cord + 4.0 * t.clearance   # than the channel it meets (equal bores meet degenerately)
            out.append(teardrop(p, (p[0], p[1], sec.thickness / 2.0 + 1.0), d / 2.0, up, lt.roof))
    return out


def pilot_axis(a: Anchor, sec) -> tuple[np.ndarray, np.ndarray]:
    """The ends (mm) of a hub clamp's set-screw pilot: along x through the cord's centreline at
    the clamp, from the groove's inner flank out past the cheek's outer face."""
    p = a.pos
    side = math.copysign(1.0, p[0])
    on_circle = a.centre + (p - a.centre) * (a.radius / np.linalg.norm((p - a.centre)[1:]))
    x_in = p[0] - side * (sec.layout.groove / 2.0)
    return np.array([x_in, *on_circle[1:]]), np.array([side * (sec.width / 2.0 + 1.0), *on_circle[1:]])


@dataclass(frozen=True)
class Blocker:
    """A region where a slicer must not put support (a closed triangle mesh, link frame, mm,
    outward faces): one tendon feature, every overhang in which bridges between its walls, at
    most :data:`BRIDGE_MM` apart. The export writes them into each part's PrusaSlicer project as
    support blockers (``export.project3mf``)."""
    label: str
    vertices: np.ndarray
    faces: np.ndarray
    #: the direction (link frame) that must lie flat as printed for the feature's overhangs to be
    #: bridges (a groove's or a pilot's axis: stood upright, a groove's upper flank is a ceiling
    #: reaching out from its floor to its mouth); None: any orientation (a channel's roof spans its
    #: width however it lies)
    flat: tuple[float, float, float] | None = None

    def holds(self, up) -> bool:
        """Whether the blocker applies with the printer's +z along ``up`` (link frame)."""
        return self.flat is None or abs(float(np.dot(self.flat, up))) < 1e-6


def feature_blockers(lt: LinkTendons, sec) -> list[Blocker]:
    """The support blockers of a link's tendon features (the routing model's, as cut by
    :func:`groove_tool`, :func:`anchor_tools` and :func:`channel_tools`), each
    :data:`BLOCKER_MARGIN` larger (a groove :data:`FLANK_MARGIN` past its flanks):

    * a **groove**: its slot over its width and sector, from half a flank outside the axle's
      clearance bore (the knot pockets in its floor included; the bore itself is not a tendon
      feature) out to where it is cut (:func:`groove_outer`), when its axis lies flat;
    * a hub clamp's **set-screw pilot** (a hole of 1.6 mm along the axis), when it lies flat;
    * a **channel**: about its axis, out to its teardrop roof's apex, past each end as cut.

    Which of them apply is up to the print orientation (:meth:`Blocker.holds`)."""
    m = BLOCKER_MARGIN
    r_in = sec.tol.axle_clear / 2.0 + units.mm(FLANK) / 2.0
    out = []
    for g in lt.grooves:
        V, F = sector_ring_mesh(g.y, g.z, g.x - g.width / 2.0 - FLANK_MARGIN, g.x + g.width / 2.0 + FLANK_MARGIN,
                                r_in, groove_outer(sec, g) + m, g.sector)
        out.append(Blocker(f"groove {g.role} {g.joint}", V, F, AXIS))
    for a in lt.anchors:
        if a.role == "hub clamp":
            p0, p1 = pilot_axis(a, sec)
            out.append(Blocker(f"set-screw pilot {a.pos[0]:+.1f}", *cylinder_mesh(p0, p1, sec.tol.screw_pilot / 2.0 + m),
                               AXIS))
    apex = 1.0 / math.sin(lt.roof)
    for k, (p0, p1, d) in enumerate(lt.channels):
        u = (p1 - p0) / np.linalg.norm(p1 - p0)
        out.append(Blocker(f"channel {k}", *cylinder_mesh(p0 - d / 2.0 * u, p1 + d / 2.0 * u, apex * d / 2.0 + m)))
    return out


def sector_ring_mesh(y: float, z: float, x0: float, x1: float, r0: float, r1: float,
                     sector: tuple[float, float] | None = None, step: float = units.rad(5.0)):
    """A closed mesh (vertices, faces; outward) of the ring r0 <= r <= r1 about the x-parallel axis
    through (y, z), x0 <= x <= x1, over the polar ``sector`` (rad; None: all round). Its polygon's
    outer chords lie outside r1 and its inner ones inside r0."""
    a0, a1 = (0.0, 2.0 * math.pi) if sector is None else sector
    n = max(2, int(math.ceil((a1 - a0) / step)))
    half = (a1 - a0) / (2.0 * n)
    ang = np.linspace(a0, a1, n, endpoint=False) if sector is None else np.linspace(a0, a1, n + 1)
    k = len(ang)
    rings = []
    for x, r in ((x0, r0 * math.cos(half)), (x0, r1 / math.cos(half)), (x1, r1 / math.cos(half)), (x1, r0 * math.cos(half))):
        rings.append(np.c_[np.full(k, x), y + r * np.cos(ang), z + r * np.sin(ang)])
    V = np.vstack(rings)
    faces = []
    segs = range(k) if sector is None else range(k - 1)
    for i in segs:
        j = (i + 1) % k
        for A in range(4):             # x0 face, outer, x1 face, inner: ring A to ring A + 1
            B = (A + 1) % 4
            faces += [(A * k + i, A * k + j, B * k + j), (A * k + i, B * k + j, B * k + i)]
    if sector is not None:             # the two radial ends
        for i, flip in ((0, False), (k - 1, True)):
            q = [0 * k + i, 1 * k + i, 2 * k + i, 3 * k + i]
            tri = [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
            faces += [t[::-1] for t in tri] if flip else tri
    return _outward(V, np.array(faces, np.int64))


def cylinder_mesh(p0, p1, r: float, n: int = 24):
    """A closed mesh (vertices, faces; outward) of the cylinder of radius r (its polygon's chords
    outside it) from p0 to p1."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    u = (p1 - p0) / np.linalg.norm(p1 - p0)
    v, w = perpendicular_frame(u)
    ang = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    rr = r / math.cos(math.pi / n)
    circle = rr * (np.cos(ang)[:, None] * v + np.sin(ang)[:, None] * w)
    V = np.vstack([p0 + circle, p1 + circle, p0, p1])
    c0, c1 = 2 * n, 2 * n + 1
    faces = []
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i), (c0, j, i), (c1, n + i, n + j)]
    return _outward(V, np.array(faces, np.int64))


def _outward(V: np.ndarray, F: np.ndarray):
    """(V, F) with the faces turned outward (a positive signed volume)."""
    t = V[F]
    if np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum() < 0.0:
        F = F[:, ::-1].copy()
    return V, F


class RoutedPart:
    """A digit part whose tendon features come from the routing model (``self.params``,
    ``self.link``, ``self.sec``): its support blockers (:func:`feature_blockers`)."""

    def support_blockers(self) -> list[Blocker]:
        return feature_blockers(link_tendons(self.params, self.link.name), self.sec)

    def verify_routing(self, shape, out: list[str]) -> list:
        """Measure the grooves of ``shape`` (:func:`verify_grooves`) into ``out``; returns the
        solid's cylindrical faces, listed once, for the caller's eyelets and pockets."""
        from ..measure import cylinders
        faces = cylinders(shape)
        verify_grooves(self, shape, link_tendons(self.params, self.link.name), out, faces)
        return faces


def knot_pocket_depth(sec, floor: float, cord: float) -> float:
    """Depth (mm) of a loop's knot pocket below its groove floor: two cord diameters, less where
    the axle's clearance bore would come within a flank."""
    return max(0.0, min(2.0 * cord, floor - sec.tol.axle_clear / 2.0 - units.mm(FLANK)))
