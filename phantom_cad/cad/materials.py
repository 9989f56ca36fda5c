"""The bill of materials of one hand: bought parts (bearings, axles, magnets, screws, servos)
and cut lengths (tendons, cable springs), from the parameters and the part geometry.
numpy only; rows of ``item``, ``spec``, ``quantity``, ``used_in`` (the export writes them as
bom.csv, ``phantom_cad.export.bom``).
"""

from __future__ import annotations


from .. import units
from ..kinematics.hand_params import HandParams
from ..kinematics.topology import CMC_SERVO, DIGITS, FINGER_CHAINS, FINGERS, N_SERVOS, SERVOS, THUMB_CHAIN, joint


#: cord added to a cut length for each knot or clamp it ends in (mm): enough to tie and trim
KNOT_ALLOWANCE_MM = 20.0


def _cords(params: HandParams) -> list[dict]:
    """One row per routed tendon (``kinematics.routing``): its cut length, from the routing model's
    rest length of its strands (plus, for a drive, what its servo winds over the travel) and a
    knot allowance per end, and how it is anchored and tensioned."""
    from ..kinematics import couplers
    from ..kinematics import routing
    from ..kinematics import routing_paths
    rest = routing_paths.lengths(params)
    split = couplers.couplers(params)
    hw = params.hardware
    g = lambda v: f"{units.mm(v):g}"  # noqa: E731
    rows = []
    for r in routing.routes(params):
        t = r.tendon
        run = sum(rest[st.name] for st in r.strands)
        if t.kind == "drive" and t.digit in split:
            cp = split[t.digit]
            ch = params.digit(t.digit).chain
            palm, finger = cp.palm_strand, cp.finger_strand
            servo = SERVOS[ch.spec.servo]
            # the palm strand winds r u_max on its pulley; the finger strand's loop is doubled round
            # the cord behind the stop: its two legs run from the bight to the knot ahead of the stop
            cut_palm = units.mm(palm + ch.servo_radius * ch.travel[1]) + 2 * KNOT_ALLOWANCE_MM
            cut_finger = units.mm(finger + cp.length) + 2 * KNOT_ALLOWANCE_MM
            rows.append({"item": "tendon", "spec": f"{g(hw.tendon_diameter)} mm braided UHMWPE, {cut_palm:.0f} mm",
                         "quantity": 1, "used_in": (
                             f"{t.name}, palm strand (drive, split at the {t.digit} socket): knotted in "
                             f"{servo.link}'s anchor hole, wound on it, across the wrist and through the palm to the "
                             "socket; the crimp "
                             f"stop crimped on its end {units.mm(palm):.1f} mm from the anchor (working length), "
                             "with the servo at u = 0")})
            rows.append({"item": "tendon", "spec": f"{g(hw.tendon_diameter)} mm braided UHMWPE, {cut_finger:.0f} mm",
                         "quantity": 1, "used_in": (
                             f"{t.name}, finger strand: a loop (knot {units.mm(3 * hw.tendon_diameter):.1f} mm "
                             f"ahead of the stop) hooked round the palm strand behind its stop, through the finger "
                             f"base's entry, G1 and G2, knotted behind G2 {units.mm(finger):.1f} mm from the loop's "
                             "bight (working length); detach at the service angle "
                             f"{units.deg(cp.service_angle):.1f} deg (docs/assembly.md)")})
            continue
        if t.kind == "drive":
            ch = params.digit(t.digit).chain
            cut = units.mm(run + ch.servo_radius * ch.travel[1]) + 2 * KNOT_ALLOWANCE_MM
            how = ("knotted in the servo pulley's anchor hole, wound on it, across the wrist (and, for the thumb, "
                   "to its turn above the CMC pulley and down the CMC axis through the column) to G1 and G2, knotted "
                   "behind G2; tensioned by setting the servo horn's zero")
            spec = f"{g(hw.tendon_diameter)} mm braided UHMWPE, {cut:.0f} mm"
        elif t.kind == "loop":
            cut = units.mm(run) + 4 * KNOT_ALLOWANCE_MM
            loop_servo = SERVOS[CMC_SERVO].title
            how = (f"closed loop: one end knotted in {loop_servo}'s pulley's strand-a anchor hole, through the forearm "
                   "module's channel and the thenar's slot, round the CMC pulley through both of its anchor holes "
                   f"(a knot in each well), back to {loop_servo}'s pulley and knotted in its strand-b anchor hole, "
                   "with the "
                   "servo and the CMC both at 0; pulled taut before the last knot")
            spec = f"{g(hw.tendon_diameter)} mm braided UHMWPE, {cut:.0f} mm"
        elif t.kind == "coupling":
            cut = units.mm(run) + 2 * KNOT_ALLOWANCE_MM
            a, b = t.joints
            how = (f"figure eight: knotted at its middle in the {b.split('_', 1)[1].upper()} groove's knot pocket, "
                   f"both ends crossed over the carrier and pinched under the M2 set screw in the "
                   f"{a.split('_', 1)[1].upper()} hub; pulled taut at rest, then the screw tightened")
            spec = f"{g(hw.tendon_diameter)} mm braided UHMWPE, {cut:.0f} mm"
        else:
            cut = units.mm(run) + 2 * KNOT_ALLOWANCE_MM
            how = "knotted on the dorsal face at both knot wells, at its free length with the digit extended"
            spec = f"{g(params.cad.spring_diameter)} mm elastic cord, {units.mm(run):.0f} mm free length ({cut:.0f} mm cut)"
        rows.append({"item": "tendon" if t.kind != "return" else "cable spring", "spec": spec, "quantity": 1,
                     "used_in": f"{t.name} ({t.kind}): {how}"})
    return rows


