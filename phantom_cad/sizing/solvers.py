"""The size-dependent choices of a parameter file, each solved from a person's measurements and
the rules the file must keep (``params.rules``, ``params.schema``), not scaled from the default.
Numbers in millimetres and degrees, as the file writes them (the rules' constants, SI, are converted
where used); each function is one choice."""

from __future__ import annotations

import math

from .. import units
from ..kinematics import closed_form as cf
from ..kinematics.dimensions import printed_hole, slot_back
from ..params.rules import MAX_FINGER_PITCH, MIN_WALL

#: the reference hand: params/phantom.toml, a 50th-percentile adult man (docs/sizing.md)
REFERENCE_LENGTH = 189.0
#: its hand breadth across metacarpals 2-5: the 50th-percentile British man (docs/sizing.md)
REFERENCE_BREADTH = 85.0
#: the 95th-percentile adult palm at the reference hand (mm): breadth, and thickness with the heel
#: (tests/cad/test_human_scale.py), scaled with the hand length
PALM_ENVELOPE = (95.0, 35.0)
#: the largest servo travel a drive's clamp keeps inside its wrap margins (routing_rules: 180 deg less
#: twice the 8 deg margin)
MAX_SERVO_TRAVEL = 164.0
#: lengths are written to half a millimetre, travels to half a degree
STEP = 0.5
#: the clearance (mm) between adjacent fingers at the default's pitch (20.5 mm for 18 mm fingers; at
#: 1 mm flexed fingers overlap, docs/parts.md)
PITCH_CLEARANCE = 2.5
#: the least distance (mm) between the boxes of neighbouring fingers flexed over every pair of their
#: commands (``kinematics.finger_clearance``); the boxes hold the parts' rounded ends by their
#: corners, so the parts stand further apart (the reference hand: 0.12 mm at its 20.5 mm pitch)
FLEXED_CLEARANCE = 0.1

#: what the sizing picks hardware from, largest first: disc magnets (diameter, thickness), and
#: bearings (bore, outer, width: 683ZZ, MR63ZZ, 682ZZ); the first that fits every digit is chosen
MAGNETS = ((5.0, 3.0), (4.0, 3.0), (4.0, 2.0), (3.0, 2.0))
BEARINGS = ((3.0, 7.0, 3.0), (3.0, 6.0, 2.5), (2.0, 5.0, 2.3))


def down(x: float, step: float = STEP) -> float:
    """``x`` rounded down to the step (a hair of float noise forgiven)."""
    return math.floor(x / step + 1e-9) * step


def up(x: float, step: float = STEP) -> float:
    return math.ceil(x / step - 1e-9) * step


def near(x: float, step: float = STEP) -> float:
    return math.floor(x / step + 0.5) * step


def thickness_limit(lengths: dict[str, float], segments: tuple[str, ...], limits: dict[str, float],
                    keys: tuple[str, ...], clearance: float) -> tuple[float, str]:
    """The thickest a digit may be (mm) and the phalanx that binds: each phalanx must be longer
    than its two joint bosses and their clearances, 2 slot_back(T) = T + 2 clearance, plus half the
    thickness when its far joint flexes past 90 deg (params.rules._segments). ``limits``: the
    joints' upper limits (rad) by key, ``keys`` the chain's joints reference first (phalanx k ends
    at joint k + 1)."""
    best, which = math.inf, ""
    for k, seg in enumerate(segments[1:]):
        far = keys[k + 1] if k + 1 < len(keys) else None
        factor = 1.5 if far is not None and limits[far] > math.pi / 2.0 else 1.0
        # slot_back is linear in T: solve factor * T + 2 clearance < length
        t = (lengths[seg] - 2.0 * slot_back(0.0, clearance)) / factor
        if t < best:
            best, which = t, seg
    return best, which


def finger_thickness_floor(magnet: tuple[float, float], wall: float, tendon: float, clearance: float,
                           magnet_clearance: float, compensation: float, bearing_outer: float) -> float:
    """The thinnest finger (mm) its base holds: the tendon enters one palm wall above the palmar
    face and passes below the two magnet pockets (params.rules._magnets), and the joint's bearing
    fits inside the thickness."""
    pocket = printed_hole(magnet[0] + 2.0 * magnet_clearance, compensation)
    relief = 2.0 * (tendon + 2.0 * clearance)
    return max(2.0 * (wall + relief / 2.0 + pocket / 2.0), pocket, bearing_outer)


