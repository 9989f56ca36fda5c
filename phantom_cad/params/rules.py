"""The rules that make the printable parts fit, checked when a parameter file loads.

Every dimension ``phantom-cad build`` relies on is checked here, as a :class:`ParamError` naming
the field, its value and the rule: a file that validates must build. The derived dimensions
follow the parts' own (phantom_cad.cad.parts.common: clearance holes d + 2 * hole_clearance,
magnet pockets (d + 2 * magnet_clearance) x (t + magnet_clearance), joint bosses of radius
thickness / 2 whose slots reach one hole clearance further). ``tests/test_validation_builds.py``
checks the claim by building randomly perturbed files that validate.
"""

from __future__ import annotations

import math

from ..kinematics.dimensions import (FLANK, HUB_GROOVE_PAST_BOSS, digit_field, finger_base_thickness_ceiling,
                                     finger_columns, printed_hole, servo_pilot_wall, slot_back, tendon_height)
from ..units import DEG, MM
from .errors import ParamError

#: the longest hand name: it names files and folders (``exports/<name>/``, ``<name>_description``)
MAX_NAME = 64
#: the thinnest wall an FDM printer makes: two perimeters of a 0.4 mm nozzle
MIN_WALL = 0.8 * MM
#: the largest hinge flexion limit the phalanges are modelled and checked for (built and verified at
#: 120 degrees; at 156 degrees a middle phalanx's recess cut splits it in two: the property test)
MAX_FLEXION = 120.0 * DEG
#: the largest finger pitch the palm layout is modelled and checked for (built and verified at 21 mm;
#: from 22 mm the palm's solid is not valid: the property test, docs/reliability.md)
MAX_FINGER_PITCH = 21.0 * MM


def _digits(fingers, thumb):
    """(field prefix, digit) of the four fingers and the thumb."""
    return [(digit_field(n), f) for n, f in fingers.items()] + [(digit_field("thumb"), thumb)]


def check_parts(c, hand_length, fingers, thumb, palm, servo, hardware, printing, cad) -> None:
    """Every rule linking the [cad] dimensions, the digits, the palm and the hardware."""
    _joints(c, fingers, thumb, hardware, printing, cad)
    _segments(c, fingers, thumb, printing, hand_length)
    _magnets(c, fingers, palm, hardware, printing, cad)
    _guides(c, fingers, thumb, palm, hardware, printing, cad)
    _servos(c, fingers, thumb, servo, hardware, printing, cad)


def _joints(c, fingers, thumb, hardware, printing, cad) -> None:
    groove = hardware.tendon_diameter + 2.0 * printing.hole_clearance
    ret = cad.spring_diameter + 2.0 * printing.hole_clearance
    cl = printing.hole_clearance
    for name, d in _digits(fingers, thumb):
        width, thick = d.width, d.thickness
        # the clevis slot holds a coupling loop's hub beside one cheek (a groove between two
        # flanks, one clearance) and the tongue beside it, which carries the return cord's groove
        # a flank inside each of its faces on both sides of the middle (kinematics.routing.layout)
        slot = width - 2.0 * cad.cheek
        hub = cl + 2.0 * FLANK + groove
        need = 2.0 * (hub + cl + FLANK) + ret
        if slot < need - 1e-12:
            raise c.error("cheek_mm", cad.cheek / MM,
                          f"leaves a {slot / MM:.3f} mm clevis slot in {name}.width_mm = {width / MM:g}; "
                          f"a loop hub, the tongue and its return groove need {need / MM:.3f} mm")
        # each joint's grooves of radius R (the loop's and the return cord's, their floors half a
        # cord inside R) lie in the tongue's boss (radius thickness / 2) and outside the axle's
        # clearance bore
        axle = printed_hole(hardware.axle_diameter + 2.0 * printing.hole_clearance, printing.hole_compensation) / 2.0
        cord = max(hardware.tendon_diameter, cad.spring_diameter)
        for key, R in zip(d.chain.joints, d.chain.radii):
            if not axle < R - cord / 2.0 - 1e-12 or not R < thick / 2.0 - 1e-12:
                raise ParamError(f"{name}.pulley_radius_mm.{key}", round(R / MM, 6),
                                 f"the joint's grooves must lie between the axle bore (radius {axle / MM:.3f} mm, "
                                 f"with hole_compensation) and the joint boss's surface ({name}.thickness_mm / 2 = "
                                 f"{thick / 2.0 / MM:g} mm): their floors lie half a cord ({cord / 2.0 / MM:g} mm, "
                                 f"the return cord's) inside the radius", c.source)
            # the return cord runs along each link at its joints' groove radius, in a channel
            # (kinematics.routing): two perimeters must stay between it and the dorsal face
            top = R + ret / 2.0 + MIN_WALL
            if top > thick / 2.0 + 1e-9:
                raise ParamError(f"{name}.pulley_radius_mm.{key}", round(R / MM, 6),
                                 f"must be <= {(thick / 2.0 - ret / 2.0 - MIN_WALL) / MM:.3f} mm: the return "
                                 f"cord's channel ({ret / MM:g} mm with clearance) runs at this radius and "
                                 f"must keep a {MIN_WALL / MM:g} mm wall under the dorsal face "
                                 f"({name}.thickness_mm / 2 = {thick / 2.0 / MM:g} mm)", c.source)
    if cad.spring_diameter + 2.0 * printing.hole_clearance >= cad.cheek - 1e-12:
        raise c.error("spring_diameter_mm", cad.spring_diameter / MM,
                      f"its channel ({(cad.spring_diameter + 2.0 * printing.hole_clearance) / MM:g} mm with "
                      f"clearance) must fit inside a clevis cheek (cheek_mm = {cad.cheek / MM:g})")


