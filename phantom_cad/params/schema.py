"""Parse and validate one parameter file into the frozen records of one hand.

The records (:class:`HandParams` and its parts) are defined in
``phantom_cad.kinematics.hand_params``, below both this layer and the models that read them, and
are exported here too. Their values are SI (metres, radians, N/m, N); the TOML file carries the
unit in each key name and is converted once, here. Every rule a parameter file must satisfy is
checked in :func:`parse`, which either returns a complete :class:`HandParams` or raises
:class:`ParamError` naming the field, the value and the rule.
"""

from __future__ import annotations

import math
from types import MappingProxyType
from typing import Any, Mapping, Protocol

from .. import canon
from ..kinematics import closed_form as cf
from ..kinematics import topology
from ..kinematics.hand_params import (Cad, ChainParams, Finger, Guide, HandParams, Hardware, Mechanics,
                                      Palm, Print, ServoBody, Thumb)
from ..kinematics.topology import FINGERS
from ..units import DEG, G_PER_CM3, MM
from .errors import ParamError
from . import rules, servos
from .reader import TomlTable

__all__ = ["SCHEMA_VERSION", "EffectLibrary", "plugin_paths", "parse", "Guide", "ChainParams", "Finger",
           "Thumb", "Mechanics", "Palm", "ServoBody", "Hardware", "Print", "Cad", "HandParams"]

SCHEMA_VERSION = 1
#: the largest coupling-loop preload (N) a file may ask for: a tenth of a 0.6 mm braided line's
#: breaking load, and many times the return cord's pull on the loops
MAX_LOOP_PRELOAD = 20.0

class EffectLibrary(Protocol):
    """What :func:`parse` needs from an effect library to read a file's ``plugins`` and
    ``[effects.*]`` tables; the caller hands one in (the calibration layer's is
    ``phantom_cad.calibration.effects.PARAMS_EFFECTS``: ``phantom_cad.load_params``,
    ``load_hand`` and the CLI pass it). The params layer never imports calibration."""

    def load_plugin(self, path: str, field_name: str, source: str | None) -> None:
        """Load one plugin file the parameter file names (ParamError naming the field on failure)."""

    def check(self, effects: Mapping[str, Mapping[str, Any]], source: str | None) -> None:
        """Raise ParamError naming the field if an ``[effects.*]`` table is not valid."""


def plugin_paths(plugins: tuple[str, ...], source: str | None) -> tuple[str, ...]:
    """The plugin files of a parameter file, resolved against the file's folder."""
    import os

    base = os.path.dirname(os.path.abspath(source)) if source else os.getcwd()
    return tuple(os.path.normpath(os.path.join(base, p)) for p in plugins)


# ---------------------------------------------------------------------------
# parsing and validation
# ---------------------------------------------------------------------------

def _guide(t: TomlTable) -> Guide:
    g = t.table("guide")
    d1 = g.number("d1_mm", gt=0) * MM
    d2 = g.number("d2_mm", gt=0) * MM
    alpha = g.number("alpha_deg", gt=0, le=180) * DEG
    g.done()
    return Guide(d1, d2, alpha)


def _limits(t: TomlTable, joints: tuple[str, ...]) -> dict[str, tuple[float, float]]:
    lt = t.table("limits_rad")
    out = {}
    for j in joints:
        lo, hi = lt.interval(j)
        if lo > 0:
            raise lt.error(j, [lo, hi], "low must be <= 0 (the rest pose q = 0 must lie in the workspace)")
        if j != "cmc" and hi > rules.MAX_FLEXION + 1e-12:
            raise lt.error(j, [lo, hi], f"high must be <= {rules.MAX_FLEXION:.4f} rad (120 deg): the phalanges "
                           "are modelled and checked for flexion up to 120 deg")
        out[j] = (lo, hi)
    lt.done()
    return out


def _radii(t: TomlTable, joints: tuple[str, ...]) -> dict[str, float]:
    rt = t.table("pulley_radius_mm")
    out = {j: rt.number(j, gt=0) * MM for j in joints}
    rt.done()
    return out


