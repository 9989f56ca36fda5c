"""Derived dimensions that the parameter rules and the models both compute: pure arithmetic on
numbers (SI), no parameter objects, so ``params.rules`` validates with exactly the laws
``kinematics.frames``, ``kinematics.routing`` and the parts build with. A foundation module
(docs/architecture.md): it imports nothing of the package.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

#: two perimeters of a 0.4 mm nozzle: the thinnest flank beside a tendon groove (m); the routing
#: model (``kinematics.routing.layout``) spaces the grooves by it
FLANK = 0.8e-3
#: how far past its joint boss a loop hub's groove is cut through the hub's rim (m;
#: ``cad.parts.tendons.groove_outer``)
HUB_GROOVE_PAST_BOSS = 1.0e-3


def digit_path(digit: str) -> tuple[str, ...]:
    """Where a digit's table sits in the parameter file, the one place: ``("thumb",)`` or
    ``("fingers", <name>)``."""
    return ("thumb",) if digit == "thumb" else ("fingers", digit)


def digit_field(digit: str) -> str:
    """The parameter file's table of a digit: ``thumb`` or ``fingers.<name>``."""
    return ".".join(digit_path(digit))


def digit_entry(tree, digit: str):
    """A digit's entry in a tree laid out like the parameter file (:func:`digit_path`): a mapping's
    ``tree["thumb"]`` / ``tree["fingers"][<name>]``, or an object's ``tree.thumb`` /
    ``tree.fingers[<name>]``."""
    head, *rest = digit_path(digit)
    node = tree[head] if isinstance(tree, Mapping) else getattr(tree, head)
    return node[rest[0]] if rest else node


def printed_hole(fit: float, compensation: float) -> float:
    """The diameter a round hole is modelled at so that it prints at ``fit``: FDM prints holes
    small (the outline is polygonised and the perimeter squeezed inward), so every hole that takes
    hardware grows by ``print.hole_compensation`` (diametral; docs/parts.md, the fit-test coupon)."""
    return fit + compensation


def slot_back(thickness: float, hole_clearance: float) -> float:
    """Distance from a joint's axis back to its clevis slot's back wall (the extension stop): the
    tongue's boss (half the digit's thickness) and a clearance. SI units."""
    return thickness / 2.0 + hole_clearance


def tendon_height(thinnest: float, wall: float) -> float:
    """z of the finger tendons where they cross the magnet face (any one unit): one palm ``wall``
    above the palmar face of the ``thinnest`` finger."""
    return -thinnest / 2.0 + wall


def magnet_pocket_centres(pocket: float, wall: float, lift: float) -> tuple[tuple[float, float], ...]:
    """(x, z) on a finger base's magnet face and its palm socket's face of the two magnet pockets'
    centres (any one unit): :func:`magnet_pocket_offset` either side, ``lift``
    (``palm.magnet_lift_mm``) dorsal of the face's centre."""
    s = magnet_pocket_offset(pocket, wall)
    return ((-s, lift), (s, lift))


def magnet_pocket_offset(pocket: float, wall: float) -> float:
    """Lateral offset (+-x of the magnet face's centre) of each of the two magnet pockets of a
    finger base and its palm socket: the pockets (diameter ``pocket``) one ``wall`` apart (lengths
    in any one unit). One implementation: the finger base and the palm cut them there, the palm's
    layout rules (``kinematics.thenar.socket_pocket_gap``) keep the thenar clear of them."""
    return (pocket + wall) / 2.0


def finger_base_thickness_ceiling(base_length: float, magnet_thickness: float, magnet_clearance: float,
                                  wall: float) -> float:
    """The thickest finger whose base holds, from its magnet face to the MCP axis (``base_length``):
    the magnet pockets (the magnet's thickness and its clearance deep), a ``wall`` and the MCP loop
    hub's groove, cut :data:`HUB_GROOVE_PAST_BOSS` past the joint boss (half the thickness). The
    groove's rim sweeps toward the magnet face over the pockets' floor. SI units."""
    return 2.0 * (base_length - magnet_thickness - magnet_clearance - wall - HUB_GROOVE_PAST_BOSS)


def servo_screw_offset(body_length: float, flange_span: float) -> float:
    """Distance along a servo's length from its body's centre to each flange screw: mid-ear, halfway
    between the body's end and the flange's (lengths in any one unit). One implementation: the servo mount
    (``cad.parts.servos``) drills its pilots there, ``params.rules`` checks the wall beside them."""
    return (body_length / 2.0 + flange_span / 2.0) / 2.0


def servo_pilot_wall(body_length: float, flange_span: float, pilot: float, hole_clearance: float) -> float:
    """The wall between a flange screw's pilot hole (diameter ``pilot``, at
    :func:`servo_screw_offset`) and the servo body's pocket (the body grown by a hole clearance):
    (flange_span - body_length) / 4 - pilot / 2 - hole_clearance. SI units."""
    return servo_screw_offset(body_length, flange_span) - pilot / 2.0 - (body_length / 2.0 + hole_clearance)


def finger_columns(pitch: float, arc_offset: float, metacarpals) -> list[tuple[float, float, float]]:
    """(x, y, phi) of each finger column's MCP (palm frame, SI, index at the origin) and its turn
    phi about -z: the columns fan out by arc_offset, phi_i = (i - (n - 1) / 2) arc_offset;
    adjacent columns meet the palm arc finger_pitch apart along the chord between them,
    perpendicular to the mean of their directions; each MCP then steps along its column by its
    metacarpal's length less the first's (the stepped metacarpal heads). One implementation:
    ``kinematics.frames`` places the fingers with it, ``params.rules`` checks their bases' room."""
    n = len(metacarpals)
    phis = [(i - (n - 1) / 2.0) * arc_offset for i in range(n)]
    x = y = 0.0
    out = []
    for i, phi in enumerate(phis):
        if i:
            m = (phis[i - 1] + phi) / 2.0
            x, y = x + pitch * math.cos(m), y - pitch * math.sin(m)
        step = metacarpals[i] - metacarpals[0]
        out.append((x + step * math.sin(phi), y + step * math.cos(phi), phi))
    return out
