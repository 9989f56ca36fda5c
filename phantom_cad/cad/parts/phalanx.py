"""Phalanges of the four fingers and the thumb, and the joint features every digit link shares.

Link frame (docs/frames.md): origin on the proximal joint axis at the middle of the width,
x along the joint axes (ulnar side of a right hand), y along the link, z dorsal.

A joint is a clevis on the parent (two cheeks that hold the axle with a press fit, a slot
between them whose back wall is the extension stop and whose palmar back corner keeps a
wedge that is the flexion stop at the joint's upper limit) and a tongue on the child (a
boss of radius thickness/2 with the tendon groove of radius R at mid-width, two bearing
seats, a clearance bore for the axle, and a dorsal heel that rests on the parent's back
wall at full extension).
"""

from __future__ import annotations

import math

import numpy as np

from ... import canon, units
from ...kinematics import frames as F
from ...kinematics.dimensions import FLANK, digit_entry
from ...kinematics.hand_params import HandParams
from ...kinematics.topology import CMC_Q, LINKS, digit_links, joint
from ..measure import eyelet_centres, point_line_distance
from .base import DORSAL_DOWN, Part, child_joint, parent_joint
from .common import DigitSection, box, build, cyl_x, cylinder, mm, prism_x, sphere
from .drive_fans import drive_fan_tools
from .tendons import (LinkTendons, RoutedPart, link_tendons, anchor_tools, channel_tools, groove_outer,
                      groove_tool, knot_pocket_depth, sector_prism, cutter,
                      parent_hub_x)


#: how far (rad) the drive's knot well behind G2 leans distally from the palmar normal (see
#: Phalanx.build): straight down, it left a 0.45-0.75 mm web beside the eyelet's near relief
KNOT_WELL_LEAN = units.rad(35.0)
#: how far (rad) the well under G2's near relief sphere leans proximally from the palmar normal,
#: where the sphere would leave a skin on the palmar face (Phalanx.build): away from the eyelet's
#: hole and the knot well, into the drive's fan
NEAR_WELL_LEAN = units.rad(20.0)

# ---------------------------------------------------------------------------
# shared joint features: each returns (body_parts, cutting_tools), link frame, mm
# ---------------------------------------------------------------------------


def tongue(sec: DigitSection, joint_name: str, lt: LinkTendons):
    """Child side of a joint whose axis is the link's x axis: cut back off the parent's hub, the
    routing model's grooves (loop groove, return cord) in it, the axle's clearance bore, and one
    bearing seat on the face that leaves a flank to every groove (none where no face does: the
    tongue then turns on the axle in its bore)."""
    t = sec.tol
    rb, T = sec.boss_radius, sec.thickness
    lo, hi = sec.tongue_span(parent_hub_x(sec.params, joint_name))
    body = [
        cyl_x(rb, lo, hi, 0.0, 0.0),
        box(lo, hi, 0.0, sec.slot_back, -T / 2.0, T / 2.0),
        box(lo, hi, -sec.slot_back, 0.0, sec.heel_z, T / 2.0),                 # extension-stop heel
    ]
    tools = [groove_tool(g, groove_outer(sec, g)) for g in lt.tongue_grooves(joint_name)]
    tools += [cyl_x(t.axle_clear / 2.0, lo - 1.0, hi + 1.0, 0.0, 0.0)]           # axle clearance bore
    face = tongue_bearing_face(sec, joint_name, lt)
    if face is not None:
        x_in = face + (t.bearing_width if face == lo else -t.bearing_width)
        x_out = face + (-1.0 if face == lo else 1.0)
        tools.append(cyl_x(t.bearing_seat / 2.0, min(x_in, x_out), max(x_in, x_out), 0.0, 0.0))
    return body, tools


