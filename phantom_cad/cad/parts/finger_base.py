"""Finger base (metacarpal module): the part a finger clips to the palm with.

Frame: origin on the MCP axis (it has no proximal joint), axes of the finger column
(x ulnar, y distal, z dorsal). From its magnet face at y = -cad.finger_base_length to the
MCP clevis at y = 0 it carries: two magnet pockets that meet the palm socket's pockets,
the tendon entry at the palm's tendon height, the metacarpal-side MCP guide eyelet at d1
from the MCP axis, the MCP clevis (axle press bore, extension stop, flexion stop at the
MCP limit), and the anchors of the two dorsal cable springs.
"""

from __future__ import annotations

import numpy as np

from ... import canon
from ...kinematics.frames import tendon_height
from ...kinematics.topology import FINGERS, digit_links
from ..measure import circular_pockets, eyelet_centres, point_line_distance
from .base import Part, child_joint, digit_table
from .common import DigitSection, box, build, cylinder, mm
from .phalanx import channel, clevis, eyelet, spring_anchor, spring_channel


class FingerBase(Part):
    """The metacarpal module of ``finger``: a link fixed to the palm by two magnets."""

    SEGMENTS = ("base",)
    #: magnet pockets on its magnet face
    MAGNETS = 2

    def __init__(self, params, finger: str):
        links = [ln for ln in digit_links(finger) if ln.segment in self.SEGMENTS]
        if finger not in params.fingers or not links:
            raise ValueError(f"unknown finger {finger!r}")
        self.params, self.finger, self.link = params, finger, links[0]
        self.sec = DigitSection(params, finger)
        self.length = mm(params.cad.finger_base_length)
        self.tendon_z = mm(tendon_height(params))
        #: the joint at its distal end (the MCP): its clevis
        self.joint = child_joint(self.link).key

    @classmethod
    def for_link(cls, params, link):
        return cls(params, link.digit)

    def inputs(self) -> dict:
        doc = self.params.document
        return {**self.common_inputs(), "finger": canon.plain(digit_table(doc, self.finger)),
                # the tendon height at the magnet face follows the thinnest finger
                "thicknesses_mm": {f: doc["fingers"][f]["thickness_mm"] for f in FINGERS}}

    def verify(self, shape) -> list[str]:
        """The metacarpal-side guide eyelet at d1 from the MCP axis; two magnet pockets."""
        out: list[str] = []
        tol = self.sec.tol
        eyes = eyelet_centres(shape, tol.tendon_hole / 2.0, tol.eyelet_length)
        d = point_line_distance(eyes[0]["centre"], (0, 0, 0), (1, 0, 0)) if len(eyes) == 1 else None
        self.expect(out, "guide d1", d, mm(self.sec.guide.d1), 0.02)
        n = len(circular_pockets(shape, tol.magnet_pocket_d / 2.0))
        if n != self.MAGNETS:
            out.append(f"{self.name}: {n} magnet pockets, expected {self.MAGNETS}")
        return out

    @property
    def magnet_offset(self) -> float:
        """Lateral offset (+/-x) of the two magnet pockets: one wall between them."""
        t = self.sec.tol
        return (t.magnet_pocket_d + t.wall) / 2.0

    def magnet_centres(self) -> list[np.ndarray]:
        """Centres of the magnet pocket openings on the magnet face (link frame, mm)."""
        return [np.array([s * self.magnet_offset, -self.length, 0.0]) for s in (-1.0, 1.0)]

    @property
    def tendon_entry(self) -> np.ndarray:
        return np.array([0.0, -self.length, self.tendon_z])

    def build(self):
        sec, t = self.sec, self.sec.tol
        W, T, Lb = sec.width, sec.thickness, self.length
        body = [box(-W / 2.0, W / 2.0, -Lb, 0.0, -T / 2.0, T / 2.0)]
        b, tools = clevis(sec, self.joint, 0.0)
        body += b
        # metacarpal-side MCP guide at d1, and the tendon path from the magnet face to it
        G1, G2 = sec.guide_points()
        b3, t3, u, (s_near, s_far) = eyelet(sec, G1, G2, clip_y=-Lb)
        body += b3
        tools += t3
        chord = float(np.linalg.norm(G1 - G2))
        tools.append(channel(s_near, s_near + u * chord / 2.0, t.tendon_relief))
        u_in = (s_far - self.tendon_entry) / np.linalg.norm(s_far - self.tendon_entry)
        tools.append(cylinder(self.tendon_entry - u_in, s_far, t.tendon_relief / 2.0))   # ends in the relief sphere
        # magnet pockets, opening on the magnet face
        for c in self.magnet_centres():
            tools.append(cylinder(c - np.array([0.0, 1.0, 0.0]),
                                  c + np.array([0.0, t.magnet_pocket_depth, 0.0]), t.magnet_pocket_d / 2.0))
        # cable springs: anchored behind the magnets, running out through the clevis
        y_anchor = -Lb + t.magnet_pocket_depth + t.wall + t.spring_hole
        tools.extend(spring_channel(sec, y_anchor, sec.boss_radius + 1.0))
        tools.extend(spring_anchor(sec, y_anchor))
        return build(body, tools)
