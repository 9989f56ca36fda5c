"""Forearm module: the six servos behind the wrist.

Frame: the forearm link frame (``kinematics.forearm_layout.T_palm_forearm``: palm axes, origin on the
wrist crease at the middle of the servo row); the part is built in the palm frame and placed
back into its own. Why the servos are here and not in the palm: docs/parts.md.

* one row of the six servos in the order of their targets (the CMC's loop servo radial, then
  thumb flexion, the pinky ulnar): the tendon servos' shafts dorsal, each turned about its shaft
  so that its drive leaves the pulley straight toward its finger's socket (the thumb's toward its
  turn onto the CMC axis); servo 6's shaft parallel to the CMC axis, its pulley in the CMC
  pulley's plane (``servo_geometry.coplanar_servo``); pockets and ear slots open along the shafts (the
  servos drop in, then their pulleys go on; in two rows servo 6's pocket and cavity open up the
  module's z kept square to its body's length, ``forearm_layout.drops_straight``), pulley cavities, M2 pilot holes under the flange ears;
* each drive's channel (the loop's two) from its pulley through the front wall, on to the palm,
  joined by a slot to its servo's drop-in pocket where it runs beside it closer than a flank
  (``ServoMount.drive_slot``), to another servo's pocket likewise (``pocket_slots``), and opened up
  through the block's top where it enters it under less than a flank (``top_slot``);
* a tab over the palm's dorsal face at the wrist with two M2 clearance holes: the module screws
  onto the palm there.
"""

from __future__ import annotations

import math

import numpy as np

from ...kinematics import forearm_layout as FL
from ...kinematics import frames as F
from ...kinematics.dimensions import FLANK
from ...kinematics.hand_params import HandParams
from ...kinematics.topology import FOREARM, SERVO_MOUNT, SERVOS, link
from ...kinematics.vectors import nearest_on_box, nearest_on_cylinder, nearest_on_swept
from ..measure import circular_pockets
from .base import Part
from .common import (Tolerances, box, build, channel_slot, channel_slots, cylinder, mm, polygon_cylinder,
                     swept_along, transform)
from . import wrist
from .servos import ServoMount


#: the servos the module holds
FOREARM_SERVOS = tuple(s.index for s in SERVOS if SERVO_MOUNT[s.drive] == FOREARM)