def tongue_obstacles(sec: DigitSection, joint_name: str, lt: LinkTendons):
    """(x0, x1, floor radius) of what the tongue at ``joint_name`` has cut into it about its axis:
    grooves, the knot pockets below them, the drive chord's fan (its closest approach)."""
    out = []
    for g in lt.tongue_grooves(joint_name):
        depth = max((knot_pocket_depth(sec, g.floor, a.cord) for a in lt.anchors if a.role == "groove clamp"
                     and abs(a.pos[0] - g.x) < 1e-6), default=0.0)
        out.append((g.x - g.width / 2.0, g.x + g.width / 2.0, g.floor - depth))
    for fixed, moving in lt.drive_sweeps:
        r = min(_segment_axis_distance(fixed, m) for m in moving)
        w = sec.tol.tendon_hole
        out.append((fixed[0] - w / 2.0, fixed[0] + w / 2.0, r - w / 2.0))
    return out


def tongue_bearing_face(sec: DigitSection, joint_name: str, lt: LinkTendons) -> float | None:
    """The tongue face (x, mm) whose bearing seat fits beside the tongue's grooves, or None."""
    lo, hi = sec.tongue_span(parent_hub_x(sec.params, joint_name))
    return sec.bearing_face(lo, hi, tongue_obstacles(sec, joint_name, lt))


def _segment_axis_distance(a, b) -> float:
    """Distance in the (y, z) plane from the x axis to the segment a-b."""
    a, b = np.asarray(a, float)[1:], np.asarray(b, float)[1:]
    d = b - a
    t = 0.0 if d @ d == 0 else min(1.0, max(0.0, -(a @ d) / (d @ d)))
    return float(np.linalg.norm(a + t * d))


def clevis(sec: DigitSection, joint: str, y: float, hub_x: float | None = None, stop_clear=None,
           standing=()):
    """Parent side of a joint whose axis is parallel to x through (y, 0); a loop's hub (groove
    plane ``hub_x``) is the material the slot leaves beside that side's cheek. ``stop_clear``: a
    function that takes the flexion stop's (y, z) outline (joint frame) and returns the outline the
    slot leaves standing (``drive_fans.clear_of_fans``); default: the whole outline. ``standing``:
    more (y, z) outlines (link frame) the slot leaves standing (:func:`relief_opening`'s keel)."""
    t = sec.tol
    rb, W, T, sw = sec.boss_radius, sec.width, sec.thickness, sec.slot_width
    body = [cyl_x(rb, -W / 2.0, W / 2.0, y, 0.0)]
    lo, hi = -sw / 2.0, sw / 2.0
    if hub_x is not None:
        if hub_x > 0:
            hi -= sec.layout.hub_width
        else:
            lo += sec.layout.hub_width
    # through the faces and through a guide's boss that hangs beyond one (a 0.6 mm sliver of the
    # thumb CMC base's MP guide boss stayed in the slot of a 170 mm hand)
    slot = box(lo, hi, y - sec.slot_back, y + rb + 1.0, -T, T)
    recess = sec.recess(sec.q_stop[joint])
    half = sw / 2.0
    if recess > 0.0:       # across the full width: the child's full-width body swings in here
        half = W / 2.0 + 1.0
        quadrant = box(-half, half, y - sec.slot_back - recess, y, -T, 0.0)
        slot = slot.fuse(quadrant.cut(cyl_x(rb, -half - 1.0, half + 1.0, y, 0.0)))
    poly = stop_wedge(sec, joint, y, stop_clear)
    if poly is not None:   # keep the flexion-stop wedge: the slot tool leaves it standing
        slot = slot.cut(prism_x(poly, -half - 0.5, half + 0.5))
    for outline in standing:
        slot = slot.cut(prism_x(outline, -half - 0.5, half + 0.5))
    tools = [slot, cyl_x(t.axle_press / 2.0, -W / 2.0 - 1.0, W / 2.0 + 1.0, y, 0.0)]
    return body, tools


