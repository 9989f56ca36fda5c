"""The palm's hold on the thumb: the CMC column's journal, the CMC pulley's cavity and the thumb
drive's turn onto the CMC axis, along the CMC axis (metres, right hand), and how well a CMC
placement fits them. numpy only; frames as in :mod:`.frames`."""

from __future__ import annotations

import functools
import math

import numpy as np

from .. import units
from .dimensions import magnet_pocket_centres, printed_hole
from .frames import (T_palm_socket, T_palm_thumb_cmc_base, cmc_pulley_radius, pulley_cavity_margin, tendon_relief,
                     trans)
from .hand_params import HandParams
from .memo import memoised
from .topology import FINGERS


_THENAR: dict = {}


def thenar(params: HandParams) -> dict[str, float]:
    """The palm's hold on the thumb (CMC base frame at rest, distances s along the CMC axis from
    the CMC centre, metres; memoised, read-only):

    * ``face``: where the axis crosses the palm's palmar face (the column enters the journal);
    * ``column_r``: the column's radius (cad.cmc_column_radius); ``journal_r`` the palm's bore;
    * ``pulley``: the CMC pulley's mid-plane: as low in the palm as its cavity allows (the cavity's
      rim a palm wall above the palmar face); ``cavity_r``, ``cavity_h``: the cavity's radius and
      half height along the axis (the pulley's flanges, running room and a clearance);
    * ``top``: the column's top, flush with the pulley's upper flange;
    * ``ceiling``: the cavity's top; ``turn``: where the thumb drive turns down onto the CMC axis,
      a palm wall and a relief above it (the drive reaches the CMC along its axis, so turning the
      CMC leaves its length alone).

    The palm cuts a slot from the cavity toward servo 6 (the loop runs in it; the pulley slides in
    through it, then the column up through the journal into it)."""
    return memoised(_THENAR, params.digest, lambda: thenar_layout(params, T_palm_thumb_cmc_base(params)), cap=16)


def thenar_layout(params: HandParams, T0: np.ndarray) -> dict[str, float]:
    """:func:`thenar` for the CMC placement T0 (T_palm_cmc_base at rest) instead of the file's."""
    a, C = T0[:3, 2], T0[:3, 3]
    c, w = params.print.hole_clearance, params.palm.wall
    Tp = params.palm.thickness
    az = max(float(a[2]), 1e-9)
    R = cmc_pulley_radius(params) + pulley_cavity_margin(params)
    h = params.cad.servo_pulley_width / 2.0 + c
    tilt = math.sqrt(max(1.0 - az * az, 0.0))
    face = (-Tp / 2.0 - C[2]) / az
    z_q = -Tp / 2.0 + w + R * tilt + h * az             # the cavity's lowest rim a wall above the face
    pulley = (z_q - C[2]) / az
    ceiling = pulley + h
    return {"face": face, "column_r": params.cad.cmc_column_radius,
            "journal_r": params.cad.cmc_column_radius + c, "pulley": pulley, "cavity_r": R,
            "cavity_h": h, "top": pulley + params.cad.servo_pulley_width / 2.0, "ceiling": ceiling,
            "turn": ceiling + w + tendon_relief(params)}


#: the CMC axis's largest tilt from the palm's normal (rad): the column along it climbs into the palm
MAX_CMC_TILT = units.rad(60.0)


def thenar_margins(params: HandParams, T0: np.ndarray) -> dict[str, float]:
    """How well the palm's thenar holds the CMC placed at T0 (T_palm_cmc_base at rest): each
    margin >= 0 where it fits. ``tilt`` (rad): the CMC axis within MAX_CMC_TILT of the palm's
    normal; ``base`` (m): the CMC base (a hub of half the thumb's width, the thumb's thickness,
    turning with the thumb) a clearance below the palm's palmar face; ``turn`` (m): the thumb
    drive's turn above the CMC pulley's cavity a relief and a wall under the dorsal face. The
    file's are checked before a build (``cad.preflight``); the placement search keeps to them."""
    a, C = T0[:3, 2], T0[:3, 3]
    th, c, w, Tp = params.thumb, params.print.hole_clearance, params.palm.wall, params.palm.thickness
    az = float(np.clip(a[2], -1.0, 1.0))
    out = {"tilt": MAX_CMC_TILT - math.acos(az)}
    top = C[2] + th.thickness / 2.0 * az + th.width / 2.0 * math.sqrt(max(1.0 - az * az, 0.0))
    out["base"] = -Tp / 2.0 - c - top
    if az <= 0.0:
        out["turn"] = -Tp
        return out
    t = thenar_layout(params, T0)
    D = T0 @ np.array([0.0, 0.0, t["turn"], 1.0])
    out["turn"] = Tp / 2.0 - (tendon_relief(params) + w) - float(D[2])
    return out


def T_cmc_base_pulley(params: HandParams) -> np.ndarray:
    """The CMC pulley's frame in the CMC base's (fixed): on the CMC axis at the pulley's mid-plane,
    the CMC base's axes (its key's flat on +y)."""
    return trans(0.0, 0.0, thenar(params)["pulley"])


def thenar_axis_point(params: HandParams, s: float) -> np.ndarray:
    """The palm-frame point (m, right hand) s along the CMC axis from the CMC centre, at rest."""
    return (T_palm_thumb_cmc_base(params) @ np.array([0.0, 0.0, s, 1.0]))[:3]


