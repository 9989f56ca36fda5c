"""Servo pulleys and the CMC pulley.

Frame (docs/frames.md, servo frame): origin on the servo output axis at the pulley's
mid-plane, z along the shaft from the servo body toward the pulley.

Every servo (u1-u6): a grooved pulley whose groove bottom radius is the chain's servo pulley
radius r_j (eq. 5: L = L0 - r_j u_j; servo 6: the CMC loop's r6), an anchor (radial hole from the
groove into an axial knot well: a drive's clamp, or each of the CMC loop's two strands' clamps)
and the horn interface: a central clearance bore for the spline screw and two horn screw holes on
the cad.horn_hole_radius circle.

The CMC pulley (link ``thumb_cmc_pulley``, frame ``thenar.T_cmc_base_pulley``): the same groove
radius r6 / cmc_gain and width, the loop's two clamps, and a keyed bore on the CMC base's column.
"""

from __future__ import annotations

import math

import numpy as np

from ... import canon, units

from ...kinematics.dimensions import digit_entry
from ...kinematics import frames
from ...kinematics.hand_params import HandParams
from ...kinematics.topology import CMC_PULLEY, N_SERVOS, SERVOS, link
from ..measure import measure_groove_radius
from .base import Part
from .common import Tolerances, box, build, cylinder, mm


#: a drive pulley's horn screws, before the turn that puts its anchor (cut on +y) at the clamp:
#: on x, square to the anchor (on it, as at 45/225 deg, they would cut the knot well)
DRIVE_HORN_ANGLES = (0.0, math.pi)


def _anchor_angles(params: HandParams, link_name: str) -> tuple[float, ...]:
    """Polar angles (rad, the link's frame at rest, right hand) of the clamps the routing model puts
    on a pulley link: a drive's (``routing_rules.servo_clamp_wrap``: every wrap inside the travel) or
    the CMC loop's two (``routing_rules.cmc_loop_clamps``)."""
    from ...kinematics import routing
    clamps = [e for r in routing.routes(params, right_handed=True) for st in r.strands for e in st.elements
              if isinstance(e, routing.Point) and e.role == "clamp" and e.link == link_name]
    return tuple(math.atan2(c.pos[1], c.pos[0]) for c in clamps)


class GroovedPulley(Part):
    """A pulley with a tendon groove of radius ``radius`` (mm: the tendon's centreline, the moment
    arm), flanges a lip above it, an anchor (radial hole into an axial knot well) at each of the
    link's clamps, cut about +y and turned there (their bisector on the clamps' bisector);
    subclasses give the bore."""

    SEGMENTS: tuple[str, ...] = ()
    COLOR = (0.20, 0.20, 0.22)

    @property
    def print_rotation(self) -> np.ndarray:
        return np.eye(3)                           # on a flange face

    @property
    def groove_floor(self) -> float:
        """Radius of the groove's floor: half a tendon inside r_j, so the tendon's centreline runs
        at r_j (the moment arm of eq. 5)."""
        return self.radius - self.tol.tendon / 2.0

    @property
    def anchor_angles(self) -> tuple[float, ...]:
        """Polar angles (rad, pulley frame at rest, right hand) of the clamps (``_anchor_angles``)."""
        return _anchor_angles(self.params, self.link.name)

    @property
    def anchor_angle(self) -> float:
        """The clamps' bisector (rad): the part is cut with it on +y and turned there."""
        a = self.anchor_angles
        return math.atan2(sum(math.sin(v) for v in a), sum(math.cos(v) for v in a))

    @property
    def lip(self) -> float:
        """Groove depth: the flanges stand two tendon diameters above the groove bottom."""
        return mm(frames.servo_pulley_lip(self.params))

    @property
    def outer_radius(self) -> float:
        return self.radius + self.lip

    @property
    def well_radius(self) -> float:
        """The axial knot well's radius, on the anchor's line (mm)."""
        return mm(self.params.cad.horn_hole_radius)

    def verify(self, shape) -> list[str]:
        """The groove bottom radius r about the pulley's axis."""
        out: list[str] = []
        try:
            r = measure_groove_radius(shape, (0, 0, 0), (0, 0, 1), self.tol.tendon_hole)
        except ValueError:
            r = None
        self.expect(out, "groove radius", r, self.groove_floor)
        return out

    def bore_tools(self) -> list:
        raise NotImplementedError

    def build(self):
        t = self.tol
        w = self.width
        body = [cylinder((0, 0, -w / 2.0), (0, 0, w / 2.0), self.outer_radius)]
        # cut with its anchor on +y and then turned to the clamp angle: cut in place, the groove
        # floor's face (its seam on +x, the anchor hole at -135 deg) came out of a mirror for the
        # left hand unorientable (BRepCheck), so the part was invalid
        tools = self.bore_tools()
        groove_w = t.tendon_hole
        outer = cylinder((0, 0, -groove_w / 2.0), (0, 0, groove_w / 2.0), self.outer_radius + 1.0)
        inner = cylinder((0, 0, -groove_w / 2.0 - 1.0), (0, 0, groove_w / 2.0 + 1.0), self.groove_floor)
        tools.append(outer.cut(inner))
        bis = self.anchor_angle
        for a in self.anchor_angles:
            rel = math.pi / 2.0 + a - bis
            d = np.array([math.cos(rel), math.sin(rel), 0.0])
            tools.append(cylinder(d * self.well_radius, d * (self.radius + 0.5), t.tendon_hole / 2.0))
            tools += [cylinder(d * self.well_radius - np.array([0, 0, w / 2.0 + 1.0]),
                               d * self.well_radius + np.array([0, 0, w / 2.0 + 1.0]), t.tendon_relief / 2.0)]
        from build123d import Axis
        return build(body, tools).rotate(Axis.Z, units.deg(self.anchor_angle) - 90.0)


