"""Palm housing.

Frame: the palm (hand) frame (docs/frames.md): origin on the index MCP axis, x ulnar,
y distal, z dorsal. Built from:

* four finger sockets: blocks whose magnet faces sit where each finger base's magnet face
  sits at rest, turned by palm.arc_offset from finger to finger (the socket face normal is
  the finger column's y), each with two magnet pockets facing the finger base's pockets
  and the tendon exit at the palm's tendon height;
* the servo bay: a slab around the tendon servos (two staggered rows, shafts along the
  palm's x, each pulley straight behind its finger's socket) with their pockets (open on
  the dorsal side for assembly), pulley cavities and M2 pilot holes at the flange ears;
* the thenar housing of the direct-drive CMC servo, coaxial with the thumb CMC axis (open on the shaft side);
* tendon channels from each socket's tendon exit straight back to its servo pulley's
  tangent point, each with the bore its drive's coupler (the crimp stop and the finger strand's
  loop, ``routing.couplers``) travels in, and the thumb tendon's channel from servo 1 out of the
  palm's radial side;
* the CMC post and arch: the thumb tendon climbs a post on servo 6's housing and reaches the
  CMC axis above the CMC base, so turning the thumb about the CMC does not change its length;
* the flexion-limiting housing (rails under each finger base, at the Table I MCP limit).
"""

from __future__ import annotations

import math

import numpy as np

from ... import canon, units
from ...kinematics import frames as F
from ...kinematics import routing
from ...kinematics.topology import FINGERS, LINKS, SERVOS, THUMB_CHAIN, chain
from ..measure import circular_pockets
from .base import Part
from .common import DigitSection, Tolerances, box, build, cylinder, mm, prism_x, sphere, transform

#: the servos in the palm's servo bay (the direct-drive CMC servo sits in the thenar housing)
BAY_SERVOS = tuple(s.index for s in SERVOS if s.drive == "tendon")


def _mm(T):
    return F.to_mm(T)


