"""Shared dimensions and geometry helpers of the printable parts.

Two layers, as in bd_warehouse: plain-Python *dimension* classes (millimetres, derived from
the validated parameter object, properties only; numpy only, importable without OCP) and
``build()`` methods that import build123d lazily and make the solid. Every mating feature
carries its print tolerance from ``params.print`` (docs/parts.md lists which):

* clearance hole (axle through a bearing's neighbour, screws, tendon):  d + 2 * hole_clearance
* press fit (bearing outer ring in its seat, axle in the clevis cheeks): d - press_fit_interference
* magnet pocket: (d + 2 * magnet_clearance) x (t + magnet_clearance)
* screw pilot (thread-forming): screw_pilot_ratio * d

Those are the fits the printed hole should measure. Every round hole that takes hardware is
modelled ``print.hole_compensation`` wider in diameter (``kinematics.dimensions.printed_hole``),
because FDM prints holes small; the tendon and spring channels are clearance channels and are
not compensated (the fit-test coupon, ``parts.coupon``, shows both).
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ... import units
from ...kinematics import frames as F
from ...kinematics import topology
from ...kinematics.dimensions import printed_hole, slot_back
from ...kinematics.hand_params import HandParams
from ..kernel import import_build123d


def mm(x: float) -> float:
    """A parameter (metres) in the CAD layer's unit, as a float."""
    return float(units.mm(float(x)))


# ---------------------------------------------------------------------------
# dimensions (numpy only)
# ---------------------------------------------------------------------------

class Tolerances:
    """The print tolerances and hardware, in mm, with the derived hole sizes."""

    def __init__(self, params: HandParams):
        pr, hw = params.print, params.hardware
        self.clearance = mm(pr.hole_clearance)
        self.interference = mm(pr.press_fit_interference)
        self.magnet_clearance = mm(pr.magnet_clearance)
        self.tendon = mm(hw.tendon_diameter)
        self.axle = mm(hw.axle_diameter)
        self.bearing_outer = mm(hw.bearing_outer)
        self.bearing_width = mm(hw.bearing_width)
        self.screw = mm(hw.screw_diameter)
        self.magnet_d = mm(hw.magnet_diameter)
        self.magnet_t = mm(hw.magnet_thickness)
        self.wall = mm(params.palm.wall)
        self.spring = mm(params.cad.spring_diameter)
        self.eyelet_length = mm(params.cad.eyelet_length)
        self.pilot_ratio = params.print.screw_pilot_ratio
        self.compensation = mm(pr.hole_compensation)

    @property
    def tendon_hole(self) -> float:
        """Diameter of tendon channels, eyelets and grooves (clearance fit)."""
        return self.tendon + 2.0 * self.clearance

    @property
    def tendon_relief(self) -> float:
        """Diameter of the relief that ends each eyelet (twice the eyelet)."""
        return 2.0 * self.tendon_hole

    def hole(self, fit: float) -> float:
        """The modelled diameter of a round hole that should print at ``fit`` (mm)."""
        return printed_hole(fit, self.compensation)

    def fit(self, hole: str) -> float:
        """The diameter (mm) the printed hole ``hole`` should measure: ``hole`` names one of the
        modelled holes below (``axle_clear``, ``axle_press``, ``bearing_seat``, ``screw_clear``,
        ``screw_pilot``, ``magnet_pocket_d``), each of which is this fit made wider by
        :meth:`hole`."""
        return {"axle_clear": self.axle + 2.0 * self.clearance,
                "axle_press": self.axle - self.interference,
                "bearing_seat": self.bearing_outer - self.interference,
                "screw_clear": self.screw + 2.0 * self.clearance,
                "screw_pilot": self.pilot_ratio * self.screw,
                "magnet_pocket_d": self.magnet_d + 2.0 * self.magnet_clearance}[hole]

    @property
    def axle_clear(self) -> float:
        """Axle clearance bore (a tongue turning on its axle): modelled diameter."""
        return self.hole(self.fit("axle_clear"))

    @property
    def axle_press(self) -> float:
        """Axle press bore (the clevis cheeks): modelled diameter."""
        return self.hole(self.fit("axle_press"))

    @property
    def bearing_seat(self) -> float:
        """Bearing outer ring press seat: modelled diameter."""
        return self.hole(self.fit("bearing_seat"))

    @property
    def screw_clear(self) -> float:
        return self.hole(self.fit("screw_clear"))

    @property
    def screw_pilot(self) -> float:
        """Pilot hole of a thread-forming (self-tapping) screw in printed material:
        ``print.screw_pilot_ratio`` of its diameter (0.8 by default: 1.6 mm for M2, a thread
        flank of 0.2 mm each side; a pilot of d - press_fit_interference left 0.02 mm), modelled
        with the hole compensation."""
        return self.hole(self.fit("screw_pilot"))

    @property
    def screw_engagement(self) -> float:
        """Depth of a self-tapping pilot hole: three screw diameters of thread in plastic."""
        return 3.0 * self.screw

    @property
    def magnet_pocket_d(self) -> float:
        return self.hole(self.fit("magnet_pocket_d"))

    @property
    def magnet_pocket_depth(self) -> float:
        return self.magnet_t + self.magnet_clearance

    @property
    def spring_hole(self) -> float:
        return self.spring + 2.0 * self.clearance