def _check_chain(t: TomlTable, chain: ChainParams, ref_limit_key: str) -> None:
    """Rules linking guides, servo pulley, travel and limits of one chain."""
    g = chain.guide
    ref = chain.joints[0]
    ref_hi = chain.limits[0][1]
    if not g.alpha > ref_hi:
        raise ParamError(
            f"{t.field('guide')}.alpha_deg", round(g.alpha / DEG, 6),
            f"must exceed the {ref.upper()} upper limit {ref_limit_key}.{ref} = {ref_hi:g} rad "
            f"({ref_hi / DEG:.2f} deg): eq. (6) gives q_{ref.upper()} <= alpha", t.source)
    lo_u, hi_u = chain.travel
    travel_field = t.field("servo_travel_deg")
    travel_val = [round(lo_u / DEG, 6), round(hi_u / DEG, 6)]
    for u in (lo_u, hi_u):
        x = float(cf.cosine_argument(u, g.d1, g.d2, g.alpha, chain.servo_radius))
        if not -1.0 <= x <= 1.0:
            L = g.L0 - chain.servo_radius * u
            raise ParamError(
                travel_field, travel_val,
                f"the cosine-law argument (d1^2 + d2^2 - L^2) / (2 d1 d2) is {x:.4f} at u = {u / DEG:g} deg, "
                f"outside [-1, 1] (chord L = L0 - r u = {L / MM:.3f} mm must stay in "
                f"[{g.chord_range[0] / MM:.3f}, {g.chord_range[1] / MM:.3f}] mm)", t.source)
    # the chord is linear in u: inside [|d1 - d2|, d1 + d2] at both ends (with its sign), it is
    # inside over the whole travel, and so is the argument (an argument inside [-1, 1] at the
    # ends alone lets the chord pass through 0 in between)
    for u in (lo_u, hi_u):
        L = g.L0 - chain.servo_radius * u
        if not g.chord_range[0] <= L <= g.chord_range[1]:
            x_max = max(float(cf.cosine_argument(v, g.d1, g.d2, g.alpha, chain.servo_radius)) for v in
                        (lo_u, hi_u, g.L0 / chain.servo_radius))
            raise ParamError(
                travel_field, travel_val,
                f"the chord L = L0 - r u is {L / MM:.3f} mm at u = {u / DEG:g} deg, outside "
                f"[{g.chord_range[0] / MM:.3f}, {g.chord_range[1] / MM:.3f}] mm: inside the travel it leaves "
                f"the cosine law's domain (the argument reaches {x_max:.4f} at L = 0)", t.source)
    # the image of the whole travel must lie inside the admissible workspace (analytic model;
    # compensation only reduces the distal joints)
    coupling = chain.ideal_coupling
    for u in (lo_u, hi_u):
        q_ref = float(cf.reference_angle(u, g.d1, g.d2, g.alpha, chain.servo_radius))
        for joint, c, (lo, hi) in zip(chain.joints, coupling, chain.limits):
            q = c * q_ref
            if q > hi + 1e-12 or q < lo - 1e-12:
                raise ParamError(
                    travel_field, travel_val,
                    f"at u = {u / DEG:g} deg the model puts {chain.digit} {joint.upper()} at {q:.4f} rad, "
                    f"outside its limits {ref_limit_key}.{joint} = [{lo:g}, {hi:g}]: "
                    f"the servo travel must map inside the workspace", t.source)


def _check_path(t: TomlTable, key: str, length: float, segment: float, r_a: float, r_b: float, segname: str):
    """A figure-eight tendon crossing between two pulleys is at least the internal tangent."""
    span_sq = segment ** 2 - (r_a + r_b) ** 2
    if span_sq <= 0:
        raise ParamError(t.field(segname), round(segment / MM, 4),
                         f"the segment must be longer than the sum of its two pulley radii "
                         f"({(r_a + r_b) / MM:g} mm) for the tendons to cross", t.source)
    minimum = math.sqrt(span_sq)
    if length < minimum:
        raise ParamError(t.field(f"path_length_mm.{key}"), round(length / MM, 6),
                         f"must be >= {minimum / MM:.2f} mm, the crossed-tendon span of the "
                         f"{segname.split('.')[-1]} segment between its pulleys", t.source)


