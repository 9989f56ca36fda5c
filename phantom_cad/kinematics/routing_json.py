"""``routing.json``: the routing model written out (per tendon its strands' path elements in link
frames, millimetres, their rest lengths, and each split drive's coupler). Deterministic."""

from __future__ import annotations


from .. import units
from .couplers import Coupler, couplers
from .hand_params import HandParams
from .routing import Point, routes
from .routing_paths import lengths
from .topology import SERVOS


def rounded_mm(metres: float) -> float:
    """A length in routing.json: millimetres to 1e-6 mm."""
    return round(units.mm(metres), 6)


def _element_doc(e) -> dict:
    if isinstance(e, Point):
        return {"type": e.kind, "role": e.role, "link": e.link, "pos_mm": [rounded_mm(v) for v in e.pos]}
    return {"type": "pulley", "role": e.role, "link": e.link, "joint": e.joint,
            "centre_mm": [rounded_mm(v) for v in e.centre], "axis": [round(v, 9) for v in e.axis],
            "radius_mm": rounded_mm(e.radius), "width_mm": rounded_mm(e.width)}


def document(params: HandParams) -> dict:
    """``routing.json``: per tendon its kind, links, joints, servo, cord and strands (each a list of
    path elements in link frames, millimetres), and the rest length of every strand."""
    rest = lengths(params)
    split = couplers(params)
    tendons = []
    for r in routes(params):
        t = r.tendon
        extra = {}
        if t.kind == "drive" and t.digit in split:
            extra["split"] = coupler_document(params, split[t.digit])
        tendons.append({
            "name": t.name, "kind": t.kind, "digit": t.digit, "links": list(t.links), "joints": list(t.joints),
            "servo": None if t.servo is None else SERVOS[t.servo].name,
            "cord": {"diameter_mm": rounded_mm(r.diameter), "stiffness": r.stiffness},
            "strands": [{"name": s.name, "rest_length_mm": rounded_mm(rest[s.name]),
                         "elements": [_element_doc(e) for e in s.elements]} for s in r.strands],
            **extra,
        })
    return {"format": "phantom_cad routing 1", "hand": params.name, "side": params.side,
            "frames": "link frames of docs/frames.md; millimetres; a pulley's strand turns positively about its axis",
            "tendons": tendons}


def coupler_document(params: HandParams, cp: Coupler) -> dict:
    """A split drive in ``routing.json`` (millimetres, degrees; s from the socket face into the palm)."""
    return {"at": "socket face", "coupler": {"stop_diameter_mm": rounded_mm(params.hardware.stop_diameter),
                                              "stop_length_mm": rounded_mm(params.hardware.stop_length),
                                              "envelope_diameter_mm": rounded_mm(cp.diameter),
                                              "envelope_length_mm": rounded_mm(cp.length),
                                              "bore_mm": rounded_mm(cp.bore)},
            "s_rest_mm": [rounded_mm(v) for v in cp.rest], "s_full_travel_mm": [rounded_mm(v) for v in cp.full],
            "channel_mm": rounded_mm(cp.channel), "run_mm": rounded_mm(cp.run),
            "palm_strand_mm": rounded_mm(cp.palm_strand), "finger_strand_mm": rounded_mm(cp.finger_strand),
            "service_angle_deg": round(units.deg(cp.service_angle), 6), "service_payout_mm": rounded_mm(cp.payout),
            "service_emergence_mm": rounded_mm(cp.emergence)}