class Forearm(ServoMount, Part):
    """The forearm module holding the tendon servos."""

    SEGMENTS = ("forearm",)
    COLOR = (0.45, 0.47, 0.52)
    SCREWS = 2

    def __init__(self, params: HandParams):
        self.params = params
        self.link = link(FOREARM)
        self.tol = Tolerances(params)
        self.pulley_width = mm(params.cad.servo_pulley_width)

    @classmethod
    def for_link(cls, params: HandParams, link):
        return cls(params)

    @property
    def print_rotation(self) -> np.ndarray:
        return F.rot_x(math.pi)[:3, :3]            # on its dorsal face (the tab flat on the bed)

    def inputs(self) -> dict:
        """Everything but the model's mechanics and effects: the servos aim at every socket."""
        return self.whole_hand_inputs()

    def verify(self, shape) -> list[str]:
        """Two flange pilot holes per servo."""
        out: list[str] = []
        n = len(self.pilot_points())
        got = len(circular_pockets(shape, self.tol.screw_pilot / 2.0))
        if got != n:
            out.append(f"{self.name}: {got} servo pilot holes, expected {n}")
        return out

    # -- placements (palm frame, mm) -------------------------------------------
    def T_palm_part(self) -> np.ndarray:
        return F.to_mm(FL.T_palm_forearm(self.params))

    def pilot_points(self) -> list[np.ndarray]:
        return [(self.T_servo(k) @ np.array([*p, 1.0]))[:3] for k in FOREARM_SERVOS for p in self.screw_points(k)]

    def extents(self) -> tuple[float, float, float, float, float, float]:
        """x0, x1, y0, y1, z0, z1 (palm frame, mm) of the module's block (``wrist.forearm_block``)."""
        return wrist.forearm_block(self.params)

    def tab(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) palm frame of the fastening tab over the palm (``wrist.tab``)."""
        return wrist.tab(self.params)

    def tab_screws(self) -> list[np.ndarray]:
        """Centres (palm frame) of the tab's two screws on the palm's dorsal face, where the palm
        drills them (``Palm.tab_screws``)."""
        from .palm import Palm

        return Palm(self.params).tab_screws()

    # -- geometry ----------------------------------------------------------------
    def body(self) -> list:
        """The module's block and its tab (palm frame): two boxes."""
        x0, x1, y0, y1, z0, z1 = self.extents()
        lo, hi = self.tab()
        return [box(x0, x1, y0, y1, z0, z1),
                box(lo[0], hi[0], lo[1] - self.tol.wall, hi[1], lo[2], hi[2])]   # into the block

    def collision_solids(self) -> list:
        """The block and the tab, unfused (their hull would reach down into the palm)."""
        T = np.linalg.inv(self.T_palm_part())
        return [transform(b, T) for b in self.body()]

    def drop_vector(self, servo: int) -> np.ndarray:
        """The sweep (palm frame, mm) that opens a servo's pocket and cavity out of the module's top
        where it does not open along its shaft (``forearm_layout.drops_straight``): the way the
        servo drops in, the module's z with its component along the servo's y (its body's length,
        where the flange pilots stand) taken out, so that the swept body keeps the pilots' walls
        however the shaft tilts; long enough to rise past the block's top from wherever the servo
        stands in it."""
        x0, x1, y0, y1, _, z1 = self.extents()
        T = self.T_servo(servo)
        d = np.array([0.0, 0.0, 1.0]) - T[2, 1] * T[:3, 1]
        d /= np.linalg.norm(d)
        return d * (z1 + 1.0 - (T[2, 3] - (x1 - x0) - (y1 - y0))) / d[2]

    def pocket_pieces(self, servo: int) -> list:
        """Servo ``servo``'s pocket as the module cuts it, one convex piece at a time: its body and
        ear pockets and its pulley's cavity, open up along the shaft through the block's top, or
        swept along :meth:`drop_vector` (``forearm_layout.drops_straight``). Per piece, a function
        of points (n, 3; palm frame, mm) giving (distance, nearest point)."""
        T = self.T_servo(servo)
        zc0, zc1 = self.cavity_span(servo)
        r = self.cavity_radius(servo)
        if FL.drops_straight(self.params, servo):
            v = T[:3, :3].T @ self.drop_vector(servo)          # the sweep in the servo frame
            up = float(np.linalg.norm(v))
            e = v / up
            pieces = [lambda x, lo=lo, hi=hi: nearest_on_swept(x, lambda y: nearest_on_box(y, lo, hi), e, up)
                      for lo, hi in self.open_pockets(servo, zc1)]
            pieces.append(lambda x: nearest_on_swept(x, lambda y: nearest_on_cylinder(y, zc0, zc1, r), e, up))
        else:
            pieces = [lambda x, lo=lo, hi=hi: nearest_on_box(x, lo, hi) for lo, hi in self.open_pockets(servo, np.inf)]
            pieces.append(lambda x: nearest_on_cylinder(x, zc0, np.inf, r))

        def palm(piece):
            def gap(points):
                d, near = piece((np.asarray(points, float) - T[:3, 3]) @ T[:3, :3])
                return d, near @ T[:3, :3].T + T[:3, 3]
            return gap
        return [palm(piece) for piece in pieces]

    def pocket_gap(self, servo: int, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(distance, nearest point) from each of ``points`` (palm frame, mm) to servo ``servo``'s
        pocket as the module cuts it (:meth:`pocket_pieces`)."""
        found = [gap(points) for gap in self.pocket_pieces(servo)]
        k = np.argmin([d for d, _ in found], axis=0)
        near = np.choose(k[:, None], [n for _, n in found])
        return np.min([d for d, _ in found], axis=0), near

    def pocket_slots(self, servo: int, side: float, length: float) -> list:
        """Slots (``common.channel_slots``) joining a drive's channel to the other servos' pockets
        where it passes one less than a flank (two perimeters) away: the strand runs past the
        pocket's corner in the open, as beside its own servo (``drive_slot``), rather than behind a
        sliver of wall. Each piece of a pocket (:meth:`pocket_pieces`) gets its own: a channel
        running along a body pocket's edge can pass over the cavity too, and a slot toward the
        pocket alone leaves a shard between the channel and the cavity."""
        p, u = self.drive_line(servo, side)
        gaps = [gap for j in FOREARM_SERVOS if j != servo for gap in self.pocket_pieces(j)]
        return channel_slots(p, u, length, self.tol.tendon_hole / 2.0, gaps, mm(FLANK))

    def top_slot(self, servo: int, side: float, length: float) -> list:
        """A slot (``common.channel_slot``) opening a drive's channel up through the block's top
        where it runs under it less than a flank (two perimeters): servo 6's strands, from its
        tilted pulley, can enter the block through the top at about 20 deg, where the roof over the
        channel's entry would taper to nothing. Where the roof is material, and on along the same
        thin run where the channel runs open beside a pocket."""
        x0, x1, y0, y1, _, z1 = self.extents()
        p, u = self.drive_line(servo, side)
        r = self.tol.tendon_hole / 2.0
        s = np.linspace(0.0, length, int(length / 0.05) + 1)
        axis = p + s[:, None] * u
        roof = z1 - axis[:, 2] - r
        inside = (axis[:, 0] > x0) & (axis[:, 0] < x1) & (axis[:, 1] > y0) & (axis[:, 1] < y1)
        open_ = np.min([self.pocket_gap(k, axis)[0] for k in FOREARM_SERVOS], axis=0) < r
        thin = inside & (roof > -2.0 * r) & (roof < mm(FLANK))
        need = np.flatnonzero(thin & ~open_)
        if not len(need):
            return []
        # on through the thin run's open stretches next to where the roof is material: a slot
        # ending where the channel meets a pocket leaves a crumb between the two
        i, j = need[0], need[-1]
        while i > 0 and thin[i - 1]:
            i -= 1
        while j < len(s) - 1 and thin[j + 1]:
            j += 1
        return [channel_slot(p, u, s[i], s[j], (0.0, 0.0, 1.0), r, mm(FLANK))]

    def build(self):
        t = self.tol
        x0, x1, y0, y1, z0, z1 = self.extents()
        body = self.body()
        tools, slots = [], []
        reach = y1 - y0 + 2.0 * wrist.TAB_LENGTH
        for k in FOREARM_SERVOS:
            Ts = self.T_servo(k)
            rc = self.cavity_radius(k)
            zc0, zc1 = self.cavity_span(k)
            if FL.drops_straight(self.params, k):
                # the pocket and the cavity swept up out of the block's top: the servo, its pulley
                # on, drops in along the drop vector (along its tilted shaft it would cut into its
                # neighbour's pocket)
                drop = self.drop_vector(k)
                for blo, bhi in self.open_pockets(k, zc1):
                    tools += swept_along(transform(box(blo[0], bhi[0], blo[1], bhi[1], blo[2], bhi[2]), Ts), drop)
                tools += swept_along(transform(polygon_cylinder((0, 0, zc0), (0, 0, zc1), rc), Ts), drop)
            else:
                # open along the shaft out of the block's top (a tilted shaft: its corners too)
                top = (z1 - Ts[2, 3]) / Ts[2, 2] + 1.0 + (x1 - x0) * math.sqrt(max(1.0 - Ts[2, 2] ** 2, 0.0)) / Ts[2, 2]
                for blo, bhi in self.open_pockets(k, top):
                    tools.append(transform(box(blo[0], bhi[0], blo[1], bhi[1], blo[2], bhi[2]), Ts))
                tools.append(transform(cylinder((0, 0, zc0), (0, 0, top), rc), Ts))
            tools += [transform(p, Ts) for p in self.pilot_tools(k)]
            # every drive runs straight on toward its target (servo 6's loop: both strands)
            for side in self.strand_sides(k):
                p, u = self.drive_line(k, side)
                tools.append(cylinder(p - u, p + u * reach, t.tendon_hole / 2.0))
                slots += self.pocket_slots(k, side, reach) + self.top_slot(k, side, reach)
                slot = self.drive_slot(k, t.tendon_hole, side=side)
                if slot is not None:
                    tools.append(transform(box(slot[0][0], slot[1][0], slot[0][1], slot[1][1], slot[0][2], slot[1][2]),
                                           Ts))
        for s in self.tab_screws():
            tools.append(cylinder(s - np.array([0, 0, 1.0]), s + np.array([0, 0, 2.0 * t.wall + 1.0]),
                                  t.screw_clear / 2.0))
        # the slots in a boolean of their own: a cut of slots, channels and pockets at once where a
        # channel also grazes a pocket can leave a shard of neither
        shape = build(body, tools, slots)
        return transform(shape, np.linalg.inv(self.T_palm_part()))