def finger_width_floor(magnet: tuple[float, float], wall: float, clearance: float, magnet_clearance: float,
                       compensation: float, cheek: float, tendon: float, spring: float, flank: float) -> float:
    """The narrowest finger (mm): two magnet pockets one palm wall apart with a two-perimeter wall
    outside each across its base (params.rules._magnets), and the clevis slot between two cheeks
    holding a loop's hub and the tongue with its return groove (params.rules._joints)."""
    pocket = printed_hole(magnet[0] + 2.0 * magnet_clearance, compensation)
    magnets = 2.0 * pocket + wall + 2.0 * units.mm(MIN_WALL)
    return max(magnets, digit_width_floor(clearance, cheek, tendon, spring, flank))


def digit_width_floor(clearance: float, cheek: float, tendon: float, spring: float, flank: float) -> float:
    """The narrowest digit's clevis (mm): two cheeks round a slot that holds a loop's hub (a groove
    between two flanks, a clearance) and the tongue with the return cord's groove."""
    groove = tendon + 2.0 * clearance
    ret = spring + 2.0 * clearance
    hub = clearance + 2.0 * flank + groove
    return 2.0 * cheek + 2.0 * (hub + clearance + flank) + ret


def section(target: float, floor: float, ceiling: float) -> float:
    """A digit's width or thickness (mm): the person's (``target``) on the half-millimetre grid,
    moved inside [floor, ceiling] (the rules' bounds); NaN when the bounds leave no room."""
    lo, hi = up(floor + 1e-6), down(ceiling - 1e-6)
    if lo > hi:
        return math.nan
    return min(max(near(target), lo), hi)


def return_room(channel: float) -> float:
    """How far (mm) inside the joint boss's surface (radius thickness / 2) the largest pulley radius
    must lie for the return cord's channel (diameter ``channel``, clearances included): the cord
    runs along each link at the radius of its joints' grooves (kinematics.routing), and its channel
    keeps a two-perimeter wall under the dorsal face (params.rules._joints)."""
    return channel / 2.0 + units.mm(MIN_WALL)


def pulley_radii(reference: tuple[float, ...], thickness: float, axle_bore: float, cord: float,
                 channel: float) -> tuple[float, ...]:
    """The joint pulley radii (mm) in the reference's ratio (5:4:5, the thumb's 5:4): the
    reference's when they fit, else scaled down until the largest lies a half cord inside the joint
    boss (radius thickness / 2) and the return cord's channel over it (:func:`return_room`) keeps
    its wall under the dorsal face, each rounded down to the micrometre; NaN when the smallest would
    then not clear the axle bore (params.rules._joints)."""
    s = min(1.0, (thickness / 2.0 - max(cord / 2.0, return_room(channel))) / max(reference))
    radii = reference if s >= 1.0 else tuple(math.floor(r * s * 1000.0) / 1000.0 for r in reference)
    if min(radii) - cord / 2.0 <= axle_bore:
        return tuple(math.nan for _ in reference)
    return radii


def path_length(segment: float, wrap: float, r_a: float, r_b: float) -> float:
    """A coupling tendon's path length (mm) across a phalanx: the phalanx's length plus the
    figure-eight's ``wrap`` round its two pulleys (the reference file's path length less its
    phalanx's, scaled with the pulley radii: the wrap depends on the pulleys, not on the phalanx), to
    the millimetre, and at least the crossed span between the pulleys, sqrt(L^2 - (R_a + R_b)^2)
    (params.schema._check_path)."""
    return max(float(round(segment + wrap)), up(math.sqrt(max(segment ** 2 - (r_a + r_b) ** 2, 0.0)), 1.0))


