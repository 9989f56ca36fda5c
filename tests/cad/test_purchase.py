"""The orderable BOM (cad.purchase) from parameters alone: packs cover quantities, totals add up,
the electronics follow the servo, and a file naming another servo changes its BOM lines, its
printed pockets and its predicted forces together. The whole-hand checks (each line's quantity
counted on the built solids, docs/bom.md) are in tests/export/test_hand.py."""

from __future__ import annotations

import copy
import json
import math

import pytest
from typer.testing import CliRunner

from phantom_cad.cad import purchase
from phantom_cad.cad.materials import bill_of_materials
from phantom_cad.cad.parts.forearm import FOREARM_SERVOS, Forearm
from phantom_cad.cli import app
from phantom_cad.params import parse, servos
from phantom_cad.params.io import dump_params


def _lines(params, grams=250.0):
    return purchase.order_lines(params, bill_of_materials(params), grams, False, ("palm",))


def _one(lines, item):
    (ln,) = [x for x in lines if x["item"] == item]
    return ln


def test_packs_cover_quantities_and_totals_add_up(hand):
    lines = _lines(hand.params)
    cat = purchase.catalogue()
    assert [ln["category"] for ln in lines] == sorted((ln["category"] for ln in lines),
                                                      key=cat["categories"].index)
    for ln in lines:
        assert ln["packs"] * ln["pack_size"] >= ln["quantity"] > 0, ln
        assert (ln["packs"] - 1) * ln["pack_size"] < ln["quantity"], ln      # no pack too many
        assert ln["line_cost"] == pytest.approx(ln["packs"] * ln["pack_size"] * ln["unit_price"], abs=0.01), ln
        assert (ln["currency"], ln["price_date"]) == (cat["currency"], cat["price_date"])
    per, total = purchase.totals(lines)
    for c in set(ln["category"] for ln in lines):
        assert per[c] == pytest.approx(sum(ln["line_cost"] for ln in lines if ln["category"] == c), abs=1e-9)
    assert total == pytest.approx(sum(ln["line_cost"] for ln in lines), abs=1e-9)
    # the cords: one spool each, its quantity the sum of the cut lengths it lists
    for item in ("tendon line", "elastic cord"):
        ln = _one(lines, item)
        cuts = [float(c.split(" mm ")[0]) for c in ln["used_in"].removeprefix("cut: ").split("; ")]
        assert ln["quantity"] == pytest.approx(sum(cuts) / 1000.0, abs=1e-6)


def test_the_default_servo_is_the_scs0009_on_its_bus():
    """The default file writes the SCS0009's numbers out: its line, a Feetech bus adapter and a
    supply for six of its stall currents with the margin, at its rated voltage."""
    from phantom_cad.params.io import load_params

    p = load_params()
    lines = _lines(p)
    sv = servos.CATALOGUE["scs0009"]
    assert _one(lines, "servo")["specification"].startswith("Feetech SCS0009")
    assert "FE-URT-1" in _one(lines, "bus adapter")["specification"]
    assert _one(lines, "servo cable")["quantity"] == 6
    need = 6 * sv.stall_current_A * 1.5
    supply = _one(lines, "power supply")
    volts, amps = (float(x) for x in supply["specification"].split(" A ")[0].split(" V "))
    assert volts == sv.voltage and amps >= need
    assert f"6 x {sv.stall_current_A:.2f} A stall x 1.5 margin = {need:.1f} A" in supply["used_in"]


def test_every_catalogue_servo_is_priced_with_its_electronics():
    cat = purchase.catalogue()
    for name, sv in servos.CATALOGUE.items():
        assert name in cat["servos"] and sv.bus in cat["buses"], name
        assert sv.stall_current_A > 0 and sv.current_source, name


def test_a_servo_of_the_files_own_is_listed_unpriced(document):
    document = copy.deepcopy(document)
    document["servo"]["stall_torque_Nm"] = 0.3          # no catalogue servo's numbers
    p = parse(document)
    assert servos.named(p.servo) is None
    lines = _lines(p)
    assert _one(lines, "servo")["line_cost"] is None
    assert not [ln for ln in lines if ln["category"] == "electronics"]
    per, total = purchase.totals(lines)
    assert total == pytest.approx(sum(ln["line_cost"] for ln in lines if ln["line_cost"] is not None))