def stop_wedge(sec: DigitSection, joint: str, y: float, stop_clear=None) -> list[tuple[float, float]] | None:
    """The (y, z) outline, link frame, of the flexion stop that :func:`clevis` (its axis at ``y``)
    leaves standing in its slot (``stop_clear`` as there), or None where there is none."""
    poly = sec.stop_polygon(sec.q_stop[joint])
    if poly is None:
        return None
    return [(py + y, pz) for py, pz in (poly if stop_clear is None else stop_clear(poly))]


#: how far (mm) a G1 eyelet's near relief runs on along the chord at rest at least (into the clevis
#: slot: as a sphere it left a 0.7 mm rim at 28 deg on the finger bases, 0.47 mm on the 170 mm
#: hand's thumb CMC base)
NEAR_RELIEF_RUN = 2.0


def near_relief(sec: DigitSection, s_near, u, wedge):
    """The tool that opens a G1 eyelet's near relief sphere (centre ``s_near``) along the chord at
    rest (``u``, toward G2), a relief wide: :data:`NEAR_RELIEF_RUN`, and on until its end lies wholly
    a clearance in front of the flexion stop (``wedge``: :func:`stop_wedge`, or None). Where the
    relief grazes the palmar face, an end under the wedge left a fin between it and the wedge's
    slope; in front of the wedge the slot is empty, so the longer run cuts nothing else."""
    return cylinder(s_near, s_near + near_relief_run(sec, s_near, u, wedge) * u, sec.tol.tendon_relief / 2.0)


def near_relief_run(sec: DigitSection, s_near, u, wedge) -> float:
    """How far (mm) :func:`near_relief` runs from the sphere's centre along ``u``."""
    t = sec.tol
    rr = t.tendon_relief / 2.0
    run = NEAR_RELIEF_RUN
    if wedge is not None and u[1] > 0.0:
        edge = max(py for py, _ in wedge)       # the wedge's foremost point: its edge on the palmar face
        # the end's disc reaches rr |u_z| behind its centre
        run = max(run, (edge + t.clearance + rr * abs(u[2]) - s_near[1]) / u[1])
    return run


#: how much wider (mm, each side) than the near relief :func:`relief_opening`'s slot is: its sides
#: stand off the relief's, never tangent to them
RELIEF_SLOT_MARGIN = 0.2


def relief_opening(sec: DigitSection, s_near, u, wedge, pad_end: float, floor: float):
    """For a G1 eyelet whose near relief (sphere at ``s_near``, run along ``u``: :func:`near_relief`;
    ``wedge``: :func:`stop_wedge` with no ``stop_clear``) would leave a skin on the palmar face
    (z = -thickness / 2): its lowest point within a wall above the face, or through it by less than
    half its radius (a rim under 60 deg). (the keel's (y, z) outline, the slot) or None elsewhere.

    The keel, under the eyelet's exit from ``pad_end`` (the clevis slot's back) to the sphere's
    centre, down to ``floor`` or a wall under the sphere, a wall beside the relief each side, holds
    the hole and the sphere's back half a wall off the face: the tendon keeps the rounded back half
    to bend on. It stands in the clevis slot, which must leave it standing as it leaves the wedge
    (:func:`clevis`'s ``standing``). The slot, a little wider than the relief, from its axis down through
    the face, opens the rest (the sphere's front half and the run)."""
    rr = sec.tol.tendon_relief / 2.0
    wall = mm(FLANK)
    face = -sec.thickness / 2.0
    low = float(s_near[2]) - rr
    if not face - rr / 2.0 < low < face + wall:
        return None
    end = np.asarray(s_near, float) + near_relief_run(sec, s_near, u, wedge) * np.asarray(u, float)
    bottom = min(floor, low - wall)
    keel = [(pad_end, bottom), (float(s_near[1]), bottom), (float(s_near[1]), face), (pad_end, face)]
    w = rr + RELIEF_SLOT_MARGIN
    slot = prism_x([(s_near[1], s_near[2]), (end[1], end[2]), (end[1], bottom - 1.0), (s_near[1], bottom - 1.0)],
                   -w, w)
    return keel, slot


