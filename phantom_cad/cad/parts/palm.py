"""Palm housing.

Frame: the palm (hand) frame (docs/frames.md): origin on the index MCP axis, x ulnar,
y distal, z dorsal. Built from:

* four finger sockets: blocks whose magnet faces sit where each finger base's magnet face
  sits at rest, turned by palm.arc_offset from finger to finger (the socket face normal is
  the finger column's y), each with two magnet pockets facing the finger base's pockets
  and the tendon exit at the palm's tendon height;
* the metacarpal block: from the wrist crease to the sockets, across the four fingers (the
  tendon servos sit in the forearm module behind the wrist, ``forearm.py``);
* the thenar housing of the direct-drive CMC servo, coaxial with the thumb CMC axis (open on the
  shaft side), joined to the block;
* tendon channels from each socket's tendon exit straight back toward its servo pulley in the
  forearm, each with the bore its drive's coupler (the crimp stop and the finger strand's
  loop, ``routing.couplers``) travels in, and the thumb tendon's channel up to the CMC post;
* two pilot holes on the dorsal face at the wrist for the forearm module's tab;
* the CMC post and arch: the thumb tendon climbs a post on servo 6's housing and reaches the
  CMC axis above the CMC base, so turning the thumb about the CMC does not change its length;
* the flexion-limiting housing (rails under each finger base, at the Table I MCP limit).
"""

from __future__ import annotations

import math

import numpy as np

from ... import units
from ...kinematics import frames as F
from ...kinematics import routing
from ...kinematics.topology import FINGERS, LINKS, SERVO_MOUNT, SERVOS, chain
from ..measure import circular_pockets
from .base import Part
from .common import DigitSection, Tolerances, box, build, cylinder, mm, prism_x, sphere, transform
from . import wrist
from .servos import ServoMount

#: the servos the palm holds (in its thenar housing: the direct-drive CMC servo)
PALM_SERVOS = tuple(s.index for s in SERVOS if SERVO_MOUNT[s.drive] == "palm")


def _mm(T):
    return F.to_mm(T)


