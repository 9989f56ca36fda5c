"""The servo mount: what a part that holds servos cuts for them (numpy only).

A servo's pocket, flange-ear slots, pulley cavity and flange pilot holes, in its servo frame
(``kinematics.frames``: origin on the shaft at the pulley's mid-plane, z along the shaft toward
the pulley, the body toward -y), in mm. The forearm module holds the six servos; the palm cuts
the drives' channels from the same lines.
"""

from __future__ import annotations

import numpy as np

from ...kinematics import forearm_layout as FL
from ...kinematics import frames as F
from ...kinematics import servo_geometry as SG
from ...kinematics.dimensions import FLANK, servo_screw_offset
from ...kinematics.topology import SERVOS
from .common import SLOT_CHORD, mm


class ServoMount:
    """Mixin of a part that holds servos: needs ``params``, ``tol`` and ``pulley_width``."""

    def T_servo(self, servo: int) -> np.ndarray:
        """Servo frame of servo ``servo`` (0-based index, topology.SERVOS), palm frame (mm)."""
        return F.to_mm(FL.T_palm_servo(self.params, servo))

    def pulley_radius(self, servo: int) -> float:
        return mm(F.servo_radius(self.params, servo))

    def strand_sides(self, servo: int) -> tuple[float, ...]:
        """The sides (servo frame x, in pulley radii) where cables leave a servo's pulley along its
        y: a tendon servo's drive at -x, the CMC loop's two strands at -x and +x."""
        return (-1.0, 1.0) if SERVOS[servo].drive == "loop" else (-1.0,)

    def drive_line(self, servo: int, side: float = -1.0) -> tuple[np.ndarray, np.ndarray]:
        """Where a servo's drive leaves its pulley, the tangent point (servo frame (side r, 0, 0):
        the servo's x is across the drive), and the drive's unit direction there (the servo's y),
        palm frame (mm)."""
        T = self.T_servo(servo)
        return (T @ np.array([side * self.pulley_radius(servo), 0.0, 0.0, 1.0]))[:3], T[:3, 1].copy()

    def cavity_radius(self, servo: int) -> float:
        return self.pulley_radius(servo) + mm(F.pulley_cavity_margin(self.params))

    def _box(self, what: str, grow: float):
        lo, hi = SG.servo_boxes(self.params)[what]
        return np.array([mm(v) for v in lo]) - grow, np.array([mm(v) for v in hi]) + grow

    def body_box(self, servo: int, grow: float = 0.0):
        """The servo's body as (lo, hi) corners in its servo frame, grown by ``grow``."""
        return self._box("body", grow)

    def ear_box(self, servo: int, grow: float = 0.0):
        """The servo's flange ears (both, as one slab across the body) in its servo frame."""
        return self._box("ears", grow)

    def cavity_span(self, servo: int) -> tuple[float, float]:
        """z extent (servo frame) of a servo's pulley cavity: from the body's top to past the pulley."""
        c = self.tol.clearance
        return self.body_box(servo, grow=c)[1][2] - c, self.pulley_width / 2.0 + c

    def screw_points(self, servo: int) -> list[np.ndarray]:
        """Flange screw centres (servo frame) on the ears' underside, mid-ear, one each end."""
        e = servo_screw_offset(mm(self.params.servo.body[0]), mm(self.params.servo.flange_span))
        z_under = self.ear_box(servo)[0][2]
        y0 = -mm(self.params.cad.servo_shaft_offset)
        return [np.array([0.0, y0 + s * e, z_under]) for s in (-1.0, 1.0)]

    def open_pockets(self, servo: int, top: float) -> list:
        """(lo, hi) corners, servo frame, of the body pocket and ear slots, open along the shaft
        up to z = ``top`` (the servo drops in before its pulley goes on)."""
        c = self.tol.clearance
        lo, hi = self.body_box(servo, grow=c)
        elo, ehi = self.ear_box(servo, grow=c)
        return [(lo, np.array([hi[0], hi[1], top])), (elo, np.array([ehi[0], ehi[1], top]))]

    def drive_slot(self, servo: int, channel: float, run: float | None = None, side: float = -1.0):
        """(lo, hi) corners, servo frame, of the slot that joins a drive's channel (diameter
        ``channel``, leaving the pulley at (side r, 0, 0) along +y) to the servo's own drop-in
        pocket where it runs beside it less than a flank (``dimensions.FLANK``) away (a pulley
        barely wider than half the body: 0.25 mm was left), over ``run`` mm of the drive (default:
        the pocket's length ahead of the shaft); None where the wall is a flank or more. From the
        channel's axis into the pocket, ``common.SLOT_CHORD`` of the channel high: no face of it
        tangent to the channel's."""
        pockets = self.open_pockets(servo, 0.0)
        edge = min(p[0][0] for p in pockets) if side < 0 else max(p[1][0] for p in pockets)
        r = self.pulley_radius(servo)
        if side * (side * (r - channel / 2.0) - edge) >= mm(FLANK):     # the wall beside the pocket
            return None
        ahead = max(p[1][1] for p in pockets)
        y1 = ahead if run is None else min(ahead, run)
        x = sorted((side * r, edge - side * 0.01))
        h = SLOT_CHORD * channel / 2.0
        return (np.array([x[0], 0.0, -h]), np.array([x[1], y1, h]))

    def pilot_tools(self, servo: int) -> list:
        """The flange screws' pilot holes (servo frame), down from the ears' underside."""
        from .common import cylinder
        t = self.tol
        return [cylinder(p + np.array([0, 0, 1.0]), p - np.array([0, 0, t.clearance + t.screw_engagement]),
                         t.screw_pilot / 2.0) for p in self.screw_points(servo)]