def keel_body(sec: DigitSection, keel):
    """The keel of :func:`relief_opening` as a solid: a wall beside the relief each side."""
    w = sec.tol.tendon_relief / 2.0 + mm(FLANK)
    return prism_x(keel, -w, w)


def _eyelet_axis(sec: DigitSection, centre_yz, toward_yz):
    """(centre, unit axis, half the hole between the relief spheres' centres, how far the boss
    reaches back, the ends of the boss's axis) of an eyelet at ``centre`` (x = 0) toward
    ``toward``, mm."""
    t = sec.tol
    c = np.array([0.0, *centre_yz])
    u = np.array([0.0, *toward_yz]) - c
    u /= np.linalg.norm(u)
    r = t.tendon_hole / 2.0
    rr = t.tendon_relief / 2.0
    half = t.eyelet_length / 2.0 + math.sqrt(rr * rr - r * r)
    # the boss reaches back past the far relief sphere but only to the near sphere's centre
    # toward the other guide, so the two guides' bosses clear each other at full flexion
    back = half + rr + t.wall / 2.0
    return c, u, half, back, (c - back * u, c + half * u)


def eyelet_boss_axis(sec: DigitSection, centre_yz, toward_yz) -> tuple[np.ndarray, np.ndarray]:
    """The ends (mm) of the axis of :func:`eyelet`'s boss (a cylinder of ``eyelet_boss_radius``)."""
    return _eyelet_axis(sec, centre_yz, toward_yz)[4]


def eyelet(sec: DigitSection, centre_yz, toward_yz, clip_palmar: bool = False, clip_y: float | None = None):
    """A tendon guide eyelet at centre (x = 0), its hole along the line toward ``toward``:
    a boss of material, a hole of exactly eyelet_length between two relief spheres.
    Returns (body, tools, axis unit vector, the two relief-sphere centres)."""
    t = sec.tol
    c, u, half, boss_back, ends = _eyelet_axis(sec, centre_yz, toward_yz)
    r = t.tendon_hole / 2.0
    rr = t.tendon_relief / 2.0
    s_near, s_far = c + half * u, c - half * u
    boss = cylinder(*ends, sec.eyelet_boss_radius)
    if clip_palmar:   # a child's guide stays inside its palmar face (the flexion-stop face)
        T = sec.thickness
        boss = boss.cut(box(-T, T, c[1] - 2.0 * boss_back, c[1] + 2.0 * boss_back, -2.0 * T, -T / 2.0))
    if clip_y is not None:   # stay in front of a mating face (the finger base's magnet face)
        T = sec.thickness
        boss = boss.cut(box(-T, T, clip_y - 4.0 * boss_back, clip_y, -2.0 * T, 2.0 * T))
    body = [boss]
    tools = [cylinder(s_far, s_near, r), sphere(s_near, rr), sphere(s_far, rr)]
    return body, tools, u, (s_near, s_far)


def channel(p0, p1, d: float, extend: float = 0.0):
    p0 = np.asarray(p0, float)
    p1 = np.asarray(p1, float)
    u = (p1 - p0) / np.linalg.norm(p1 - p0)
    return cylinder(p0 - extend * u, p1 + extend * u, d / 2.0)


# ---------------------------------------------------------------------------
# phalanges
# ---------------------------------------------------------------------------