def _segments(c, fingers, thumb, printing, hand_length) -> None:
    """A phalanx reaches past the clevis slots of its two joints; the thumb metacarpal carries the
    CMC hub and the MP clevis."""
    for name, d in _digits(fingers, thumb):
        back = slot_back(d.thickness, printing.hole_clearance)
        # the phalanges follow the metacarpal; the k-th starts at joint k and ends at joint k + 1
        segments = d.chain.spec.segments[1:]
        far_limits = dict(zip(segments, [*d.chain.limits[1:], None]))
        for seg in segments:
            length = getattr(d, seg)
            need = 2.0 * back
            far = far_limits[seg]
            if far is not None and far[1] > math.pi / 2.0:
                need += d.thickness / 2.0     # beyond 90 degrees the far clevis is recessed by T/2
            if length <= need + 1e-12:
                raise ParamError(f"{name}.length_fraction.{seg}", round(length / hand_length, 6),
                                 f"the {seg} phalanx ({length / MM:.2f} mm at hand_length_mm = {hand_length / MM:g}) "
                                 f"must be longer than its two joint bosses and their clearances "
                                 f"({need / MM:.2f} mm: {name}.thickness_mm + 2 hole_clearance"
                                 f"{', + half the thickness for a far joint flexing past 90 degrees' if need > 2.0 * back else ''})",
                                 c.source)
    back = slot_back(thumb.thickness, printing.hole_clearance)
    if thumb.metacarpal <= thumb.width / 2.0 + back + 1e-12:
        raise ParamError("thumb.length_fraction.metacarpal", round(thumb.metacarpal / hand_length, 6),
                         f"the thumb metacarpal ({thumb.metacarpal / MM:.2f} mm) must be longer than the CMC hub "
                         f"(half thumb.width_mm = {thumb.width / 2.0 / MM:g}) and the MP clevis "
                         f"({back / MM:.2f} mm)", c.source)


