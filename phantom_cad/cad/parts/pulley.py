"""Servo pulleys (tendon hubs) and the thumb CMC hub.

Frame (docs/frames.md, servo frame): origin on the servo output axis at the pulley's
mid-plane, z along the shaft from the servo body toward the pulley.

Tendon servos (u1-u5): a grooved pulley whose groove bottom radius is the chain's
servo pulley radius r_j (eq. 5: L = L0 - r_j u_j), a tendon anchor (radial hole from the
groove into an axial knot well) and the horn interface: a central clearance bore for the
spline screw and two horn screw holes on the cad.horn_hole_radius circle.
The direct-drive servo (u6, thumb CMC): a hub of radius thumb.cmc_horn_radius, coaxial with the
CMC axis, with the same horn interface plus two pilot holes for the screws that come
through the thumb CMC base.
"""

from __future__ import annotations

import math

import numpy as np

from ... import canon

from ...kinematics import frames
from ...kinematics.topology import N_SERVOS, SERVOS, link
from ..measure import coaxial, cylinders, measure_groove_radius
from .base import Part, digit_table
from .common import Tolerances, build, cylinder, mm

#: angular positions (rad) of the holes on the horn circle
HORN_ANGLES = (math.pi / 4.0, 5.0 * math.pi / 4.0)        # horn screws (through the pulley into the horn)
BASE_ANGLES = (3.0 * math.pi / 4.0, 7.0 * math.pi / 4.0)  # CMC base screws (into the servo-6 hub)
#: a drive pulley's horn screws, before the turn that puts its anchor (cut on +y) at the clamp:
#: on x, square to the anchor (on it, as at 45/225 deg, they would cut the knot well)
DRIVE_HORN_ANGLES = (0.0, math.pi)


class ServoPulley(Part):
    """The pulley (tendon servo) or hub (direct drive) on servo ``servo`` (0-based index in
    u order, topology.SERVOS)."""

    SEGMENTS = ("servo_pulley",)
    COLOR = (0.20, 0.20, 0.22)

    def __init__(self, params, servo: int):
        if servo not in range(N_SERVOS):
            raise ValueError(f"servo must be 0..{N_SERVOS - 1} (u1..u{N_SERVOS}), got {servo!r}")
        self.params, self.servo = params, SERVOS[servo]
        self.link = link(self.servo.link)
        self.tol = Tolerances(params)
        self.width = mm(params.cad.servo_pulley_width)
        self.horn_radius = mm(params.cad.horn_hole_radius)
        self.radius = mm(frames.servo_radius(params, servo))

    @classmethod
    def for_link(cls, params, link):
        return cls(params, link.servo)

    @property
    def is_hub(self) -> bool:
        return self.servo.drive == "direct"

    @property
    def print_rotation(self) -> np.ndarray:
        return np.eye(3)                           # on a flange face

    def inputs(self) -> dict:
        doc = self.params.document
        if self.is_hub:
            src = {"cmc_horn_radius_mm": doc["thumb"]["cmc_horn_radius_mm"]}
        else:
            # the radius, and the travel that places the drive's clamp (routing.servo_clamp_wrap)
            table = digit_table(doc, self.servo.digit)
            src = {k: canon.plain(table[k]) for k in ("servo_pulley_radius_mm", "servo_travel_deg")}
        return {**self.common_inputs(), "servo": self.servo.label, **src}

    def verify(self, shape) -> list[str]:
        """The hub radius (direct drive) or the groove bottom radius r_j about the shaft."""
        out: list[str] = []
        if self.is_hub:
            cs = [c for c in cylinders(shape) if coaxial(c, (0, 0, 0), (0, 0, 1))]
            self.expect(out, "hub radius", max((c["radius"] for c in cs), default=None), self.radius)
        else:
            try:
                r = measure_groove_radius(shape, (0, 0, 0), (0, 0, 1), self.tol.tendon_hole)
            except ValueError:
                r = None
            self.expect(out, "groove radius", r, self.groove_floor)
        return out

    @property
    def groove_floor(self) -> float:
        """Radius of the groove's floor: half a tendon inside r_j, so the tendon's centreline runs
        at r_j (the moment arm of eq. 5)."""
        return self.radius - self.tol.tendon / 2.0

    @property
    def anchor_angle(self) -> float:
        """Polar angle (rad, pulley frame at u = 0, right hand) of the drive's clamp: where the
        routing model anchors it (``routing.servo_clamp_wrap``: every wrap inside the travel)."""
        from ...kinematics import routing
        clamp = next(st.elements[0] for r in routing.routes(self.params, right_handed=True)
                     if r.tendon.kind == "drive" and r.tendon.servo == self.servo.index for st in r.strands)
        return math.atan2(clamp.pos[1], clamp.pos[0])

    @property
    def lip(self) -> float:
        """Groove depth: the flanges stand two tendon diameters above the groove bottom."""
        return mm(frames.servo_pulley_lip(self.params))

    @property
    def outer_radius(self) -> float:
        return self.radius if self.is_hub else self.radius + self.lip

    def _holes(self, angles, d):
        h = self.width / 2.0 + 1.0
        return [cylinder((self.horn_radius * math.cos(a), self.horn_radius * math.sin(a), -h),
                         (self.horn_radius * math.cos(a), self.horn_radius * math.sin(a), h), d / 2.0)
                for a in angles]

    def build(self):
        t = self.tol
        w = self.width
        body = [cylinder((0, 0, -w / 2.0), (0, 0, w / 2.0), self.outer_radius)]
        tools = [cylinder((0, 0, -w / 2.0 - 1.0), (0, 0, w / 2.0 + 1.0), t.screw_clear / 2.0)]
        if self.is_hub:
            tools += self._holes(HORN_ANGLES, t.screw_clear)
            tools += self._holes(BASE_ANGLES, t.screw_pilot)
            return build(body, tools)
        # a drive pulley is cut with its anchor on +y and then turned to the clamp angle: cut in
        # place, the groove floor's face (its seam on +x, the anchor hole at -135 deg) came out of
        # a mirror for the left hand unorientable (BRepCheck), so the part was invalid
        tools += self._holes(DRIVE_HORN_ANGLES, t.screw_clear)
        groove_w = t.tendon_hole
        outer = cylinder((0, 0, -groove_w / 2.0), (0, 0, groove_w / 2.0), self.outer_radius + 1.0)
        inner = cylinder((0, 0, -groove_w / 2.0 - 1.0), (0, 0, groove_w / 2.0 + 1.0), self.groove_floor)
        tools.append(outer.cut(inner))
        d = np.array([0.0, 1.0, 0.0])
        tools.append(cylinder(d * self.horn_radius, d * (self.radius + 0.5), t.tendon_hole / 2.0))
        tools += [cylinder(d * self.horn_radius - np.array([0, 0, w / 2.0 + 1.0]),
                           d * self.horn_radius + np.array([0, 0, w / 2.0 + 1.0]), t.tendon_relief / 2.0)]
        from build123d import Axis
        return build(body, tools).rotate(Axis.Z, math.degrees(self.anchor_angle) - 90.0)