class Phalanx(RoutedPart, Part):
    """One phalanx of a digit: ``segment`` is its link's segment (``proximal``, ``middle``,
    ``distal``; the thumb has no middle). Dimensions in mm; the joints at its two ends come
    from the topology (the joint at its origin, and the next link's joint)."""

    #: the links a flexion joint moves (every digit link but the CMC base)
    SEGMENTS = tuple(dict.fromkeys(ln.segment for ln in LINKS
                                   if ln.parent_joint and joint(ln.parent_joint).index != CMC_Q))

    def __init__(self, params: HandParams, digit: str, segment: str):
        links = [ln for ln in digit_links(digit) if ln.segment in self.SEGMENTS]
        if not links:
            raise ValueError(f"unknown digit {digit!r}")
        allowed = tuple(ln.segment for ln in links)
        if segment not in allowed:
            raise ValueError(f"{digit} has no {segment!r} phalanx (allowed: {allowed})")
        self.params, self.segment = params, segment
        self.link = links[allowed.index(segment)]
        self.sec = DigitSection(params, digit)
        self.length = mm(getattr(params.digit(digit), self.link.length_key))
        nxt = child_joint(self.link)
        #: joint key at this link's origin, and at its far end (None for the distal phalanx)
        self.proximal_joint = parent_joint(self.link).key
        self.distal_joint = nxt.key if nxt is not None else None
        if self.length <= 2.0 * self.sec.slot_back:
            raise ValueError(f"{digit} {segment} length {self.length:.2f} mm is shorter than two joint bosses")

    @classmethod
    def for_link(cls, params: HandParams, link):
        return cls(params, link.digit, link.segment)

    def inputs(self) -> dict:
        doc = self.params.document
        key = "finger" if self.digit in doc["fingers"] else "thumb"
        return {**self.common_inputs(), key: canon.plain(digit_entry(doc, self.digit))}

    @property
    def has_guide(self) -> bool:
        """The phalanx-side guide of the reference joint (MCP, thumb MP) sits on the link that
        joint moves, at d2."""
        return parent_joint(self.link).is_reference

    @property
    def tip_y(self) -> float:
        """Far end of the part along y: the fingertip, or the clevis boss beyond the distal axis."""
        return self.length if self.distal_joint is None else self.length + self.sec.boss_radius

    @property
    def tip_radius(self) -> float:
        """Radius of the fingertip's half cylinder (distal phalanx): half the thickness, or less
        (``frames.fingertip``)."""
        return mm(F.fingertip(self.params, self.digit)[1])

    def pad(self) -> np.ndarray:
        """T_link_pad (mm) of a fingertip (``frames.T_distal_pad``): the centre of its contact pad,
        on the tip's half cylinder ``frames.PAD_ANGLE`` (45 deg) from the palmar face toward the
        tip, its z axis the outward surface normal there, its x the link's x."""
        if self.distal_joint is not None:
            raise ValueError(f"{self.name} is not a fingertip")
        return F.to_mm(F.T_distal_pad(self.params, self.digit))

    def verify(self, shape) -> list[str]:
        """The routing model's grooves on this link (floor R - cord / 2); on the guide link, the
        eyelet at d2."""
        out: list[str] = []
        tol = self.sec.tol
        faces = self.verify_routing(shape, out)     # the grooves; the faces, for the eyelet and the pockets
        if self.has_guide:
            eyes = eyelet_centres(shape, tol.tendon_hole / 2.0, tol.eyelet_length, faces=faces)
            d = point_line_distance(eyes[0]["centre"], (0, 0, 0), (1, 0, 0)) if len(eyes) == 1 else None
            self.expect(out, "guide d2", d, mm(self.sec.guide.d2), 0.02)
        return out

    @property
    def print_rotation(self) -> np.ndarray:
        """On its dorsal face: the least overhang of the axis-aligned ways (``export.orient``
        measures it); its tendon channels' roofs point up (``print_up``)."""
        return DORSAL_DOWN

    def build(self):
        sec, t = self.sec, self.sec.tol
        W, T, L = sec.width, sec.thickness, self.length
        lt = link_tendons(self.params, self.link.name)
        body, tools = tongue(sec, parent_joint(self.link).name, lt)
        if self.distal_joint is None:       # fingertip: a half-cylinder of radius T/2 (or less)
            r_tip = self.tip_radius
            y_c = L - r_tip
            body.append(box(-W / 2.0, W / 2.0, sec.slot_back, y_c, -T / 2.0, T / 2.0))
            tip = cyl_x(r_tip, -W / 2.0, W / 2.0, y_c, 0.0).cut(
                box(-W / 2.0 - 1.0, W / 2.0 + 1.0, y_c - r_tip - 1.0, y_c, -T / 2.0 - 1.0, T / 2.0 + 1.0))
            body.append(tip)
        else:
            body.append(box(-W / 2.0, W / 2.0, sec.slot_back, L, -T / 2.0, T / 2.0))
            b2, t2 = clevis(sec, self.distal_joint, L, lt.hubs().get(child_joint(self.link).name))
            body += b2
            tools += t2
        tools += hub_grooves(sec, lt)
        if self.has_guide:
            G1, G2 = sec.guide_points()
            b3, t3, u, (s_near, s_far) = eyelet(sec, G2, lt.eyelet_toward(G2), clip_palmar=True)
            body += b3
            tools += t3
            # the drive ends here: knotted behind G2, in a well from the far relief to the palmar
            # face, leaning distally by KNOT_WELL_LEAN so that the web between it and the near relief
            # (under the eyelet's hole) stays a wall thick where both reach the palmar face
            drop = s_far[2] + T / 2.0 + 1.0
            tools.append(cylinder(s_far, (0.0, s_far[1] + drop * math.tan(KNOT_WELL_LEAN), -T / 2.0 - 1.0),
                                  t.tendon_relief / 2.0))
            # where the near relief sphere's lowest point stands less than a wall above the palmar
            # face (0.4 mm on the 205 mm hands' thumb), a well opens it through the face, leaning
            # proximally (the hole's palmar edge and the knot well stay whole), a little wider than
            # the sphere (never tangent to it)
            rr, face = t.tendon_relief / 2.0, -T / 2.0
            if face < s_near[2] - rr < face + mm(FLANK):
                drop = s_near[2] - face + 1.0
                tools.append(cylinder(s_near, (0.0, s_near[1] - drop * math.tan(NEAR_WELL_LEAN), face - 1.0),
                                      rr + RELIEF_SLOT_MARGIN))
            flanks = tuple(g.x + k * g.width / 2.0 for g in lt.tongue_grooves(parent_joint(self.link).name)
                           for k in (-1.0, 1.0))
            tools += drive_fan_tools(lt, sec, float(np.linalg.norm(s_near - np.array([0.0, *G2]))),
                                     flanks=flanks, span=(-sec.slot_back - 1.0, sec.slot_back))
        tools += channel_tools(lt, faces=(sec.slot_back, L - sec.slot_back), up=self.print_up)   # its shoulders
        tools += anchor_tools(lt, sec, self.print_up)
        return build(body, tools)


