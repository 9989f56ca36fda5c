"""The pinch as the printed fingertips meet, without CAD (numpy only; link frames, right hand, mm
like ``cad.grasp``, which measures the same pinch on the solids).

``kinematics.opposition`` models each fingertip by the capsule inside it. The printed tip
(``cad.parts.phalanx``) is that capsule's cylinder cut square at the digit's width: a box from the
clevis slot's back to the tip's axis and a half cylinder about the link's x beyond it. Where the
capsules meet at an angle, the square ends' rims stand up to 2.8 mm proud of the capsule's round
ends, and the solids meet there first: a contact the capsules put on the pad can land on the tip's
end on the solids (the thumb's rim, 0.1-2.4 mm dorsal of its pad: docs/opposition.md, "On the
printed tips").

:class:`PrintedTip` is that shape, with the exact distance of a point to it (the least of the
distances to the box and to the half cylinder, each a clamp). Two tips' distance is the least
distance of either tip's surface samples (:data:`SPACING_MM` apart, the rims included) to the other
tip: at most the samples' spacing over the true one, never under it.

:func:`first_pinch` closes the finger onto the still thumb at the model's contacts
(``opposition.contact_commands``, the bisection ``power_grasp.close_onto``, the pad test
:func:`on_pad`, the thumb's tip clear of the finger's middle phalanx: on a long thin hand it can
reach under it, 213 x 75 mm's ring) for any distance: :func:`printed_pinch` with these shapes' (what ``size`` asks of a
placement before it writes it), ``cad.grasp.solid_contact`` with OpenCascade's on the solids.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .. import units
from . import frames as F
from . import link_frames as LF
from . import opposition
from .hand_params import HandParams
from .power_grasp import REACH_MM, close_onto
from .topology import THUMB_CHAIN, chain, digit_links

#: the spacing (mm) of a tip's surface samples
SPACING_MM = 0.25


@dataclass(frozen=True)
class PrintedTip:
    """A distal phalanx's tip as printed, in its link frame (mm): the box x in [-w, w], y in
    [back, L - r], z in [-h, h] and the half cylinder of radius r about the line y = L - r, z = 0,
    y >= L - r, over the same x."""
    length: float           # L
    radius: float           # r
    half_width: float       # w
    half_thickness: float   # h
    back: float             # the clevis slot's back: where the box starts

    @classmethod
    def middle_of(cls, params: HandParams, finger: str) -> "PrintedTip":
        """A finger's middle phalanx as printed, near enough: its width and thickness from the PIP
        axis to the DIP axis, rounded about the DIP axis by half its thickness (the clevis's cheeks
        round the joint's boss)."""
        d = params.digit(finger)
        h = units.mm(d.thickness) / 2.0
        length = units.mm(F.segment_length(params, digit_links(finger)[-2]))
        return cls(length + h, h, units.mm(d.width) / 2.0, h, 0.0)

    @classmethod
    def of(cls, params: HandParams, digit: str) -> "PrintedTip":
        L, r, w = F.fingertip(params, digit)
        d = params.digit(digit)
        return cls(units.mm(L), units.mm(r), units.mm(w), units.mm(d.thickness) / 2.0,
                   units.mm(F.slot_back(d.thickness, params.print.hole_clearance)))

    def closest(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The distance (n,) of points p (n, 3) to the tip (0 inside) and the tip's nearest points
        (n, 3)."""
        w, h, r, yc = self.half_width, self.half_thickness, self.radius, self.length - self.radius
        box = np.clip(p, (-w, self.back, -h), (w, yc, h))
        dy = np.maximum(p[:, 1] - yc, 0.0)
        rho = np.hypot(dy, p[:, 2])
        scale = np.where(rho > r, r / np.maximum(rho, 1e-300), 1.0)
        cyl = np.stack([np.clip(p[:, 0], -w, w), yc + dy * scale, p[:, 2] * scale], axis=1)
        d_box, d_cyl = np.linalg.norm(p - box, axis=1), np.linalg.norm(p - cyl, axis=1)
        nearer = (d_cyl < d_box)[:, None]
        return np.minimum(d_box, d_cyl), np.where(nearer, cyl, box)

    @cached_property
    def surface(self) -> np.ndarray:
        """Samples (n, 3) of the tip's surface, about :data:`SPACING_MM` apart: its outline in the
        y-z plane (the palmar face, the step to the half cylinder where it is thinner, the arc, the
        dorsal face) at x from -w to w, and its two end faces filled."""
        s, w, h, r = SPACING_MM, self.half_width, self.half_thickness, self.radius
        yc = self.length - r

        def line(a, b):
            n = max(int(math.ceil(math.dist(a, b) / s)), 1)
            t = np.linspace(0.0, 1.0, n + 1)[:-1, None]
            return np.asarray(a) + t * (np.asarray(b) - np.asarray(a))

        arc_n = max(int(math.ceil(math.pi * r / s)), 1)
        a = np.linspace(-math.pi / 2.0, math.pi / 2.0, arc_n + 1)
        outline = np.vstack([line((self.back, -h), (yc, -h)), line((yc, -h), (yc, -r)),
                             np.stack([yc + r * np.cos(a), r * np.sin(a)], axis=1),
                             line((yc, r), (yc, h)), line((yc, h), (self.back, h))])
        xs = np.linspace(-w, w, max(int(math.ceil(2.0 * w / s)), 1) + 1)
        mantle = np.column_stack([np.repeat(xs, len(outline)), np.tile(outline, (len(xs), 1))])
        gy, gz = np.meshgrid(np.arange(self.back, self.length, s), np.arange(-h, h, s), indexing="ij")
        inside = (gy <= yc) | (np.hypot(gy - yc, gz) <= r)
        face = np.column_stack([gy[inside], gz[inside]])
        ends = [np.column_stack([np.full(len(face), x), face]) for x in (-w, w)]
        return np.vstack([mantle, *ends])


def on_pad(params: HandParams, T_hand_link: np.ndarray, digit: str, point) -> bool:
    """Whether a point (hand frame, mm) of a digit's distal phalanx lies on its pad: in the link's
    frame (``T_hand_link``, mm) on its palmar half (z <= 0) and its distal half (y >= L / 2,
    ``frames.fingertip``)."""
    x = np.linalg.solve(T_hand_link, np.r_[np.asarray(point, float), 1.0])[:3]
    return bool(x[2] <= 0.0 and x[1] >= units.mm(F.fingertip(params, digit)[0]) / 2.0)


def tips_distance(a: PrintedTip, Ta: np.ndarray, b: PrintedTip, Tb: np.ndarray):
    """The distance (mm) of two tips posed by T_hand_link (mm) and their closest points (hand
    frame, mm): the nearer of each tip's surface samples to the other tip."""
    Ra, Rb = Ta[:3, :3], Tb[:3, :3]
    pa = a.surface @ Ra.T + Ta[:3, 3]                   # a's samples in the hand
    da, qa = b.closest((pa - Tb[:3, 3]) @ Rb)            # ... to b, in b's frame
    pb = b.surface @ Rb.T + Tb[:3, 3]
    db, qb = a.closest((pb - Ta[:3, 3]) @ Ra)
    i, j = int(np.argmin(da)), int(np.argmin(db))
    if da[i] <= db[j]:
        return float(da[i]), pa[i], qa[i] @ Rb.T + Tb[:3, 3]
    return float(db[j]), qb[j] @ Ra.T + Ta[:3, 3], pb[j]


@dataclass(frozen=True)
class Pinch:
    """Where the thumb's and a finger's distal phalanges meet pad to pad: the commands (rad, one per
    servo), their distance (mm) and closest points (hand frame, mm), and the model's contacts tried
    before it (why each was passed over)."""
    finger: str
    u: np.ndarray
    distance_mm: float
    thumb_point: np.ndarray
    finger_point: np.ndarray
    tried: tuple[str, ...]


def _distal(digit: str) -> str:
    return digit_links(digit)[-1].name


def first_pinch(hand, finger: str, distance, reach_mm: float = REACH_MM,
                n: int = opposition.CANDIDATES, blocked=lambda u: None) -> Pinch | None:
    """The first of the model's contacts (``opposition.contact_commands``) at which the finger,
    flexing from rest onto the still thumb, comes within (0, reach_mm] mm of it (``close_onto``)
    with the closest points on both pads (:func:`on_pad`) and nothing else in the way; None when
    none of the n does. ``distance(u)`` measures the two distal phalanges at commands u: (distance
    mm, T_hand_link (mm) of the thumb's and of the finger's, the closest point on each, hand frame,
    mm); ``blocked(u)`` says why the pinch at u is not clean (the thumb's tip meeting the finger's
    middle phalanx), or None."""
    p = hand.params
    k = chain(finger).servo
    tried: list[str] = []
    for u_end in opposition.contact_commands(hand, finger, n):
        def measure(s: float):
            u = u_end.copy()
            u[k] = s * u_end[k]
            return (*distance(u), u)

        where = f"{units.deg(u_end).round(2).tolist()} deg"
        found = close_onto(measure, reach_mm)
        if found is None:
            tried.append(f"{where}: not within (0, {reach_mm}] mm from rest to the contact, or already at rest")
            continue
        _, (d, Ta, Tb, pa, pb, u) = found
        if not (on_pad(p, Ta, THUMB_CHAIN.digit, pa) and on_pad(p, Tb, finger, pb)):
            tried.append(f"{where}: {d:.3f} mm apart, not pad to pad")
            continue
        why = blocked(u)
        if why is not None:
            tried.append(f"{where}: {d:.3f} mm apart pad to pad, but {why}")
            continue
        return Pinch(finger, u, float(d), np.asarray(pa, float), np.asarray(pb, float), tuple(tried))
    return None


def printed_pinch(hand, finger: str, reach_mm: float = REACH_MM, n: int = opposition.CANDIDATES) -> Pinch | None:
    """:func:`first_pinch` on the printed tips (right-hand frames), the thumb's tip kept off the
    finger's middle phalanx (:meth:`PrintedTip.middle_of`): what ``cad.grasp.solid_contact`` finds
    on the solids."""
    p = hand.params
    thumb, tip, middle = PrintedTip.of(p, THUMB_CHAIN.digit), PrintedTip.of(p, finger), PrintedTip.middle_of(p, finger)
    a_name, b_name, m_name = _distal(THUMB_CHAIN.digit), _distal(finger), digit_links(finger)[-2].name

    def poses(u):
        return LF.link_transforms(p, hand.forward(u, compensated=True), mirrored=False)

    def distance(u):
        T = poses(u)
        Ta, Tb = F.to_mm(T[a_name]), F.to_mm(T[b_name])
        d, pa, pb = tips_distance(thumb, Ta, tip, Tb)
        return d, Ta, Tb, pa, pb

    def blocked(u):
        T = poses(u)
        d, _, _ = tips_distance(thumb, F.to_mm(T[a_name]), middle, F.to_mm(T[m_name]))
        return None if d > 0.0 else f"the thumb's tip meets the {finger}'s middle phalanx"

    return first_pinch(hand, finger, distance, reach_mm, n, blocked)
