"""Thumb CMC base: the thumb's metacarpal module, turned about the CMC axis by servo 6.

Frame: origin on the CMC axis (the frame's z, coaxial with servo 6's output), y along the
thumb metacarpal to the MP axis at y = thumb.metacarpal, z toward the thumb's dorsal side
(docs/frames.md). Features: a hub of radius thumb.cmc_horn_radius that sits on servo
pulley 6 with four clearance holes on the horn circle (two for the screws into the hub,
two for access to the horn screws) and the spline-screw bore; the metacarpal arm; the MP
clevis (axle press bore, extension and flexion stops at the MP limit); the
metacarpal-side MP guide eyelet at d1_th; the tendon path from the hub to the eyelet; the
anchors of the two cable springs. The thumb phalanges are phalanx.Phalanx("thumb", ...).
"""

from __future__ import annotations

import math

import numpy as np

from ... import canon
from ...kinematics.topology import CMC_Q, JOINTS, link
from ..measure import eyelet_centres, point_line_distance
from .base import DORSAL_DOWN, Part, child_joint, digit_table
from .common import DigitSection, box, build, cylinder, mm, prism_x, sphere
from .phalanx import NEAR_RELIEF_RUN, clevis, eyelet, hub_grooves
from .tendons import link_tendons, anchor_tools, channel_tools, drive_fan_tools, guide_entry, verify_grooves
from .pulley import BASE_ANGLES, HORN_ANGLES


class ThumbCMCBase(Part):
    """The thumb's metacarpal module: the link the CMC joint turns (its parent joint is the
    CMC, direct drive by the CMC servo)."""

    SEGMENTS = ("cmc_base",)

    def __init__(self, params):
        self.params = params
        self.link = link(JOINTS[CMC_Q].child)
        self.sec = DigitSection(params, self.link.digit)
        self.length = mm(getattr(params.digit(self.link.digit), self.link.length_key))
        self.hub_radius = mm(params.thumb.cmc_horn_radius)
        self.horn_radius = mm(params.cad.horn_hole_radius)
        #: the joint at its distal end (the thumb MP): its clevis
        self.joint = child_joint(self.link).key
        if self.length <= self.hub_radius + self.sec.slot_back:
            raise ValueError(f"thumb metacarpal {self.length:.2f} mm leaves no arm between the CMC hub "
                             f"(radius {self.hub_radius:g} mm) and the {self.joint.upper()} clevis")

    @classmethod
    def for_link(cls, params, link):
        return cls(params)

    def inputs(self) -> dict:
        return {**self.common_inputs(), "thumb": canon.plain(digit_table(self.params.document, self.digit))}

    def verify(self, shape) -> list[str]:
        """The metacarpal-side guide eyelet at d1 from the MP axis (at y = metacarpal)."""
        out: list[str] = []
        tol = self.sec.tol
        verify_grooves(self, shape, link_tendons(self.params, self.link.name), out)
        eyes = eyelet_centres(shape, tol.tendon_hole / 2.0, tol.eyelet_length)
        d = (point_line_distance(eyes[0]["centre"], (0, self.length, 0), (1, 0, 0)) if len(eyes) == 1
             else None)
        self.expect(out, "guide d1", d, mm(self.sec.guide.d1), 0.02)
        return out

    def guide_point(self) -> np.ndarray:
        """The metacarpal-side MP guide (x, y, z) in this part's frame."""
        G1, _ = self.sec.guide_points()
        return np.array([0.0, self.length + G1[0], G1[1]])

    @property
    def print_rotation(self) -> np.ndarray:
        """On its dorsal face, as the phalanges (``export.orient`` measures it)."""
        return DORSAL_DOWN

    def build(self):
        sec, t = self.sec, self.sec.tol
        W, T, L = sec.width, sec.thickness, self.length
        body = [cylinder((0, 0, -T / 2.0), (0, 0, T / 2.0), self.hub_radius),
                box(-W / 2.0, W / 2.0, 0.0, L, -T / 2.0, T / 2.0)]
        lt = link_tendons(self.params, self.link.name)
        b, tools = clevis(sec, self.joint, L, lt.hubs().get(child_joint(self.link).name))
        body += b
        tools += hub_grooves(sec, lt)
        G1, G2 = sec.guide_points()
        shift = np.array([L, 0.0])
        b3, guide, u, (s_near, s_far) = eyelet(sec, G1 + shift, lt.eyelet_toward(G1 + shift))
        body += b3
        guide += drive_fan_tools(lt, sec, float(np.linalg.norm(s_near - np.array([0.0, *(G1 + shift)]))))
        # the near relief leaves through the clevis slot's back along the chord at rest, as on the
        # finger bases
        guide.append(cylinder(s_near, s_near + NEAR_RELIEF_RUN * u, t.tendon_relief / 2.0))
        # the tendon comes down the CMC axis (through the hub's central bore, from the palm's
        # arch above) and turns along the arm to the eyelet: CMC rotation leaves its length alone.
        # The turn is rounded by a sphere one tendon radius wider than the bore (a sphere as wide
        # as the bore would touch it along a circle, and the arm channel through that circle
        # leaves edges 1e-5 mm long that tessellate with holes)
        turn = np.array([0.0, 0.0, s_far[2]])
        guide.append(sphere(turn, max(t.tendon_relief / 2.0 + t.clearance,
                                      t.screw_clear / 2.0 + t.tendon_hole / 2.0)))
        end = guide_entry(turn, np.array([0.0, *(G1 + shift)]), s_far)
        guide.append(cylinder(turn, end, t.tendon_hole / 2.0))
        # the arm channel runs half a tendon hole above the palmar face (the MP guide sits 0.4 mm
        # inside it): a skin of 0.06 mm would stay under it, so the channel is a slot open to the
        # face, and on through the eyelet's boss where that hangs below the face (0.44 mm was left)
        r = t.tendon_hole / 2.0
        floor = -T / 2.0 - 2.0 * sec.eyelet_boss_radius - 1.0
        guide.append(prism_x([(turn[1], turn[2]), (end[1], end[2]), (end[1], floor), (turn[1], floor)], -r, r))
        # hub: spline-screw bore and the four holes on the horn circle
        h = T / 2.0 + 1.0
        tools.append(cylinder((0, 0, -h), (0, 0, h), t.screw_clear / 2.0))
        for a in HORN_ANGLES + BASE_ANGLES:
            c = self.horn_radius * np.array([math.cos(a), math.sin(a), 0.0])
            tools.append(cylinder(c - (0, 0, h), c + (0, 0, h), t.screw_clear / 2.0))
        return build(body, tools, guide, channel_tools(lt, up=self.print_up) + anchor_tools(lt, sec, self.print_up))
