"""Palm housing.

Frame: the palm (hand) frame (docs/frames.md): origin on the index MCP axis, x ulnar,
y distal, z dorsal. Built from:

* four finger sockets: blocks whose magnet faces sit where each finger base's magnet face
  sits at rest, turned by palm.arc_offset from finger to finger (the socket face normal is
  the finger column's y), each with two magnet pockets facing the finger base's pockets
  and the tendon exit at the palm's tendon height;
* the metacarpal block: from its back face (the wrist crease, or the thenar's back,
  ``servo_geometry.palm_back``) to the sockets, across the four fingers (the servos sit in the forearm
  module behind it, ``forearm.py``);
* the thenar block, radial of the metacarpal block: the journal that holds the CMC base's column
  (from the palmar face up along the CMC axis), the cavity of the CMC pulley on that column with
  its slot toward servo 6 (the loop runs in it; the pulley slides in through it, the column up
  through the journal into it) and, above it, the thumb drive's turn onto the CMC axis
  (``thenar.thenar``);
* tendon channels from each socket's tendon exit straight back toward its servo pulley in the
  forearm, each with the bore its drive's coupler (the crimp stop and the finger strand's
  loop, ``couplers.couplers``) travels in; the thumb drive's channel from the back face to its
  turn and down the CMC axis (turning the thumb about the CMC leaves its length alone);
* two pilot holes on the dorsal face at the back for the forearm module's tab;
* the flexion-limiting housing (rails under each finger base, at the Table I MCP limit);
* the heel: a pad ``palm.heel_height_mm`` below the metacarpal block's palmar face, from its back
  face ``palm.heel_length_mm`` distally (the heel of the hand); an object held in the palm's
  hollow, in front of it, cannot slide out toward the wrist when the fingertips press it there
  (docs/parts.md "Power grasp").
"""

from __future__ import annotations

import math

import numpy as np

from ... import units
from ...kinematics import couplers
from ...kinematics import forearm_layout as FL
from ...kinematics import frames as F
from ...kinematics import servo_geometry as SG
from ...kinematics import thenar as TH
from ...kinematics.dimensions import FLANK
from ...kinematics.hand_params import HandParams
from ...kinematics.topology import FINGERS, LINKS, chain
from ...kinematics.vectors import clipped_acos, nearest_on_box, nearest_on_cylinder
from ..measure import circular_pockets
from .base import Part
from .common import (DigitSection, Tolerances, as_solid, box, build, channel_slots, cylinder, extrude_up, mm, polygon_cylinder,
                     prism_x, swept_along, transform,
                     turn_sphere)
from . import wrist
from .servos import ServoMount

#: a face of the thenar's cuts turned up to this (deg) from the thenar block's radial face makes a
#: wall with it (``export.walls.WALL_DEG``: further turned, an edge)
FACE_DEG = 30.0


def _mm(T):
    return F.to_mm(T)