@functools.cache
def _circle(n: int) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of n angles evenly round the circle (read-only: shared)."""
    a = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    cos, sin = np.cos(a), np.sin(a)
    cos.flags.writeable = sin.flags.writeable = False
    return cos, sin


def _ring(T0: np.ndarray, s: float, r: float, n: int = 24) -> np.ndarray:
    """Points (n, 3) of the circle of radius r about the CMC axis, s along it (palm frame)."""
    cos, sin = _circle(n)
    pts = np.empty((n, 4))
    pts[:, 0], pts[:, 1], pts[:, 2], pts[:, 3] = r * cos, r * sin, s, 1.0
    return (T0 @ pts.T).T[:, :3]


def thenar_cuts(params: HandParams, T0: np.ndarray | None = None) -> dict[str, tuple[float, float, float]]:
    """What the palm cuts round the CMC axis, as (s0, s1, radius) (m, s along the CMC axis from the
    CMC centre, :func:`thenar`): ``journal`` (the column's bore from the palmar face to the pulley's
    cavity), ``cavity`` (the CMC pulley's cavity) and ``turn`` (the thumb drive's relief where it
    turns onto the axis). ``T0``: another CMC placement than the file's (T_palm_cmc_base at rest)."""
    t = thenar(params) if T0 is None else thenar_layout(params, T0)
    r = tendon_relief(params)
    return {"journal": (t["face"], t["pulley"] - t["cavity_h"], t["journal_r"]),
            "cavity": (t["pulley"] - t["cavity_h"], t["ceiling"], t["cavity_r"]),
            "turn": (t["turn"] - r, t["turn"] + r, r)}


def thenar_points(params: HandParams, T0: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Points (m, palm frame, right hand) of what the palm's thenar holds round the CMC axis
    (:func:`thenar_cuts`), each grown by a palm wall (the journal across only: it runs from the
    palmar face into the cavity): ``journal``, ``cavity`` and ``turn``. The palm's thenar block is
    their bounding box, clipped to the palm's faces; only the journal and the turn set how far
    radial it reaches (the cavity is cut where it reaches past that: open, as its slot toward
    servo 6 is).
    ``T0``: another CMC placement than the file's (T_palm_cmc_base at rest)."""
    if T0 is None:
        T0 = T_palm_thumb_cmc_base(params)
        cuts = thenar_cuts(params)
    else:
        cuts = thenar_cuts(params, T0)
    w = params.palm.wall
    (j0, j1, rj), (c0, c1, rc), (t0, t1, rt) = cuts["journal"], cuts["cavity"], cuts["turn"]
    return {"journal": np.vstack([_ring(T0, s, rj + w) for s in (j0, j1)]),
            "cavity": np.vstack([_ring(T0, s, rc + w) for s in (c0 - w, c1 + w)]),
            "turn": np.vstack([_ring(T0, s, rt + w) for s in (t0 - w, t1 + w)])}


def socket_pocket_gap(params: HandParams, T0: np.ndarray | None = None) -> tuple[float, str, str]:
    """(gap (m), finger, cut): the least distance from the finger sockets' magnet pockets to the
    thenar's cuts (:func:`thenar_cuts`), and where it is; negative where a cut reaches into a
    pocket. Each pocket (diameter and depth as the finger base's, at
    ``dimensions.magnet_pocket_centres`` on its socket's face, ``frames.T_palm_socket``)
    is sampled on its wall and bottom; a point's distance to a cut is the largest of its radial and
    its two axial distances (a lower bound: the gap is never overstated).
    ``T0``: another CMC placement than the file's (T_palm_cmc_base at rest)."""
    pr, hw = params.print, params.hardware
    pocket = printed_hole(hw.magnet_diameter + 2.0 * pr.magnet_clearance, pr.hole_compensation)
    depth = hw.magnet_thickness + pr.magnet_clearance
    centres = magnet_pocket_centres(pocket, params.palm.wall, params.palm.magnet_lift)
    a = np.linspace(0.0, 2.0 * math.pi, 72, endpoint=False)
    rings = [(r, d) for d in np.linspace(0.0, depth, 7) for r in (pocket / 2.0,)] + \
            [(pocket / 2.0 * k / 4.0, depth) for k in range(4)]
    # socket frame: y the face's outward normal, the pockets reach depth behind the face
    local = np.vstack([np.c_[sx + r * np.cos(a), np.full_like(a, -d), sz + r * np.sin(a), np.ones_like(a)]
                       for sx, sz in centres for r, d in rings])
    T0 = T_palm_thumb_cmc_base(params) if T0 is None else T0
    Ti = np.linalg.inv(T0)
    cuts = thenar_cuts(params, T0)
    best = (math.inf, "", "")
    for f in FINGERS:
        L = (Ti @ T_palm_socket(params, f) @ local.T).T
        rho, s = np.hypot(L[:, 0], L[:, 1]), L[:, 2]
        for name, (s0, s1, r) in cuts.items():
            gap = float(np.maximum(np.maximum(rho - r, s0 - s), s - s1).min())
            if gap < best[0]:
                best = (gap, f, name)
    return best
