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
from ...kinematics.dimensions import digit_entry, magnet_pocket_centres
from ...kinematics.frames import tendon_height
from ...kinematics.hand_params import HandParams
from ...kinematics.topology import FINGERS, digit_links
from ..measure import circular_pockets, eyelet_centres, point_line_distance
from .base import MAGNET_DOWN, Part, child_joint
from .common import DigitSection, box, build, cylinder, mm
from .phalanx import clevis, eyelet, hub_grooves, near_relief, stop_wedge
from .drive_fans import clear_of_fans, drive_fan_tools, guide_entry
from .tendons import RoutedPart, link_tendons, anchor_tools, channel_tools


class FingerBase(RoutedPart, Part):
    """The metacarpal module of ``finger``: a link fixed to the palm by two magnets."""

    SEGMENTS = ("base",)
    #: magnet pockets on its magnet face
    MAGNETS = 2

    def __init__(self, params: HandParams, finger: str):
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
    def for_link(cls, params: HandParams, link):
        return cls(params, link.digit)

    def inputs(self) -> dict:
        doc = self.params.document
        return {**self.common_inputs(), "finger": canon.plain(digit_entry(doc, self.finger)),
                # the tendon height at the magnet face follows the thinnest finger; the pockets'
                # lift is an optional key of the palm's table (absent: 0)
                "thicknesses_mm": {f: doc["fingers"][f]["thickness_mm"] for f in FINGERS},
                "magnet_lift_mm": next((v for k, v in doc["palm"].items() if k == "magnet_lift_mm"), 0.0)}

    def verify(self, shape) -> list[str]:
        """The metacarpal-side guide eyelet at d1 from the MCP axis; two magnet pockets."""
        out: list[str] = []
        tol = self.sec.tol
        faces = self.verify_routing(shape, out)     # the grooves; the faces, for the eyelet and the pockets
        eyes = eyelet_centres(shape, tol.tendon_hole / 2.0, tol.eyelet_length, faces=faces)
        d = point_line_distance(eyes[0]["centre"], (0, 0, 0), (1, 0, 0)) if len(eyes) == 1 else None
        self.expect(out, "guide d1", d, mm(self.sec.guide.d1), 0.02)
        n = len(circular_pockets(shape, tol.magnet_pocket_d / 2.0, faces=faces))
        if n != self.MAGNETS:
            out.append(f"{self.name}: {n} magnet pockets, expected {self.MAGNETS}")
        return out

    def magnet_centres(self) -> list[np.ndarray]:
        """Centres of the magnet pocket openings on the magnet face (link frame, mm;
        ``dimensions.magnet_pocket_centres``)."""
        t = self.sec.tol
        return [np.array([x, -self.length, z])
                for x, z in magnet_pocket_centres(t.magnet_pocket_d, t.wall, mm(self.params.palm.magnet_lift))]

    @property
    def tendon_entry(self) -> np.ndarray:
        return np.array([0.0, -self.length, self.tendon_z])

    @property
    def print_rotation(self) -> np.ndarray:
        """On its magnet face: the least overhang of the axis-aligned ways (``export.orient``
        measures it); its channels stand nearly upright."""
        return MAGNET_DOWN

    def build(self):
        sec, t = self.sec, self.sec.tol
        W, T, Lb = sec.width, sec.thickness, self.length
        body = [box(-W / 2.0, W / 2.0, -Lb, 0.0, -T / 2.0, T / 2.0)]
        lt = link_tendons(self.params, self.link.name)
        # metacarpal-side MCP guide at d1, and the tendon path from the magnet face to it
        G1, G2 = sec.guide_points()
        b3, guide, u, (s_near, s_far) = eyelet(sec, G1, lt.eyelet_toward(G1), clip_y=-Lb)
        start = float(np.linalg.norm(s_near - np.array([0.0, *G1])))
        # the MCP stop's wedge, left standing in the clevis slot, ends in an edge on the palmar face
        # over the drive's fan: it stands only where it lies a flank clear of the fan
        def stop_clear(poly):
            return clear_of_fans(lt, sec, start, poly)
        b, tools = clevis(sec, self.joint, 0.0, lt.hubs().get(child_joint(self.link).name), stop_clear)
        body += b + b3
        tools += hub_grooves(sec, lt)
        # the drive's run from the magnet face toward G1 (routing), a clearance hole that ends inside
        # the far relief sphere (a wider one would bite the eyelet)
        g1 = np.array([0.0, *G1])
        end = guide_entry(self.tendon_entry, g1, s_far)
        u_in = (end - self.tendon_entry) / np.linalg.norm(end - self.tendon_entry)
        guide.append(cylinder(self.tendon_entry - u_in, end, t.tendon_hole / 2.0))
        guide += drive_fan_tools(lt, sec, start)
        # the near relief leaves through the clevis slot's back wall along the chord at rest, past the
        # flexion stop's wedge
        guide.append(near_relief(sec, s_near, u, stop_wedge(sec, self.joint, 0.0, stop_clear)))
        # magnet pockets, opening on the magnet face
        for c in self.magnet_centres():
            tools.append(cylinder(c - np.array([0.0, 1.0, 0.0]),
                                  c + np.array([0.0, t.magnet_pocket_depth, 0.0]), t.magnet_pocket_d / 2.0))
        # the loop's hub clamp, the return cord's channel and knot well (routing model)
        return build(body, tools, guide, channel_tools(lt, up=self.print_up) + anchor_tools(lt, sec, self.print_up))
