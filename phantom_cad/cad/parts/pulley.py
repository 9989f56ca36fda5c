"""Servo pulleys (tendon hubs) and the thumb CMC hub.

Frame (docs/frames.md, servo frame): origin on the servo output axis at the pulley's
mid-plane, z along the shaft from the servo body toward the pulley.

Servos 1-5 (tendon servos): a grooved pulley whose groove bottom radius is the chain's
servo pulley radius r_j (eq. 5: L = L0 - r_j u_j), a tendon anchor (radial hole from the
groove into an axial knot well) and the horn interface: a central clearance bore for the
spline screw and two horn screw holes on the cad.horn_hole_radius circle.
Servo 6 (thumb CMC, direct drive): a hub of radius thumb.cmc_horn_radius, coaxial with the
CMC axis, with the same horn interface plus two pilot holes for the screws that come
through the thumb CMC base.
"""

from __future__ import annotations

import math

import numpy as np

from ...kinematics import frames
from .common import Tolerances, build, cylinder, mm

#: angular positions (rad) of the holes on the horn circle
HORN_ANGLES = (math.pi / 4.0, 5.0 * math.pi / 4.0)        # horn screws (through the pulley into the horn)
BASE_ANGLES = (3.0 * math.pi / 4.0, 7.0 * math.pi / 4.0)  # CMC base screws (into the servo-6 hub)
ANCHOR_ANGLE = math.pi / 2.0                              # tendon anchor


class ServoPulley:
    def __init__(self, params, servo: int):
        """``servo`` is 1-based, as in the paper (u1..u6)."""
        if servo not in range(1, 7):
            raise ValueError(f"servo must be 1..6, got {servo!r}")
        self.params, self.servo = params, servo
        self.tol = Tolerances(params)
        self.width = mm(params.cad.servo_pulley_width)
        self.horn_radius = mm(params.cad.horn_hole_radius)
        if servo == 6:
            self.radius = mm(params.thumb.cmc_horn_radius)
        else:
            self.radius = mm(params.chains[servo - 1].servo_radius)

    @property
    def name(self) -> str:
        return f"servo_pulley_{self.servo}"

    @property
    def is_hub(self) -> bool:
        return self.servo == 6

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
        tools += self._holes(HORN_ANGLES, t.screw_clear)
        if self.is_hub:
            tools += self._holes(BASE_ANGLES, t.screw_pilot)
        else:
            groove_w = t.tendon_hole
            outer = cylinder((0, 0, -groove_w / 2.0), (0, 0, groove_w / 2.0), self.outer_radius + 1.0)
            inner = cylinder((0, 0, -groove_w / 2.0 - 1.0), (0, 0, groove_w / 2.0 + 1.0), self.radius)
            tools.append(outer.cut(inner))
            a = ANCHOR_ANGLE
            d = np.array([math.cos(a), math.sin(a), 0.0])
            tools.append(cylinder(d * self.horn_radius, d * (self.radius + 0.5), t.tendon_hole / 2.0))
            tools += [cylinder(d * self.horn_radius - np.array([0, 0, w / 2.0 + 1.0]),
                               d * self.horn_radius + np.array([0, 0, w / 2.0 + 1.0]), t.tendon_relief / 2.0)]
        return build(body, tools, self.name)