class Palm(ServoMount, Part):
    """The palm housing: the root link."""

    SEGMENTS = ("palm",)
    COLOR = (0.55, 0.57, 0.60)

    def __init__(self, params):
        self.params = params
        self.link = next(ln for ln in LINKS if ln.parent is None)
        self.tol = Tolerances(params)
        self.thickness = mm(params.palm.thickness)
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
            ang = units.deg(math.acos(float(np.clip(a @ b, -1.0, 1.0))))
            if abs(ang - want) > 1e-6:
                out.append(f"{self.name}: socket normals {ang:.6f} deg apart, expected {want:g}")
        return out

    # -- placements (mm) ---------------------------------------------------
    def T_socket(self, finger: str) -> np.ndarray:
        return _mm(F.T_palm_socket(self.params, finger))

    def magnet_centres(self, finger: str) -> list[np.ndarray]:
        """Opening centres of the socket's magnet pockets, palm frame (mm)."""
        from .finger_base import FingerBase
        s = FingerBase(self.params, finger).magnet_offset
        T = self.T_socket(finger)
        return [(T @ np.array([sx, 0.0, 0.0, 1.0]))[:3] for sx in (-s, s)]

    @property
    def couplers(self) -> dict:
        """The finger drives' couplers (``routing.couplers``: metres, s from the socket face)."""
        return routing.couplers(self.params)

    def pocket_boxes(self, servo: int) -> list:
        """(lo, hi) corners, servo frame, of the boxes the thenar housing cuts for the servo's body
        and its flange ears: open on the shaft side (the servo drops in before the hub goes on)."""
        return self.open_pockets(servo, self.body_box(servo)[1][2] + self.tol.clearance + 1.0)

    def housing_box(self, servo: int):
        """(lo, hi) corners, servo frame, of the thenar housing around a servo outside the bay: a
        wall around its body and ears, up to its output face (``frames.thenar_housing_box``)."""
        lo, hi = F.thenar_housing_box(self.params)
        return np.array([mm(v) for v in lo]), np.array([mm(v) for v in hi])

    def metacarpal_x(self) -> tuple[float, float]:
        """x extent (mm) of the metacarpal block (``wrist.metacarpal_x``)."""
        return wrist.metacarpal_x(self.params)

    def extents(self):
        """x0, x1, y0, y1 (mm) of the metacarpal block: across the sockets, from the wrist crease
        to behind the socket faces."""
        x0, x1 = self.metacarpal_x()
        return x0, x1, mm(F.wrist_y(self.params)), self.slab_front()

    def _placed_box(self, T, lo, hi) -> np.ndarray:
        return F.box_corners(lo, hi) @ T[:3, :3].T + T[:3, 3]

    def thenar_web(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) palm frame (mm) of the web that joins the CMC servo's housing to the metacarpal
        block: radial of the block over the housing's length, the palm's thickness, as far radial
        as the CMC hub (which turns with the thumb) and the tendon post leave a clearance. Empty
        (lo not below hi) when the housing lies beyond the block's length or the hub or post reaches
        the block."""
        from .pulley import ServoPulley
        (k,) = PALM_SERVOS
        c = self.tol.clearance
        T = self.T_servo(k)
        hub = ServoPulley(self.params, k)
        r, h = hub.outer_radius, hub.width / 2.0
        a = self.cmc_arch()
        rp, w = a["r_post"], self.tol.wall
        stops = np.vstack([self._placed_box(T, (-r, -r, -h), (r, r, h)),
                           self._placed_box(self.T_cmc(), (-rp, a["y_post"] - rp, a["z_floor"] - w),
                                            (rp, a["y_post"] + rp, a["z_hi"]))])
        housing = self._placed_box(T, *self.housing_box(k))
        x0, _, y0, y1 = self.extents()
        Tp = self.thickness
        return (np.array([stops[:, 0].max() + c, max(y0, housing[:, 1].min()), -Tp / 2.0]),
                np.array([x0 + w, min(y1, housing[:, 1].max()), Tp / 2.0]))

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
        CMC axis (``kinematics.frames.thumb_arch``: the routing model runs the drive over them)."""
        return {k: mm(v) for k, v in F.thumb_arch(self.params).items()}

    def thumb_tendon_path(self) -> list[np.ndarray]:
        """Palm-frame points (mm) of the thumb drive on the palm (``wrist.thumb_drive_path``)."""
        return wrist.thumb_drive_path(self.params)

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
        return build(*self.solids())

    def collision_solids(self) -> list:
        """The convex solids the palm is fused from (boxes, the limiter rails' convex prisms, the
        CMC post and arch, servo 6's housing), before its cuts: the stepped sockets' notches and
        the thenar's outline stay open, the channels and pockets are filled."""
        return self.solids()[0]

    def solids(self) -> tuple[list, list]:
        """(body, tools): the convex solids fused into the palm and the tools cut from it."""
        t, Tp = self.tol, self.thickness
        x0, x1, y0, y1 = self.extents()
        body = [box(x0, x1, y0, y1, -Tp / 2.0, Tp / 2.0)]
        lo, hi = self.thenar_web()
        if np.all(hi > lo):
            body.append(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))
        tools = []
        # finger sockets
        for f in FINGERS:
            T = self.T_socket(f)
            W = mm(self.params.fingers[f].width)
            # back to the wrist crease, the block's turned back corners no further (the metacarpal
            # block fills the rest)
            depth = (T[1, 3] - y0 - W / 2.0 * abs(T[1, 0])) / T[1, 1]
            body.append(transform(box(-W / 2.0, W / 2.0, -depth, 0.0, -Tp / 2.0, Tp / 2.0), T))
            for m in self.magnet_centres(f):
                n = T[:3, 1]
                tools.append(cylinder(m + n, m - n * t.magnet_pocket_depth, t.magnet_pocket_d / 2.0))
            # tendon: socket exit straight back to the servo pulley's tangent point
            tangent, _ = self.drive_line(chain(f).servo)
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
        # the CMC servo's housing (pocket open on the shaft side, ear slots, flange pilots)
        for k in PALM_SERVOS:
            Ts = self.T_servo(k)
            for lo, hi in self.pocket_boxes(k):      # body pocket and ear slots
                tools.append(transform(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]), Ts))
            lo, hi = self.housing_box(k)
            body.append(transform(box(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]), Ts))
            tools += [transform(p, Ts) for p in self.pilot_tools(k)]
        # pilot holes for the forearm module's tab screws, down from the dorsal face
        for p in wrist.tab_screws(self.params):
            tools.append(cylinder(p + np.array([0, 0, 1.0]), p - np.array([0, 0, t.screw_engagement]),
                                  t.screw_pilot / 2.0))
        return body, tools
