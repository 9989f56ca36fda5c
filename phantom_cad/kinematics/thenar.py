"""The palm's hold on the thumb: the CMC column's journal, the CMC pulley's cavity and the thumb
drive's turn onto the CMC axis, along the CMC axis (metres, right hand), and how well a CMC
placement fits them. numpy only; frames as in :mod:`.frames`."""

from __future__ import annotations

import math

import numpy as np

from .. import units
from .frames import T_palm_thumb_cmc_base, cmc_pulley_radius, pulley_cavity_margin, tendon_relief, trans
from .hand_params import HandParams
from .memo import memoised


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


def _ring(T0: np.ndarray, s: float, r: float, n: int = 24) -> np.ndarray:
    """Points (n, 3) of the circle of radius r about the CMC axis, s along it (palm frame)."""
    a = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    pts = np.c_[r * np.cos(a), r * np.sin(a), np.full_like(a, s), np.ones_like(a)]
    return (T0 @ pts.T).T[:, :3]


def thenar_points(params: HandParams, T0: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Points (m, palm frame, right hand) of what the palm's thenar holds round the CMC axis
    (:func:`thenar`), each grown by a palm wall: ``journal`` (the column's bore from the palmar face
    to the pulley's cavity), ``cavity`` (the CMC pulley's cavity) and ``turn`` (the thumb drive's
    turn onto the axis). The palm's thenar block is their bounding box, clipped to the palm's faces;
    only the journal and the turn set how far radial it reaches (the cavity is cut where it reaches
    past that: open, as its slot toward servo 6 is).
    ``T0``: another CMC placement than the file's (T_palm_cmc_base at rest)."""
    if T0 is None:
        T0, t = T_palm_thumb_cmc_base(params), thenar(params)
    else:
        t = thenar_layout(params, T0)
    w = params.palm.wall
    rj = t["journal_r"] + w
    return {"journal": np.vstack([_ring(T0, s, rj) for s in (t["face"], t["pulley"] - t["cavity_h"])]),
            "cavity": np.vstack([_ring(T0, s, t["cavity_r"] + w) for s in (t["pulley"] - t["cavity_h"] - w,
                                                                          t["ceiling"] + w)]),
            "turn": np.vstack([_ring(T0, s, tendon_relief(params) + w) for s in (t["turn"] - tendon_relief(params) - w,
                                                                                  t["turn"] + tendon_relief(params) + w)])}
