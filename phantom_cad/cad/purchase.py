"""The orderable bill of materials: the assembly's rows (``materials.bill_of_materials``: what the
parts use) turned into one line per purchasable item, with its shop specification, the quantity
the hand needs, the packs to order and their typical cost (``parts_catalogue.toml``), plus the
electronics of the file's servo (``params.servos``: its bus adapter, cables and a supply sized
from six stall currents) and the filament. numpy-free; ``export.bom`` writes the lines as
bom.csv and bom.md.

A line: category, item, specification, quantity, unit, pack_size, packs, unit_price, currency,
price_date, line_cost (packs x pack price), used_in. An item the catalogue does not price (a
servo of the file's own) has no price or cost and is counted in no total.
"""

from __future__ import annotations

import functools
import math
import re
import tomllib
from collections import defaultdict
from pathlib import Path

from .. import units
from ..kinematics.hand_params import HandParams
from ..params import servos as servo_catalogue

CATALOGUE = Path(__file__).with_name("parts_catalogue.toml")
#: self-tapping screw lengths sold (mm)
SCREW_LENGTHS = (4, 5, 6, 8, 10, 12, 14, 16, 20)
#: the columns of a line, in bom.csv's order
COLUMNS = ("category", "item", "specification", "quantity", "unit", "pack_size", "packs", "unit_price",
           "currency", "price_date", "line_cost", "used_in")
#: the category of an assembly row the catalogue has no item for
OTHER = "other"


@functools.cache
def catalogue() -> dict:
    return tomllib.loads(CATALOGUE.read_text(encoding="utf-8"))


def _num(pattern: str, text: str) -> float | None:
    m = re.search(pattern, text)
    return float(m.group(1)) if m else None


def _line(category: str, item: str, spec: str, quantity: float, unit: str, pack: float,
          pack_price: float | None, used_in: str) -> dict:
    cat = catalogue()
    packs = math.ceil(round(quantity / pack, 9))
    priced = pack_price is not None
    return {"category": category, "item": item, "specification": spec, "quantity": quantity, "unit": unit,
            "pack_size": pack, "packs": packs,
            "unit_price": round(pack_price / pack, 4) if priced else None,
            "currency": cat["currency"], "price_date": cat["price_date"],
            "line_cost": round(packs * pack_price, 2) if priced else None, "used_in": used_in}


def _item(key: str, quantity: float, used_in: str, **dims) -> dict:
    it = catalogue()["items"][key]
    return _line(it["category"], it["name"], it["spec"].format(**dims), quantity, it["unit"],
                 it["pack"], it["pack_price"], used_in)


def supply(params: HandParams, n_servos: int) -> dict | None:
    """The power supply for ``n_servos`` of the file's catalogue servo: its voltage, the current
    they draw all stalled times the margin, the smallest rating at or above it and its price;
    None for a servo the catalogue does not have."""
    name = servo_catalogue.named(params.servo)
    if name is None:
        return None
    sv = servo_catalogue.CATALOGUE[name]
    sup = catalogue()["supply"]
    need = n_servos * sv.stall_current_A * sup["margin"]
    amps, price = next(((a, p) for a, p in sup["ratings"] if a >= need - 1e-9), sup["ratings"][-1])
    return {"volts": sv.voltage, "stall_A": sv.stall_current_A, "margin": sup["margin"], "need_A": need,
            "rating_A": amps, "pack_price": price, "n": n_servos}


def _electronics(params: HandParams, n_servos: int) -> list[dict]:
    """The servos and what connects and powers them, from the file's catalogue servo and its bus."""
    cat = catalogue()
    name = servo_catalogue.named(params.servo)
    g = lambda v: f"{units.mm(v):g}"  # noqa: E731
    if name is None:
        body = " x ".join(g(v) for v in params.servo.body)
        return [_line("servos", "servo", f"the parameter file's own servo, body {body} mm (not in the catalogue: "
                      "no price, no electronics)", n_servos, "pcs", 1, None, "forearm module: servos u1-u6")]
    sv = servo_catalogue.CATALOGUE[name]
    bus = cat["buses"][sv.bus]
    out = [_line("servos", "servo", cat["servos"][name]["spec"], n_servos, "pcs", 1, cat["servos"][name]["pack_price"],
                 f"forearm module: servos u1-u6 ({sv.title}: {params.servo.stall_torque:g} N m stall "
                 f"at {sv.voltage:g} V)")]
    for spec, price in bus["adapter"]:
        out.append(_line("electronics", "bus adapter", spec, 1, "pcs", 1, price,
                         f"the computer to the servos' {sv.bus} bus"))
    out.append(_line("electronics", "servo cable", bus["cable"], n_servos, "pcs", bus["cable_pack"],
                     bus["cable_pack_price"], f"one per servo: {n_servos} servos to the adapter"))
    out.append(_line("electronics", "USB cable", cat["usb_cable"]["spec"], 1, "pcs", 1, cat["usb_cable"]["pack_price"],
                     "the computer to the bus adapter"))
    s = supply(params, n_servos)
    out.append(_line("electronics", "power supply", cat["supply"]["spec"].format(v=s["volts"], a=s["rating_A"]), 1,
                     "pcs", 1, s["pack_price"],
                     f"the servos' power: {s['n']} x {s['stall_A']:.2f} A stall x {s['margin']:g} margin = "
                     f"{s['need_A']:.1f} A at {s['volts']:g} V ({sv.current_source})"))
    return out


def _who(row: dict) -> str:
    """A cut row's tendon, e.g. ``index_drive, palm strand``."""
    return row["used_in"].split(" (")[0].split(":")[0]