def _check_compliance(mechanics: Mechanics, fingers: Mapping[str, Finger], thumb: Thumb,
                      source: str | None) -> None:
    """Eq. (13): the tendon's stretch (compliance k_s / EA) takes back part of each coupled joint's
    motion; it must not take all of it (a coupled joint that stands still or extends while its
    reference joint flexes)."""
    kappa = mechanics.spring_k / mechanics.tendon_EA
    for d in [*fingers.values(), thumb]:
        c = d.chain
        comp = cf.coupling_vector(c.radii, c.path_lengths, kappa)
        for key, a in zip(c.joints[1:], comp[1:]):
            if not a > 0.0:
                raise ParamError("mechanics.tendon_EA_N", mechanics.tendon_EA,
                                 f"with spring_k_N_per_m = {mechanics.spring_k:g} the tendon stretch leaves "
                                 f"{c.digit} {key.upper()} a coupling of {a:.4g} (eq. 13): a coupled joint must "
                                 f"flex with its {c.joints[0].upper()}, so EA must be larger", source)


def _fractions(t: TomlTable, names: tuple[str, ...], hand_length: float) -> dict[str, float]:
    ft = t.table("length_fraction")
    out = {n: ft.number(n, gt=0, lt=1) * hand_length for n in names}
    ft.done()
    return out


def _digit(t: TomlTable, spec: topology.Chain, extra_limits: tuple[str, ...],
           hand_length: float) -> tuple[dict[str, float], float, float, ChainParams, dict[str, tuple[float, float]]]:
    """What a finger and the thumb share: segments, section, pulleys, guide, servo, limits, tendon.

    ``spec`` is the digit's topology chain (joint keys reference first; the file lists them
    distal first). Returns (segment lengths, width, thickness, chain, limits).
    """
    joints = spec.keys
    seg = _fractions(t, spec.segments, hand_length)
    width = t.number("width_mm", gt=0) * MM
    thickness = t.number("thickness_mm", gt=0) * MM
    R = _radii(t, joints[::-1])
    guide = _guide(t)
    r = t.number("servo_pulley_radius_mm", gt=0) * MM
    travel = tuple(v * DEG for v in t.interval("servo_travel_deg"))
    limits = _limits(t, joints[::-1] + extra_limits)
    pt = t.table("path_length_mm")
    paths = tuple(pt.number(key, gt=0) * MM for key, _ in spec.spans)
    pt.done()
    chain = ChainParams(spec, tuple(R[j] for j in joints), paths,
                        tuple(limits[j] for j in joints), guide, r, travel)
    _check_chain(t, chain, t.field("limits_rad"))
    for (key, crossed), length, a, b in zip(spec.spans, paths, joints, joints[1:]):
        _check_path(t, key, length, seg[crossed], R[a], R[b], f"length_fraction.{crossed}")
    return seg, width, thickness, chain, limits


def _finger(t: TomlTable, name: str, hand_length: float) -> Finger:
    seg, width, thickness, chain, _ = _digit(t, topology.chain(name), (), hand_length)
    t.done()
    return Finger(name, seg["metacarpal"], seg["proximal"], seg["middle"], seg["distal"],
                  width, thickness, chain)


