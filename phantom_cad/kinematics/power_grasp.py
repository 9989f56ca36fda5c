"""The power grasp's cylinder across the palm, on the model (numpy only; palm frame, right hand,
mm like ``cad.grasp``, which measures the same grasp on the solids).

* Its size: the paper's 35 mm on its 189 mm hand, scaled with the hand's length
  (:func:`power_grasp_diameter_mm`).
* Where it lies: its axis along the knuckle line (the palm frame's x), :data:`PALM_GAP_MM` under the
  palmar face (:func:`resting_z`); on a palm with a heel, laid against it, :data:`PALM_GAP_MM` off
  the heel's front edge (:func:`laid_axis_y`: as a hand lays a bar into its palm, the heel stopping
  it on its wrist side).
* How each finger first meets it, flexing from rest (:func:`first_contacts`): each of the finger's
  phalanges as a box to its rounded far end's axis and that end round it (the clevis boss, the
  fingertip: ``finger_clearance.link_boxes``, ``rounded_ends``), over a fine grid of its command;
  the wrap angle of the closest point about the axis (:func:`wrap_angle_deg`). The shapes hold the
  parts, the rounded ends as the parts have them: which phalanx meets the cylinder first is the
  parts' (a box's corner past a round end would meet it early, and make the fingertip wrap it
  where the part's proximal phalanx meets it first).
* :func:`wrapping_axis_y`: the most distal axis at which every finger's first contact lies past
  the cylinder's equator, which ``sizing`` puts the heel behind.

Also the bisection both solid grasps close a digit with (:func:`close_onto`), which needs no solid.
"""

from __future__ import annotations

import math

import numpy as np

from .. import units
from .finger_clearance import BOX_EDGES, box_corners, link_boxes, posed_boxes, rounded_ends
from .forearm_layout import heel_box, heel_clear_y
from .hand_params import HandParams
from .servo_geometry import palm_back
from .topology import FINGERS, digit_links

#: the surface distance (mm) a grasp's contacts must come within to count as touching
REACH_MM = 1.0
#: bisection steps on a digit's command (2^-40 of its travel)
STEPS = 40
#: OpenCascade's confusion tolerance (Precision::Confusion, model units: mm): two points nearer than
#: this are one, so a distance at or under it is a contact, not a gap
CONFUSION_MM = 1e-7
#: how far (mm) the power grasp's cylinder lies off the palm's palmar face and off its heel: in
#: contact, within reach
PALM_GAP_MM = 0.5
#: the power grasp's cylinder: the paper's 35 mm on its 189 mm hand, scaled with the hand's length
POWER_GRASP_MM, POWER_GRASP_HAND_MM = 35.0, 189.0
#: the fractions of each finger's travel :func:`first_contacts` poses it at: a fingertip moves well
#: under :data:`REACH_MM` from one to the next, so the first within reach is not past it
CONTACT_GRID = np.linspace(0.0, 1.0, 401)
#: the step (mm) :func:`wrapping_axis_y` moves the cylinder by, from the knuckle line to the wrist
AXIS_STEP_MM = 0.5


def power_grasp_diameter_mm(params: HandParams) -> float:
    """The diameter (mm) of the power grasp's cylinder for a hand: :data:`POWER_GRASP_MM` times its
    length over :data:`POWER_GRASP_HAND_MM`."""
    return POWER_GRASP_MM * units.mm(params.hand_length) / POWER_GRASP_HAND_MM


def close_onto(distance_at, reach_mm: float = REACH_MM):
    """Bisection on a command fraction s in [0, 1] (0 the digit at rest, 1 at the end of the move)
    for a distance in (CONFUSION_MM, reach_mm]: ``distance_at(s)`` returns (distance mm, anything); the result
    is (s, that tuple) or None when the digit is already within reach at rest, never gets within
    reach at s = 1, or the bisection ends without a distance in the band."""
    first = distance_at(0.0)
    if first[0] <= reach_mm:
        return None
    last = distance_at(1.0)
    if last[0] > reach_mm:
        return None
    lo, hi = 0.0, 1.0
    for _ in range(STEPS):
        s = 0.5 * (lo + hi)
        r = distance_at(s)
        if r[0] > reach_mm:
            lo = s
        elif r[0] <= CONFUSION_MM:
            hi = s
        else:
            return s, r
    return None


def wrap_angle_deg(point, axis_y_mm: float, axis_z_mm: float) -> float:
    """The angle (deg, 0-360) of a point (hand frame, mm) about the cylinder's axis, from the palm's
    contact line (+z, dorsal: toward the palm) toward the fingertips (+y): 90 is the cylinder's
    distal side, 180 its palmar side, under it."""
    return float(units.deg(np.arctan2(float(point[1]) - axis_y_mm, float(point[2]) - axis_z_mm)) % 360.0)


def resting_z(params: HandParams, diameter_mm: float) -> float:
    """z (mm) of the axis of the cylinder lying :data:`PALM_GAP_MM` under the palmar face."""
    return -units.mm(params.palm.thickness) / 2.0 - PALM_GAP_MM - diameter_mm / 2.0