class ServoPulley(GroovedPulley):
    """The pulley on servo ``servo`` (0-based index in u order, topology.SERVOS): a drive's, or the
    CMC loop's on servo 6."""

    SEGMENTS = ("servo_pulley",)

    def __init__(self, params: HandParams, servo: int):
        if servo not in range(N_SERVOS):
            raise ValueError(f"servo must be 0..{N_SERVOS - 1} ({SERVOS[0].label}..{SERVOS[-1].label}), got {servo!r}")
        self.params, self.servo = params, SERVOS[servo]
        self.link = link(self.servo.link)
        self.tol = Tolerances(params)
        self.width = mm(params.cad.servo_pulley_width)
        self.horn_radius = mm(params.cad.horn_hole_radius)
        self.radius = mm(frames.servo_radius(params, servo))

    @classmethod
    def for_link(cls, params: HandParams, link):
        return cls(params, link.servo)

    def inputs(self) -> dict:
        doc = self.params.document
        if self.servo.drive == "loop":
            # the loop's clamp depends on the CMC travel only
            th = doc["thumb"]
            src = {k: canon.plain(th[k]) for k in ("cmc_pulley_radius_mm", "cmc_servo_travel_deg", "cmc_gain")}
        else:
            # the radius, and the travel that places the drive's clamp (routing_rules.servo_clamp_wrap)
            table = digit_entry(doc, self.servo.digit)
            src = {k: canon.plain(table[k]) for k in ("servo_pulley_radius_mm", "servo_travel_deg")}
        return {**self.common_inputs(), "servo": self.servo.label, **src}

    def bore_tools(self) -> list:
        """The spline screw's clearance bore and the two horn screws' holes (on x, square to the
        anchor: on it, as at 45/225 deg, they would cut the knot well)."""
        t, w = self.tol, self.width
        out = [cylinder((0, 0, -w / 2.0 - 1.0), (0, 0, w / 2.0 + 1.0), t.screw_clear / 2.0)]
        h = w / 2.0 + 1.0
        for a in DRIVE_HORN_ANGLES:
            c = (self.horn_radius * math.cos(a), self.horn_radius * math.sin(a))
            out.append(cylinder((c[0], c[1], -h), (c[0], c[1], h), t.screw_clear / 2.0))
        return out


class CMCPulley(GroovedPulley):
    """The CMC pulley: on the CMC base's column inside the palm, turned by servo 6's loop (equal
    radii: q15 = u6); its bore is the column's keyed end (``thumb.KEY_DEPTH``): the flats touch, the
    round is a clearance fit (a drop of glue holds it)."""

    SEGMENTS = ("cmc_pulley",)

    def __init__(self, params: HandParams):
        self.params = params
        self.link = link(CMC_PULLEY)
        self.tol = Tolerances(params)
        self.width = mm(params.cad.servo_pulley_width)
        self.radius = mm(frames.cmc_pulley_radius(params))
        self.column_radius = mm(params.cad.cmc_column_radius)

    @classmethod
    def for_link(cls, params: HandParams, link):
        return cls(params)

    def inputs(self) -> dict:
        """The loop's clamp lies where the strands from servo 6 arrive: the whole hand but its
        mechanics places it (the servo row, the CMC placement)."""
        return self.whole_hand_inputs()

    @property
    def well_radius(self) -> float:
        """The knot well between the bore and the groove floor."""
        return (self.column_radius + self.tol.clearance + self.groove_floor) / 2.0

    def bore_tools(self) -> list:
        """The keyed bore: the column's round with a hole clearance (compensated) cut by the key's
        flat on +y, touching the column's, in the pulley frame before the turn to the clamp angle (so
        the flat is turned back to +y)."""
        from .thumb import KEY_DEPTH
        t, w = self.tol, self.width
        r = t.hole(2.0 * (self.column_radius + t.clearance)) / 2.0
        bore = cylinder((0, 0, -w / 2.0 - 1.0), (0, 0, w / 2.0 + 1.0), r)
        flat = box(-r - 1.0, r + 1.0, self.column_radius - KEY_DEPTH, r + 1.0, -w / 2.0 - 2.0, w / 2.0 + 2.0)
        from build123d import Axis
        return [bore.cut(flat).rotate(Axis.Z, 90.0 - units.deg(self.anchor_angle))]
