"""A parameter file for a person (``phantom-cad size``): the default hand's file
(params/phantom.toml) as the template, every size-dependent choice re-solved for the person's hand
length, breadth and measured segments (:mod:`.solvers`), the thumb's CMC placement the
reference's scaled where it opposes, else searched for opposition as ``params opposition --solve``
does (``kinematics.thumb_placement``), and the result validated. Imports params and kinematics,
never CAD: the caller hands in the CAD layer's pre-build check (``cad.preflight.check``).
docs/sizing.md."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Callable

from .. import units
from ..errors import ParamError, UserError
from ..kinematics.dimensions import FLANK, digit_entry, finger_base_thickness_ceiling, printed_hole
from ..kinematics.hand_params import HandParams
from ..kinematics.topology import DIGITS, FINGERS, chain
from ..params import DEFAULT_PARAMS, load_document, parse
from ..params.rules import MIN_WALL
from . import solvers as S
from .inputs import Person, check_person, read_segments

__all__ = ["Person", "Sizing", "read_segments", "size", "segment_lengths", "HAND_LENGTH_RANGE",
           "HAND_BREADTH_RANGE"]

#: the hand lengths (mm) the sizing tries: beyond them no adult hand lies (the files it writes
#: validate from 135 mm, docs/sizing.md; a length that does not is refused with its binding rule)
HAND_LENGTH_RANGE = (50.0, 400.0)
#: the hand breadths (mm) the sizing accepts: the widths they set are tested over it (docs/sizing.md)
HAND_BREADTH_RANGE = (65.0, 105.0)


class Infeasible(UserError):
    """No file for this hand length keeps ``rule`` (the binding rule, one line, no remedy):
    :func:`size` names the nearest hand length that works."""

    def __init__(self, rule: str):
        self.rule = rule
        super().__init__(rule)


@dataclass(frozen=True)
class Sizing:
    document: dict            # the parameter file, as TOML tables
    params: HandParams        # the document validated
    margin: float             # rad: the opposition margin of the placement chosen
    searched: bool            # the placement is the search's (False: the reference's, scaled)
    unpinched: tuple[str, ...] = ()   # the opposed fingers whose pads the thumb's misses on the printed tips

    @property
    def opposes(self) -> bool:
        """The thumb's pad meets the index, middle and ring pads squarely on the model (margin >= 0)
        and on the printed tips."""
        return self.margin >= 0.0 and not self.unpinched

    @property
    def rank(self) -> tuple:
        """Better placements rank higher: the printed tips' pinches missed, then the margin."""
        return -len(self.unpinched), self.margin


def template() -> dict:
    """The reference hand's document (params/phantom.toml)."""
    return load_document(DEFAULT_PARAMS)


def segment_lengths(person: Person, doc: dict) -> dict[str, dict[str, float]]:
    """Every digit's segment lengths (mm): the person's where measured, else the reference file's
    fraction of the hand length (Buchholz, Armstrong & Goldstein 1992, Table 1)."""
    out = {}
    for d in DIGITS:
        fractions = digit_entry(doc, d)["length_fraction"]
        given = person.segments.get(d, {})
        out[d] = {s: given.get(s, fractions[s] * person.hand_length) for s in chain(d).segments}
    return out


def _check_range(person: Person) -> None:
    for flag, v, (lo, hi), what in (
            ("--hand-length", person.hand_length, HAND_LENGTH_RANGE, "the lengths the sizing tries"),
            ("--hand-breadth", person.hand_breadth, HAND_BREADTH_RANGE, "the breadths the sizing is tested over")):
        if not math.isfinite(v) or not lo <= v <= hi:
            nearest = lo if not v > lo else hi
            raise UserError(f"{flag} {v:g}: must lie in [{lo:g}, {hi:g}] mm, {what} (docs/sizing.md); nearest "
                            f"that works: {flag} {nearest:g}")
    if person.side not in ("right", "left"):
        raise UserError(f"--side {person.side}: must be right or left")