def _thumb(t: TomlTable, hand_length: float) -> Thumb:
    cmc = topology.JOINTS[topology.CMC_Q].key
    seg, width, thickness, chain, limits = _digit(t, topology.chain("thumb"), (cmc,), hand_length)
    gain = t.number("cmc_gain", gt=0)
    cmc_travel = tuple(v * DEG for v in t.interval("cmc_servo_travel_deg"))
    if isinstance(t.data, dict) and "cmc_horn_radius_mm" in t.data:
        raise t.error("cmc_horn_radius_mm", t.data["cmc_horn_radius_mm"],
                      f"not a parameter: {topology.SERVOS[topology.CMC_SERVO].title} does not sit under the CMC "
                      "(it turns it through a cable loop from the forearm module): name the loop's pulley "
                      "radius cmc_pulley_radius_mm instead (docs/parameters.md)")
    horn = t.number("cmc_pulley_radius_mm", gt=0) * MM
    twist = t.number("twist_deg", ge=-90, le=90, default=0.0) * DEG
    lo, hi = limits[cmc]
    q15, u6 = topology.JOINTS[topology.CMC_Q].label, topology.SERVOS[topology.CMC_SERVO].label
    for u in cmc_travel:
        if not lo - 1e-12 <= gain * u <= hi + 1e-12:
            raise t.error("cmc_servo_travel_deg", [round(v / DEG, 6) for v in cmc_travel],
                          f"{q15} = cmc_gain * {u6} = {gain * u:.4f} rad at {u6} = {u / DEG:g} deg is outside "
                          f"the CMC limits [{lo:g}, {hi:g}]: the servo travel must map inside the workspace")
    t.done()
    return Thumb(seg["metacarpal"], seg["proximal"], seg["distal"], width, thickness, chain,
                 gain, limits[cmc], cmc_travel, horn, twist)


def _cad(c: TomlTable, hand_length: float, fingers: Mapping[str, Finger], thumb: Thumb, palm: Palm,
         servo: ServoBody, hardware: Hardware, printing: Print) -> Cad:
    """[cad]: the few dimensions only the printable parts need, and the rules that make them fit."""
    cad = Cad(
        finger_base_length=c.number("finger_base_length_mm", gt=0) * MM,
        cheek=c.number("cheek_mm", gt=0) * MM,
        eyelet_length=c.number("eyelet_length_mm", gt=0) * MM,
        spring_diameter=c.number("spring_diameter_mm", gt=0) * MM,
        servo_pulley_width=c.number("servo_pulley_width_mm", gt=0) * MM,
        horn_hole_radius=c.number("horn_hole_radius_mm", gt=0) * MM,
        servo_shaft_offset=c.number("servo_shaft_offset_mm", ge=0) * MM,
        module_stop_margin=c.number("module_stop_margin_deg", ge=0, le=10) * DEG,
        servo_ear_offset=c.number("servo_ear_offset_mm", ge=0) * MM,
        servo_ear_thickness=c.number("servo_ear_thickness_mm", gt=0) * MM,
        cmc_column_radius=c.number("cmc_column_radius_mm", gt=0, default=3.5) * MM,
    )
    c.done()
    rules.check_parts(c, hand_length, fingers, thumb, palm, servo, hardware, printing, cad)
    return cad


def _servo(s: TomlTable) -> ServoBody:
    """``[servo]``: the file's numbers, or a catalogue servo's (``model``, :mod:`.servos`) for
    those it leaves out."""
    model = s.string("model", servos.names()) if "model" in s.data else None
    given = servos.CATALOGUE[model].values() if model else {}

    def number(key: str, **bounds) -> float:
        if key not in s.data and model and key not in given:
            raise s.error(key, None, f"is required: the catalogue's {model} ({servos.CATALOGUE[model].title}) has "
                          "no mounting ears, and the printed pocket holds a servo by its ears")
        return s.number(key, **bounds, **({"default": given[key]} if key in given else {}))

    if "body_mm" in s.data or not model:
        body = s.vector("body_mm", 3, gt=0)
    else:
        body = tuple(s.check_number(f"body_mm[{i}]", v, gt=0) for i, v in enumerate(given["body_mm"]))
    out = ServoBody(tuple(v * MM for v in body),
                    number("flange_span_mm", gt=0) * MM, number("screw_diameter_mm", gt=0) * MM,
                    number("stall_torque_Nm", gt=0, le=100.0), number("speed_deg_s", gt=0, le=1e4) * DEG,
                    s.number("stall_error_deg", gt=0, le=30.0, default=1.0) * DEG, model)
    s.done()
    return out


