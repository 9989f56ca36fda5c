"""Rules of the palm's layout, checked when a parameter file loads (before any solid is built).

The palm's thenar holds the CMC where the frames place it: whether it can is measured by
``kinematics.thenar.thenar_margins`` (numpy), which the placement search keeps to as well; this
module turns a miss into the same :class:`ParamError` as the schema, naming the field, and runs the
routing model's own refusals (no OpenCascade). ``check`` is called by every command that loads a
parameter file for building or validating (``params validate``, ``build``, ``demo``).
"""

from __future__ import annotations


from .. import units
from ..params import ParamError
from ..params.rules import MIN_WALL
from ..kinematics.hand_params import HandParams
from ..kinematics.topology import SERVOS, chain
from .parts.common import mm


def check(params: HandParams) -> None:
    """Raise ParamError if the palm's thenar cannot hold the CMC (``thenar.thenar``): the CMC axis
    must climb into the palm within 60 deg of its normal (the column along it enters the palm's
    journal), the CMC base (a hub of half the thumb's width, the thumb's thickness, turning with the
    thumb) must stay a clearance below the palm's palmar face, and the thumb drive's turn above the
    CMC pulley's cavity a wall under the dorsal face; and if the routing model finds no clamp
    position for a loop or a drive (``routing.routes`` raises the ParamError: a joint's travel too
    large for its loop's pulleys and carrier), or a finger drive's coupler has no room in its palm
    channel or does not come out at the service angle (``couplers.couplers``) or its bore passes within
    two perimeters of a magnet pocket (``couplers.pocket_walls``), or if the tendons are
    too soft for the routed statics to couple every joint (``statics.hand_statics``: what ``Hand``
    computes, so a file that validates makes a model), or if the palm's heel
    reaches past the metacarpal block's front; and if the thenar's cuts (journal, cavity, turn) come
    within two perimeters of a finger socket's magnet pockets (``thenar.socket_pocket_gap``), or a
    servo's flange screw pilot opens above the forearm module's top (``forearm_layout.pilot_headroom``),
    or the CMC base comes within a clearance of the palm's heel (``forearm_layout.heel_gap``) or of the
    forearm module's block (``forearm_layout.forearm_gap``); or if no place along the forearm tab
    keeps a tab screw's pilot two perimeters from the palm's cuts (``Palm.tab_screws``); or if
    a print aid the build makes beside the parts refuses the file (``print_aids.AIDS``: the angle
    gauge's faces too short for its marks)."""
    from ..kinematics import couplers
    from ..kinematics import forearm_layout as FL
    from ..kinematics import frames as F
    from ..kinematics import routing, statics
    from ..kinematics import servo_geometry as SG
    from ..kinematics import thenar as TH

    src = params.source
    T0 = F.T_palm_thumb_cmc_base(params)
    fit = TH.thenar_margins(params, T0)
    if fit["tilt"] < 0.0:
        tilt = units.deg(TH.MAX_CMC_TILT - fit["tilt"])
        raise ParamError("palm.thumb_cmc_axis_deg", [round(units.deg(v), 6) for v in params.palm.thumb_cmc_axis],
                         f"tilts the CMC axis {tilt:.1f} deg from the palm's normal: the palm holds the CMC on a "
                         f"column along it, which must climb into the palm within {units.deg(TH.MAX_CMC_TILT):g} deg "
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
    gap, finger, cut = TH.socket_pocket_gap(params)
    if gap < MIN_WALL - 1e-12:
        names = {"journal": "column's journal", "cavity": "CMC pulley's cavity", "turn": "thumb drive's turn"}
        raise ParamError("palm.thumb_cmc_offset_mm", [round(mm(v), 6) for v in params.palm.thumb_cmc_offset],
                         f"with palm.thumb_cmc_axis_deg the palm's {names[cut]} comes {mm(gap):.3f} mm from the "
                         f"fingers.{finger} socket's magnet pockets (negative: into them); the gap must be >= "
                         f"{mm(MIN_WALL):g} mm, two perimeters", src)
    floor = cmc_base_floor(params)
    heel = FL.heel_gap(params, floor=floor)
    if heel < params.print.hole_clearance - 1e-12:
        raise ParamError("palm.thumb_cmc_offset_mm", [round(mm(v), 6) for v in params.palm.thumb_cmc_offset],
                         f"with palm.thumb_cmc_axis_deg and the palm's heel (palm.heel_height_mm = "
                         f"{mm(params.palm.heel_height):g}, palm.heel_length_mm = {mm(params.palm.heel_length):g}) "
                         f"the CMC base (its hub, its column up to the palm and its arm) comes {mm(heel):.3f} mm from "
                         f"the heel (negative: into it); the gap must be >= print.hole_clearance_mm = "
                         f"{mm(params.print.hole_clearance):g} mm", src)
    module = FL.forearm_gap(params, floor=floor)
    if module < params.print.hole_clearance - 1e-12:
        raise ParamError("palm.thumb_cmc_offset_mm", [round(mm(v), 6) for v in params.palm.thumb_cmc_offset],
                         f"with palm.thumb_cmc_axis_deg the CMC base (its hub, its column up to the palm and its arm) "
                         f"comes {mm(module):.3f} mm from the forearm module's block behind the palm (negative: into "
                         f"it); the gap must be >= print.hole_clearance_mm = {mm(params.print.hole_clearance):g} mm",
                         src)
    head, k = FL.pilot_headroom(params)
    if head < -1e-12:
        raise ParamError("servo.body_mm", [round(mm(v), 6) for v in params.servo.body],
                         f"places servo {SERVOS[k].label}'s flange screw pilot {mm(-head):.3f} mm above the forearm "
                         f"module's top (palm.thickness_mm / 2 + palm.wall_mm = "
                         f"{mm(SG.forearm_top(params)):g} mm): the pilot must open at or below it, so that the "
                         "screw's thread gets its full depth in the module", src)
    if params.palm.heel_height > 0.0:
        from .parts.palm import Palm

        x0, x1, y0, y1 = Palm(params).extents()
        if mm(params.palm.heel_length) > y1 - y0 + 1e-9:
            raise ParamError("palm.heel_length_mm", round(mm(params.palm.heel_length), 6),
                             f"must be <= {y1 - y0:.3f} mm: the heel lies under the metacarpal block, from its back "
                             "face to at most the block's front (behind the finger sockets and their flexion "
                             "limiters)", src)
    routing.routes(params)
    couplers.couplers(params)
    walls = couplers.pocket_walls(params)
    digit = min(walls, key=walls.get)
    if walls[digit] < MIN_WALL - 1e-9:
        raise ParamError("palm.magnet_lift_mm", round(mm(params.palm.magnet_lift), 6),
                         f"the {digit} drive's coupler bore passes {mm(walls[digit]):.3f} mm from a magnet pocket of "
                         f"its socket (it runs level toward servo {SERVOS[chain(digit).servo].label}): the wall "
                         f"must be >= {mm(MIN_WALL):g} mm, two perimeters; a larger palm.magnet_lift_mm (the "
                         "pockets higher) or smaller magnets open it", src)
    statics.hand_statics(params)
    # the forearm tab's screws move in along the tab off the palm's cuts; none that clears is refused
    from .parts.palm import Palm

    Palm(params).tab_screws()
    # the print aids refuse in their constructors what they cannot make (the angle gauge: faces too
    # short for their marks), which every build makes beside the parts
    from .print_aids import AIDS

    for aid in AIDS:
        aid(params)


def cmc_base_floor(params: HandParams) -> float:
    """z (m, the CMC base's frame) of the CMC base's lowest face: below its hub's palmar face where
    the MP guide's boss hangs lower (``cad.parts.thumb.ThumbCMCBase.palmar_floor``). The placement
    search is given it (``thumb_placement.thenar_constraint``): it does not depend on the placement."""
    from .parts.thumb import ThumbCMCBase

    return units.m(ThumbCMCBase(params).palmar_floor)