def _force(path) -> dict:
    r = CliRunner().invoke(app, ["force", "--params", str(path), "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.output)


def test_naming_another_servo_changes_its_lines_pockets_and_force_together(document, tmp_path):
    """``[servo] model = "mg90s"``: the servo line names it, the electronics become a PWM board's,
    the supply is sized from its stall current, the forearm's pockets take its body, and
    ``phantom-cad force`` predicts forces scaled by its stall torque (the posture is the same:
    half of each servo's travel)."""
    base_doc, document = copy.deepcopy(document), copy.deepcopy(document)
    document["servo"] = {"model": "mg90s"}
    paths = {}
    for name, doc in (("scs0009", base_doc), ("mg90s", document)):
        paths[name] = tmp_path / f"{name}.toml"
        dump_params(doc, paths[name])
    a, b = parse(base_doc), parse(document)
    sv_a, sv_b = servos.CATALOGUE["scs0009"], servos.CATALOGUE["mg90s"]

    la, lb = _lines(a), _lines(b)
    assert _one(lb, "servo")["specification"] == purchase.catalogue()["servos"]["mg90s"]["spec"]
    assert _one(lb, "servo")["specification"] != _one(la, "servo")["specification"]
    adapters = [ln["specification"] for ln in lb if ln["item"] == "bus adapter"]
    assert any("PCA9685" in s for s in adapters) and not any("FE-URT-1" in s for s in adapters)
    assert "JR/Futaba" in _one(lb, "servo cable")["specification"]
    need = 6 * sv_b.stall_current_A * 1.5
    assert f"{need:.1f} A at {sv_b.voltage:g} V" in _one(lb, "power supply")["used_in"]

    # the pockets: the drop-in pocket of each servo is its body plus the clearance all round
    for params, sv in ((a, sv_a), (b, sv_b)):
        fa = Forearm(params)
        c = fa.tol.clearance
        for k in FOREARM_SERVOS:
            lo, hi = fa.body_box(k, grow=c)
            assert sorted(hi - lo) == pytest.approx(sorted(v + 2 * c for v in sv.body_mm), abs=1e-9)

    # the force at the same posture: the drive pulls tau / r, so in proportion to the stall torque;
    # the pad's force follows it (less the return cord's share, which does not scale), and is what
    # the default file predicts with the MG90S's stall torque (--servo)
    fa_, fb_ = _force(paths["scs0009"]), _force(paths["mg90s"])
    assert (fa_["stall_torque_Nm"], fb_["stall_torque_Nm"]) == (sv_a.stall_torque_Nm, sv_b.stall_torque_Nm)
    assert fa_["u_deg"] == fb_["u_deg"]
    ratio = sv_b.stall_torque_Nm / sv_a.stall_torque_Nm
    assert len(fa_["digits"]) == 5
    for d, f in fa_["digits"].items():
        g = fb_["digits"][d]
        assert g["drive_tension_N"] == pytest.approx(f["drive_tension_N"] * ratio, rel=1e-5), d
        assert g["force_N"] < f["force_N"] and not math.isclose(g["force_N"], f["force_N"]), d
    r = CliRunner().invoke(app, ["force", "--params", str(paths["scs0009"]), "--servo", "mg90s", "--json"])
    assert r.exit_code == 0, r.output
    # (the MG90S's body moves the forearm's servos a little: the routing, so the forces, by < 0.01 %)
    for d, f in json.loads(r.output)["digits"].items():
        assert fb_["digits"][d]["force_N"] == pytest.approx(f["force_N"], rel=1e-4), d


def test_a_row_the_catalogue_has_no_item_for_is_listed_unpriced(hand):
    rows = [{"item": "axle", "spec": "a pin of no stated length", "quantity": 2, "used_in": "somewhere"},
            {"item": "washer", "spec": "M2 washer", "quantity": 4, "used_in": "elsewhere"}]
    lines = purchase.order_lines(hand.params, rows)
    assert [(ln["category"], ln["item"], ln["quantity"], ln["line_cost"]) for ln in lines] == [
        ("other", "axle", 2, None), ("other", "washer", 4, None)]