class Palm(Part):
    """The palm housing: the root link."""

    SEGMENTS = ("palm",)
    COLOR = (0.55, 0.57, 0.60)

    def __init__(self, params):
        self.params = params
        self.link = next(ln for ln in LINKS if ln.parent is None)
        self.tol = Tolerances(params)
        self.thickness = mm(params.palm.thickness)
        sv = params.servo
        self.servo_body = tuple(mm(v) for v in sv.body)           # length, width, height
        self.flange_span = mm(sv.flange_span)
        self.shaft_offset = mm(params.cad.servo_shaft_offset)
        self.pulley_width = mm(params.cad.servo_pulley_width)
        self.tendon_z = mm(F.tendon_height(params))

    @classmethod
    def for_link(cls, params, link):
        return cls(params)

    @property
    def print_rotation(self) -> np.ndarray:
        return F.rot_x(math.pi)[:3, :3]            # on its dorsal face

    def inputs(self) -> dict:
        """Everything but the model's mechanics and effects: the palm carries every socket and servo."""
        doc = self.params.document
        out = {k: canon.plain(v) for k, v in doc.items() if k not in ("mechanics", "effects", "hand")}
        out["side"] = doc["hand"]["side"]
        out["hand_length_mm"] = doc["hand"]["hand_length_mm"]
        return out

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
            ang = units.deg(math.acos(float(np.clip(a @ b, -1.0, 1.0))))
            if abs(ang - want) > 1e-6:
                out.append(f"{self.name}: socket normals {ang:.6f} deg apart, expected {want:g}")
        return out

    # -- placements (mm) ---------------------------------------------------
    def T_socket(self, finger: str) -> np.ndarray:
        return _mm(F.T_palm_socket(self.params, finger))

    def T_servo(self, servo: int) -> np.ndarray:
        """Servo frame of servo ``servo`` (0-based index, topology.SERVOS)."""
        return _mm(F.T_palm_servo(self.params, servo))

    def magnet_centres(self, finger: str) -> list[np.ndarray]:
        """Opening centres of the socket's magnet pockets, palm frame (mm)."""
        from .finger_base import FingerBase
        s = FingerBase(self.params, finger).magnet_offset
        T = self.T_socket(finger)
        return [(T @ np.array([sx, 0.0, 0.0, 1.0]))[:3] for sx in (-s, s)]

    def pulley_radius(self, servo: int) -> float:
        return mm(F.servo_radius(self.params, servo))

    @property
    def couplers(self) -> dict:
        """The finger drives' couplers (``routing.couplers``: metres, s from the socket face)."""
        return routing.couplers(self.params)

    def _servo_box(self, what: str, grow: float):
        lo, hi = F.servo_boxes(self.params)[what]
        return np.array([mm(v) for v in lo]) - grow, np.array([mm(v) for v in hi]) + grow

    def body_box(self, servo: int, grow: float = 0.0):
        """The servo's body as (lo, hi) corners in its servo frame, grown by ``grow``
        (``frames.servo_boxes``)."""
        return self._servo_box("body", grow)

    def ear_box(self, servo: int, grow: float = 0.0):
        """The servo's flange ears (both, as one slab across the body) in its servo frame."""
        return self._servo_box("ears", grow)

    def cavity_radius(self, servo: int) -> float:
        return self.pulley_radius(servo) + mm(F.pulley_cavity_margin(self.params))

    def pocket_boxes(self, servo: int) -> list:
        """(lo, hi) corners, servo frame, of the boxes the palm cuts for the servo's body and its
        flange ears: open toward the dorsal face in the bay (drop-in from the back, ears in slots),
        open on the shaft side in the thenar housing (the servo drops in before the hub goes on)."""
        c = self.tol.clearance
        lo, hi = self.body_box(servo, grow=c)
        elo, ehi = self.ear_box(servo, grow=c)
        if servo in BAY_SERVOS:
            Tp = self.thickness
            return [(lo, np.array([Tp, hi[1], hi[2]])), (elo, np.array([Tp, ehi[1], ehi[2]]))]
        return [(lo, np.array([hi[0], hi[1], hi[2] + 1.0])), (elo, np.array([ehi[0], ehi[1], hi[2] + 1.0]))]

    def cavity_span(self, servo: int) -> tuple[float, float]:
        """z extent (servo frame) of a bay servo's pulley cavity: from the body's top to past the pulley."""
        c = self.tol.clearance
        return self.body_box(servo, grow=c)[1][2] - c, self.pulley_width / 2.0 + c

    def housing_box(self, servo: int):
        """(lo, hi) corners, servo frame, of the thenar housing around a servo outside the bay: a
        wall around its body and ears, up to its output face."""
        c, w = self.tol.clearance, self.tol.wall
        hlo, hhi = self.body_box(servo, grow=c + w)
        glo, ghi = self.ear_box(servo, grow=c + w)
        top = self.body_box(servo, grow=c)[1][2] - c
        return (np.array([hlo[0], min(hlo[1], glo[1]), hlo[2]]),
                np.array([hhi[0], max(hhi[1], ghi[1]), top]))

    def screw_points(self, servo: int) -> list[np.ndarray]:
        """Flange screw centres (servo frame) on the ears' underside, mid-ear, one each end."""
        L, W, H = self.servo_body
        e = (L / 2.0 + self.flange_span / 2.0) / 2.0
        z_under = self.ear_box(servo)[0][2]
        return [np.array([0.0, -self.shaft_offset + s * e, z_under]) for s in (-1.0, 1.0)]

    def _corners(self, T, lo, hi):
        pts = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        return (T @ pts.T).T[:, :3]

    def extents(self):
        """Slab x/y extents (mm) enclosing the socket roots and the bay's servos, one wall around."""
        w, c = self.tol.wall, self.tol.clearance
        pts = []
        for k in BAY_SERVOS:
            T = self.T_servo(k)
            lo, hi = self.body_box(k, grow=c + w)
            pts.append(self._corners(T, lo, hi))
            lo, hi = self.ear_box(k, grow=c + w)
            pts.append(self._corners(T, lo, hi))
            rc = self.cavity_radius(k) + w
            pts.append(self._corners(T, np.array([-rc, -rc, -self.pulley_width / 2.0 - c - w]),
                                     np.array([rc, rc, self.pulley_width / 2.0 + c + w])))
        pts = np.vstack(pts)
        y_front = self.slab_front()
        return pts[:, 0].min(), pts[:, 0].max(), pts[:, 1].min(), y_front

    def slab_front(self) -> float:
        """The slab stops behind every socket face (its trailing corner), one clearance back."""
        ys = []
        for f in FINGERS:
            T = self.T_socket(f)
            W = mm(self.params.fingers[f].width)
            for sx in (-W / 2.0, W / 2.0):
                ys.append((T @ np.array([sx, 0.0, 0.0, 1.0]))[1])
        return min(ys) - self.tol.clearance

    # -- thumb tendon over the CMC axis --------------------------------------
    def T_cmc(self) -> np.ndarray:
        return _mm(F.T_palm_thumb_cmc_base(self.params))

    def cmc_arch(self) -> dict:
        """Dimensions (CMC frame, mm) of the post and arch that carry the thumb tendon onto the
        CMC axis (``kinematics.routing.thumb_arch``: the routing model places them)."""
        return {k: mm(v) for k, v in routing.thumb_arch(self.params).items()}

    def thumb_tendon_path(self) -> list[np.ndarray]:
        """Palm-frame points (mm) of the thumb drive where the routing model runs it on the palm:
        where it leaves servo 1's pulley (tangent), the turn just outside the pulley's cavity, the
        post entry, the post top, the point above the CMC axis, the CMC axis at the arch's
        underside (``kinematics.routing``, right hand)."""
        st = next(s for r in routing.routes(self.params, right_handed=True)
                  if r.tendon.kind == "drive" and r.tendon.digit == THUMB_CHAIN.digit for s in r.strands)
        run = next(r for r in routing.runs(self.params, right_handed=True) if r.strand == st.name and "palm" in r.links)
        tangent = np.asarray(units.mm(np.array(run.ends["palm"][0])), float)
        pts = [np.asarray(units.mm(np.array(e.pos)), float) for e in st.elements
               if isinstance(e, routing.Point) and e.link == "palm"]
        return [tangent] + pts

    def cmc_arch_body(self):
        a = self.cmc_arch()
        w, r = self.tol.wall, a["r_post"]
        post = cylinder((0.0, a["y_post"], a["z_floor"] - w), (0.0, a["y_post"], a["z_hi"]), r)
        arch = box(-r, r, a["y_post"], r, a["z_lo"], a["z_hi"])
        return [post, arch]

    def cmc_arch_tools(self):
        """Tendon channel in the post and arch (CMC frame): relief spheres at the bends."""
        a = self.cmc_arch()
        t = self.tol
        r, rr = t.tendon_hole / 2.0, t.tendon_relief / 2.0
        e = np.array([0.0, a["y_post"], a["z_entry"]])
        top = np.array([0.0, a["y_post"], a["z_mid"]])
        over = np.array([0.0, 0.0, a["z_mid"]])
        # the entry hole is the channel from the turn (``build``: one cylinder along that line)
        return [sphere(e, rr), cylinder(e, top, r), sphere(top, rr),
                cylinder(top, over, r), sphere(over, rr),
                cylinder(over, (0.0, 0.0, a["z_lo"] - 1.0), r)]

    def limiter_polygon(self, finger: str) -> list[tuple[float, float]]:
        """(y, z) outline, in the finger base frame (MCP axis at the origin), of the palm's
        flexion limiter: from inside the socket block to the plane the proximal phalanx's
        palmar face (z_child = -thickness/2) reaches at the MCP upper limit."""
        sec = DigitSection(self.params, finger)
        q = sec.q_max[chain(finger).keys[0]]       # the reference joint (MCP)
        s, c = math.sin(q), math.cos(q)
        rb = sec.boss_radius
        Lb = mm(self.params.cad.finger_base_length)
        z_top = -sec.thickness / 2.0 - self.tol.clearance
        z_bot = -self.thickness / 2.0
        y_at = lambda z: (-rb - z * c) / s  # noqa: E731
        return [(-Lb - self.tol.wall, z_bot), (y_at(z_bot), z_bot), (y_at(z_top), z_top),
                (-Lb - self.tol.wall, z_top)]

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
        t, Tp = self.tol, self.thickness
        c, w = t.clearance, t.wall
        x0, x1, y0, y1 = self.extents()
        body = [box(x0, x1, y0, y1, -Tp / 2.0, Tp / 2.0)]
        tools = []
        # finger sockets
        for f in FINGERS:
            T = self.T_socket(f)
            W = mm(self.params.fingers[f].width)
            depth = T[1, 3] - y0
            body.append(transform(box(-W / 2.0, W / 2.0, -depth, 0.0, -Tp / 2.0, Tp / 2.0), T))
            for m in self.magnet_centres(f):
                n = T[:3, 1]
                tools.append(cylinder(m + n, m - n * t.magnet_pocket_depth, t.magnet_pocket_d / 2.0))
            # tendon: socket exit straight back to the servo pulley's tangent point
            k = chain(f).servo
            Ts = self.T_servo(k)
            r = self.pulley_radius(k)
            tangent = (Ts @ np.array([-r, 0.0, 0.0, 1.0]))[:3]   # servo x = palm z: bottom of the pulley
            exit_ = (T @ np.array([0.0, 0.0, self.tendon_z, 1.0]))[:3]
            u = (tangent - exit_) / np.linalg.norm(tangent - exit_)
            tools.append(cylinder(exit_ - u, tangent + u, t.tendon_hole / 2.0))
            # the drive's coupler (crimp stop and loop): a bore from the socket face to a clearance
            # past where it is at full travel (routing.couplers)
            cp = self.couplers[f]
            tools.append(cylinder(exit_ - u, exit_ + u * mm(cp.bore_end), mm(cp.bore) / 2.0))
        # flexion-limiting housing: two rails under each finger base whose sloped fronts are
        # where the proximal phalanx's palmar face lies at the MCP limit (Table I)
        for f in FINGERS:
            for rail in self.limiter_rails(f):
                body.append(transform(rail, _mm(F.T_palm_finger_base(self.params, f))))
        # thumb tendon: from servo 1's pulley along its plane to the turn, then (in the air)
        # to the CMC post, up the post, along the arch and down the CMC axis into the thumb
        pts = self.thumb_tendon_path()
        u = (pts[1] - pts[0]) / np.linalg.norm(pts[1] - pts[0])
        tools.append(cylinder(pts[0] - u, pts[1], t.tendon_hole / 2.0))
        tools.append(sphere(pts[1], t.tendon_relief / 2.0))            # the turn
        tools.append(cylinder(pts[1], pts[2], t.tendon_hole / 2.0))   # through the post's entry
        Tc = self.T_cmc()
        for tool in self.cmc_arch_tools():
            tools.append(transform(tool, Tc))
        for part in self.cmc_arch_body():
            body.append(transform(part, Tc))
        # servo pockets, pulley cavities, flange screws
        for servo in SERVOS:
            k = servo.index
            Ts = self.T_servo(k)
            for lo, hi in self.pocket_boxes(k):      # body pocket and ear slots
                tools.append(transform(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]), Ts))
            if k in BAY_SERVOS:
                rc = self.cavity_radius(k)
                zc0, zc1 = self.cavity_span(k)
                tools.append(transform(cylinder((0, 0, zc0), (0, 0, zc1), rc), Ts))
                tools.append(transform(box(0.0, Tp, -rc, rc, zc0, zc1), Ts))
            else:
                lo, hi = self.housing_box(k)
                body.append(transform(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]), Ts))
            for p in self.screw_points(k):
                tools.append(transform(cylinder(p + np.array([0, 0, 1.0]), p - np.array([0, 0, c + t.screw_engagement]),
                                                t.screw_pilot / 2.0), Ts))
        return build(body, tools)