def guide(reference: tuple[float, float, float], thickness: float, tendon: float, clearance: float,
          eyelet: float, base_room: float) -> tuple[float, float, float]:
    """(d1, d2, alpha) of a digit's guides (mm, mm, deg): the reference's where they fit, else the
    nearest inside the rules (params.rules._guides): the phalanx-side eyelet clears the joint boss
    (d2 >= T/2 + clearance + eyelet/2) and lies inside the palmar face (d2 cos(alpha/2) <= T/2 -
    tendon/2 - clearance); the metacarpal-side eyelet's boss joins the palmar face (d1 cos(alpha/2)
    <= T/2 + 2 r_hole) and its relief stays within ``base_room`` behind the joint (the finger base,
    or the thumb metacarpal's arm). NaN where no d1 or d2 fits."""
    d1, d2, alpha = reference
    c, s = math.cos(units.rad(alpha) / 2.0), math.sin(units.rad(alpha) / 2.0)
    r_hole = tendon / 2.0 + clearance
    d2_lo = thickness / 2.0 + clearance + eyelet / 2.0
    d2_hi = (thickness / 2.0 - r_hole) / c
    d1_hi = min((thickness / 2.0 + 2.0 * r_hole) / c,
                (base_room - eyelet / 2.0 - (math.sqrt(3.0) + 2.0) * r_hole) / s)
    d2_new = min(max(d2, up(d2_lo)), down(d2_hi))
    d1_new = min(d1, down(d1_hi))
    if not d2_lo - 1e-9 <= d2_new <= d2_hi + 1e-9 or d1_new <= 0.0:
        return math.nan, math.nan, alpha
    return d1_new, d2_new, alpha


def servo_travel(d1: float, d2: float, alpha: float, r: float, radii: tuple[float, ...],
                 limits: tuple[float, ...]) -> float:
    """The servo travel's upper end (deg, to the half degree below): the servo angle at which the
    first joint of the chain reaches its Table I limit, the reference joint at min_j limit_j / c_j
    (c = the ideal coupling, eq. 13 without stretch), through the inverse cosine law (eq. 6).
    Inside the travel the model maps every joint inside its limits and the chord inside the law's
    domain (q_ref < alpha)."""
    c = cf.ideal_coupling(radii)
    q_ref = min(lim / float(k) for lim, k in zip(limits, c))
    return down(units.deg(float(cf.servo_angle(q_ref, d1, d2, units.rad(alpha), r))))


def finger_pitch(widths: tuple[float, ...]) -> float:
    """MCP to MCP along the palm arc (mm): the widest finger and the default's clearance between
    flexed neighbours (:data:`PITCH_CLEARANCE`), at most the palm layout's MAX_FINGER_PITCH."""
    return min(up(max(widths) + PITCH_CLEARANCE), units.mm(MAX_FINGER_PITCH))


def scaled(reference: float, hand_length: float, step: float = STEP) -> float:
    """A length of the reference hand for a hand of ``hand_length`` (mm), rounded down (the palm's
    thickness and heel: a palm no thicker than the human envelope scaled the same way)."""
    return down(reference * hand_length / REFERENCE_LENGTH, step)



def palm_layout(widths: dict[str, float], metacarpals: dict[str, float], arc_offset: float,
                base_length: float, clearance: float) -> tuple[float, dict[str, float]]:
    """(finger pitch, finger widths) in mm: the pitch of :func:`finger_pitch`, raised on the
    half-millimetre grid until each finger base's magnet face clears its neighbour's column by half
    their widths and a clearance (the stepped metacarpal heads put one face beside the other's
    column: params.rules._guides); at the palm layout's largest pitch, the wider of a pair that
    still touches is narrowed instead. ``metacarpals`` and ``widths`` in finger order."""
    from ..kinematics.dimensions import finger_columns
    from ..params.rules import base_room

    names = list(widths)
    widths = dict(widths)
    pitch = finger_pitch(tuple(widths.values()))
    top = units.mm(MAX_FINGER_PITCH)
    while True:
        cols = dict(zip(names, finger_columns(units.m(pitch), units.rad(arc_offset),
                                              [units.m(metacarpals[n]) for n in names])))
        tight = None
        for a, b in zip(names, names[1:]):
            room = base_room(cols[a], cols[b], units.m(base_length))
            if units.mm(room) < (widths[a] + widths[b]) / 2.0 + clearance - 1e-9:
                tight = (a, b)
                break
        if tight is None:
            return pitch, widths
        if pitch + STEP <= top + 1e-9:
            pitch += STEP
        else:
            a, b = tight
            wider = a if widths[a] >= widths[b] else b
            widths[wider] -= STEP