def laid_axis_y(params: HandParams, diameter_mm: float) -> float | None:
    """y (mm) of the axis of the cylinder laid against the palm's heel (``forearm_layout.heel_box``):
    at :func:`resting_z`, :data:`PALM_GAP_MM` off the heel's front (its lower front edge where the
    cylinder reaches under it); None for a flat palm."""
    if heel_box(params) is None:
        return None
    r = units.m(diameter_mm / 2.0 + PALM_GAP_MM)
    return units.mm(heel_clear_y(params, units.m(resting_z(params, diameter_mm)), r))


def first_contacts(params: HandParams, hand, diameter_mm: float, axis_y_mm: float,
                   axis_z_mm: float | None = None, posed: dict | None = None) -> dict:
    """{finger: (fraction of its travel, link, wrap angle deg) or None} where each finger, flexing
    from rest (the model's compensated joint angles), first comes within :data:`REACH_MM` of the
    cylinder whose axis runs along x at (axis_y_mm, axis_z_mm) (default :func:`resting_z`): its
    phalanges' shapes (:func:`posed_links`) over :data:`CONTACT_GRID`; None where it is within
    reach at rest or never is. The cylinder is taken as long as the hand is wide, so a shape's
    distance to it is its outline's (projected along x) distance to the axis, less the radius.
    ``posed``: :func:`posed_links`'s, reused across cylinders."""
    posed = posed if posed is not None else posed_links(params, hand)
    z = resting_z(params, diameter_mm) if axis_z_mm is None else axis_z_mm
    out = {}
    for f, (segments, links, radii) in posed.items():
        gap, point, box = cylinder_gaps(segments, radii, diameter_mm, axis_y_mm, z)
        within = np.flatnonzero(gap <= REACH_MM)
        if gap[0] <= REACH_MM or not len(within):
            out[f] = None
            continue
        i = int(within[0])
        out[f] = (float(CONTACT_GRID[i]), links[int(box[i])], wrap_angle_deg((0.0, *point[i]), axis_y_mm, z))
    return out


def cylinder_gaps(segments: np.ndarray, radii: np.ndarray, diameter_mm: float, axis_y_mm: float,
                  axis_z_mm: float):
    """(the least gap (mm) at each pose, the nearest point (y, z) there, the shape it lies on)
    between shapes whose edges projected along x are ``segments`` (poses, shapes, 12, 2, 2; mm),
    each grown by its radius (``radii``, mm), and the cylinder: the distance from the axis to a
    shape's outline, less both radii. Where the axis lies outside an outline, the outline's nearest
    point lies on a projected edge (the hull's edges are among them, the others lie inside it);
    inside, it is past contact, and no gap counts then."""
    q = np.array([axis_y_mm, axis_z_mm])
    a, b = segments[..., 0, :], segments[..., 1, :]
    ab = b - a
    t = np.clip(np.einsum("...i,...i", q - a, ab) / np.maximum(np.einsum("...i,...i", ab, ab), 1e-18), 0.0, 1.0)
    near = a + t[..., None] * ab
    d = np.linalg.norm(near - q, axis=-1) - np.asarray(radii)[None, :, None]   # (poses, shapes, 12)
    flat = d.reshape(d.shape[0], -1)
    k = flat.argmin(axis=1)
    box, edge = np.divmod(k, d.shape[2])
    rows = np.arange(len(k))
    return flat[rows, k] - diameter_mm / 2.0, near[rows, box, edge], box


def posed_links(params: HandParams, hand) -> dict:
    """{finger: (its moving links' shapes' edges projected along x (fractions, shapes, 12, 2, 2) mm,
    the link of each shape, each shape's radius mm)} over :data:`CONTACT_GRID`
    (``finger_clearance.posed_boxes``, compensated): each phalanx a box to its rounded end's axis,
    the tongue behind its joint, and the end round that axis (an edge, its radius the end's: the
    projection of the half cylinder lies within it)."""
    boxes = posed_boxes(params, hand, CONTACT_GRID, compensated=True, rounded=True)
    out = {}
    for f in FINGERS:
        per_link, ends = link_boxes(params, f, rounded=True), rounded_ends(params, f)
        links, radii = [], []
        for ln in digit_links(f)[1:]:
            n = len(per_link[ln.name])
            links += [ln.name] * n
            radii += [0.0] * (n - 1) + [units.mm(ends[ln.name][1])]
        corners = units.mm(box_corners(boxes[f][1]))[:, :, 1:]                     # (n, 8, (y, z))
        segments = corners[:, BOX_EDGES]                                           # (n, 12, 2, 2)
        out[f] = (segments.reshape(len(CONTACT_GRID), len(links), *segments.shape[1:]), links, np.array(radii))
    return out


def wrapping_axis_y(params: HandParams, hand, diameter_mm: float) -> float | None:
    """The most distal y (mm, on an :data:`AXIS_STEP_MM` grid from the knuckle line toward the wrist)
    at which every finger's first contact with the cylinder at :func:`resting_z`
    (:func:`first_contacts`) lies past its equator (wrap over 90 deg: it presses the cylinder toward
    the palm); None when none does over the palm, whose back the cylinder stays in front of."""
    posed = posed_links(params, hand)
    back = units.mm(palm_back(params)) + diameter_mm / 2.0
    for k in range(int(math.floor(-back / AXIS_STEP_MM)) + 1):
        y = -k * AXIS_STEP_MM
        found = first_contacts(params, hand, diameter_mm, y, posed=posed)
        if all(c is not None and c[2] > 90.0 for c in found.values()):
            return y
    return None