def _bearings(params: HandParams) -> dict[str, int]:
    """Bearings per digit: one per joint whose tongue has a face where the seat fits beside the
    grooves (``phalanx.tongue_bearing_face``); the others turn on the axle in their bore."""
    from .parts.common import DigitSection
    from .parts.phalanx import tongue_bearing_face
    from .parts.tendons import link_tendons
    out = {}
    for spec in FINGER_CHAINS + (THUMB_CHAIN,):
        sec = DigitSection(params, spec.digit)
        n = 0
        for jn in spec.joint_names:
            j = joint(jn)
            if tongue_bearing_face(sec, jn, link_tendons(params, j.child)) is not None:
                n += 1
        out[spec.digit] = n
    return out


def bill_of_materials(params: HandParams) -> list[dict]:
    hw = params.hardware
    g = lambda v: f"{units.mm(v):g}"  # noqa: E731
    n_joints = {c.digit: len(c.keys) for c in FINGER_CHAINS + (THUMB_CHAIN,)}
    n_bearings = _bearings(params)
    bom = [{
        "item": "bearing",
        "spec": f"{g(hw.bearing_bore)} x {g(hw.bearing_outer)} x {g(hw.bearing_width)} mm (683ZZ class)",
        "quantity": sum(n_bearings.values()),
        "used_in": "one per joint where it fits beside the tendon grooves, in the child link's tongue: " + ", ".join(
            f"{d} x{n} of {n_joints[d]}" for d, n in n_bearings.items()),
    }] if sum(n_bearings.values()) else []      # none fits: every joint turns on its axle
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
                "quantity": 2 * N_SERVOS,
                "used_in": "servo flanges: servos 1-6 into the forearm module's pilot holes"})
    from .parts import wrist
    tab = params.palm.wall + engage
    bom.append({"item": "screw", "spec": f"M{g(hw.screw_diameter)} x {units.mm(tab):.0f} self-tapping",
                "quantity": len(wrist.tab_screw_places(params)),
                "used_in": "the forearm module's tab into the palm's dorsal face at the wrist"})
    bom.append({"item": "screw", "spec": f"M{g(hw.screw_diameter)} horn screw (servo accessory)",
                "quantity": 2 * N_SERVOS, "used_in": "servo pulleys 1-6 to their horns"})
    n_loops = sum(n - 1 for n in n_joints.values())
    from ..kinematics import couplers
    from ..kinematics import routing
    # the hub clamp's pilot: from the cheek's outer face across the loop's groove (parts.tendons)
    pilot = min(params.digit(d).width / 2.0 - abs(routing.layout(params, d).loop_x[0]) + routing.layout(params, d).groove / 2.0
                for d in n_joints)
    bom.append({"item": "screw", "spec": f"M{g(hw.screw_diameter)} x {int(units.mm(pilot))} set screw (grub screw)",
                "quantity": n_loops, "used_in": "one per coupling loop: clamps and tensions it in its hub"})
    bom += _cords(params)
    split = couplers.couplers(params)
    bom.append({"item": "crimp stop", "spec": f"crimp sleeve {g(hw.stop_diameter)} x {g(hw.stop_length)} mm "
                f"for {g(hw.tendon_diameter)} mm cord", "quantity": len(split),
                "used_in": "ends the palm strand of each finger drive at the magnet face: "
                + ", ".join(f"{d}_drive" for d in split)})
    sv = params.servo
    bom.append({"item": "servo",
                "spec": "micro servo, body " + " x ".join(g(v) for v in sv.body) + " mm (SCS0009 class)",
                "quantity": N_SERVOS,
                "used_in": f"forearm module: {SERVOS[THUMB_CHAIN.servo].label} thumb flexion, "
                           f"{SERVOS[FINGER_CHAINS[0].servo].label}-{SERVOS[FINGER_CHAINS[-1].servo].label} fingers, "
                           f"{SERVOS[CMC_SERVO].label} thumb CMC (through the CMC loop)"})
    return bom
