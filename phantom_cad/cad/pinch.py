"""Opposition on the solids: the servo commands at which the thumb's distal phalanx comes within
reach of an opposed fingertip, measured with OpenCascade on the built parts (docs/opposition.md).

The kinematic model (``kinematics.opposition``) finds where the fingertips' capsules meet; the
capsules lie inside the printed tips, so there the solids touch or overlap. This module turns a
model contact into a measured one: for each of the model's contacts (``model_contacts``: squarest
first, one per distinct thumb command), the thumb holds still and the finger flexes onto it from
rest; a bisection on the finger's command finds where OpenCascade's distance between the two
distal phalanges lies in (0, reach] mm (0 is touching or overlapping: OpenCascade cannot tell the
two apart, so it is never accepted). The first contact whose closest points lie on both pads
(``on_pad``) is returned (``solid_contact``).

Used by ``bench/hand_figures.py`` (the opposition pictures are drawn at these commands) and by
tests/cad/test_opposition_on_solids.py, which re-measures what it returns with other tools.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics import frames, opposition
from ..kinematics.topology import CMC_SERVO, N_SERVOS, THUMB_CHAIN, chain, digit_links
from .assembly import pose_transforms
from .measure import placed

#: the surface distance (mm) the pads must come within (issue 12)
REACH_MM = 1.0
#: how many of the model's contacts (distinct thumb commands, squarest first) are tried
CANDIDATES = 8
#: bisection steps on the finger's command (2^-40 of its travel)
STEPS = 40


@dataclass(frozen=True)
class SolidContact:
    """A measured pinch: the commands (rad, one per servo), the solids' distance there (mm) and
    the closest points (hand frame, mm) on the thumb's and the finger's distal phalanges."""
    finger: str
    u: np.ndarray
    distance_mm: float
    thumb_point: np.ndarray
    finger_point: np.ndarray
    tried: tuple[str, ...]       # the model contacts tried before it (why each was passed over)


def model_contacts(hand, finger: str, n: int = CANDIDATES) -> list[np.ndarray]:
    """The model's command vectors where the thumb's tip meets the finger's (capsules overlapping
    by at most ``opposition.CONTACT_BAND``), squarest first (the facing angle), one per distinct
    thumb command, at most n."""
    p = hand.params
    T0 = frames.thumb_cmc_placement(p.palm.thumb_cmc_offset, p.palm.thumb_cmc_axis)
    thumb = opposition.thumb_tips(hand).placed(T0)
    tips = opposition.finger_tips(hand, finger)
    gap, angle = opposition.contacts(thumb, tips)
    ok = (gap <= 0.0) & (gap >= -opposition.CONTACT_BAND)
    out, seen = [], set()
    for flat in np.argsort(np.where(ok, angle, np.inf), axis=None, kind="stable"):
        i, j = np.unravel_index(int(flat), gap.shape)
        if not ok[i, j] or len(out) == n:
            break
        if i in seen:
            continue
        seen.add(i)
        u = np.zeros(N_SERVOS)
        u[THUMB_CHAIN.servo], u[CMC_SERVO] = thumb.u[i]
        u[chain(finger).servo] = tips.u[j, 0]
        out.append(u)
    return out


def on_pad(params, T_hand_link: np.ndarray, digit: str, point) -> bool:
    """Whether a point (hand frame, mm) of a digit's distal phalanx lies on its pad: in the link's
    frame on its palmar half (z <= 0) and its distal half (y >= L / 2, ``frames.fingertip``)."""
    x = np.linalg.solve(T_hand_link, np.r_[np.asarray(point, float), 1.0])[:3] * 1e-3
    return bool(x[2] <= 0.0 and x[1] >= frames.fingertip(params, digit)[0] / 2.0)


def _distal(digit: str) -> str:
    return digit_links(digit)[-1].name


def solid_contact(hand, solids: dict, finger: str, reach_mm: float = REACH_MM,
                  n: int = CANDIDATES) -> SolidContact | None:
    """The first of the model's contacts (``model_contacts``) at which the finger, flexing from rest
    onto the still thumb, brings the two distal phalanges within (0, reach_mm] mm of each other with
    the closest points on both pads; None when none of the n does. ``solids``: the built parts in
    their link frames (mm), at least the two distal phalanges."""
    p = hand.params
    a_name, b_name = _distal(THUMB_CHAIN.digit), _distal(finger)
    k = chain(finger).servo
    tried: list[str] = []
    for u_end in model_contacts(hand, finger, n):
        def measure(s: float):
            u = u_end.copy()
            u[k] = s * u_end[k]
            T = pose_transforms(p, hand.forward(u, compensated=True))
            a, b = placed(solids[a_name], T[a_name]), placed(solids[b_name], T[b_name])
            d, pa, pb = a.distance_to_with_closest_points(b)
            return u, T, d, np.array(tuple(pa)), np.array(tuple(pb))

        where = f"{np.degrees(u_end).round(2).tolist()} deg"
        if measure(0.0)[2] <= reach_mm:
            tried.append(f"{where}: the finger at rest is already within reach")
            continue
        lo, hi, d = 0.0, 1.0, None
        for _ in range(STEPS):
            s = 0.5 * (lo + hi)
            u, T, d, pa, pb = measure(s)
            if d > reach_mm:
                lo = s
            elif d <= 0.0:
                hi = s
            else:
                break
        if not 0.0 < d <= reach_mm:
            tried.append(f"{where}: no command of the finger's brings the solids within (0, {reach_mm}] mm")
            continue
        if not (on_pad(p, T[a_name], THUMB_CHAIN.digit, pa) and on_pad(p, T[b_name], finger, pb)):
            tried.append(f"{where}: {d:.3f} mm apart, not pad to pad")
            continue
        return SolidContact(finger, u, float(d), pa, pb, tuple(tried))
    return None
