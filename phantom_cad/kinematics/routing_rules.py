"""The rules a tendon route must keep: every wrap of a loop's or a servo's clamp stays inside
(WRAP_MARGIN, 180 deg - WRAP_MARGIN) over the joint's or servo's travel; a ParamError naming the
parameter field when no clamp position can. numpy-free."""

from __future__ import annotations

import math

from .. import units
from ..errors import ParamError
from .dimensions import digit_field
from .hand_params import HandParams
from .topology import CMC_SERVO, SERVOS, joint, link


#: every wrap stays this far inside (0, 180 deg) over the joint's whole travel (rad)
WRAP_MARGIN = units.rad(8.0)


#: a loop's clamps are placed for a travel this far past the joint's upper limit (rad)
TRAVEL_MARGIN = units.rad(3.0)


def clamp_angle(lo: float, hi: float, what: str, params: HandParams, field: str, value, why: str) -> float:
    """The middle of [lo, hi]; a ParamError naming ``field`` (its ``value``) when it is empty: no
    clamp keeps every wrap of ``what`` inside (WRAP_MARGIN, 180 deg - WRAP_MARGIN) over the travel
    (``why``: what that asks of the parameters, in their words)."""
    if hi - lo < 0.0:
        raise ParamError(field, value, f"no clamp position on the {what} keeps every wrap inside "
                         f"({units.deg(WRAP_MARGIN):g}, {180 - units.deg(WRAP_MARGIN):g} deg) over the "
                         f"travel: {why}", params.source)
    return (lo + hi) / 2.0


def joint_travel(params: HandParams, jname: str) -> float:
    j = joint(jname)
    lim = dict(zip(params.digit(j.digit).chain.joints, params.digit(j.digit).chain.limits))[j.key]
    return lim[1] + TRAVEL_MARGIN + (params.cad.module_stop_margin if link(j.parent).segment == "base" else 0.0)


def limit_field(params: HandParams, digit: str, jname: str) -> tuple[str, list[float]]:
    """The parameter field (and its value) a loop's clamp rule names: the joint's limits."""
    ch = params.digit(digit).chain
    key = joint(jname).key
    return f"{digit_field(digit)}.limits_rad.{key}", [round(v, 6) for v in dict(zip(ch.joints, ch.limits))[key]]


def loop_travel_rule(ja: str, jb: str, carrier: str, jname: str, q: float, gamma: float, L: float,
                      Ra: float, Rb: float) -> str:
    """Why a loop's clamp cannot be placed: both clamps exist while each joint's travel (limit +
    margins) stays under 2 gamma - 2 WRAP_MARGIN, gamma = acos((R_a + R_b) / L)."""
    m = WRAP_MARGIN
    stop = " + cad.module_stop_margin_deg" if link(joint(jname).parent).segment == "base" else ""
    return (f"the {joint(jname).key.upper()} travel ({units.deg(q):.2f} deg: the upper limit + "
            f"{units.deg(TRAVEL_MARGIN):g} deg{stop}) must stay under 2 acos((R_{joint(ja).key} + "
            f"R_{joint(jb).key}) / L_{link(carrier).segment}) - {2 * units.deg(m):g} deg = "
            f"{units.deg(2 * gamma - 2 * m):.2f} deg (L = {units.mm(L):.2f} mm, R = {units.mm(Ra):g} and "
            f"{units.mm(Rb):g} mm: smaller pulley radii or a longer phalanx allow more)")


def servo_clamp_wrap(params: HandParams, servo: int) -> float:
    """Wrap (rad) of a drive on its servo pulley at u = 0: the largest that keeps the wrap inside
    (margin, 180 deg - margin) over the servo's travel, so that unwinding below the travel to the
    service angle pays the most cord out (:class:`Coupler`)."""
    digit = SERVOS[servo].digit
    lo, travel = params.digit(digit).chain.travel
    m = units.deg(WRAP_MARGIN)
    hi = math.pi - WRAP_MARGIN - travel
    clamp_angle(WRAP_MARGIN, hi, f"{SERVOS[servo].title} pulley", params,
                 f"{digit_field(digit)}.servo_travel_deg", [round(units.deg(lo), 6), round(units.deg(travel), 6)],
                 f"the servo's travel must be at most {180 - 2 * m:g} deg (a wrap is modelled up to 180 deg)")
    return hi


#: how far (rad) each of the CMC loop's clamps sits inside the wraps the travel allows
LOOP_CLAMP_MARGIN = units.rad(2.0)


def cmc_loop_clamps(params: HandParams) -> tuple[tuple[float, float], tuple[float, float]]:
    """Polar angles (rad, right hand, each pulley's frame at rest: servo 6's, and the CMC pulley's
    turned so that its y points away from servo 6) of the CMC loop's clamps, strand a's and strand
    b's, on servo 6's pulley and on the CMC pulley. Each strand winds on one pulley as it unwinds
    from the other; its wrap stays inside (WRAP_MARGIN, 180 deg - WRAP_MARGIN) over a pulley's
    travel T (servo 6's; the CMC's, cmc_gain times it). Each clamp sits LOOP_CLAMP_MARGIN inside its
    strand's allowed wraps, on the side that keeps the two clamps of a pulley furthest apart:
    180 deg - 2 WRAP_MARGIN - T - 2 LOOP_CLAMP_MARGIN (70.1 deg by default), room for two knot
    wells."""
    lo, hi = params.thumb.cmc_travel
    m, d = WRAP_MARGIN, LOOP_CLAMP_MARGIN
    out = []
    for what, travel in ((f"{SERVOS[CMC_SERVO].title}'s pulley", hi - lo), ("CMC pulley", params.thumb.cmc_gain * (hi - lo))):
        clamp_angle(m + d, math.pi - m - d - travel, f"CMC loop's {what}", params,
                     "thumb.cmc_servo_travel_deg", [round(units.deg(lo), 6), round(units.deg(hi), 6)],
                     f"the pulley's travel must be at most {180 - 2 * units.deg(m + d):g} deg (a wrap is "
                     f"modelled up to 180 deg, each clamp {units.deg(d):g} deg inside it)")
        out.append(travel)
    ts, tq = out
    # servo 6: a winds (wrap m + d at rest, clamp at pi + wrap), b unwinds (m + d + T, clamp at -wrap)
    servo = (math.pi + m + d, -(m + d + ts))
    # the CMC pulley: a unwinds (m + d + T, clamp at pi - wrap), b winds (m + d, clamp at wrap)
    cmc = (math.pi - (m + d + tq), m + d)
    return servo, cmc