def order_lines(params: HandParams, rows: list[dict], filament_g: float | None = None,
                sliced: bool = False, parts: tuple[str, ...] = ()) -> list[dict]:
    """The order lines of a hand from its assembly rows (``assembly.bill_of_materials``), in the
    catalogue's category order. ``filament_g``: the printed ``parts``' filament (g), from the
    slicer when ``sliced``, else their estimated mass; None: no filament line."""
    hw = params.hardware
    g = lambda v: f"{units.mm(v):g}"  # noqa: E731
    by_item: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        by_item[r["item"]].append(r)
    lines: list[dict] = []
    unknown: list[dict] = []        # rows whose spec names no size this module reads
    if (n_servos := sum(r["quantity"] for r in by_item.pop("servo", []))):
        lines += _electronics(params, n_servos)
    if (bearings := by_item.pop("bearing", [])):
        dims = tuple(round(units.mm(v), 6) for v in (hw.bearing_bore, hw.bearing_outer, hw.bearing_width))
        lines.append(_item("bearing", sum(r["quantity"] for r in bearings), "; ".join(r["used_in"] for r in bearings),
                           name="683ZZ " if dims == (3.0, 7.0, 3.0) else "", b=g(hw.bearing_bore),
                           o=g(hw.bearing_outer), w=g(hw.bearing_width)))
    pins: dict[float, list[dict]] = defaultdict(list)
    for r in by_item.pop("axle", []):
        if (length := _num(r"([0-9.]+) mm long", r["spec"])) is None:
            unknown.append(r)
        else:
            pins[length].append(r)
    for length in sorted(pins):
        rs = pins[length]
        lines.append(_item("pin", sum(r["quantity"] for r in rs), "; ".join(r["used_in"] for r in rs),
                           d=g(hw.axle_diameter), l=f"{length:g}"))
    screws: dict[tuple[str, float | None], list[dict]] = defaultdict(list)
    for r in by_item.pop("screw", []):
        length = _num(r"x ([0-9.]+)", r["spec"])
        engage = _num(r"([0-9.]+) mm thread engagement", r["spec"])
        if "horn screw" in r["spec"]:
            screws["horn_screw", None].append(r)
        elif length is not None:
            screws["set_screw" if "set screw" in r["spec"] else "self_tapping", length].append(r)
        elif engage is not None:
            # through the servo's ear into its pilot: the longest sold length that does not bottom out
            reach = engage + units.mm(params.cad.servo_ear_thickness)
            screws["self_tapping", max(v for v in SCREW_LENGTHS if v <= reach + 1e-9)].append(r)
        else:
            unknown.append(r)
    kinds = ("self_tapping", "set_screw", "horn_screw")
    for key, length in sorted(screws, key=lambda k: (kinds.index(k[0]), k[1] or 0.0)):
        rs = screws[key, length]
        lines.append(_item(key, sum(r["quantity"] for r in rs), "; ".join(r["used_in"] for r in rs),
                           d=g(hw.screw_diameter), l=f"{length:g}" if length is not None else ""))
    if (crimps := by_item.pop("crimp stop", [])):
        lines.append(_item("crimp", sum(r["quantity"] for r in crimps), "; ".join(r["used_in"] for r in crimps),
                           d=g(hw.stop_diameter), l=g(hw.stop_length), t=g(hw.tendon_diameter)))
    if (magnets := by_item.pop("magnet", [])):
        lines.append(_item("magnet", sum(r["quantity"] for r in magnets), "; ".join(r["used_in"] for r in magnets),
                           d=g(hw.magnet_diameter), t=g(hw.magnet_thickness)))
    for key, item, pattern, dims in (
            ("line", "tendon", r", ([0-9.]+) mm$", {"t": g(hw.tendon_diameter)}),
            ("elastic", "cable spring", r"\(([0-9.]+) mm cut\)", {"d": g(params.cad.spring_diameter)})):
        cuts = []
        for r in by_item.pop(item, []):
            if (cut := _num(pattern, r["spec"])) is None:
                unknown.append(r)
            else:
                cuts.append((cut * r["quantity"], _who(r)))
        if cuts:
            lines.append(_item(key, round(sum(c for c, _ in cuts) / 1000.0, 3),
                               "cut: " + "; ".join(f"{c:g} mm {who}" for c, who in cuts), **dims))
    if filament_g is not None:
        how = ("the slicer's filament mass" if sliced else
               "not sliced: their estimated mass (volume x density x infill); "
               "phantom-cad build --slice gives the slicer's filament mass")
        lines.append(_item("filament", round(filament_g, 1), f"the {len(parts)} printed parts ({', '.join(parts)}): "
                           + how))
    # what the catalogue has no item for: listed, not priced
    for r in unknown + [r for rs in by_item.values() for r in rs]:
        lines.append(_line(OTHER, r["item"], r["spec"], r["quantity"], "pcs", 1, None, r["used_in"]))
    order = {c: i for i, c in enumerate(catalogue()["categories"] + [OTHER])}
    return sorted(lines, key=lambda ln: order[ln["category"]])   # stable: the order above within a category


def totals(lines: list[dict]) -> tuple[dict[str, float], float]:
    """The cost per category (in the catalogue's order, the categories the lines have) and of the
    hand, of the priced lines."""
    per: dict[str, float] = {}
    for ln in lines:
        per.setdefault(ln["category"], 0.0)
        if ln["line_cost"] is not None:
            per[ln["category"]] = round(per[ln["category"]] + ln["line_cost"], 2)
    return per, round(sum(per.values()), 2)
