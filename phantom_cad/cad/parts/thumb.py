"""Thumb CMC base: the thumb's metacarpal module, turned about the CMC axis by servo 6's loop.

Frame: origin on the CMC axis (the frame's z), y along the thumb metacarpal to the MP axis at
y = thumb.metacarpal, z toward the thumb's dorsal side (docs/frames.md). Features: a hub of half
the thumb's width round the axis; the column (radius cad.cmc_column_radius) up the axis into the
palm's journal, hollow for the drive, its end keyed by a flat for the CMC pulley
(``pulley.CMCPulley``);
the metacarpal arm; the MP clevis (axle press bore, extension and flexion stops at the MP limit);
the metacarpal-side MP guide eyelet at d1_th; the drive's path down the column and along the arm
to the eyelet; the anchors of the two cable springs; a palmar pad under the hub and the arm, as
deep as the eyelet's boss reaches below the palmar face, so the part prints on that face
(``PALMAR_DOWN``: the MP axis flat, its hub groove bridged, the column upright). The thumb phalanges are
phalanx.Phalanx("thumb", ...).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ... import canon
from ... import units
from ...kinematics import frames as F
from ...kinematics import routing
from ...kinematics import thenar as TH
from ...kinematics.dimensions import digit_entry
from ...kinematics.hand_params import HandParams
from ...kinematics.topology import CMC_Q, JOINTS, link
from ..measure import eyelet_centres, point_line_distance
from .base import PALMAR_DOWN, Part, child_joint
from .common import DigitSection, box, build, cylinder, cylinder_floor, mm, prism_x, sphere, transform
from .phalanx import (clevis, eyelet, eyelet_boss_axis, hub_grooves, keel_body, near_relief, relief_opening,
                      stop_wedge)
from .drive_fans import drive_fan_tools, guide_entry
from .tendons import RoutedPart, link_tendons, anchor_tools, channel_tools


#: depth (mm) of the flat that keys the column's end to the CMC pulley [choice]
KEY_DEPTH = 1.0


class ThumbCMCBase(RoutedPart, Part):
    """The thumb's metacarpal module: the link the CMC joint turns (its parent joint is the
    CMC, direct drive by the CMC servo)."""

    SEGMENTS = ("cmc_base",)

    def __init__(self, params: HandParams):
        self.params = params
        self.link = link(JOINTS[CMC_Q].child)
        self.sec = DigitSection(params, self.link.digit)
        self.length = mm(getattr(params.digit(self.link.digit), self.link.length_key))
        self.hub_radius = mm(params.thumb.width) / 2.0
        #: the column and the CMC pulley (thenar.thenar, mm along the axis)
        self.thenar = {k: mm(v) for k, v in TH.thenar(params).items()}
        #: the joint at its distal end (the thumb MP): its clevis
        self.joint = child_joint(self.link).key
        #: the MP side's turn (mm): a twisted thumb's arm, MP clevis, guide and their channels are
        #: cut in the MP's frame before the twist (``tendons.link_tendons`` reads them there) and
        #: turned with it about the metacarpal's length; the hub and the column stay
        self.turn = np.eye(4)
        turned = routing.mp_turn(params)
        if turned is not None:
            _, R, o = turned
            o = np.asarray(units.mm(o), float)
            self.turn[:3, :3], self.turn[:3, 3] = R, o - R @ o
        if self.length <= self.hub_radius + self.sec.slot_back:
            raise ValueError(f"thumb metacarpal {self.length:.2f} mm leaves no arm between the CMC hub "
                             f"(radius {self.hub_radius:g} mm) and the {self.joint.upper()} clevis")

    @classmethod
    def for_link(cls, params: HandParams, link):
        return cls(params)

    def inputs(self) -> dict:
        """The thumb's table and the palm's (its thickness and the CMC placement set the column's
        length, ``thenar.thenar``)."""
        doc = self.params.document
        return {**self.common_inputs(), "thumb": canon.plain(digit_entry(doc, self.digit)),
                "palm": canon.plain(doc["palm"])}

    def guide_boss(self) -> tuple[np.ndarray, np.ndarray]:
        """The metacarpal-side MP guide: (its centre (y, z), the point its hole points to), mm."""
        G1 = self.guide_point()[1:]
        return G1, link_tendons(self.params, self.link.name).eyelet_toward(G1)

    @property
    def flat_floor(self) -> float:
        """z (mm) of the MP side's palmar face in the MP's frame before any twist: the palmar face
        (-thickness / 2), or lower, as low as the MP guide's boss reaches below it (the MP guide
        sits inside the palmar face, its boss does not); the pad fills the arm down to it as far as
        the MP clevis slot's back."""
        G1, toward = self.guide_boss()
        return min(-self.sec.thickness / 2.0,
                   cylinder_floor(*eyelet_boss_axis(self.sec, G1, toward), self.sec.eyelet_boss_radius))

    @property
    def palmar_floor(self) -> float:
        """z (mm) of the face the part prints on: the MP side's palmar face (``flat_floor``), or,
        twisted, the turned arm's and pad's lowest edge (x = +-W / 2 at the pad's face or the
        dorsal face) where that lies lower; the hub and the keel under the turned arm reach down
        to it."""
        flat = self.flat_floor
        if not self.twisted:
            return flat
        return min(flat, *(float(self.turn[2, 0] * x + self.turn[2, 2] * z) for x in self._half_widths()
                           for z in (flat, self.sec.thickness / 2.0)))

    def _half_widths(self) -> tuple[float, float]:
        return (-self.sec.width / 2.0, self.sec.width / 2.0)

    @property
    def twisted(self) -> bool:
        return not np.array_equal(self.turn, np.eye(4))

    def verify(self, shape) -> list[str]:
        """The metacarpal-side guide eyelet at d1 from the MP axis (at y = metacarpal); the solid's
        lowest point on the palmar pad's face (``palmar_floor``: the part rests on it)."""
        out: list[str] = []
        bb = shape.bounding_box(optimal=True)
        self.expect(out, "lowest z", bb.min.Z, self.palmar_floor, 0.02)
        tol = self.sec.tol
        if self.twisted:   # the MP side measured where it was cut (a left hand's part is mirrored)
            turn = F.mirror(self.turn) if self.params.side == "left" else self.turn
            shape = transform(shape, np.linalg.inv(turn))
        faces = self.verify_routing(shape, out)     # the grooves; the faces, for the eyelet and the pockets
        eyes = eyelet_centres(shape, tol.tendon_hole / 2.0, tol.eyelet_length, faces=faces)
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
        """On its palmar pad (``PALMAR_DOWN``): the MP axis lies flat, so the MP hub groove's
        ceiling is a bridge between its flanks (its support blocker holds), the clevis slot is
        open upward, the column stands up (``export.orient`` measures it). On its side, the MP
        hub groove's inner flank was a 3.8 mm cantilever over the groove, and took support."""
        return PALMAR_DOWN

    def T_pulley(self) -> np.ndarray:
        """The CMC pulley's frame in this part's (mm)."""
        return F.to_mm(TH.T_cmc_base_pulley(self.params))

    def key_tool(self):
        """The flat on the column's end (pulley frame: on its +y), over the pulley and a clearance
        below it."""
        t = self.thenar
        r = t["column_r"]
        h = mm(self.params.cad.servo_pulley_width) / 2.0
        c = self.sec.tol.clearance
        return transform(box(-r - 1.0, r + 1.0, r - KEY_DEPTH, r + 1.0, -h - c, t["top"] - t["pulley"] + 1.0),
                         self.T_pulley())

    def support_blockers(self) -> list:
        """The tendon features' blockers (``RoutedPart``), turned with the MP side they are cut in."""
        out = super().support_blockers()
        if not self.twisted:
            return out
        R, t = self.turn[:3, :3], self.turn[:3, 3]
        return [replace(b, vertices=b.vertices @ R.T + t,
                        **({} if getattr(b, "flat", None) is None else {"flat": tuple(R @ np.asarray(b.flat, float))}))
                for b in out]

    def build(self):
        sec, t = self.sec, self.sec.tol
        W, T, L = sec.width, sec.thickness, self.length
        zp = self.palmar_floor
        zf = self.flat_floor
        R = self.turn[:3, :3]
        # the MP side, cut in the MP's frame before the twist
        arm = [box(-W / 2.0, W / 2.0, 0.0, L, -T / 2.0, T / 2.0)]
        if zf < -T / 2.0:     # the pad, from the hub to the clevis slot's back
            arm.append(box(-W / 2.0, W / 2.0, 0.0, L - sec.slot_back, zf, -T / 2.0 + 0.01))
        lt = link_tendons(self.params, self.link.name)
        G1, toward = self.guide_boss()
        b3, guide, u, (s_near, s_far) = eyelet(sec, G1, toward)
        wedge = stop_wedge(sec, self.joint, L)
        # where the near relief would leave a skin on the palmar face: a keel under the eyelet's exit
        # and a slot under the rest (relief_opening)
        opening = relief_opening(sec, s_near, u, wedge, L - sec.slot_back, zf)
        b, tools = clevis(sec, self.joint, L, lt.hubs().get(child_joint(self.link).name),
                          standing=[opening[0]] if opening else ())
        if opening:
            arm.append(keel_body(sec, opening[0]))
        tools += hub_grooves(sec, lt)
        G = np.array([0.0, *G1])
        side_body = b + b3
        guide += drive_fan_tools(lt, sec, float(np.linalg.norm(s_near - G)))
        # the near relief leaves through the clevis slot's back along the chord at rest, past the
        # flexion stop's wedge, as on the finger bases. Its run has the near sphere's radius and
        # starts at its centre, so the two touch along a great circle; in one boolean with the
        # sphere, where the sphere grazes the palmar face (0.03 mm through it on a 205 x 95 mm
        # hand), the cut left the sphere's back half as a second solid: the run is cut after, with
        # the slot that opens the relief there (relief_opening)
        relief = [near_relief(sec, s_near, u, wedge), *([opening[1]] if opening else [])]
        # the tendon comes down the CMC axis (through the hub's central bore, from the palm's
        # arch above) and turns along the arm to the eyelet: CMC rotation leaves its length alone.
        # The turn is rounded by a sphere one tendon radius wider than the bore (a sphere as wide
        # as the bore would touch it along a circle, and the arm channel through that circle
        # leaves edges 1e-5 mm long that tessellate with holes)
        turn = np.array([0.0, 0.0, s_far[2]])
        r_turn = max(t.tendon_relief / 2.0 + t.clearance, t.screw_clear / 2.0 + t.tendon_hole / 2.0)
        guide.append(sphere(turn, r_turn))
        end = guide_entry(turn, G, s_far)
        guide.append(cylinder(turn, end, t.tendon_hole / 2.0))
        # the arm channel runs half a tendon hole above the palmar face (the MP guide sits 0.4 mm
        # inside it): a skin of 0.06 mm would stay under it, so the channel is a slot open to the
        # face, and on through the eyelet's boss where that hangs below the face (0.44 mm was left)
        r = t.tendon_hole / 2.0
        floor = -T / 2.0 - 2.0 * sec.eyelet_boss_radius - 1.0
        guide.append(prism_x([(turn[1], turn[2]), (end[1], end[2]), (end[1], floor), (turn[1], floor)], -r, r))
        # and the turn opens through the palmar pad below it, as it opened through the palmar face
        # (a skin of 0.73 mm stayed under its sphere); the cord bears on the bend's inner side
        guide.append(cylinder(turn, (0.0, 0.0, floor), r_turn))
        up = R.T @ self.print_up if self.twisted else self.print_up     # the printer's +z where they are cut
        later = channel_tools(lt, up=up) + anchor_tools(lt, sec, up)
        hub = cylinder((0, 0, zp), (0, 0, T / 2.0), self.hub_radius)
        column = cylinder((0, 0, 0.0), (0, 0, self.thenar["top"]), self.thenar["column_r"])
        axis_tools = [self.key_tool(), cylinder(turn, (0.0, 0.0, self.thenar["top"] + 1.0), t.tendon_hole / 2.0)]
        if not self.twisted:
            return build([hub, arm[0], column, *arm[1:], *side_body], tools + axis_tools, guide, relief, later)
        moved = lambda shapes: [transform(x, self.turn) for x in shapes]  # noqa: E731
        # under the turned arm a keel down to the floor the part prints on, from the hub to the
        # clevis slot's back; the drive's turn on the CMC axis joins the turned arm's channel by a
        # bore across the hub, about the metacarpal's length like the twist
        corners = [self.turn[:3, :3] @ np.array([x, 0.0, z]) for x in self._half_widths() for z in (zf, T / 2.0)]
        xs = [c[0] for c in corners]
        keel = box(min(xs), max(xs), 0.0, L - sec.slot_back, zp, 0.0)
        turned_turn = (self.turn @ np.array([*turn, 1.0]))[:3]
        joint_tools = [sphere(turn, r_turn), cylinder(turn, turned_turn, t.tendon_hole / 2.0)]
        return build([hub, *moved(arm), column, keel, *moved(side_body)], moved(tools) + axis_tools,
                     moved(guide) + joint_tools, moved(relief), moved(later))