def _magnets(c, fingers, palm, hardware, printing, cad) -> None:
    """Two magnet pockets side by side, one wall apart, on every finger base's magnet face and the
    palm socket facing it; the tendon enters below them."""
    if palm.wall < MIN_WALL - 1e-12:
        raise ParamError("palm.wall_mm", round(palm.wall / MM, 6),
                         f"must be >= {MIN_WALL / MM:g} mm, two perimeters of a 0.4 mm nozzle "
                         "(the thinnest wall an FDM printer makes)", c.source)
    pocket = printed_hole(hardware.magnet_diameter + 2.0 * printing.magnet_clearance, printing.hole_compensation)
    span = 2.0 * pocket + palm.wall          # both pockets and the wall between them
    thinnest = min(f.thickness for f in fingers.values())
    tendon_z = tendon_height(thinnest, palm.wall)
    relief = 2.0 * (hardware.tendon_diameter + 2.0 * printing.hole_clearance)
    # centred pockets (no lift) are held by the rule below that they fit at all
    highest = max(thinnest / 2.0 - MIN_WALL - pocket / 2.0, 0.0)
    if palm.magnet_lift > highest + 1e-12:
        raise ParamError("palm.magnet_lift_mm", round(palm.magnet_lift / MM, 6),
                         f"must be <= {highest / MM:.3f} mm: the magnet pockets ({pocket / MM:.3f} mm) must keep a "
                         f"{MIN_WALL / MM:g} mm wall under the thinnest finger's dorsal face (thickness_mm = "
                         f"{thinnest / MM:g})", c.source)
    for n, f in fingers.items():
        if span + 2.0 * MIN_WALL > f.width + 1e-12:
            raise ParamError("hardware.magnet.diameter_mm", round(hardware.magnet_diameter / MM, 6),
                             f"two magnet pockets ({pocket / MM:.3f} mm each with magnet_clearance and "
                             f"hole_compensation), the palm.wall_mm between them and a {MIN_WALL / MM:g} mm wall "
                             f"outside each ({(span + 2.0 * MIN_WALL) / MM:.3f} mm) must fit across the "
                             f"fingers.{n} magnet face (width_mm = {f.width / MM:g})", c.source)
        if pocket >= f.thickness - 1e-12:
            raise ParamError("hardware.magnet.diameter_mm", round(hardware.magnet_diameter / MM, 6),
                             f"a magnet pocket ({pocket / MM:.3f} mm) must fit in the fingers.{n} magnet face "
                             f"(thickness_mm = {f.thickness / MM:g})", c.source)
        if tendon_z + relief / 2.0 > palm.magnet_lift - pocket / 2.0 + 1e-12:
            raise ParamError("hardware.magnet.diameter_mm", round(hardware.magnet_diameter / MM, 6),
                             f"the tendon enters the fingers.{n} base {-tendon_z / MM:.3f} mm below its centre "
                             f"(one palm.wall_mm above the thinnest finger's palmar face); its channel "
                             f"({relief / MM:.3f} mm) must pass below the magnet pockets ({pocket / MM:.3f} mm)",
                             c.source)
    if pocket + 2.0 * palm.wall > palm.thickness + 1e-12:
        raise ParamError("palm.thickness_mm", round(palm.thickness / MM, 6),
                         f"a finger socket holds a magnet pocket ({pocket / MM:.3f} mm) with a wall each side: "
                         f"must be >= {(pocket + 2.0 * palm.wall) / MM:.3f} mm", c.source)
    thickest = max(f.thickness for f in fingers.values())
    if palm.thickness <= thickest + 2.0 * printing.hole_clearance + 1e-12:
        raise ParamError("palm.thickness_mm", round(palm.thickness / MM, 6),
                         f"must exceed the thickest finger ({thickest / MM:g} mm) + 2 hole_clearance: the palm's "
                         "flexion limiter sits under each finger base", c.source)


def base_room(a: tuple[float, float, float], b: tuple[float, float, float], base_length: float) -> float:
    """Room between two neighbouring finger bases (``kinematics.dimensions.finger_columns`` a and b,
    m): the nearer of each magnet face (base_length behind its MCP) to the other's column
    centreline, where the face lies beside that column (behind its MCP); inf where neither does."""
    return min(_face_room(a, b, base_length), _face_room(b, a, base_length))


def _face_room(a: tuple[float, float, float], b: tuple[float, float, float], base_length: float) -> float:
    """Distance from the centre of finger a's magnet face (base_length behind its MCP) to finger
    b's column centreline, when that face lies beside b's column (behind b's MCP); inf if not."""
    ax, ay, pa = a
    bx, by, pb = b
    fx, fy = ax - base_length * math.sin(pa), ay - base_length * math.cos(pa)
    dx, dy = math.sin(pb), math.cos(pb)
    along = (fx - bx) * dx + (fy - by) * dy
    return abs((fx - bx) * dy - (fy - by) * dx) if along <= 0.0 else math.inf


