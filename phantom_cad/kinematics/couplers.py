"""The drive's split at a magnet-held finger's socket face: the coupler (a crimped stop with the
finger strand's loop on it), where it runs over the travel, and the service angle that pays it out
of the socket; a ParamError naming ``hardware.tendon_stop`` when it does not fit. numpy only."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import units
from ..errors import ParamError
from . import forearm_layout as FL
from . import frames as F
from .dimensions import magnet_pocket_centres, printed_hole
from .hand_params import HandParams
from .memo import memoised
from .routing import Point, Strand, routes
from .routing_paths import pose, strand_nodes, strand_path
from .routing_rules import WRAP_MARGIN, servo_clamp_wrap
from .topology import CHAINS, SERVOS, chain, joint, link
from .vectors import nearest_on_cylinder


@dataclass(frozen=True)
class Coupler:
    """The drive of a magnet-held finger is split at the socket face into a *palm strand* (servo
    pulley to a crimped stop) and a *finger strand* (a loop round the palm strand behind the stop,
    to G2). Distances ``s`` run from the socket face into the palm along the drive's straight run
    (metres); the coupler is the stop with the loop on it: its knot (3 cord diameters), the stop,
    and the loop's bight behind it (1 cord diameter)."""
    digit: str
    diameter: float          # its envelope: the stop and the loop's two legs beside it
    length: float            # its envelope along the run
    bore: float              # the palm's bore for it (envelope + two clearances)
    run: float               # the straight run from the socket face to the servo pulley's tangent point
    channel: float           # the part of the run outside the pulley's cavity: the bore's room
    rest: tuple[float, float]          # s of its distal and proximal ends at u = 0
    full: tuple[float, float]          # at the end of the travel
    service_angle: float     # rad (< 0): the servo command that pays the palm strand out
    payout: float            # how much it pays out
    bearing: float           # s of the stop's proximal face at rest (where the loop's bight bears)
    palm_strand: float       # working length: from the clamp on the servo pulley to the stop's proximal face
    finger_strand: float     # working length: from the loop's bight to the knot at G2 (the two add up to the drive)

    @property
    def emergence(self) -> float:
        """How far beyond the socket face the coupler's proximal end comes at the service angle."""
        return self.payout - self.rest[1]

    @property
    def bore_end(self) -> float:
        """s where the palm's bore ends: a clearance past the coupler at full travel."""
        return self.full[1] + self.bore / 2.0 - self.diameter / 2.0


def pocket_walls(params: HandParams) -> dict[str, float]:
    """The thinnest wall (m) each split drive's coupler bore in the palm leaves to its socket's two
    magnet pockets (right-hand frames): the bore's axis from the tendon's exit on the socket face
    toward the servo pulley's tangent point (it runs level, at the tendon's height), sampled to the
    bore's end; each pocket a flat-bottomed cylinder into the face. Where the drive runs off the
    socket's axis toward its servo the bore drifts sideways under a pocket; lifting the pockets
    (``palm.magnet_lift_mm``) or smaller magnets open the wall."""
    hw, pr = params.hardware, params.print
    pocket = printed_hole(hw.magnet_diameter + 2.0 * pr.magnet_clearance, pr.hole_compensation)
    depth = hw.magnet_thickness + pr.magnet_clearance
    centres = magnet_pocket_centres(pocket, params.palm.wall, params.palm.magnet_lift)
    out = {}
    for digit, cp in couplers(params).items():
        s = chain(digit).servo
        T = F.T_palm_socket(params, digit)
        face = F.socket_tendon_point(params, digit)
        tangent = (FL.T_palm_servo(params, s) @ np.array([-F.servo_radius(params, s), 0.0, 0.0, 1.0]))[:3]
        u = (tangent - face) / np.linalg.norm(tangent - face)
        axis = face + np.linspace(0.0, cp.bore_end, 1201)[:, None] * u
        R = np.c_[T[:3, 0], T[:3, 2], -T[:3, 1]]              # a pocket's frame: z into the face
        gaps = [nearest_on_cylinder((axis - (T @ np.array([sx, 0.0, sz, 1.0]))[:3]) @ R, 0.0, depth, pocket / 2.0)[0]
                for sx, sz in centres]
        out[digit] = float(np.min(gaps)) - cp.bore / 2.0
    return out