class Palm(ServoMount, Part):
    """The palm housing: the root link."""

    SEGMENTS = ("palm",)
    COLOR = (0.55, 0.57, 0.60)

    def __init__(self, params: HandParams):
        self.params = params
        self.link = next(ln for ln in LINKS if ln.parent is None)
        self.tol = Tolerances(params)
        self.thickness = mm(params.palm.thickness)
        self.heel_height = mm(params.palm.heel_height)
        self.heel_length = mm(params.palm.heel_length)
        self.pulley_width = mm(params.cad.servo_pulley_width)
        self.tendon_z = mm(F.tendon_height(params))

    @classmethod
    def for_link(cls, params: HandParams, link):
        return cls(params)

    @property
    def print_rotation(self) -> np.ndarray:
        return F.rot_x(math.pi)[:3, :3]            # on its dorsal face

    def inputs(self) -> dict:
        """Everything but the model's mechanics and effects: the palm carries every socket and servo."""
        return self.whole_hand_inputs()

    def verify(self, shape) -> list[str]:
        """Two magnet pockets per finger socket; adjacent socket normals arc_offset apart."""
        out: list[str] = []
        pk = circular_pockets(shape, self.tol.magnet_pocket_d / 2.0)
        from .finger_base import FingerBase
        n = FingerBase.MAGNETS * len(FINGERS)
        if len(pk) != n:
            out.append(f"{self.name}: {len(pk)} magnet pockets, expected {n}")
            return out
        normals = []
        for p in sorted(pk, key=lambda p: p["centre"][0] * (1 if self.params.side == "right" else -1)):
            if not normals or np.linalg.norm(p["facing"] - normals[-1]) > 1e-9:
                normals.append(p["facing"])
        want = units.deg(self.params.palm.arc_offset)
        for a, b in zip(normals, normals[1:]):
            ang = units.deg(clipped_acos(a @ b))
            if abs(ang - want) > 1e-6:
                out.append(f"{self.name}: socket normals {ang:.6f} deg apart, expected {want:g}")
        return out

    # -- placements (mm) ---------------------------------------------------
    def T_socket(self, finger: str) -> np.ndarray:
        return _mm(F.T_palm_socket(self.params, finger))

    def magnet_centres(self, finger: str) -> list[np.ndarray]:
        """Opening centres of the socket's magnet pockets, palm frame (mm)."""
        from .finger_base import FingerBase
        T = self.T_socket(finger)
        return [(T @ np.array([x, 0.0, z, 1.0]))[:3] for x, _, z in FingerBase(self.params, finger).magnet_centres()]

    @property
    def couplers(self) -> dict:
        """The finger drives' couplers (``couplers.couplers``: metres, s from the socket face)."""
        return couplers.couplers(self.params)

    def extents(self):
        """x0, x1, y0, y1 (mm) of the metacarpal block: across the sockets and ulnar far enough for
        the finger drives' channels (``forearm_layout.metacarpal_x``), from the palm's back face to behind
        the socket faces."""
        x0, x1 = (mm(v) for v in FL.metacarpal_x(self.params))
        return x0, x1, mm(SG.palm_back(self.params)), self.slab_front()

    def heel(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(lo, hi) palm frame (mm) of the heel, under the metacarpal block from its back face, or None
        (a flat palm: ``palm.heel_height_mm`` 0)."""
        if self.heel_height <= 0.0:
            return None
        x0, x1, y0, _ = self.extents()
        return (np.array([x0, y0, -self.thickness / 2.0 - self.heel_height]),
                np.array([x1, y0 + self.heel_length, -self.thickness / 2.0]))

    def _placed_box(self, T, lo, hi) -> np.ndarray:
        return SG.box_corners(lo, hi) @ T[:3, :3].T + T[:3, 3]

    def thenar_block(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) palm frame (mm) of the thenar block: the bounding box of the journal's and the
        turn's walls across x (the pulley's cavity is cut open where it reaches past), of everything it holds
        (``thenar.thenar_points``) along y, from the palm's palmar to its dorsal face, reaching a
        wall into the metacarpal block. Empty (lo not below hi) where it all lies inside the block."""
        pts = {k: units.mm(v) for k, v in TH.thenar_points(self.params).items()}
        allp = np.vstack(list(pts.values()))
        x0 = self.extents()[0]
        xs = np.vstack([pts["journal"], pts["turn"]])[:, 0]
        Tp = self.thickness
        return (np.array([xs.min(), max(allp[:, 1].min(), self.extents()[2]), -Tp / 2.0]),
                np.array([x0 + self.tol.wall, allp[:, 1].max(), Tp / 2.0]))

    def socket_box(self, finger: str) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) in its socket frame (``T_socket``, mm) of a finger's socket block: the finger's
        width across, the palm's thickness, back to the wrist crease, its turned back corners no
        further (the metacarpal block fills the rest)."""
        T = self.T_socket(finger)
        W, Tp = mm(self.params.fingers[finger].width), self.thickness
        y0 = self.extents()[2]
        depth = (T[1, 3] - y0 - W / 2.0 * abs(T[1, 0])) / T[1, 1]
        return np.array([-W / 2.0, -depth, -Tp / 2.0]), np.array([W / 2.0, 0.0, Tp / 2.0])

    def side_region(self, finger: str, side: float):
        """The open space beside a socket block's side (``side`` -1 radial, +1 ulnar) ahead of the
        slab, a sliver deep (:data:`OUTSIDE_STEP`), over the stretch of the side up to the socket face
        no other socket block covers, as (T, lo, hi): a box in the socket frame T, open ahead and
        palmar and dorsal; None where another block covers the side at the face."""
        y1 = self.extents()[3]
        T, (blo, bhi) = self.T_socket(finger), self.socket_box(finger)
        x = bhi[0] if side > 0 else blo[0]
        y_slab = (y1 - T[1, 3] - T[1, 0] * x) / T[1, 1]          # where the side meets the slab's front
        ys = np.arange(max(y_slab, blo[1]), 0.0, OUTSIDE_STEP)
        if not len(ys):
            return None
        pts = np.column_stack([np.full(len(ys), x + side * OUTSIDE_STEP), ys, np.zeros(len(ys))])
        pts = pts @ T[:3, :3].T + T[:3, 3]
        covered = np.zeros(len(ys), bool)
        for g in FINGERS:
            if g != finger:
                Tg, (glo, ghi) = self.T_socket(g), self.socket_box(g)
                covered |= nearest_on_box((pts - Tg[:3, 3]) @ Tg[:3, :3], glo, ghi)[0] == 0.0
        if covered[-1]:
            return None
        first = ys[np.flatnonzero(covered)[-1] + 1] if covered.any() else ys[0]
        deep = x + side * OUTSIDE_STEP
        return T, np.array([min(x, deep), first, -np.inf]), np.array([max(x, deep), np.inf, np.inf])

    def outside_regions(self) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The open space beside the palm's outer side faces as boxes (T, lo, hi; a box in frame T,
        palm frame mm, open where a bound is infinite): radial of the metacarpal block ahead of the
        thenar block, ulnar of it, and beside the outer sides of the outermost socket blocks
        (:meth:`side_region`). Between two socket blocks the palm is filled where it is thin
        (:meth:`gap_fillers`)."""
        x0, x1, y0, y1 = self.extents()
        lo, hi = self.thenar_block()
        ahead = hi[1] if np.all(hi > lo) else y0
        inf = np.inf
        out = [(np.eye(4), np.array([-inf, ahead, -inf]), np.array([x0, y1, inf])),
               (np.eye(4), np.array([x1, y0, -inf]), np.array([inf, y1, inf]))]
        for finger, side in ((FINGERS[0], -1.0), (FINGERS[-1], 1.0)):
            region = self.side_region(finger, side)
            if region is not None:
                out.append(region)
        return out

    def _finger_axes(self, finger: str) -> list[tuple[np.ndarray, float]]:
        """(points on the axis (n, 3), radius) of a finger's coupler bore and of its drive channel as
        far as the metacarpal block's back, palm frame (mm)."""
        exit_, tangent = self.finger_drive(finger)
        u = (tangent - exit_) / np.linalg.norm(tangent - exit_)
        back = (self.extents()[2] - exit_[1]) / u[1] if u[1] < 0.0 else np.linalg.norm(tangent - exit_)
        cp = self.couplers[finger]
        bore = exit_ + np.arange(0.0, mm(cp.bore_end), OUTSIDE_STEP)[:, None] * u
        drive = exit_ + np.arange(0.0, back, OUTSIDE_STEP)[:, None] * u
        return [(bore, mm(cp.bore) / 2.0), (drive, self.tol.tendon_hole / 2.0)]

    def gap_fillers(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(lo, hi) palm frame (mm) of the boxes filling the gap between two neighbouring socket blocks
        ahead of the slab where either finger's coupler bore or drive channel runs less than a flank
        from it (two rows of servos slant the drives toward their servos): between the two
        sockets' centres, from inside the slab to a clearance behind both socket faces where they
        face each other. The knuckles' faces and everything ahead of them stay as they are."""
        Tp, c = self.thickness, self.tol.clearance
        y1 = self.extents()[3]
        out = []
        for a, b in zip(FINGERS, FINGERS[1:]):
            sides = [r for r in (self.side_region(a, 1.0), self.side_region(b, -1.0)) if r is not None]
            if not sides:
                continue
            thin = False
            for f in (a, b):
                for pts, r in self._finger_axes(f):
                    for T, lo, hi in sides:
                        d = nearest_on_box((pts - T[:3, 3]) @ T[:3, :3], lo, hi)[0]
                        thin |= bool(np.any(d - r < mm(FLANK)))
            if not thin:
                continue
            Ta, Tb = self.T_socket(a), self.T_socket(b)
            wa, wb = mm(self.params.fingers[a].width) / 2.0, mm(self.params.fingers[b].width) / 2.0
            faces = [Ta[1, 3], (Ta @ np.array([wa, 0.0, 0.0, 1.0]))[1], Tb[1, 3], (Tb @ np.array([-wb, 0.0, 0.0, 1.0]))[1]]
            out.append((np.array([Ta[0, 3], y1 - 1.0, -Tp / 2.0]), np.array([Tb[0, 3], min(faces) - c, Tp / 2.0])))
        return out

    def outside_gap(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(distance, nearest point) from each of ``points`` (palm frame, mm) to the open space beside
        the palm's side faces (:meth:`outside_regions`)."""
        found = [(nearest_on_box((points - T[:3, 3]) @ T[:3, :3], lo, hi), T) for T, lo, hi in self.outside_regions()]
        d = np.array([dn[0] for dn, _ in found])
        near = np.array([dn[1] @ T[:3, :3].T + T[:3, 3] for dn, T in found])
        k = np.argmin(d, axis=0)
        return d[k, np.arange(len(points))], near[k, np.arange(len(points))]

    def slab_front(self) -> float:
        """The slab stops behind every socket face (its trailing corner), one clearance back."""
        ys = []
        for f in FINGERS:
            T = self.T_socket(f)
            W = mm(self.params.fingers[f].width)
            for sx in (-W / 2.0, W / 2.0):
                ys.append((T @ np.array([sx, 0.0, 0.0, 1.0]))[1])
        return min(ys) - self.tol.clearance

    # -- the thenar: the CMC's column, its pulley and the thumb drive's turn --------
    def T_cmc(self) -> np.ndarray:
        return _mm(F.T_palm_thumb_cmc_base(self.params))

    def thenar(self) -> dict:
        """``thenar.thenar`` in mm (CMC base frame: distances along the CMC axis)."""
        return {k: mm(v) for k, v in TH.thenar(self.params).items()}

    def thumb_tendon_path(self) -> list[np.ndarray]:
        """Palm-frame points (mm) of the thumb drive on the palm (``wrist.thumb_drive_path``)."""
        return wrist.thumb_drive_path(self.params)

    def thenar_tools(self) -> list:
        """The journal (from below the palmar face to the cavity), the pulley's cavity and its slot
        out of the palm toward servo 6 (CMC base frame): the loop's two strands run in it, in the
        pulley's plane, and the pulley slides in through it."""
        t = self.thenar()
        R, h, q = t["cavity_r"], t["cavity_h"], t["pulley"]
        z0, z1, rj = self.journal()
        journal = cylinder((0.0, 0.0, z0), (0.0, 0.0, z1), rj)
        cavity = cylinder((0.0, 0.0, q - h), (0.0, 0.0, q + h), R)
        return [journal, cavity, *(transform(box(0.0, length, -R, R, -h, h), M) for M, length in self.cavity_sweeps())]

    def journal(self) -> tuple[float, float, float]:
        """(z0, z1, radius) of the CMC column's journal (CMC base frame): from below the palmar face
        all round (the axis is tilted: the journal's end disc too) to half a millimetre into the
        pulley's cavity."""
        t = self.thenar()
        az = self.T_cmc()[2, 2]
        below = 1.0 + t["journal_r"] * math.sqrt(max(1.0 - az * az, 0.0)) / az
        return t["face"] - below, t["pulley"] - t["cavity_h"] + 0.5, t["journal_r"]

    def cavity_sweeps(self) -> list[tuple[np.ndarray, float]]:
        """(frame, length) of each sweep of the CMC pulley's cavity (CMC base frame: the frame's x
        along the sweep in the pulley's plane, its origin on the axis at the pulley's mid-plane; the
        sweep a box from x = 0 to the length, the cavity's radius either side, its height): toward
        servo 6 (servo 6's pulley lies in that plane) out of the palm, and, where the cavity reaches
        the palm's back face (``servo_geometry.palm_back`` is its back), on out through that face (a
        cylinder tangent to the face, or one sampled a hair inside it, left a skin of 0 to 0.55 mm)."""
        t = self.thenar()
        R, h, q = t["cavity_r"], t["cavity_h"], t["pulley"]

        def frame(v: np.ndarray) -> np.ndarray:
            M = np.eye(4)
            M[:3, 0], M[:3, 1], M[:3, 2], M[:3, 3] = v, np.cross([0.0, 0.0, 1.0], v), (0.0, 0.0, 1.0), (0.0, 0.0, q)
            return M

        phi = FL.cmc_loop_direction(self.params) + math.pi
        out = [(frame(np.array([math.cos(phi), math.sin(phi), 0.0])), 4.0 * R + 60.0)]
        back = self.back_sweep()
        if back is not None:
            v, n = back
            depth = ((self.T_cmc() @ np.array([0.0, 0.0, q, 1.0]))[1] - mm(SG.palm_back(self.params)) + 2.0 * (R + h)) / n
            out.append((frame(v), depth))
        return out

    def thenar_gap(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(distance, nearest point) from each of ``points`` (palm frame, mm) to the thenar's cuts
        (:meth:`thenar_tools`: the journal, the CMC pulley's cavity and its sweeps)."""
        t = self.thenar()
        R, h, q = t["cavity_r"], t["cavity_h"], t["pulley"]
        Tc = self.T_cmc()
        local = (points - Tc[:3, 3]) @ Tc[:3, :3]               # CMC base frame
        found = [(nearest_on_cylinder(local, *self.journal()), Tc), (nearest_on_cylinder(local, q - h, q + h, R), Tc)]
        for M, length in self.cavity_sweeps():
            W = Tc @ M
            found.append((nearest_on_box((points - W[:3, 3]) @ W[:3, :3], (0.0, -R, -h), (length, R, h)), W))
        d = np.array([dn[0] for dn, _ in found])
        near = np.array([dn[1] @ W[:3, :3].T + W[:3, 3] for dn, W in found])
        k = np.argmin(d, axis=0)
        return d[k, np.arange(len(points))], near[k, np.arange(len(points))]

    def cavity_lip_openings(self) -> list:
        """Where a sweep of the CMC pulley's cavity (:meth:`cavity_sweeps`, tilted with the CMC axis)
        rises within two perimeters (and the mesh's tolerance) of the palm's dorsal face, the lip
        between them is cut away: its top face's part that close, extruded up through the dorsal
        face (palm frame). Nothing where every sweep stays below."""
        t = self.thenar()
        R, h = t["cavity_r"], t["cavity_h"]
        Tc = self.T_cmc()
        top = self.thickness / 2.0
        out = []
        for M, length in self.cavity_sweeps():
            W = Tc @ M
            corners = [(W @ np.array([x, y, h, 1.0]))[:3] for x, y in ((0.0, -R), (length, -R), (length, R), (0.0, R))]
            cos = abs(W[2, 2])                              # the top face's tilt from the dorsal face
            lip = (mm(FLANK) + mm(self.params.print.stl_tolerance) * 2.0) / max(cos, 1e-6)
            poly = _clip_above(corners, top - lip)
            if len(poly) >= 3:
                out.append(extrude_up(poly, top + 1.0 - min(p[2] for p in poly)))
        return out

    def cavity_face_openings(self) -> list:
        """Where the CMC pulley's cavity or a sweep of it (:meth:`thenar_tools`) comes within two
        perimeters (and the mesh's tolerance, over the cosine of a face turned :data:`FACE_DEG` from
        it) of the thenar block's radial face (:meth:`thenar_block`), the material between is cut
        away: that part of the cut (its cavity a prism of plane faces holding the cylinder) swept
        radially out through the face (palm frame), and on up or down through the dorsal or palmar
        face where it comes as close to that too. The sweeps, tilted with the CMC axis, run at an
        angle to the face: a lip left between them would taper to nothing. Nothing where the cuts
        stay further in."""
        lo, hi = self.thenar_block()
        if not np.all(hi > lo):
            return []
        t = self.thenar()
        R, h, q = t["cavity_r"], t["cavity_h"], t["pulley"]
        Tc = self.T_cmc()
        lip = (mm(FLANK) + 2.0 * mm(self.params.print.stl_tolerance)) / math.cos(math.radians(FACE_DEG))
        face, top = float(lo[0]), self.thickness / 2.0
        cuts = [transform(polygon_cylinder((0.0, 0.0, q - h), (0.0, 0.0, q + h), R, 64), Tc)]
        cuts += [transform(box(0.0, length, -R, R, -h, h), Tc @ M) for M, length in self.cavity_sweeps()]
        reach = 2.0 * (hi[1] - lo[1] + hi[2] - lo[2]) + 4.0 * R + 200.0
        near = box(face - reach, face + lip, lo[1] - reach, hi[1] + reach, lo[2] - reach, hi[2] + reach)
        out = []
        for cut in cuts:
            part = cut & near
            if part is None or part.volume <= 1e-9:             # None: nothing in common
                continue
            opening = _fused(swept_along(part, (-(lip + reach), 0.0, 0.0)))
            # on out through the dorsal or palmar face where the part comes that close to it too: a
            # rod would stand along the corner between the two openings
            inside = part & box(face, face + lip, lo[1], hi[1], -top, top)
            if inside is None or inside.volume <= 1e-9:
                continue
            bb = inside.bounding_box()
            if bb.max.Z > top - lip:
                opening = _fused(swept_along(opening, (0.0, 0.0, 2.0 * top)))
            if bb.min.Z < -top + lip:
                opening = _fused(swept_along(opening, (0.0, 0.0, -2.0 * top)))
            out.append(opening)
        return out

    def back_sweep(self) -> tuple[np.ndarray, float] | None:
        """(v, n): the unit vector, in the CMC base frame and the pulley's plane, along which the
        pulley's cavity is swept out through the palm's back face (the palm's -y projected into that
        plane), and the length n of that projection; None when the CMC axis lies along the palm's y."""
        back = -self.T_cmc()[1, :3]             # the palm's -y in the CMC base frame
        n = math.hypot(back[0], back[1])
        if n <= 1e-6:
            return None
        return np.array([back[0] / n, back[1] / n, 0.0]), n

    def thumb_channel_relief(self, path: list[np.ndarray]) -> list:
        """Where the thumb drive's channel enters the back face over the CMC pulley cavity's back
        opening (``thenar_tools``: the cavity swept out through the back face) with less than two
        perimeters (``rules.MIN_WALL``) of palm between them, the material between is cut: a slot of
        the channel's width from the channel down into the opening, from outside the back face to
        where the wall reaches two perimeters (the 170 mm hand: a 0.52 mm skin otherwise). The cord
        runs in its channel's slot there, open toward the cavity. [] where the wall is thick enough.
        ``path``: ``thumb_tendon_path()``."""
        from ...params.rules import MIN_WALL

        back = self.back_sweep()
        if back is None:
            return []
        v = back[0]
        w = np.cross([0.0, 0.0, 1.0], v)
        t = self.thenar()
        T0 = self.T_cmc()
        R, h, q = t["cavity_r"], t["cavity_h"], t["pulley"]
        r = self.tol.tendon_hole / 2.0
        p0, p1 = path[:2]
        Ti = np.linalg.inv(T0)
        y_back = mm(SG.palm_back(self.params))
        ss = np.linspace(0.0, 1.0, 401)
        thin = []
        for s in ss:
            x = p0 + s * (p1 - p0)
            c = (Ti @ np.append(x, 1.0))[:3]
            over = c @ v >= 0.0 and abs(c @ w) <= R + r
            if x[1] >= y_back - 1.0 and over and c[2] - q - h - r < mm(MIN_WALL):
                thin.append(s)
        if not thin:
            return []
        s0, s1 = min(thin), min(max(thin) + 1.0 / 400.0, 1.0)
        a0, a1 = p0 + s0 * (p1 - p0), p0 + s1 * (p1 - p0)
        d = (a1 - a0) / np.linalg.norm(a1 - a0)
        axis = T0[:3, 2]
        z = axis - (axis @ d) * d
        z /= np.linalg.norm(z)
        # down to a hair inside the opening's top face (the plane z_CMC = q + h)
        drop = max(float((Ti @ np.append(a, 1.0))[2] - q - h) for a in (a0, a1)) + 0.05
        drop /= float(z @ axis)
        M = np.eye(4)
        M[:3, 0], M[:3, 1], M[:3, 2], M[:3, 3] = d, np.cross(z, d), z, a0
        return [transform(box(0.0, float(np.linalg.norm(a1 - a0)), -r, r, -drop, 0.0), M)]

    def finger_drive(self, finger: str) -> tuple[np.ndarray, np.ndarray]:
        """(exit, tangent) of a finger's drive through the palm (palm frame, mm): from its socket's
        exit straight back to its servo pulley's tangent point."""
        tangent, _ = self.drive_line(chain(finger).servo)
        return (self.T_socket(finger) @ np.array([0.0, 0.0, self.tendon_z, 1.0]))[:3], tangent

    def drive_channels(self) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
        """(name, a, b, radius) of each drive's channel through the palm, a cylinder from a to b
        (palm frame, mm): each finger drive from a millimetre before its socket's exit to one past
        its servo pulley's tangent point; the thumb drive from a millimetre before servo 1's tangent
        to its turn, and from the turn down the CMC axis past the cavity's ceiling by as much again;
        its turn a sphere (a = b) of the relief's radius."""
        r = self.tol.tendon_hole / 2.0
        out = []
        for f in FINGERS:
            exit_, tangent = self.finger_drive(f)
            u = (tangent - exit_) / np.linalg.norm(tangent - exit_)
            out.append((f"{f} drive", exit_ - u, tangent + u, r))
        pts = self.thumb_tendon_path()
        u = (pts[1] - pts[0]) / np.linalg.norm(pts[1] - pts[0])
        out += [("thumb drive", pts[0] - u, pts[1], r), ("thumb drive's turn", pts[1], pts[1], self.tol.tendon_relief / 2.0),
                ("thumb drive", pts[1], pts[2] - (pts[1] - pts[2]), r)]
        return out

    def pilot_gap(self, centre: np.ndarray) -> tuple[float, str]:
        """(gap (mm), cut) from a tab screw's pilot at ``centre`` (on the dorsal face; the pilot a
        cylinder from a millimetre above down its engagement) to the palm's nearest cut it could
        meet there: a drive's channel (:meth:`drive_channels`, its axis sampled every PILOT_SAMPLE
        against the pilot's cylinder) or the thenar's cuts (:meth:`thenar_gap` from points on the
        pilot's side and floor, as far apart)."""
        t, h = self.tol, PILOT_SAMPLE
        rp, z0, z1 = t.screw_pilot / 2.0, -t.screw_engagement, 1.0
        best = (math.inf, "")
        for name, a, b, r in self.drive_channels():
            n = max(int(np.ceil(np.linalg.norm(b - a) / h)), 1)
            axis = a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)
            d = float(np.min(nearest_on_cylinder(axis - centre, z0, z1, rp)[0])) - r
            if d < best[0]:
                best = (d, name)
        ring = np.linspace(0.0, 2.0 * math.pi, max(int(np.ceil(2.0 * math.pi * rp / h)), 8), endpoint=False)
        zs = np.linspace(z0, z1, int(np.ceil((z1 - z0) / h)) + 1)
        side = np.array([(rp * math.cos(a), rp * math.sin(a), z) for z in zs for a in ring])
        floor = np.array([(rho * math.cos(a), rho * math.sin(a), z0)
                          for rho in np.arange(0.0, rp, h) for a in ring])
        d = float(np.min(self.thenar_gap(centre + np.vstack([side, floor]))[0]))
        return min(best, (d, "thenar's cut (CMC pulley cavity, journal)"))

    def tab_screws(self) -> list[np.ndarray]:
        """Centres (palm frame, mm) of the forearm tab's two screws on the dorsal face: each at its
        place (``wrist.tab_screw_places``) or moved in along the tab, in steps of SCREW_STEP, by the
        least that keeps its pilot two perimeters (``rules.MIN_WALL``) from the palm's cuts
        (:meth:`pilot_gap`): the pilot reaches three screw diameters into the palm, past the level
        of the drives that run under a thin palm's dorsal face. Both the palm's pilots and the
        module's clearance holes are drilled here. ParamError (field ``hardware.screw_diameter_mm``:
        the pilot's width and depth) where no place up to the tab's middle does."""
        from ...params import ParamError
        from ...params.rules import MIN_WALL

        lo, hi = wrist.tab(self.params)
        middle, wall = (lo[0] + hi[0]) / 2.0, mm(MIN_WALL)
        out = []
        for place, inward in wrist.tab_screw_places(self.params):
            steps = max(int(np.floor(inward * (middle - place[0]) / SCREW_STEP)), 0)
            closest = (-math.inf, "")
            for k in range(steps + 1):
                c = place + np.array([inward * k * SCREW_STEP, 0.0, 0.0])
                gap = self.pilot_gap(c)
                if gap[0] >= wall:
                    out.append(c)
                    break
                closest = max(closest, gap)
            else:
                raise ParamError("hardware.screw_diameter_mm", round(mm(self.params.hardware.screw_diameter), 6),
                                 f"the forearm tab's screw pilot in the palm's dorsal face comes within {closest[0]:.3f} "
                                 f"mm of the {closest[1]} wherever it is placed from x = {place[0]:.1f} mm to the "
                                 f"tab's middle ({middle:.1f} mm); it must keep {wall:g} mm (two perimeters): "
                                 "a smaller screw's pilot is narrower and shallower", self.params.source)
        return out

    def limiter_polygon(self, finger: str) -> list[tuple[float, float]]:
        """(y, z) outline (mm), in the finger base frame, of the palm's flexion limiter
        (``frames.limiter_outline``)."""
        return [(mm(y), mm(z)) for y, z in F.limiter_outline(self.params, finger)]

    def limiter_x(self, finger: str) -> tuple[float, float]:
        """Inner and outer |x| of the two rails: clear of the guide eyelet bosses, flush with the finger."""
        sec = DigitSection(self.params, finger)
        return sec.eyelet_boss_radius + self.tol.clearance, sec.width / 2.0

    def limiter_rails(self, finger: str):
        poly = self.limiter_polygon(finger)
        x0, x1 = self.limiter_x(finger)
        return [prism_x(poly, x0, x1), prism_x(poly, -x1, -x0)]

    # -- geometry ----------------------------------------------------------
    def build(self):
        # the face openings in a cut of their own: each is a cut swept out, its prisms on its faces
        return build(*self.solids(), self.cavity_face_openings())

    def collision_solids(self) -> list:
        """The convex solids the palm is fused from (boxes, the limiter rails' convex prisms),
        before its cuts: the stepped sockets' notches stay open, the channels, pockets and the
        thenar's cavity are filled."""
        return self.solids()[0]

    def solids(self) -> tuple[list, list]:
        """(body, tools): the convex solids fused into the palm and the tools cut from it."""
        t, Tp = self.tol, self.thickness
        x0, x1, y0, y1 = self.extents()
        body = [box(x0, x1, y0, y1, -Tp / 2.0, Tp / 2.0)]
        lo, hi = self.thenar_block()
        if np.all(hi > lo):
            body.append(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))
        heel = self.heel()
        if heel is not None:
            body.append(box(heel[0][0], heel[1][0], heel[0][1], heel[1][1], heel[0][2], heel[1][2]))
        tools = []
        channels = self.drive_channels()
        channels, thumb = dict(zip(FINGERS, channels)), channels[len(FINGERS):]
        # finger sockets
        for f in FINGERS:
            T = self.T_socket(f)
            slo, shi = self.socket_box(f)
            body.append(transform(box(slo[0], shi[0], slo[1], shi[1], slo[2], shi[2]), T))
            for m in self.magnet_centres(f):
                n = T[:3, 1]
                tools.append(cylinder(m + n, m - n * t.magnet_pocket_depth, t.magnet_pocket_d / 2.0))
            # tendon: socket exit straight back to the servo pulley's tangent point
            exit_, tangent = self.finger_drive(f)
            _, a, b, r = channels[f]
            u = (tangent - exit_) / np.linalg.norm(tangent - exit_)
            tools.append(cylinder(a, b, r))
            # where it passes the thenar's cuts or a side face less than a flank away (a drive
            # leaving the palm's side at a slant), it runs into them by a slot
            tools += channel_slots(exit_, u, float(np.linalg.norm(tangent - exit_)), t.tendon_hole / 2.0,
                                   [self.thenar_gap, self.outside_gap], mm(FLANK))
            # the drive's coupler (crimp stop and loop): a bore from the socket face to a clearance
            # past where it is at full travel (couplers.couplers); opened likewise to the side
            # where it runs by an outer face under a flank (the slot, narrower than the bore by
            # more than its clearances, does not let the coupler out)
            cp = self.couplers[f]
            tools.append(cylinder(exit_ - u, exit_ + u * mm(cp.bore_end), mm(cp.bore) / 2.0))
            tools += channel_slots(exit_ - u, u, 1.0 + mm(cp.bore_end), mm(cp.bore) / 2.0, [self.outside_gap],
                                   mm(FLANK))
        for lo, hi in self.gap_fillers():
            body.append(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))
        # flexion-limiting housing: two rails under each finger base whose sloped fronts are
        # where the proximal phalanx's palmar face lies at the MCP limit (Table I)
        for f in FINGERS:
            for rail in self.limiter_rails(f):
                body.append(transform(rail, _mm(F.T_palm_finger_base(self.params, f))))
        # the thenar: the journal, the CMC pulley's cavity and its radial slot
        Tc = self.T_cmc()
        tools += [transform(tool, Tc) for tool in self.thenar_tools()] + self.cavity_lip_openings()
        # thumb drive: from servo 1's pulley level to its turn above the cavity, down the CMC axis
        # (its run on down the column is the CMC base's)
        pts = self.thumb_tendon_path()
        u = (pts[1] - pts[0]) / np.linalg.norm(pts[1] - pts[0])
        (_, a0, b0, r0), (_, turn, _, rt), (_, a1, b1, r1) = thumb
        tools += [cylinder(a0, b0, r0), turn_sphere(turn, rt, u, pts[2] - pts[1]), cylinder(a1, b1, r1)]
        tools += self.thumb_channel_relief(pts)
        # (the CMC loop's two strands run in the cavity's slot toward servo 6: no channel)
        # pilot holes for the forearm module's tab screws, down from the dorsal face
        for p in self.tab_screws():
            tools.append(cylinder(p + np.array([0, 0, 1.0]), p - np.array([0, 0, t.screw_engagement]),
                                  t.screw_pilot / 2.0))
        return body, tools


#: the spacing (mm) of the points along a socket block's side at which it is found beside the open
#: space or beside another socket block, and along a drive at which its wall to that space is found
OUTSIDE_STEP = 0.05

#: the spacing (mm) of the points a tab screw's pilot is measured at against the palm's cuts
PILOT_SAMPLE = 0.05

#: the step (mm) by which a tab screw moves in along the tab off the palm's cuts [choice]
SCREW_STEP = 0.25


def _fused(pieces: list):
    """One solid of a convex sweep's pieces (``common.swept_along``)."""
    return as_solid(pieces[0].fuse(*pieces[1:]).clean())


def _clip_above(poly: list[np.ndarray], z: float) -> list[np.ndarray]:
    """The part of a planar polygon (its vertices in order) at or above height z
    (Sutherland-Hodgman against one plane)."""
    out = []
    for a, b in zip(poly, poly[1:] + poly[:1]):
        if a[2] >= z:
            out.append(a)
        if (a[2] >= z) != (b[2] >= z):
            out.append(a + (b - a) * (z - a[2]) / (b[2] - a[2]))
    return out