def _guides(c, fingers, thumb, palm, hardware, printing, cad) -> None:
    names = list(fingers)
    metacarpals = [f.metacarpal for f in fingers.values()]
    cols = dict(zip(names, finger_columns(palm.finger_pitch, palm.arc_offset, metacarpals)))
    for a, b in zip(names, names[1:]):
        # adjacent finger bases converge toward the arc centre, and the stepped heads put one face
        # behind the other: each magnet face must clear the neighbour's column
        room = base_room(cols[a], cols[b], cad.finger_base_length)
        need = (fingers[a].width + fingers[b].width) / 2.0 + printing.hole_clearance
        if room < need - 1e-12:
            raise c.error("finger_base_length_mm", cad.finger_base_length / MM,
                          f"the {a} and {b} bases are {room / MM:.3f} mm apart at their magnet faces "
                          f"(palm.arc_offset_deg = {palm.arc_offset / DEG:g}), they need "
                          f"{need / MM:.3f} mm (half widths + hole_clearance)")
    for n, f in fingers.items():
        # the magnet pockets, a wall and the MCP loop hub's groove fit between the base's magnet face
        # and the MCP axis
        ceiling = finger_base_thickness_ceiling(cad.finger_base_length, hardware.magnet_thickness,
                                                printing.magnet_clearance, MIN_WALL)
        if f.thickness > ceiling + 1e-12:
            base_need = cad.finger_base_length + (f.thickness - ceiling) / 2.0
            raise c.error("finger_base_length_mm", cad.finger_base_length / MM,
                          f"must be >= {base_need / MM:.3f} mm (fingers.{n}: the magnet pockets (magnet "
                          f"thickness + clearance), a wall of {MIN_WALL / MM:g} mm and the MCP loop hub's groove "
                          f"({HUB_GROOVE_PAST_BOSS / MM:g} mm past the boss, half the thickness))")
    for n, f in fingers.items():
        # the MCP clevis in the finger base: its slot (and, past 90 degrees of the module's stop,
        # its recess of half a thickness) leaves a wall before the magnet face
        q_stop = f.chain.limits[0][1] + cad.module_stop_margin
        need = f.thickness / 2.0 + printing.hole_clearance + palm.wall
        if q_stop > math.pi / 2.0:
            need += f.thickness / 2.0
        if cad.finger_base_length < need - 1e-12:
            raise ParamError(f"fingers.{n}.limits_rad.mcp", [round(v, 6) for v in f.chain.limits[0]],
                             f"with cad.module_stop_margin_deg the MCP clevis stops at {q_stop / DEG:.2f} deg; its slot"
                             f"{' and recess (past 90 degrees)' if q_stop > math.pi / 2.0 else ''} need "
                             f"{need / MM:.3f} mm of the finger base (cad.finger_base_length_mm = "
                             f"{cad.finger_base_length / MM:g})", c.source)
    for name, d in _digits(fingers, thumb):
        # the phalanx-side guide eyelet lies inside the phalanx: above its palmar face
        g = d.chain.guide
        depth = g.d2 * math.cos(g.alpha / 2.0)
        room = d.thickness / 2.0 - (hardware.tendon_diameter / 2.0 + printing.hole_clearance)
        if depth > room + 1e-12:
            raise ParamError(f"{name}.guide.d2_mm", round(g.d2 / MM, 6),
                             f"puts the phalanx guide eyelet {depth / MM:.3f} mm below the joint axis "
                             f"(d2 cos(alpha / 2)); its hole must stay inside the phalanx's palmar face "
                             f"(<= {room / MM:.3f} mm: half the thickness - half the tendon hole)", c.source)
        # the phalanx-side guide eyelet must lie outside the joint's pulley boss
        need = d.thickness / 2.0 + printing.hole_clearance + cad.eyelet_length / 2.0
        if g.d2 < need - 1e-12:
            raise ParamError(f"{name}.guide.d2_mm", round(g.d2 / MM, 6),
                             f"must be >= {need / MM:.3f} mm (half the thickness + hole_clearance + half "
                             "cad.eyelet_length): the phalanx guide eyelet must clear the joint boss", c.source)
    r_hole = hardware.tendon_diameter / 2.0 + printing.hole_clearance

    def reach(g):
        """How far behind its joint axis the metacarpal-side eyelet and its relief reach."""
        return g.d1 * math.sin(g.alpha / 2.0) + cad.eyelet_length / 2.0 + (math.sqrt(3.0) + 2.0) * r_hole

    for n, f in fingers.items():
        # the metacarpal-side guide eyelet (and its relief) must fit inside the finger base
        g = f.chain.guide
        if reach(g) > cad.finger_base_length + 1e-12:
            raise ParamError(f"fingers.{n}.guide.d1_mm", round(g.d1 / MM, 6),
                             f"puts the guide eyelet {reach(g) / MM:.3f} mm behind the MCP axis, beyond the finger "
                             f"base's magnet face (cad.finger_base_length_mm = {cad.finger_base_length / MM:g})",
                             c.source)
    for name, d in _digits(fingers, thumb):
        # the metacarpal-side guide eyelet hangs below its metacarpal: its boss (the relief plus half a
        # wall around it) must still reach into the palmar face, so the eyelet's relief (radius
        # 2 r_hole) may lie at most half a thickness + 2 r_hole below the joint axis
        g = d.chain.guide
        depth = g.d1 * math.cos(g.alpha / 2.0)
        room = d.thickness / 2.0 + 2.0 * r_hole
        if depth > room + 1e-12:
            raise ParamError(f"{name}.guide.d1_mm", round(g.d1 / MM, 6),
                             f"puts the metacarpal-side guide eyelet {depth / MM:.3f} mm below the joint axis "
                             f"(d1 cos(alpha / 2)); its boss must join the metacarpal's palmar face "
                             f"(<= {room / MM:.3f} mm: half the thickness + the eyelet's relief radius)", c.source)
    # the thumb's metacarpal-side eyelet (and its relief) lies on the arm, in front of the CMC hub
    g = thumb.chain.guide
    arm = thumb.metacarpal - thumb.width / 2.0
    if reach(g) > arm + 1e-12:
        raise ParamError("thumb.guide.d1_mm", round(g.d1 / MM, 6),
                         f"puts the guide eyelet {reach(g) / MM:.3f} mm behind the MP axis, into the CMC hub: the "
                         f"arm between the hub (half thumb.width_mm = {thumb.width / 2.0 / MM:g}) and "
                         f"the MP axis is {arm / MM:.3f} mm long", c.source)