def hub_grooves(sec: DigitSection, lt: LinkTendons) -> list:
    """The grooves of the loop hubs a link carries, cut out through the hub's rim. Where the rim (a
    cylinder one millimetre past the boss) leaves the dorsal or palmar face it would meet it at a
    shallow angle and leave a knife edge (0.07 mm at 27 deg); there the groove is opened square to
    the face, out to where the rim lies a flank (0.8 mm) inside it."""
    wall = mm(FLANK)
    tools = []
    for g in (g for g in lt.grooves if g.role == "hub"):
        outer = groove_outer(sec, g)
        tools.append(groove_tool(g, outer))
        for side in (1.0, -1.0):
            floor = sec.thickness / 2.0 - wall - side * g.z          # the slab's floor from the axis
            if not 0.0 < floor < outer:
                continue
            yw = math.sqrt(outer * outer - floor * floor)
            z0, z1 = sorted((side * (sec.thickness / 2.0 - wall), side * (sec.thickness / 2.0 + 1.0)))
            slab = box(g.x - g.width / 2.0, g.x + g.width / 2.0, g.y - yw, g.y + yw, z0, z1)
            wedge = sector_prism(g, outer + 2.0)
            tools.append(slab if wedge is None else cutter(slab.intersect(wedge)))
    return tools