def _refuse(digit: str, seg: str, length: float, given: bool, floor: float, ceiling: float, factor: float,
            clearance: float, why: str) -> UserError:
    """The thickness a digit needs does not fit in one of its phalanges: Infeasible (:func:`size`
    names the nearest hand length) or, for a measured phalanx, the measured length that works."""
    rule = (f"the {digit} {seg} phalanx ({length:.2f} mm) leaves the {digit} at most {ceiling:.2f} mm thick (its "
            f"two joint bosses and clearances must fit in it), the {digit} needs at least {floor:.2f} mm ({why})")
    if not given:
        return Infeasible(rule)
    need = factor * floor + 2.0 * clearance
    return UserError(f"{rule}; nearest that works: {digit}.{seg} >= {S.up(need + 1e-6, 0.1):.1f} mm in --segments")


def _hardware(doc: dict, lengths: dict) -> tuple[tuple[float, float], tuple[float, float, float]]:
    """The largest magnet and bearing of the catalogue (:data:`solvers.MAGNETS`, ``BEARINGS``) with
    which every finger's thickness floor stays under what its phalanges allow."""
    pr, palm, hw = doc["print"], doc["palm"], doc["hardware"]
    for magnet in S.MAGNETS:
        for bearing in S.BEARINGS:
            floor = S.finger_thickness_floor(magnet, palm["wall_mm"], hw["tendon_diameter_mm"],
                                             pr["hole_clearance_mm"], pr["magnet_clearance_mm"],
                                             pr.get("hole_compensation_mm", 0.2), bearing[1])
            if all(S.thickness_limit(lengths[f], chain(f).segments, _limits(doc, f), chain(f).keys,
                                     pr["hole_clearance_mm"])[0] > S.up(floor + 1e-6) for f in FINGERS):
                return magnet, bearing
    return S.MAGNETS[-1], S.BEARINGS[-1]


def _limits(doc: dict, digit: str) -> dict[str, float]:
    return {k: v[1] for k, v in digit_entry(doc, digit)["limits_rad"].items()}