class DigitSection:
    """Cross-section and joint dimensions (mm) shared by every link of one digit."""

    def __init__(self, params: HandParams, digit: str):
        self.params = params
        self.digit = digit
        d = params.digit(digit)
        self.tol = Tolerances(params)
        self.width = mm(d.width)
        self.thickness = mm(d.thickness)
        self.cheek = mm(params.cad.cheek)
        chain = d.chain
        self.R = {j: mm(r) for j, r in zip(chain.joints, chain.radii)}
        #: upper limits (Table I): where the operational stops engage
        self.q_max = {j: lim[1] for j, lim in zip(chain.joints, chain.limits)}
        #: where this digit module's own hard stops engage: a reference joint whose parent is a
        #: magnet-held finger base (the finger MCP) goes cad.module_stop_margin further (the
        #: palm housing stops it at q_max)
        self.q_stop = dict(self.q_max)
        ref = topology.joint(topology.chain(digit).joint_names[0])
        if topology.link(ref.parent).segment == "base":
            self.q_stop[ref.key] = self.q_max[ref.key] + params.cad.module_stop_margin
        self.guide = chain.guide

    @cached_property
    def layout(self):
        """The routing model's planes of this digit's loops and return cord (``routing.layout``), mm."""
        from types import SimpleNamespace

        from ...kinematics import routing
        lay = routing.layout(self.params, self.digit)
        return SimpleNamespace(slot_half=mm(lay.slot_half), groove=mm(lay.groove), return_groove=mm(lay.return_groove),
                               loop_x=tuple(mm(x) for x in lay.loop_x), return_x=mm(lay.return_x),
                               hub_width=mm(lay.hub_width))

    def tongue_span(self, hub_x: float | None) -> tuple[float, float]:
        """x extent (lo, hi) of a joint's tongue: one clearance inside the slot, and one clearance
        off the parent's hub on the side that has one (``hub_x``: its groove plane)."""
        s, c = self.slot_width / 2.0, self.tol.clearance
        lo, hi = -(s - c), s - c
        if hub_x is not None:
            if hub_x > 0:
                hi = s - self.layout.hub_width - c
            else:
                lo = -(s - self.layout.hub_width - c)
        return lo, hi

    def bearing_face(self, lo: float, hi: float, obstacles) -> float | None:
        """The tongue face (x) a bearing seat opens on, or None when none fits: the seat (bearing
        width deep, the seat's radius) must stay a flank (``routing.FLANK``) from every groove,
        pocket and relief of the tongue (``obstacles``: (x0, x1, floor radius)); of two faces that
        fit, the one with more material between."""
        from ...kinematics import routing
        t = self.tol
        r_seat = t.bearing_seat / 2.0
        best, face = -1.0, None
        for f, x0, x1 in ((lo, lo, lo + t.bearing_width), (hi, hi - t.bearing_width, hi)):
            gap = math.inf
            for a, b, floor in obstacles:
                dx = max(0.0, a - x1, x0 - b)
                dr = floor - r_seat
                gap = min(gap, math.hypot(dx, max(0.0, dr)) if (dx > 0 or dr > 0) else -1.0)
            if gap >= mm(routing.FLANK) and gap > best:
                best, face = gap, f
        return face

    @property
    def boss_radius(self) -> float:
        """Radius of a joint's tongue boss and of the rounded clevis ends."""
        return self.thickness / 2.0

    @property
    def slot_width(self) -> float:
        return self.width - 2.0 * self.cheek

    @property
    def tongue_width(self) -> float:
        return self.slot_width - 2.0 * self.tol.clearance

    @property
    def slot_back(self) -> float:
        """Distance from a joint axis back to its clevis slot's back wall (extension stop face)."""
        return mm(slot_back(self.params.digit(self.digit).thickness, self.params.print.hole_clearance))

    @property
    def groove_width(self) -> float:
        return self.tol.tendon_hole

    @property
    def groove_outer(self) -> float:
        """The groove is cut from R out just past the boss surface."""
        return self.boss_radius + self.tol.clearance

    @property
    def spring_x(self) -> float:
        """Lateral offset of the two dorsal cable-spring channels (+/-): mid-cheek, so they pass
        beside the joint tongue and through the clevis cheeks."""
        return (self.slot_width / 2.0 + self.width / 2.0) / 2.0

    @property
    def spring_z(self) -> float:
        return self.thickness / 2.0 - self.tol.wall - self.tol.spring_hole / 2.0

    @property
    def heel_z(self) -> float:
        """Lower edge of the tongue's dorsal heel (the extension stop): half the boss radius."""
        return self.boss_radius / 2.0

    @property
    def eyelet_boss_radius(self) -> float:
        return self.tol.tendon_relief / 2.0 + self.tol.wall / 2.0

    def guide_points(self) -> tuple[np.ndarray, np.ndarray]:
        """Guide eyelet centres (y, z) relative to the reference joint (MCP / MP) axis at rest,
        mm (``frames.guide_offsets``: G1 at d1, G2 at d2, alpha apart about the palmar side)."""
        G1, G2 = F.guide_offsets(self.guide)
        return units.mm(G1), units.mm(G2)

    def recess(self, q_max: float) -> float:
        """Beyond 90 degrees of flexion the child's palmar face would reach the slot's back wall
        below the axis before q_max: the palmar half of the back wall is then recessed by
        half a thickness and the flexion-stop wedge rebuilt in it."""
        return self.thickness / 2.0 if q_max > math.pi / 2.0 else 0.0

    def stop_polygon(self, q_max: float) -> list[tuple[float, float]] | None:
        """(y, z) polygon, relative to the joint axis, of the flexion stop left in the palmar back
        corner of a clevis slot: the child's palmar face (z_child = -boss radius) lies on its
        edge exactly when the joint reaches q_max."""
        rb = self.boss_radius
        y0 = -self.slot_back - self.recess(q_max)
        rect = [(y0, -self.thickness / 2.0), (y0 + 2.0 * self.thickness, -self.thickness / 2.0),
                (y0 + 2.0 * self.thickness, 0.0), (y0, 0.0)]
        s, c = math.sin(q_max), math.cos(q_max)
        poly = clip_halfplane(rect, lambda p: -(p[0] * s + p[1] * c) - rb)
        if len(poly) < 3 or polygon_area(poly) < 0.25:
            return None
        return poly


