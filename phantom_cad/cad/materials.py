"""The bill of materials of one hand: bought parts (bearings, axles, magnets, screws, servos)
and cut lengths (tendons, cable springs), from the parameters and the part geometry.
numpy only; rows of ``item``, ``spec``, ``quantity``, ``used_in`` (the export writes them as
bom.csv, ``phantom_cad.export.bom``).
"""

from __future__ import annotations

import numpy as np

from .. import units
from ..kinematics import frames as F
from ..kinematics.topology import (CMC_Q, CMC_SERVO, DIGITS, FINGER_CHAINS, FINGERS, JOINTS, N_SERVOS, SERVOS,
                                   THUMB_CHAIN)


def _tendon_lengths(params) -> dict[str, float]:
    """Cut length (mm) of each tendon: servo pulley tangent -> palm -> finger base -> guides ->
    along the phalanges to the distal anchor, plus the length wound on the servo pulley over
    its full travel."""
    out = {}
    for spec in FINGER_CHAINS:
        f = spec.digit
        fp = params.fingers[f]
        chain = fp.chain
        exit_ = F.socket_tendon_point(params, f)
        Ts = F.T_palm_servo(params, spec.servo)
        tangent = (Ts @ np.array([-chain.servo_radius, 0, 0, 1.0]))[:3]
        palm = np.linalg.norm(exit_ - tangent)
        base = params.cad.finger_base_length
        run = palm + base + chain.guide.L0 + fp.proximal + fp.middle + fp.distal / 2.0
        wrap = chain.servo_radius * chain.travel[1]
        out[f] = units.mm(run + wrap)
    th = params.thumb
    from .parts.palm import Palm   # numpy only until build()
    palm = Palm(params)
    path = palm.thumb_tendon_path()             # mm: servo -> palm exit -> post -> arch -> CMC axis
    run = units.m(sum(float(np.linalg.norm(b - a)) for a, b in zip(path, path[1:])))
    run += units.m(palm.cmc_arch()["z_lo"])     # down the CMC axis to the CMC base's mid-plane
    run += th.metacarpal + th.chain.guide.L0 + th.proximal + th.distal / 2.0
    out[THUMB_CHAIN.digit] = units.mm(run + th.chain.servo_radius * th.chain.travel[1])
    return out


def _spring_lengths(params) -> dict[str, float]:
    """Free length (mm) of each dorsal cable spring, anchor to anchor at full extension."""
    out = {}
    for f in FINGERS:
        fp = params.fingers[f]
        out[f] = units.mm(params.cad.finger_base_length + fp.proximal + fp.middle + fp.distal / 2.0)
    th = params.thumb
    out[THUMB_CHAIN.digit] = units.mm(th.metacarpal + th.proximal + th.distal / 2.0)
    return out


def bill_of_materials(params) -> list[dict]:
    hw = params.hardware
    g = lambda v: f"{units.mm(v):g}"  # noqa: E731
    n_joints = {c.digit: len(c.keys) for c in FINGER_CHAINS + (THUMB_CHAIN,)}
    bom = [{
        "item": "bearing",
        "spec": f"{g(hw.bearing_bore)} x {g(hw.bearing_outer)} x {g(hw.bearing_width)} mm (683ZZ class)",
        "quantity": 2 * sum(n_joints.values()),
        "used_in": "two per joint, in the child link's tongue: " + ", ".join(
            f"{d} x{n}" for d, n in n_joints.items()),
    }]
    for d in DIGITS:
        width = units.mm(params.digit(d).width)
        bom.append({"item": "axle", "spec": f"{g(hw.axle_diameter)} mm steel pin, {width:g} mm long",
                    "quantity": n_joints[d], "used_in": f"{d} joints (pressed into the clevis cheeks)"})
    bom.append({"item": "magnet", "spec": f"disc {g(hw.magnet_diameter)} x {g(hw.magnet_thickness)} mm (N52)",
                "quantity": 4 * len(FINGERS),
                "used_in": "two per finger base and two per palm socket"})
    from .parts.common import Tolerances   # numpy only
    engage = units.m(Tolerances(params).screw_engagement)
    bom.append({"item": "screw",
                "spec": f"M{g(hw.screw_diameter)} self-tapping, {g(engage)} mm thread engagement + servo flange",
                "quantity": 2 * N_SERVOS, "used_in": "servo flanges into the palm's pilot holes"})
    bom.append({"item": "screw", "spec": f"M{g(hw.screw_diameter)} horn screw (servo accessory)",
                "quantity": 2 * N_SERVOS, "used_in": "servo pulleys 1-6 to their horns"})
    cmc = params.thumb.thickness + params.print.hole_clearance + engage
    bom.append({"item": "screw", "spec": f"M{g(hw.screw_diameter)} x {units.mm(cmc):.0f} self-tapping",
                "quantity": 2, "used_in": f"{JOINTS[CMC_Q].child} through its hub into {SERVOS[CMC_SERVO].link}"})
    for d, L in _tendon_lengths(params).items():
        bom.append({"item": "tendon", "spec": f"{g(hw.tendon_diameter)} mm braided UHMWPE, {L:.0f} mm",
                    "quantity": 1, "used_in": f"{d}: servo pulley to distal anchor"})
    for d, L in _spring_lengths(params).items():
        bom.append({"item": "cable spring",
                    "spec": f"{g(params.cad.spring_diameter)} mm elastic cord, {L:.0f} mm free length",
                    "quantity": 2, "used_in": f"{d}: dorsal return path, base anchor to distal anchor"})
    sv = params.servo
    bom.append({"item": "servo",
                "spec": "micro servo, body " + " x ".join(g(v) for v in sv.body) + " mm (SCS0009 class)",
                "quantity": N_SERVOS, "used_in": "palm: u1 thumb flexion, u2-u5 fingers, u6 thumb CMC"})
    return bom