def build_document(person: Person) -> dict:
    """The person's parameter file as TOML tables, every size-dependent choice solved; the CMC
    placement the reference's, scaled with the hand length (:func:`size` searches it)."""
    _check_range(person)
    ref = template()
    doc = copy.deepcopy(ref)
    hl = person.hand_length
    lengths = segment_lengths(person, ref)
    check_person(person, lengths)
    doc["hand"].update(name=person.name, side=person.side, hand_length_mm=hl)
    pr, cad, hw = doc["print"], doc["cad"], doc["hardware"]
    cl, comp = pr["hole_clearance_mm"], pr.get("hole_compensation_mm", 0.2)
    magnet, bearing = _hardware(ref, lengths)
    hw["magnet"] = {"diameter_mm": magnet[0], "thickness_mm": magnet[1]}
    hw["bearing"] = {"bore_mm": bearing[0], "outer_mm": bearing[1], "width_mm": bearing[2]}
    hw["axle_diameter_mm"] = bearing[0]
    axle_bore = printed_hole(bearing[0] + 2.0 * cl, comp) / 2.0
    cord = max(hw["tendon_diameter_mm"], cad["spring_diameter_mm"])
    channel = cad["spring_diameter_mm"] + 2.0 * cl        # the return cord's channel
    widths = {}
    for d in DIGITS:
        t, r = digit_entry(doc, d), digit_entry(ref, d)
        spec = chain(d)
        limits = _limits(ref, d)
        given = person.segments.get(d, {})
        ceiling, seg = S.thickness_limit(lengths[d], spec.segments, limits, spec.keys, cl)
        if d != "thumb":
            # the finger base holds the magnets, a wall and the MCP loop hub's groove between its magnet
            # face and the MCP axis (params.rules._guides)
            ceiling = min(ceiling, units.mm(finger_base_thickness_ceiling(
                units.m(cad["finger_base_length_mm"]), units.m(magnet[1]), units.m(pr["magnet_clearance_mm"]),
                MIN_WALL)))
        if d == "thumb":
            # the smallest pulley outside the axle bore, the largest (in ratio) inside the joint boss
            ratio = max(r["pulley_radius_mm"].values()) / min(r["pulley_radius_mm"].values())
            t_floor = max(bearing[1], 2.0 * (ratio * (axle_bore + cord / 2.0)
                                             + max(cord / 2.0, S.return_room(channel))))
            w_floor = S.digit_width_floor(cl, cad["cheek_mm"], hw["tendon_diameter_mm"], cad["spring_diameter_mm"],
                                          units.mm(FLANK))
            why = f"the joint bearing ({bearing[1]:g} mm) and pulleys outside the axle bore"
        else:
            t_floor = S.finger_thickness_floor(magnet, doc["palm"]["wall_mm"], hw["tendon_diameter_mm"], cl,
                                               pr["magnet_clearance_mm"], comp, bearing[1])
            w_floor = S.finger_width_floor(magnet, doc["palm"]["wall_mm"], cl, pr["magnet_clearance_mm"], comp,
                                           cad["cheek_mm"], hw["tendon_diameter_mm"], cad["spring_diameter_mm"],
                                           units.mm(FLANK))
            why = (f"the tendon enters its base below two {magnet[0]:g} x {magnet[1]:g} mm magnet pockets, one "
                   f"palm wall above the palmar face")
        thick = S.section(r["thickness_mm"] * hl / S.REFERENCE_LENGTH, t_floor, ceiling)
        if math.isnan(thick):
            far = spec.keys[spec.segments.index(seg)] if spec.segments.index(seg) < len(spec.keys) else None
            factor = 1.5 if far is not None and limits[far] > math.pi / 2.0 else 1.0
            raise _refuse(d, seg, lengths[d][seg], seg in given, S.up(t_floor + 1e-6), ceiling, factor, cl, why)
        w_target = given.get("width", r["width_mm"] * person.hand_breadth / S.REFERENCE_BREADTH)
        if d == "thumb":
            w_ceiling = 2.0 * (lengths[d]["metacarpal"] - thick / 2.0 - cl)
        else:
            w_ceiling = units.mm(S.MAX_FINGER_PITCH) - S.PITCH_CLEARANCE
        width = S.section(w_target, w_floor, w_ceiling)
        if math.isnan(width):
            why = (f"its metacarpal, {lengths[d]['metacarpal']:.2f} mm, holds the CMC hub of half its width"
                   if d == "thumb" else "the finger pitch's largest less the room between flexed fingers")
            raise Infeasible(f"the {d} must be at least {w_floor:.2f} mm wide (its clevis and magnet pockets) and "
                             f"at most {w_ceiling:.2f} mm ({why})")
        widths[d] = width
        radii = S.pulley_radii(tuple(r["pulley_radius_mm"][k] for k in spec.keys), thick, axle_bore, cord,
                                channel)
        if math.isnan(radii[0]):
            raise Infeasible(f"the {d} ({thick:g} mm thick) holds no pulleys between the axle bore "
                             f"({axle_bore:.2f} mm) and its joint bosses")
        base_room = cad["finger_base_length_mm"] if d != "thumb" else lengths[d]["metacarpal"] - width / 2.0
        g = r["guide"]
        d1, d2, alpha = S.guide((g["d1_mm"], g["d2_mm"], g["alpha_deg"]), thick, hw["tendon_diameter_mm"], cl,
                                cad["eyelet_length_mm"], base_room)
        if math.isnan(d1):
            raise Infeasible(f"the {d} ({thick:g} mm thick) leaves its guide eyelets no room between the joint "
                             "boss and its palmar face")
        travel_hi = S.servo_travel(d1, d2, alpha, r["servo_pulley_radius_mm"], radii,
                                   tuple(limits[k] for k in spec.keys))
        if travel_hi > S.MAX_SERVO_TRAVEL:
            raise Infeasible(f"the {d} servo would turn {travel_hi:g} deg to reach its joint limits, more than the "
                             f"{S.MAX_SERVO_TRAVEL:g} deg a drive's clamp allows")
        t.update(length_fraction={s: round(lengths[d][s] / hl, 6) for s in spec.segments},
                 width_mm=width, thickness_mm=thick,
                 pulley_radius_mm={k: radii[spec.keys.index(k)] for k in r["pulley_radius_mm"]},
                 guide={"d1_mm": d1, "d2_mm": d2, "alpha_deg": alpha},
                 servo_travel_deg=[0.0, travel_hi],
                 path_length_mm={key: S.path_length(
                     lengths[d][seg],
                     (r["path_length_mm"][key] - r["length_fraction"][seg] * S.REFERENCE_LENGTH) * radii[0]
                     / r["pulley_radius_mm"][spec.keys[0]], radii[i], radii[i + 1])
                     for i, (key, seg) in enumerate(spec.spans)})
    palm = doc["palm"]
    palm["finger_pitch_mm"], narrowed = S.palm_layout(
        {f: widths[f] for f in FINGERS}, {f: lengths[f]["metacarpal"] for f in FINGERS}, palm["arc_offset_deg"],
        cad["finger_base_length_mm"], cl)
    for f in FINGERS:
        digit_entry(doc, f)["width_mm"] = narrowed[f]
    thickest = max(digit_entry(doc, f)["thickness_mm"] for f in FINGERS)
    palm["thickness_mm"] = max(S.scaled(ref["palm"]["thickness_mm"], hl), S.up(thickest + 2.0 * cl + 1e-6))
    palm["heel_height_mm"] = S.scaled(ref["palm"]["heel_height_mm"], hl)
    palm["heel_length_mm"] = S.scaled(ref["palm"]["heel_length_mm"], hl)       # placed by heel()
    palm["thumb_cmc_offset_mm"] = [round(v * hl / S.REFERENCE_LENGTH, 4) for v in ref["palm"]["thumb_cmc_offset_mm"]]
    flexed_spacing(doc)
    palm["thickness_mm"] = palm_thickness(doc)
    heel(doc)
    magnet_lift(doc)
    return doc


