"""Grasps measured on the solids: the servo commands at which the built parts close onto what they
hold, with OpenCascade's distances (docs/opposition.md, docs/parts.md "Power grasp").

Both grasps close a digit from rest onto something that holds still, by a bisection on the digit's
command (``close_onto``): the solids' distance must end in (CONFUSION_MM, reach] mm (0 is touching or
overlapping: OpenCascade cannot tell the two apart, and on overlapping solids its distance can come
out a few 1e-15 mm instead of 0, so nothing at or under its confusion tolerance is accepted).

**Pinch** (``solid_contact``). The kinematic model (``kinematics.opposition``) finds where the
fingertips' capsules meet; the capsules lie inside the printed tips, so there the solids touch or
overlap. For each of the model's contacts (``opposition.contact_commands``: squarest first, one per distinct
thumb command), the thumb holds still and the finger flexes onto it from rest. The first contact
whose closest points lie on both pads (``printed_tips.on_pad``), with the thumb's distal phalanx
clear of the finger's middle one, is returned.

**Power grasp** (``cylinder_grasp``, ``power_grasp``). A cylinder lies across the palm, its axis
along the knuckle line (the palm frame's x), resting against the palm (``PALM_GAP_MM`` off it,
``resting_axis_z``), laid against its heel where it has one (``kinematics.power_grasp``), and
spanning the finger bases; each finger flexes from rest until one of its
phalanges comes within reach of it; the thumb turns out of the way (the first command pair of a grid over its CMC's
and its IP/MP's travel where its parts clear the cylinder and the closed fingers). The first-contact
criterion (``CylinderGrasp.past_equator``): every finger touches it before the end of its travel at a
point past its equator (the *wrap angle*, about the axis from the palm's contact line (0 deg) toward
the fingertips, over 90 deg), so that at first contact each finger presses it toward the palm.
Whether the closing hand then holds it is a question of dynamics: tests/export/test_mjcf.py
simulates it in MuJoCo (it does, against the palm's heel: docs/parts.md "Power grasp").

**The fist** (``fingertips_to_palm``): each fingertip's distance to the palm with every tendon servo
at the end of its travel, which ``phantom-cad check`` reports (``export.check.fist_rows``).

Used by ``bench/hand_figures.py`` (the opposition and power-grasp pictures are drawn at these
commands) and by tests/cad/test_opposition_on_solids.py and tests/cad/test_power_grasp.py, which
re-measure what they return with other tools.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics import opposition
from ..kinematics.printed_tips import Pinch, first_pinch
from ..kinematics.power_grasp import CONFUSION_MM, PALM_GAP_MM, REACH_MM, STEPS, close_onto, laid_axis_y, wrap_angle_deg
from ..kinematics.topology import CMC_SERVO, FINGERS, THUMB_CHAIN, chain, digit_links
from .assembly import pose_transforms
from .measure import placed


#: ``resting_axis_z`` stops rising when its clearance is within this of the gap (mm)
ADVANCE_TOL_MM = 1e-9
#: the thumb's CMC and IP/MP commands tried (evenly over each travel) to turn it out of the way of the
#: power grasp's cylinder and the closed fingers
THUMB_CMC_STEPS, THUMB_FLEX_STEPS = 21, 5


def _distal(digit: str) -> str:
    return digit_links(digit)[-1].name


def solid_contact(hand, solids: dict, finger: str, reach_mm: float = REACH_MM,
                  n: int = opposition.CANDIDATES) -> Pinch | None:
    """The first of the model's contacts (``opposition.contact_commands``) at which the finger,
    flexing from rest onto the still thumb, brings the two distal phalanges within (0, reach_mm] mm of
    each other with the closest points on both pads; None when none of the n does
    (``printed_tips.first_pinch`` with OpenCascade's distance). ``solids``: the built parts in their
    link frames (mm), at least the two distal phalanges."""
    p = hand.params
    a_name, b_name, m_name = _distal(THUMB_CHAIN.digit), _distal(finger), digit_links(finger)[-2].name

    def distance(u):
        T = pose_transforms(p, hand.forward(u, compensated=True))
        a, b = placed(solids[a_name], T[a_name]), placed(solids[b_name], T[b_name])
        d, pa, pb = a.distance_to_with_closest_points(b)
        return d, T[a_name], T[b_name], np.array(tuple(pa)), np.array(tuple(pb))

    def blocked(u):
        if m_name not in solids:
            return None
        T = pose_transforms(p, hand.forward(u, compensated=True))
        d = placed(solids[a_name], T[a_name]).distance_to(placed(solids[m_name], T[m_name]))
        return None if d > CONFUSION_MM else f"the thumb's tip meets the {finger}'s middle phalanx"

    return first_pinch(hand, finger, distance, reach_mm, n, blocked)


# ---------------------------------------------------------------------------
# power grasp: a cylinder across the palm

@dataclass(frozen=True)
class FingerOnCylinder:
    """Where a finger, flexing from rest, first comes within reach of the cylinder: its command as
    a fraction of its travel, the distance (mm), the phalanx and point (hand frame, mm) closest to
    the cylinder, and the wrap angle (deg) of that point about the cylinder's axis."""
    finger: str
    fraction: float
    distance_mm: float
    link: str
    point: np.ndarray
    wrap_deg: float


@dataclass(frozen=True)
class CylinderGrasp:
    """A cylinder across the palm (axis along the palm frame's x at (axis_y_mm, axis_z_mm), from
    x_mm[0] to x_mm[1]) and how the hand closes on it: the commands ``u`` (rad; each finger at its
    contact, or at the end of its travel where it has none; the thumb out of the way), the palm's
    distance to it, each finger's contact (None: it never comes within reach, or already is at
    rest) and the thumb's distance at ``u`` from the cylinder and the closed fingers (None: no
    command on the thumb's grid clears them, or the fingers do not reach past its equator, where the
    thumb is not tried)."""
    diameter_mm: float
    axis_y_mm: float
    axis_z_mm: float
    x_mm: tuple[float, float]
    u: np.ndarray
    palm_mm: float
    fingers: dict
    thumb_mm: float | None

    @property
    def past_equator(self) -> bool:
        """Every finger touches the cylinder past its equator (wrap over 90 deg: at first contact it
        presses the cylinder toward the palm), and the thumb clears it. A necessary condition of a
        power grasp, not a sufficient one: it says nothing of where the cylinder goes as the
        fingers press on (tests/export/test_mjcf.py simulates that)."""
        return self.thumb_mm is not None and all(c is not None and c.wrap_deg > 90.0
                                                 for c in self.fingers.values())

    def solid(self):
        """The cylinder as a build123d solid (hand frame, mm)."""
        return cylinder_solid(self.diameter_mm, self.axis_y_mm, self.axis_z_mm, self.x_mm)


def full_travel(hand) -> np.ndarray:
    """The servo commands of the closed fist: every tendon servo at the end of its travel, the CMC's
    loop servo at rest."""
    u = np.array(hand.u_max, float)
    u[CMC_SERVO] = 0.0
    return u


def fingertips_to_palm(hand, solids: dict) -> dict[str, float]:
    """{finger: the distance (mm, OpenCascade's) from its distal phalanx to the palm} at
    :func:`full_travel` (the analytic model's joint angles), the palm at rest. ``solids``: the palm
    and the fingers' distal phalanges in their link frames (mm). A report, not a requirement: under
    the paper's Table I limits the curled fingertips stay 11-26 mm from the palm (docs/parts.md
    "Power grasp")."""
    p = hand.params
    T = pose_transforms(p, hand.forward(full_travel(hand)))
    palm = placed(solids["palm"], T["palm"])
    return {f: float(placed(solids[_distal(f)], T[_distal(f)]).distance_to(palm)) for f in FINGERS}


def cylinder_solid(diameter_mm: float, axis_y_mm: float, axis_z_mm: float, x_mm: tuple[float, float]):
    """A cylinder of ``diameter_mm`` whose axis runs along the hand frame's x from x_mm[0] to
    x_mm[1] at (y, z) = (axis_y_mm, axis_z_mm)."""
    from .parts.common import bd

    b = bd()
    length = x_mm[1] - x_mm[0]
    return b.Pos(0.5 * (x_mm[0] + x_mm[1]), axis_y_mm, axis_z_mm) * b.Rot(0, 90, 0) * b.Cylinder(
        diameter_mm / 2.0, length)


def cylinder_distance(shape, diameter_mm: float, axis_y_mm: float, axis_z_mm: float,
                      x_mm: tuple[float, float], cylinder=None) -> tuple[float, np.ndarray]:
    """(distance (mm), the shape's closest point (hand frame, mm)) from a shape to the cylinder of
    :func:`cylinder_solid`, as OpenCascade's distance between the solids gives it, in a third of its
    time where it can: d - R, d the shape's distance to the axis (a segment) at a point whose foot on
    the axis's line lies between its ends. Every point of the cylinder is within R of the axis, so
    no point of the shape comes nearer than d - R, and that point's foot makes it d - R (at or below
    0 the shape touches or enters the cylinder, where OpenCascade says 0). Otherwise (a cap may be
    nearest) the solids' distance."""
    from .parts.common import bd

    b = bd()
    axis = b.Edge.make_line(b.Vector(x_mm[0], axis_y_mm, axis_z_mm), b.Vector(x_mm[1], axis_y_mm, axis_z_mm))
    d, pa, _ = shape.distance_to_with_closest_points(axis)
    if x_mm[0] <= pa.X <= x_mm[1]:
        return d - diameter_mm / 2.0, np.array(tuple(pa))
    cyl = cylinder if cylinder is not None else cylinder_solid(diameter_mm, axis_y_mm, axis_z_mm, x_mm)
    d, pa, _ = shape.distance_to_with_closest_points(cyl)
    return d, np.array(tuple(pa))


def resting_axis_z(palm, diameter_mm: float, axis_y_mm: float, x_mm: tuple[float, float],
                   gap_mm: float = PALM_GAP_MM) -> float:
    """The z (mm, hand frame) of the axis of a cylinder across the palm at ``axis_y_mm``, as close to
    the palm solid as it comes with ``gap_mm`` between them (OpenCascade's distance): under the palmar
    face, or held off by the heel's edge where it reaches over it.

    Conservative advancement: from below the palm's lowest point, the cylinder rises by its measured
    clearance less the gap. The distance between two solids changes by at most the length of a
    translation, so no step passes the gap: one step under a flat face, a few under an edge (each
    leaves the clearance times 1 - cos of the contact normal's angle to z). What is left after
    ``STEPS`` steps (a contact normal near horizontal) is bisected."""
    R = diameter_mm / 2.0
    bb = palm.bounding_box()
    lo, hi = bb.min.Z - gap_mm - R, bb.max.Z            # at lo the cylinder clears the palm by gap_mm

    def clearance(z: float) -> float:
        return max(cylinder_distance(palm, diameter_mm, axis_y_mm, z, x_mm)[0], 0.0) - gap_mm

    for _ in range(STEPS):
        step = clearance(lo)
        if step <= ADVANCE_TOL_MM:
            return lo
        lo += step
    for _ in range(STEPS):
        mid = 0.5 * (lo + hi)
        if clearance(mid) >= 0.0:
            lo = mid
        else:
            hi = mid
    return lo


def _finger_links(finger: str) -> list[str]:
    """The links that move when the finger flexes (every one but its base)."""
    return [ln.name for ln in digit_links(finger)[1:]]


def cylinder_grasp(hand, solids: dict, diameter_mm: float, axis_y_mm: float,
                   reach_mm: float = REACH_MM) -> CylinderGrasp:
    """Close the hand on a cylinder of ``diameter_mm`` across the palm at ``axis_y_mm`` (palm frame):
    it rests against the palm (``PALM_GAP_MM`` off the palm solid, ``resting_axis_z``) and spans the
    finger bases (their solids' x extent, at rest). ``solids``: every part in its link frame (mm): the
    palm, the finger and thumb parts."""
    from .parts.common import bd

    p = hand.params
    T0 = pose_transforms(p)
    palm = placed(solids["palm"], T0["palm"])
    boxes = [placed(solids[ln.name], T0[ln.name]).bounding_box() for f in FINGERS for ln in digit_links(f)[:1]]
    x = (min(bb.min.X for bb in boxes), max(bb.max.X for bb in boxes))
    z = resting_axis_z(palm, diameter_mm, axis_y_mm, x)
    cyl = cylinder_solid(diameter_mm, axis_y_mm, z, x)
    lo = np.asarray(hand.u_min, float)
    span = np.asarray(hand.u_max, float) - lo
    u = lo.copy()
    fingers = {}
    for f in FINGERS:
        k, links = chain(f).servo, _finger_links(f)

        def measure(s: float):
            v = u.copy()
            v[k] = lo[k] + s * span[k]
            T = pose_transforms(p, hand.forward(v, compensated=True))
            best = None
            for n in links:
                d, pa = cylinder_distance(placed(solids[n], T[n]), diameter_mm, axis_y_mm, z, x, cyl)
                if best is None or d < best[0]:
                    best = (d, n, pa)
            return best

        found = close_onto(measure, reach_mm)
        if found is None:
            fingers[f] = None
            u[k] = lo[k] + span[k]
            continue
        s, (d, n, point) = found
        u[k] = lo[k] + s * span[k]
        fingers[f] = FingerOnCylinder(f, float(s), float(d), n, point, wrap_angle_deg(point, axis_y_mm, z))
    # the thumb out of the way of the cylinder and of the closed fingers (where the fingers reach past its
    # equator: elsewhere the grasp fails anyway): the first command pair, the CMC's grid outermost, the
    # IP/MP's inner, where the thumb's parts clear the cylinder, then the fingers
    thumb_mm = None
    if all(c is not None and c.wrap_deg > 90.0 for c in fingers.values()):
        T = pose_transforms(p, hand.forward(u, compensated=True))
        closed = bd().Compound(children=[placed(solids[n], T[n]) for f in FINGERS for n in _finger_links(f)])
        thumb_links = [ln.name for ln in digit_links(THUMB_CHAIN.digit)]
        k1 = THUMB_CHAIN.servo
        for s6 in np.linspace(0.0, 1.0, THUMB_CMC_STEPS):
            for s1 in np.linspace(0.0, 1.0, THUMB_FLEX_STEPS):
                u[CMC_SERVO] = lo[CMC_SERVO] + s6 * span[CMC_SERVO]
                u[k1] = lo[k1] + s1 * span[k1]
                T = pose_transforms(p, hand.forward(u, compensated=True))
                thumb = [placed(solids[n], T[n]) for n in thumb_links]
                d = min(cylinder_distance(t, diameter_mm, axis_y_mm, z, x, cyl)[0] for t in thumb)
                if d > 0.0:
                    d = min(d, min(t.distance_to(closed) for t in thumb))
                if d > 0.0:
                    thumb_mm = float(d)
                    break
            if thumb_mm is not None:
                break
    return CylinderGrasp(float(diameter_mm), float(axis_y_mm), float(z), (float(x[0]), float(x[1])), u.copy(),
                         float(palm.distance_to(cyl)), fingers, thumb_mm)


def power_grasp(hand, solids: dict, diameter_mm: float, step_mm: float = 5.0,
                reach_mm: float = REACH_MM) -> tuple[CylinderGrasp | None, list[CylinderGrasp]]:
    """(the grasp of the cylinder of ``diameter_mm`` across the palm if every finger reaches past its
    equator there (``CylinderGrasp.past_equator``), else None; every grasp tried). On a palm with a
    heel the cylinder is laid against it (``kinematics.power_grasp.laid_axis_y``), the one position
    tried; on a flat palm it is tried from the palm's distal edge (the axis over the palm solid's most
    distal point) toward the wrist in ``step_mm`` steps, as long as the axis lies over the palm, and
    the first position that wraps is the grasp."""
    p = hand.params
    laid = laid_axis_y(p, diameter_mm)
    if laid is not None:
        g = cylinder_grasp(hand, solids, diameter_mm, laid, reach_mm)
        return (g if g.past_equator else None), [g]
    T0 = pose_transforms(p)
    box = placed(solids["palm"], T0["palm"]).bounding_box()
    tried = []
    y = box.max.Y
    while y >= box.min.Y:
        g = cylinder_grasp(hand, solids, diameter_mm, y, reach_mm)
        tried.append(g)
        if g.past_equator:
            return g, tried
        y -= step_mm
    return None, tried