def clip_halfplane(poly, f):
    """Sutherland-Hodgman: keep the part of a convex polygon where f(p) >= 0 (f affine)."""
    out = []
    n = len(poly)
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        fa, fb = f(a), f(b)
        if fa >= 0:
            out.append(a)
        if (fa >= 0) != (fb >= 0):
            t = fa / (fa - fb)
            out.append((a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])))
    return out


def polygon_area(poly) -> float:
    a = 0.0
    for i in range(len(poly)):
        x0, y0 = poly[i]
        x1, y1 = poly[(i + 1) % len(poly)]
        a += x0 * y1 - x1 * y0
    return abs(a) / 2.0


def internal_tangents(ra: float, yb: float, rb: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The two crossing (internal) tangents between circle ra at y=0 and rb at y=yb in the (y, z)
    plane: the figure-eight tendon paths. Returns [(point on a, point on b), ...]."""
    cb = (ra + rb) / yb
    sb = math.sqrt(max(0.0, 1.0 - cb * cb))
    out = []
    for sign in (1.0, -1.0):
        pa = np.array([ra * cb, sign * ra * sb])
        pb = np.array([yb - rb * cb, -sign * rb * sb])
        out.append((pa, pb))
    return out


# ---------------------------------------------------------------------------
# geometry (build123d imported lazily)
# ---------------------------------------------------------------------------

def bd():
    return import_build123d()


def box(x0, x1, y0, y1, z0, z1):
    b = bd()
    return b.Solid.make_box(x1 - x0, y1 - y0, z1 - z0, b.Plane(origin=(x0, y0, z0)))


def cylinder(p0, p1, r: float):
    """Solid cylinder of radius r from point p0 to point p1."""
    b = bd()
    p0 = np.asarray(p0, float)
    p1 = np.asarray(p1, float)
    axis = p1 - p0
    h = float(np.linalg.norm(axis))
    axis = axis / h
    ref = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    xdir = np.cross(axis, ref)
    xdir /= np.linalg.norm(xdir)
    return b.Solid.make_cylinder(r, h, b.Plane(origin=tuple(p0), x_dir=tuple(xdir), z_dir=tuple(axis)))


def cylinder_floor(p0, p1, r: float) -> float:
    """The lowest z (mm) of the solid cylinder of radius ``r`` on the axis p0 -> p1: an end
    circle's lowest point, its centre's z less r times the sine of the axis's angle from z."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    u = (p1 - p0) / np.linalg.norm(p1 - p0)
    return float(min(p0[2], p1[2]) - r * math.sqrt(max(0.0, 1.0 - u[2] * u[2])))


def teardrop(p0, p1, r: float, up=None, roof: float = units.rad(45.0)):
    """A hole of radius r from p0 to p1 that prints without support when ``up`` (a unit vector in
    the same frame: the printer's +z) is given: a cylinder whose top is a roof of two planes at
    ``roof`` (rad, ``print_rules.roof_angle``) from the vertical, meeting r / sin(roof) above the
    axis (a teardrop). A hole that stands steeper than that, or no ``up``: the plain cylinder."""
    p0 = np.asarray(p0, float)
    p1 = np.asarray(p1, float)
    if up is None:
        return cylinder(p0, p1, r)
    axis = (p1 - p0) / np.linalg.norm(p1 - p0)
    up = np.asarray(up, float)
    across = up - (up @ axis) * axis            # the up direction in the hole's cross-section
    # the round wall's steepest face looks down acos(|across|) from the vertical: round is enough
    # when that is at least 90 deg - roof (the roof's own faces look down no steeper)
    if np.linalg.norm(across) <= math.sin(roof) + 1e-9:
        return cylinder(p0, p1, r)
    b = bd()
    e1 = across / np.linalg.norm(across)
    plane = b.Plane(origin=tuple(p0), x_dir=tuple(e1), z_dir=tuple(axis))
    t = units.deg(math.pi / 2.0 - roof)      # the roof touches the circle at +-(90 deg - roof)
    arc = b.Edge.make_circle(r, plane, start_angle=t, end_angle=360.0 - t)
    apex = plane.from_local_coords((r / math.sin(roof), 0.0, 0.0))
    wire = b.Wire([arc, b.Edge.make_line(arc.position_at(1.0), apex), b.Edge.make_line(apex, arc.position_at(0.0))])
    return b.Solid.extrude(b.Face(wire), b.Vector(*(p1 - p0)))


def polygon_cylinder(p0, p1, r: float, n: int = 32):
    """A prism of ``n`` sides about the axis p0 -> p1 whose flats stand ``r`` from the axis (it
    holds the cylinder of radius r): a convex solid of plane faces (:func:`swept_along`)."""
    b = bd()
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    axis = (p1 - p0) / np.linalg.norm(p1 - p0)
    ref = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(axis, ref)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    R = r / math.cos(math.pi / n)
    a = 2.0 * math.pi * np.arange(n) / n
    pts = [b.Vector(*(p0 + R * (math.cos(t) * e1 + math.sin(t) * e2))) for t in a]
    return b.Solid.extrude(b.Face(b.Wire.make_polygon(pts, close=True)), b.Vector(*(p1 - p0)))


def swept_along(solid, vector) -> list:
    """A convex solid of plane faces swept by ``vector``, as tools: the solid and the prism each
    face turned along the sweep makes (a point the sweep reaches outside the solid lies past one
    of those faces, within ``vector`` of it: the union is the sweep)."""
    b = bd()
    v = b.Vector(*(float(c) for c in vector))
    out = [solid]
    for f in solid.faces():
        if f.normal_at().dot(v) > 1e-9 * v.length:
            out.append(b.Solid.extrude(f, v))
    return out


def cyl_x(r: float, x0: float, x1: float, y: float, z: float):
    return cylinder((x0, y, z), (x1, y, z), r)


def sphere(c, r: float):
    b = bd()
    return b.Solid.make_sphere(r).moved(b.Location(tuple(float(v) for v in c)))


def turn_sphere(c, r: float, into, out):
    """A sphere rounding a channel's turn at c, from direction ``into`` to ``out``, with its poles
    and its seam away from the two channels: a channel through a sphere's pole or along its seam
    can leave OpenCascade's cut with no solid at all (the two channels lie on its equator, the
    seam opposite their bisector)."""
    b = bd()
    a = -np.asarray(into, float) / np.linalg.norm(into)       # the openings, seen from c
    o = np.asarray(out, float) / np.linalg.norm(out)
    n = np.cross(a, o)
    if np.linalg.norm(n) < 1e-9:                                # straight on: any normal will do
        n = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    n /= np.linalg.norm(n)
    seam = -(a + o)
    if np.linalg.norm(seam) < 1e-9:
        seam = np.cross(n, a)
    seam -= n * (seam @ n)
    seam /= np.linalg.norm(seam)
    plane = b.Plane(origin=tuple(float(v) for v in c), x_dir=tuple(float(v) for v in seam),
                    z_dir=tuple(float(v) for v in n))
    return b.Solid.make_sphere(r, plane=plane)


#: a cut whose nearest point lies within this angle (deg) of a channel's axis, ahead or behind, is
#: not beside it: the channel meets its face square
SQUARE_DEG = 30.0
#: a point nearer a cut than this (mm) lies in it: far above a swept cut's search tolerance
#: (``kinematics.vectors.nearest_on_swept``), far below anything printed
INSIDE = 1e-6
#: a slot joining a channel to a cut is this fraction of the channel's diameter high, so that its
#: faces cross the channel's cylinder instead of lying tangent to it: OpenCascade's cut leaves a
#: loose sliver or an invalid face where a box face grazes a cylinder (sized hands showed both)
SLOT_CHORD = 0.8


def channel_slot(p, u, s0: float, s1: float, toward, r: float, flank: float):
    """A slot opening a channel (radius ``r``, its axis from ``p`` along the unit vector ``u``) from
    ``s0`` to ``s1`` along it: a box :data:`SLOT_CHORD` of a channel wide, from a channel radius
    before ``s0`` to one past ``s1``, from the axis toward ``toward`` (a direction; its part square
    to the axis) two channel radii and flanks and half a millimetre."""
    p, u = np.asarray(p, float), np.asarray(u, float)
    y = np.asarray(toward, float) - u * (np.asarray(toward, float) @ u)
    y /= np.linalg.norm(y)
    M = np.eye(4)
    M[:3, 0], M[:3, 1], M[:3, 2], M[:3, 3] = u, y, np.cross(u, y), p
    h = SLOT_CHORD * r
    return transform(box(s0 - r, s1 + r, 0.0, 2.0 * (r + flank) + 0.5, -h, h), M)


def channel_slots(p, u, length: float, r: float, gaps, flank: float) -> list:
    """Slots (:func:`channel_slot`) joining a channel (radius ``r``, its axis from ``p`` along the
    unit vector ``u`` for ``length``) to each cut whose wall to it is under ``flank`` somewhere along
    it: per run of the axis under a flank from the cut and outside it, from the run's first point to
    its last (up to where the axis enters the cut), from the channel's axis toward the cut's nearest
    point into it (past where any of those points' walls was: the cut's nearest face turns along
    the run). A run where the cut lies only ahead or behind (within :data:`SQUARE_DEG` of the axis:
    the channel meets its face square) needs none. ``gaps``: per cut, a function of points (n, 3)
    giving (distance, nearest point)."""
    p, u = np.asarray(p, float), np.asarray(u, float)
    s = np.linspace(0.0, length, int(length / 0.05) + 1)
    axis = p + s[:, None] * u
    out = []
    for gap in gaps:
        d, near = gap(axis)
        to = near - axis
        across = to - np.outer(to @ u, u)             # the way to the cut, square to the axis
        beside = np.linalg.norm(across, axis=1) > math.sin(math.radians(SQUARE_DEG)) * d
        near_ = np.flatnonzero((d < r + flank) & (d >= INSIDE))
        for run in np.split(near_, np.flatnonzero(np.diff(near_) > 1) + 1):
            side = run[beside[run]]
            if not len(side):
                continue
            i = side[int(np.argmin(d[side]))]
            out.append(channel_slot(p, u, s[run[0]], s[run[-1]], across[i], r, flank))
    return out


def extrude_up(poly, height: float):
    """A planar polygon (3D vertices in order) extruded ``height`` along +z."""
    b = bd()
    wire = b.Wire.make_polygon([b.Vector(*(float(v) for v in p)) for p in poly], close=True)
    return b.Solid.extrude(b.Face(wire), b.Vector(0, 0, height))


def prism_x(poly_yz, x0: float, x1: float):
    """Extrude a (y, z) polygon along x from x0 to x1."""
    b = bd()
    pts = [b.Vector(x0, float(y), float(z)) for y, z in poly_yz]
    wire = b.Wire.make_polygon(pts, close=True)
    face = b.Face(wire)
    return b.Solid.extrude(face, b.Vector(x1 - x0, 0, 0))


def transform(shape, T: np.ndarray):
    """Move a shape by a 4x4 rigid transform (mm)."""
    return shape.moved(location(T))


def location(T: np.ndarray):
    """build123d Location of a 4x4 rigid transform (mm)."""
    b = bd()
    T = np.asarray(T, float)
    plane = b.Plane(origin=tuple(T[:3, 3]), x_dir=tuple(T[:3, 0]), z_dir=tuple(T[:3, 2]))
    return b.Location(plane)


def ring_x(r_in: float, r_out: float, width: float, y: float = 0.0, z: float = 0.0):
    """Annulus about an x-parallel axis through (y, z), centred on x = 0 (a groove cutter)."""
    outer = cyl_x(r_out, -width / 2.0, width / 2.0, y, z)
    inner = cyl_x(r_in, -width / 2.0 - 1.0, width / 2.0 + 1.0, y, z)
    return outer.cut(inner)


def as_solid(shape):
    """The one solid of a boolean result as a ``Solid``; a result of several solids is returned
    as it is, for the verification (``phantom_cad.cad.verify``, the one place a part's
    validity is checked) to refuse."""
    b = bd()
    solids = shape.solids()
    if len(solids) != 1:
        return shape
    s = solids[0]
    return b.Solid(s.wrapped) if not isinstance(s, b.Solid) else s


def build(body_parts, tools, *later):
    """Fuse the body parts and cut every tool in one boolean, then each group of ``later`` tools
    in one boolean of its own (OpenCascade's multi-tool cut can leave material where several
    tools overlap one another at tangent or coincident faces: a guide eyelet's relief sphere
    inside a clevis slot, measured by ``cad.clearance``); the result should be one valid solid
    (checked once per part by ``phantom_cad.cad.verify``)."""
    body = body_parts[0]
    if len(body_parts) > 1:
        body = body.fuse(*body_parts[1:])
    for group in (tools, *later):
        if group:
            body = as_solid(body.cut(*group))
    return as_solid(body)