#: how far (mm) behind the most distal position where every finger wraps the power grasp's cylinder
#: the heel lays it: it covers where the model's shapes and the parts meet it apart
#: (kinematics.power_grasp); the hold in MuJoCo keeps within its limits over a few millimetres
#: behind that position (docs/parts.md "Power grasp")
HEEL_MARGIN = 1.0
#: the grid (mm) the heel's length is solved on
HEEL_STEP = 0.1


def heel(doc: dict) -> None:
    """The palm's heel (``palm.heel_height_mm``, ``heel_length_mm``): as deep as the 95th-percentile
    palm envelope at this hand length leaves below the metacarpal block (:data:`solvers.PALM_ENVELOPE`,
    at least the reference's heel in proportion), and as long as puts the power grasp's cylinder,
    laid against it (``kinematics.power_grasp.laid_axis_y``), :data:`HEEL_MARGIN` behind the most
    distal position where every finger's first contact lies past its equator (``wrapping_axis_y``).
    Infeasible where no position across the palm wraps."""
    from ..kinematics import power_grasp as PG
    from ..kinematics.forearm_layout import heel_box, heel_clear_y
    from ..kinematics.model import Hand
    from ..kinematics.servo_geometry import palm_back

    palm = doc["palm"]
    envelope = S.PALM_ENVELOPE[1] * doc["hand"]["hand_length_mm"] / S.REFERENCE_LENGTH
    palm["heel_height_mm"] = max(palm["heel_height_mm"], S.down(envelope - palm["thickness_mm"]))
    p = parse(doc)
    diameter = PG.power_grasp_diameter_mm(p)
    wraps = PG.wrapping_axis_y(p, Hand(p, compensation="paper"), diameter)      # as the check closes it
    if wraps is None:
        raise Infeasible(f"no position across the palm where every finger's first contact with the power grasp's "
                         f"{diameter:.1f} mm cylinder lies past its equator (a finger meets it first on its "
                         "distal side)")
    # the cylinder's axis lies a fixed distance in front of the heel's front: the heel's length moves both
    ahead = heel_clear_y(p, units.m(PG.resting_z(p, diameter)), units.m(diameter / 2.0 + PG.PALM_GAP_MM)) \
        - float(heel_box(p)[1][1])
    front = units.m(wraps - HEEL_MARGIN) - ahead
    palm["heel_length_mm"] = round(round(units.mm(front - palm_back(p)) / HEEL_STEP) * HEEL_STEP, 6)