def parse(document: Mapping[str, Any], source: str | None = None,
          effects: EffectLibrary | None = None) -> HandParams:
    """Validate a parsed parameter document and build the frozen :class:`HandParams`.

    ``effects``: the effect library that loads the file's ``plugins`` and checks its
    ``[effects.*]`` tables (:class:`EffectLibrary`). Without one they are checked for their shape
    only (a list of paths, tables) and kept as written: what builds geometry never reads them, and
    ``phantom_cad.make_hand`` checks them again when it builds the model."""
    root = TomlTable(dict(document), "", source)
    version = root.number("schema_version")
    if version != SCHEMA_VERSION:
        raise root.error("schema_version", root.data["schema_version"], f"must be {SCHEMA_VERSION}")

    h = root.table("hand")
    name = h.string("name")
    if not name or not all(c.isascii() and (c.isalnum() or c in "-_") for c in name):
        raise h.error("name", name, "must be a non-empty name of ASCII letters, digits, '-' and '_'")
    if len(name) > rules.MAX_NAME:
        raise h.error("name", name[:20] + "...", f"must have at most {rules.MAX_NAME} characters (it names "
                      f"the export folder and files), not {len(name)}")
    side = h.string("side", ("right", "left"))
    hand_length = h.number("hand_length_mm", gt=0, le=1000) * MM
    h.done()

    ft = root.table("fingers")
    for key in ft.keys():
        if key not in FINGERS:
            raise ft.error(key, "{...}", f"unknown finger '{key}' (allowed: {', '.join(FINGERS)})")
    fingers = {n: _finger(ft.table(n), n, hand_length) for n in FINGERS}
    ft.done()

    thumb = _thumb(root.table("thumb"), hand_length)

    m = root.table("mechanics")
    mechanics = Mechanics(m.number("spring_k_N_per_m", ge=0), m.number("tendon_EA_N", gt=0),
                          m.number("loop_preload_N", ge=0, le=MAX_LOOP_PRELOAD, default=0.0))
    m.done()
    _check_compliance(mechanics, fingers, thumb, source)

    p = root.table("palm")
    palm = Palm(
        arc_offset=p.number("arc_offset_deg", ge=0, lt=30) * DEG,
        finger_pitch=p.number("finger_pitch_mm", gt=0) * MM,
        thickness=p.number("thickness_mm", gt=0) * MM,
        wall=p.number("wall_mm", gt=0) * MM,
        thumb_cmc_offset=tuple(v * MM for v in p.vector("thumb_cmc_offset_mm", 3)),
        thumb_cmc_axis=tuple(v * DEG for v in p.vector("thumb_cmc_axis_deg", 3, ge=-180, le=180)),
        heel_height=p.number("heel_height_mm", ge=0, default=0.0) * MM,
        heel_length=p.number("heel_length_mm", ge=0, default=0.0) * MM,
        magnet_lift=p.number("magnet_lift_mm", ge=0, default=0.0) * MM,
    )
    if (palm.heel_height > 0.0) != (palm.heel_length > 0.0):
        key, v = (("palm.heel_length_mm", palm.heel_length) if palm.heel_height > 0.0
                  else ("palm.heel_height_mm", palm.heel_height))
        raise ParamError(key, round(v / MM, 6), "must be > 0 with the other heel dimension (both 0: a flat palm)",
                         source)
    p.done()
    if palm.finger_pitch > rules.MAX_FINGER_PITCH + 1e-12:
        raise ParamError("palm.finger_pitch_mm", palm.finger_pitch / MM,
                         f"must be <= {rules.MAX_FINGER_PITCH / MM:g} mm: the palm layout is modelled and checked "
                         "up to it (from 22 mm its solid is not valid)", source)
    for n in FINGERS:
        if fingers[n].width >= palm.finger_pitch + 1e-12:
            raise ParamError(f"fingers.{n}.width_mm", fingers[n].width / MM,
                             f"must be < palm.finger_pitch_mm = {palm.finger_pitch / MM:g} "
                             "(adjacent fingers would overlap)", source)

    servo = _servo(root.table("servo"))
    if servo.flange_span <= servo.body[0]:
        raise ParamError("servo.flange_span_mm", servo.flange_span / MM,
                         f"must exceed the body length servo.body_mm[0] = {servo.body[0] / MM:g}", source)

    hw = root.table("hardware")
    b = hw.table("bearing")
    bore, outer, bw = b.number("bore_mm", gt=0) * MM, b.number("outer_mm", gt=0) * MM, b.number("width_mm", gt=0) * MM
    if outer <= bore:
        raise b.error("outer_mm", outer / MM, f"must exceed bore_mm = {bore / MM:g}")
    b.done()
    axle = hw.number("axle_diameter_mm", gt=0) * MM
    if axle > bore + 1e-12:
        raise hw.error("axle_diameter_mm", axle / MM, f"must be <= hardware.bearing.bore_mm = {bore / MM:g}")
    mg = hw.table("magnet")
    magnet_d, magnet_t = mg.number("diameter_mm", gt=0) * MM, mg.number("thickness_mm", gt=0) * MM
    mg.done()
    tendon = hw.number("tendon_diameter_mm", gt=0) * MM
    st = hw.table("tendon_stop", default={})
    stop_d = st.number("diameter_mm", gt=0, default=2.0) * MM
    stop_len = st.number("length_mm", gt=0, default=3.0) * MM
    if stop_d < 2.0 * tendon - 1e-12:
        raise st.error("diameter_mm", stop_d / MM, "must be >= twice hardware.tendon_diameter_mm = "
                       f"{2.0 * tendon / MM:g} "
                       "(a crimp stop is a sleeve round the cord)")
    st.done()
    hardware = Hardware(bore, outer, bw, axle, magnet_d, magnet_t,
                        hw.number("screw_diameter_mm", gt=0) * MM, tendon, stop_d, stop_len)
    hw.done()
    for n in FINGERS:
        f = fingers[n]
        if hardware.bearing_width >= f.width:
            raise ParamError("hardware.bearing.width_mm", bw / MM,
                             f"must be < fingers.{n}.width_mm = {f.width / MM:g} (a joint's bearing sits in its "
                             f"tongue; the parts seat one where it fits beside the tendon grooves)", source)
        if hardware.bearing_outer >= f.thickness:
            raise ParamError("hardware.bearing.outer_mm", outer / MM,
                             f"must be < fingers.{n}.thickness_mm = {f.thickness / MM:g}", source)

    pr = root.table("print")
    printing = Print(
        hole_clearance=pr.number("hole_clearance_mm", ge=0, lt=1) * MM,
        press_fit_interference=pr.number("press_fit_interference_mm", ge=0, lt=0.5) * MM,
        magnet_clearance=pr.number("magnet_clearance_mm", ge=0, lt=1) * MM,
        stl_tolerance=pr.number("stl_tolerance_mm", ge=0.001, le=1) * MM,
        density=pr.number("density_g_per_cm3", gt=0, lt=25) * G_PER_CM3,
        infill=pr.number("infill", gt=0, le=1),
        screw_pilot_ratio=pr.number("screw_pilot_ratio", gt=0.6, lt=1.0, default=0.8),
        hole_compensation=pr.number("hole_compensation_mm", ge=0, le=0.5, default=0.2) * MM,
        layer_height=pr.number("layer_height_mm", ge=0.05, le=0.3, default=0.2) * MM,
    )
    pr.done()

    cad = _cad(root.table("cad"), hand_length, fingers, thumb, palm, servo, hardware, printing)

    plugins = root._get("plugins", [])
    if not isinstance(plugins, list) or not all(isinstance(v, str) and v.strip() for v in plugins):
        raise root.error("plugins", plugins, "must be a list of file paths (Python files that register effects, "
                         "relative to this parameter file)")
    plugins = tuple(plugins)
    if effects is not None:
        for i, path in enumerate(plugin_paths(plugins, source)):
            effects.load_plugin(path, f"plugins[{i}]", source)
    et = root.table("effects", default={})
    effect_params = {key: dict(et.table(key).data) for key in et.keys()}
    et.done()
    if effect_params and effects is not None:
        effects.check(effect_params, source)   # the library knows each effect's parameters and bounds

    root.done()
    return HandParams(
        name=name, side=side, hand_length=hand_length,
        fingers=MappingProxyType(fingers), thumb=thumb, mechanics=mechanics, palm=palm,
        servo=servo, hardware=hardware, print=printing, cad=cad,
        effects=canon.freeze(effect_params), document=canon.freeze(dict(document)), source=source,
        plugins=plugins,
    )