def _drive_strand(params: HandParams, digit: str) -> Strand:
    """The drive's strand as :func:`routes` gives it (mirrored for a left hand), for posing with
    :func:`pose`."""
    return next(r.strands[0] for r in routes(params) if r.tendon.kind == "drive" and r.tendon.digit == digit)


def split_digits() -> tuple[str, ...]:
    """The digits whose drive is split at their magnet face: the magnet-held fingers (the thumb is
    fixed to the palm)."""
    return tuple(ch.digit for ch in CHAINS if link(joint(ch.joint_names[0]).parent).segment == "base")


def couplers(params: HandParams) -> dict[str, Coupler]:
    """The coupler of every split drive (right-hand frames; the left hand's are their mirror image,
    of the same dimensions). Refuses, naming ``hardware.tendon_stop``, a file whose coupler does not
    stay in its channel over the travel or does not come out of the socket at the service angle."""
    return memoised(_COUPLERS, params.digest, lambda: _couplers(params), cap=16)


_COUPLERS: dict = {}


def _couplers(params: HandParams) -> dict[str, Coupler]:
    hw, c = params.hardware, params.print.hole_clearance
    d = hw.tendon_diameter
    D = hw.stop_diameter + 2.0 * d
    Lc = d + hw.stop_length + 3.0 * d
    s0 = 2.0 * c
    Ts = pose(params)
    out = {}
    for digit in split_digits():
        spec = chain(digit)
        servo = SERVOS[spec.servo]
        ch = params.digit(digit).chain
        r = ch.servo_radius
        strand = _drive_strand(params, digit)
        nodes = strand_nodes(strand, Ts)
        k = next(i for i, e in enumerate(strand.elements) if isinstance(e, Point) and e.role == "interface")
        tangent, face = nodes[k - 1][1], nodes[k][0]
        to_face, _ = strand_path(params, Strand(strand.name, strand.elements[:k + 1]), Ts)
        from_face, _ = strand_path(params, Strand(strand.name, strand.elements[k:]), Ts)
        run = float(np.linalg.norm(face - tangent))
        cavity = math.sqrt((r + F.pulley_cavity_margin(params)) ** 2 - r ** 2)
        channel = run - cavity
        travel = r * ch.travel[1]
        full = (s0 + travel, s0 + Lc + travel)
        field = "hardware.tendon_stop.length_mm"
        value = round(units.mm(hw.stop_length), 6)
        if full[1] + c > channel + 1e-12:
            raise ParamError(field, value, f"the {digit} drive's coupler (stop, loop and knot: {units.mm(Lc):.2f} mm) "
                             f"travels {units.mm(travel):.2f} mm into the palm from {units.mm(s0):.2f} mm behind the socket "
                             "face; "
                             f"with a clearance it needs {units.mm(full[1] + c):.2f} mm of channel, it has "
                             f"{units.mm(channel):.2f} mm before {servo.title}'s pulley cavity", params.source)
        # the clamp sits for the largest wrap the travel allows (servo_clamp_wrap): unwinding to the
        # smallest (WRAP_MARGIN) pays the palm strand out
        service = WRAP_MARGIN - servo_clamp_wrap(params, servo.index)
        payout = -r * service
        bearing = s0 + 3.0 * d + hw.stop_length
        cp = Coupler(digit, D, Lc, D + 2.0 * c, run, channel, (s0, s0 + Lc), full, service, payout,
                     bearing, to_face - bearing, from_face + bearing)
        if cp.emergence < hw.stop_diameter - 1e-12:
            raise ParamError(field, value, f"at the service angle ({units.deg(cp.service_angle):.1f} deg) "
                             f"{servo.title} pays out {units.mm(payout):.2f} mm: the {digit} coupler "
                             f"({units.mm(Lc):.2f} mm) "
                             f"comes {units.mm(cp.emergence):.2f} mm out of the socket, it must come at least the stop's "
                             f"diameter ({units.mm(hw.stop_diameter):g} mm) out to slip the loop off", params.source)
        out[digit] = cp
    return out