#: the grid (mm) palm.magnet_lift_mm is solved on
LIFT_STEP = 0.1


def magnet_lift(doc: dict) -> None:
    """Lift the magnet pockets on the finger bases' magnet faces and the palm sockets
    (``palm.magnet_lift_mm``, on a 0.1 mm grid) until every finger drive's coupler bore, which runs
    below them toward its servo, keeps two perimeters to them (``couplers.pocket_walls``, the rule
    ``cad.preflight`` checks) at the document's placement; not at all where the bores clear, and
    no higher than the rule allows (a wall under the thinnest finger's dorsal face): where nothing
    clears the document keeps the pockets centred, and the rule refuses it naming the wall."""
    from ..kinematics import couplers

    palm = doc["palm"]
    palm.pop("magnet_lift_mm", None)
    for k in range(200):
        if k:
            palm["magnet_lift_mm"] = round(k * LIFT_STEP, 6)
        try:
            if min(couplers.pocket_walls(parse(doc)).values()) >= MIN_WALL - 1e-12:
                return
        except ParamError:
            break
    palm.pop("magnet_lift_mm", None)


def flexed_spacing(doc: dict) -> None:
    """Raise the document's finger pitch on the half-millimetre grid until neighbouring fingers,
    flexed over every pair of their commands, stay :data:`solvers.FLEXED_CLEARANCE` apart
    (``kinematics.finger_clearance.neighbour_clearance``: the phalanges' boxes and the finger bases');
    at the palm layout's largest pitch, narrow the wider of the pair that comes closest instead
    (Infeasible when it is then narrower than its rules allow)."""
    from ..kinematics.finger_clearance import neighbour_clearance
    from ..kinematics.model import Hand

    palm = doc["palm"]
    top = units.mm(S.MAX_FINGER_PITCH)
    while True:
        p = parse(doc)
        gap, (a, b) = neighbour_clearance(p, Hand(p, compensation="paper"))    # the ideal coupling
        if units.mm(gap) >= S.FLEXED_CLEARANCE - 1e-9:
            return
        if palm["finger_pitch_mm"] + S.STEP <= top + 1e-9:
            palm["finger_pitch_mm"] += S.STEP
            continue
        wa, wb = digit_entry(doc, a)["width_mm"], digit_entry(doc, b)["width_mm"]
        wider = a if wa >= wb else b
        digit_entry(doc, wider)["width_mm"] -= S.STEP
        try:
            parse(doc)
        except ParamError as exc:
            raise Infeasible(f"the {a} and {b} fingers, flexed, come {units.mm(gap):.2f} mm apart at the largest "
                             f"finger pitch ({top:g} mm); the {wider} cannot be narrower ({exc})") from None


def palm_thickness(doc: dict) -> float:
    """The palm's thickness (mm): the document's (the reference's scaled, or the thickest finger's
    limiter), raised on the half-millimetre grid until the thumb drive's turn onto the CMC axis,
    above the CMC pulley's cavity, keeps its relief and wall under the dorsal face
    (``kinematics.thenar.thenar_margins``, the rule ``cad.preflight`` checks) at the document's CMC
    placement."""
    from ..kinematics import frames as F
    from ..kinematics import thenar as TH

    trial = copy.deepcopy(doc)
    for _ in range(40):
        p = parse(trial)
        if TH.thenar_margins(p, F.T_palm_thumb_cmc_base(p))["turn"] >= 0.0:
            break
        trial["palm"]["thickness_mm"] += S.STEP
    return trial["palm"]["thickness_mm"]


