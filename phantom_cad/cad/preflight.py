"""Rules of the palm's layout, checked when a parameter file loads (before any solid is built).

The palm places the thenar housing and the finger sockets from the frames
(phantom_cad.kinematics.frames); whether they fit together is a question of the parts'
own dimension classes, so these rules live here, numpy only (no OpenCascade), and raise the
same :class:`ParamError` as the schema. ``check`` is called by every command that loads a
parameter file for building or validating (``params validate``, ``build``, ``demo``).
"""

from __future__ import annotations

import itertools

import numpy as np

from ..kinematics.topology import FINGERS, SERVOS
from ..params import ParamError
from ..params.rules import MIN_WALL
from .parts.common import mm
from .parts.palm import PALM_SERVOS, Palm


def _obb(T: np.ndarray, lo, hi):
    """(centre, axes as columns, half extents) of the box [lo, hi] placed by T (mm)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c = T[:3, :3] @ ((lo + hi) / 2.0) + T[:3, 3]
    return c, T[:3, :3], (hi - lo) / 2.0


def overlap(a, b) -> float:
    """Penetration depth of two oriented boxes (separating-axis theorem), the smallest overlap
    along the 15 candidate axes (mm): when they are apart, minus their largest separation along
    those axes (a lower bound of their distance)."""
    ca, Ra, ha = a
    cb, Rb, hb = b
    d = cb - ca
    axes = [Ra[:, i] for i in range(3)] + [Rb[:, i] for i in range(3)]
    for i, j in itertools.product(range(3), range(3)):
        n = np.cross(Ra[:, i], Rb[:, j])
        if np.linalg.norm(n) > 1e-9:
            axes.append(n / np.linalg.norm(n))
    depth = np.inf
    for n in axes:
        ra = np.sum(ha * np.abs(Ra.T @ n))
        rb = np.sum(hb * np.abs(Rb.T @ n))
        depth = min(depth, ra + rb - abs(d @ n))
    return float(depth)


def servo_tools(palm: Palm, k: int) -> list:
    """The boxes the palm cuts for servo ``k`` (pocket, ear slots), as oriented boxes in the palm
    frame."""
    T = palm.T_servo(k)
    return [_obb(T, lo, hi) for lo, hi in palm.pocket_boxes(k)]


def magnet_pockets(palm: Palm, finger: str) -> list:
    """The socket's two magnet pockets as boxes around their cylinders, grown by the thinnest
    printable wall (params.rules.MIN_WALL)."""
    t = palm.tol
    T = palm.T_socket(finger)
    w = mm(MIN_WALL)
    r = t.magnet_pocket_d / 2.0 + w
    from .parts.finger_base import FingerBase
    s = FingerBase(palm.params, finger).magnet_offset
    return [_obb(T, (sx - r, -t.magnet_pocket_depth - w, -r), (sx + r, 0.0, r)) for sx in (-s, s)]


def check(params) -> None:
    """Raise ParamError if the palm's servo pockets reach a finger socket's magnet pockets, if
    the thenar housing of the CMC servo does not join the palm, or if the CMC servo's hub (which
    turns with the thumb) or the thumb tendon's post comes closer to the palm than a clearance; and
    if the routing model finds no clamp position for a loop or a drive (``routing.routes`` raises
    the ParamError: a joint's travel too large for its loop's pulleys and carrier), or a finger
    drive's coupler has no room in its palm channel or does not come out at the service angle
    (``routing.couplers``)."""
    from ..kinematics import routing

    routing.routes(params)
    routing.couplers(params)
    palm = Palm(params)
    src = params.source
    pockets = {f: magnet_pockets(palm, f) for f in FINGERS}
    for servo in (SERVOS[k] for k in PALM_SERVOS):
        for tool in servo_tools(palm, servo.index):
            for f, boxes in pockets.items():
                if any(overlap(tool, b) > 1e-9 for b in boxes):
                    raise ParamError(
                        "servo.flange_span_mm", round(mm(params.servo.flange_span), 6),
                        f"the palm's pocket for servo {servo.label} (body servo.body_mm, ears "
                        f"flange_span_mm, pulley cavity) leaves less than {mm(MIN_WALL):g} mm (two perimeters) to the "
                        f"{f} socket's magnet pockets: the servo does not fit behind the finger sockets", src)
    # the thenar housing (around the CMC servo) must join the palm (its metacarpal block or the web
    # between them) by at least a wall
    x0, x1, y0, y1 = palm.extents()
    slabs = [_obb(np.eye(4), (x0, y0, -palm.thickness / 2.0), (x1, y1, palm.thickness / 2.0))]
    lo, hi = palm.thenar_web()
    if np.all(hi > lo):
        slabs.append(_obb(np.eye(4), lo, hi))
    (k,) = PALM_SERVOS
    w = palm.tol.wall
    housing = _obb(palm.T_servo(k), *palm.housing_box(k))
    depth = max(overlap(housing, slab) for slab in slabs)
    if depth < w - 1e-9:
        raise ParamError(
            "palm.thumb_cmc_offset_mm", [round(mm(v), 6) for v in params.palm.thumb_cmc_offset],
            f"with palm.thumb_cmc_axis_deg the CMC servo's housing overlaps the palm by {max(depth, 0.0):.3f} mm; "
            f"it must join it by at least a wall ({w:g} mm) or the palm prints in two pieces", src)
    # the hub on the CMC servo's shaft turns the thumb, and the post on the housing's end wall
    # carries the thumb tendon to the CMC axis through the air: both must clear the palm slab by a
    # clearance (bounding boxes, so conservative at the rounds; issue 8, property test seed 5:
    # the hub 1161 mm^3 inside the palm; the post inside the slab makes the palm an invalid solid)
    from .parts.pulley import ServoPulley

    hub = ServoPulley(params, k)
    r, h, c = hub.outer_radius, hub.width / 2.0, palm.tol.clearance
    a = palm.cmc_arch()
    rp = a["r_post"]
    for what, box in (
            ("hub (radius thumb.cmc_horn_radius_mm, width cad.servo_pulley_width_mm)",
             _obb(palm.T_servo(k), (-r, -r, -h), (r, r, h))),
            ("tendon post (on its housing's end wall)",
             _obb(palm.T_cmc(), (-rp, a["y_post"] - rp, a["z_floor"] - w), (rp, a["y_post"] + rp, a["z_hi"])))):
        depth = max(overlap(box, slab) for slab in slabs) + c
        if depth > 1e-9:
            raise ParamError(
                "palm.thumb_cmc_offset_mm", [round(mm(v), 6) for v in params.palm.thumb_cmc_offset],
                f"with palm.thumb_cmc_axis_deg the CMC servo's {what} comes {depth:.3f} mm closer to the "
                f"palm than the clearance ({c:g} mm): it must stand clear of the palm", src)