def _servos(c, fingers, thumb, servo, hardware, printing, cad) -> None:
    pulleys = [(name, d.chain.servo_radius) for name, d in _digits(fingers, thumb)]
    screw_hole = printed_hole(hardware.screw_diameter + 2.0 * printing.hole_clearance, printing.hole_compensation)
    for name, r in pulleys + [("thumb.cmc", thumb.cmc_pulley_radius)]:
        limit = r - screw_hole / 2.0 - hardware.tendon_diameter
        if cad.horn_hole_radius > limit + 1e-12:
            raise c.error("horn_hole_radius_mm", cad.horn_hole_radius / MM,
                          f"must be <= {limit / MM:.3f} mm so the horn screws stay inside the "
                          f"{name} pulley radius {r / MM:g} mm")
    if cad.servo_ear_offset + cad.servo_ear_thickness >= servo.body[2] - 1e-12:
        raise c.error("servo_ear_offset_mm", cad.servo_ear_offset / MM,
                      f"with servo_ear_thickness_mm = {cad.servo_ear_thickness / MM:g} the ears must lie on the "
                      f"servo body (height servo.body_mm[2] = {servo.body[2] / MM:g})")
    # each flange ear's screw pilot (mid-ear, kinematics.dimensions.servo_screw_offset) keeps a wall
    # to the body's pocket: a pilot breaking into the pocket is no blind hole and holds no thread
    pilot = printed_hole(printing.screw_pilot_ratio * hardware.screw_diameter, printing.hole_compensation)
    L, span = servo.body[0], servo.flange_span
    if servo_pilot_wall(L, span, pilot, printing.hole_clearance) < MIN_WALL - 1e-12:
        longest = span - 4.0 * (pilot / 2.0 + printing.hole_clearance + MIN_WALL)
        raise ParamError("servo.body_mm", [round(v / MM, 6) for v in servo.body],
                         f"a body {L / MM:g} mm long leaves the flange ears (servo.flange_span_mm = {span / MM:g}) "
                         f"too short for their screw pilots ({pilot / MM:.3f} mm, mid-ear, with "
                         f"hole_compensation) and a {MIN_WALL / MM:g} mm wall to the body's pocket: the length "
                         f"must be <= {longest / MM:.3f} mm", c.source)
    if cad.servo_shaft_offset >= servo.body[0] / 2.0:
        raise c.error("servo_shaft_offset_mm", cad.servo_shaft_offset / MM,
                      f"must be < half the servo body length ({servo.body[0] / 2.0 / MM:g} mm)")