def _works(person: Person, check: Callable[[HandParams], None]) -> bool:
    try:
        check(parse(build_document(person)))
    except (UserError, ParamError):
        return False
    return True


def nearest_length(person: Person, check: Callable[[HandParams], None]) -> float | None:
    """The whole millimetre of hand length nearest the person's whose file validates (the person's
    breadth and measured segments kept; the reference placement scaled), or None: bisection between
    the person's length and the reference's (the lengths that validate are one interval around it,
    docs/sizing.md), or beyond the reference up to the end of :data:`HAND_LENGTH_RANGE`."""
    from dataclasses import replace

    def works(hl: float) -> bool:
        return _works(replace(person, hand_length=hl), check)

    ref = S.REFERENCE_LENGTH
    if not works(ref):
        far = HAND_LENGTH_RANGE[1] if person.hand_length < ref else HAND_LENGTH_RANGE[0]
        if not works(far):
            return None
        ref = far
    bad = float(math.floor(person.hand_length) if person.hand_length < ref else math.ceil(person.hand_length))
    good = ref
    while abs(good - bad) > 1.0:
        mid = float(math.floor((good + bad) / 2.0))
        if works(mid):
            good = mid
        else:
            bad = mid
    return good


def _opposition(params: HandParams) -> tuple[float, tuple[str, ...]]:
    """The opposition margin (rad, ``kinematics.opposition``) and the opposed fingers whose pads the
    thumb's pad does not meet on the printed tips (``kinematics.printed_tips``: where the tips'
    square ends meet first, as the solids' do)."""
    from ..kinematics import opposition, printed_tips
    from ..kinematics.model import Hand

    hand = Hand(params)
    reach = opposition.reach(hand)
    margin = min(reach[f].margin for f in opposition.OPPOSED)
    if margin < 0.0:
        return margin, opposition.OPPOSED
    return margin, tuple(f for f in opposition.OPPOSED if printed_tips.printed_pinch(hand, f) is None)


#: the placement searches (population, generations) tried in turn, one seed each, while the best
#: placement does not oppose (:attr:`Sizing.opposes`): ``params opposition --solve``'s, then larger
#: ones (the landscape has several optima: docs/opposition.md; the search maximizes the capsules'
#: margin, and of its optima some meet the printed tips pad to pad and some do not)
SEARCHES = ((8, 60),) + ((12, 80),) * 5


