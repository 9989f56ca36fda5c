"""Rules of the palm's layout, checked when a parameter file loads (before any solid is built).

The palm places the thenar (the CMC's journal, its pulley's cavity) and the finger sockets from the frames
(phantom_cad.kinematics.frames); whether they fit together is a question of the parts'
own dimension classes, so these rules live here, numpy only (no OpenCascade), and raise the
same :class:`ParamError` as the schema. ``check`` is called by every command that loads a
parameter file for building or validating (``params validate``, ``build``, ``demo``).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ..params import ParamError
from ..params.rules import MIN_WALL
from .parts.common import mm
from .parts.palm import Palm



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
    """Raise ParamError if the palm's thenar cannot hold the CMC (``frames.thenar``): the CMC axis
    must climb into the palm within 60 deg of its normal (the column along it enters the palm's
    journal), the CMC base (a hub of half the thumb's width, the thumb's thickness, turning with the
    thumb) must stay a clearance below the palm's palmar face, and the thumb drive's turn above the
    CMC pulley's cavity a wall under the dorsal face; and if the routing model finds no clamp
    position for a loop or a drive (``routing.routes`` raises the ParamError: a joint's travel too
    large for its loop's pulleys and carrier), or a finger drive's coupler has no room in its palm
    channel or does not come out at the service angle (``routing.couplers``)."""
    from ..kinematics import frames as F
    from ..kinematics import routing

    src = params.source
    T0 = F.T_palm_thumb_cmc_base(params)
    fit = F.thenar_margins(params, T0)
    if fit["tilt"] < 0.0:
        tilt = math.degrees(F.MAX_CMC_TILT - fit["tilt"])
        raise ParamError("palm.thumb_cmc_axis_deg", [round(math.degrees(v), 6) for v in params.palm.thumb_cmc_axis],
                         f"tilts the CMC axis {tilt:.1f} deg from the palm's normal: the palm holds the CMC on a "
                         f"column along it, which must climb into the palm within {math.degrees(F.MAX_CMC_TILT):g} deg "
                         "of its normal", src)
    Tp = params.palm.thickness
    if fit["base"] < -1e-12:
        raise ParamError("palm.thumb_cmc_offset_mm", [round(mm(v), 6) for v in params.palm.thumb_cmc_offset],
                         f"with palm.thumb_cmc_axis_deg the CMC base's top comes {mm(-fit['base']):.3f} mm too close to "
                         f"the palm's palmar face ({mm(-Tp / 2.0):g} mm): the CMC base (a hub of half thumb.width_mm, "
                         "thumb.thickness_mm thick, turning with the thumb) hangs a clearance below the palm and "
                         "its column climbs into the palm's journal", src)
    if fit["turn"] < -1e-12:
        raise ParamError("palm.thickness_mm", round(mm(Tp), 6),
                         f"leaves the thumb drive's turn onto the CMC axis, above the CMC pulley's cavity (radius "
                         f"thumb.cmc_pulley_radius_mm with its flanges and running room, tilted with the CMC axis), "
                         f"{mm(-fit['turn']):.3f} mm short of a relief and a wall under the dorsal face: a thicker "
                         "palm, a smaller pulley or a CMC axis nearer the palm's normal", src)
    routing.routes(params)
    routing.couplers(params)