def size(person: Person, check: Callable[[HandParams], None] | None = None, search: bool = True,
         seed: int = 0, searches: int = len(SEARCHES), floor: Callable[[HandParams], float] | None = None) -> Sizing:
    """The person's validated parameter file. ``check``: what else a file must pass (the CAD
    layer's ``preflight.check``); ``floor``: the CMC base's lowest face the search keeps off the
    palm's heel and the forearm module (the CAD layer's ``preflight.cmc_base_floor``). The CMC
    placement is the reference's, scaled with the hand length, where the thumb's pad meets the
    index, middle and ring pads on it (:attr:`Sizing.opposes`): the placement whose postures and
    grasps docs/postures.md and docs/grasps.md measure. Where it does not, and ``search``, it is
    searched (seconds), with up to ``searches`` of :data:`SEARCHES` (seeds ``seed``, ``seed + 1``,
    ...) until a placement opposes; of the placements that validate, the best ranked
    (:attr:`Sizing.rank`) is kept. A UserError or ParamError (one line) when nothing validates."""
    check = check or (lambda p: None)
    try:
        doc = build_document(person)
        start = parse(doc)
        check(start)
    except (Infeasible, ParamError) as exc:
        rule = exc.rule if isinstance(exc, Infeasible) else f"{exc.field} = {exc.value!r}: {exc.rule}"
        found = nearest_length(person, check)
        nearest = (f"--hand-length {found:g}" if found is not None else
                   f"none between {HAND_LENGTH_RANGE[0]:g} and {HAND_LENGTH_RANGE[1]:g} mm with these segments")
        raise UserError(f"--hand-length {person.hand_length:g}: {rule}; nearest that works: {nearest}") from None
    best, error = None, None

    def consider(d: dict, searched: bool) -> None:
        nonlocal best, error
        try:
            p = parse(d)
            check(p)
        except ParamError as exc:
            error = error or exc
            return
        margin, unpinched = _opposition(p)
        found = Sizing(d, p, margin, searched, unpinched)
        if best is None or found.rank > (best.rank[0], best.margin + 1e-9):
            best = found

    consider(doc, False)
    if search:
        from ..kinematics import thumb_placement
        from ..kinematics.model import Hand

        constraint = thumb_placement.thenar_constraint(start, floor=floor(start) if floor else None)
        for k, (population, generations) in enumerate(SEARCHES[:searches]):
            if best is not None and best.opposes:
                break
            sol = thumb_placement.solve(Hand(start), seed=seed + k, population=population,
                                        generations=generations, constraint=constraint)
            solved = copy.deepcopy(doc)
            solved["palm"]["thumb_cmc_offset_mm"] = [round(float(units.mm(v)), 4) for v in sol.offset]
            solved["palm"]["thumb_cmc_axis_deg"] = [round(float(units.deg(v)), 4) for v in sol.axis]
            try:
                heel(solved)        # its length counts from the palm's back face, which the thenar may move
            except (Infeasible, ParamError):
                pass                # consider() refuses what does not validate
            magnet_lift(solved)
            consider(solved, True)
    if best is None:
        raise error
    if not best.opposes:
        raise UserError(opposition_refusal(person, best, check, search, seed, floor))
    return best


def opposition_refusal(person: Person, best: Sizing, check, search: bool, seed: int, floor=None) -> str:
    """Why a file that validates is refused: the thumb's pad does not meet the pads of index,
    middle and ring squarely (``kinematics.opposition``: margin < 0), or not on the printed tips
    (``kinematics.printed_tips``), at any placement tried; and the nearest input that works, if the
    breadth of the reference hand's proportion does."""
    from dataclasses import replace

    from ..kinematics import opposition
    from ..kinematics.model import Hand

    if best.margin >= 0.0:
        rule = (f"--hand-length {person.hand_length:g} --hand-breadth {person.hand_breadth:g}: on the printed tips the "
                f"thumb's pad meets no {' or '.join(best.unpinched)} pad (their square ends meet first; "
                f"opposition margin {units.deg(best.margin):+.1f} deg on the capsules)")
    else:
        reach = opposition.reach(Hand(best.params))
        worst = min(opposition.OPPOSED, key=lambda f: reach[f].margin)
        what = ("never faces the thumb's" if not math.isfinite(reach[worst].gap) or reach[worst].gap > 0.0
                else f"meets the thumb's {-units.deg(reach[worst].margin):.1f} deg outside the "
                     f"{units.deg(opposition.PAD_CONE):g} deg pad cone")
        rule = (f"--hand-length {person.hand_length:g} --hand-breadth {person.hand_breadth:g}: the {worst} pad {what} "
                f"(opposition margin {units.deg(best.margin):+.1f} deg, must be >= 0 for index, middle and ring)")
    breadth = round(person.hand_length * S.REFERENCE_BREADTH / S.REFERENCE_LENGTH)
    if breadth != person.hand_breadth:
        try:
            size(replace(person, hand_breadth=breadth), check, search, seed, searches=1, floor=floor)
            return f"{rule}; nearest that works: --hand-breadth {breadth:g} (the reference hand's proportion)"
        except UserError:
            pass
    return f"{rule}; no nearer input found (docs/sizing.md: the supported range)"
