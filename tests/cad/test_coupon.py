"""The fit-test coupon (phantom_cad.cad.coupon) and the hole compensation, measured on the solids.

Known answers by hand from the parameter document: each hole's modelled diameter is its fit plus
print.hole_compensation_mm (hardware holes) or its fit alone (tendon channels); the coupon is two
boxes laid out hole by hole with one palm wall between holes, less the holes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.cad import measure

pytest.importorskip("build123d")


def _holes(doc):
    """{key: (modelled diameter, depth, vertical?)} by hand from the document (mm)."""
    hw, pr = doc["hardware"], doc["print"]
    comp = pr.get("hole_compensation_mm", 0.2)
    cl, itf = pr["hole_clearance_mm"], pr["press_fit_interference_mm"]
    seat = hw["bearing"]["outer_mm"] - itf + comp
    a_clear = hw["axle_diameter_mm"] + 2 * cl + comp
    a_press = hw["axle_diameter_mm"] - itf + comp
    magnet = hw["magnet"]["diameter_mm"] + 2 * pr["magnet_clearance_mm"] + comp
    pilot = 0.8 * hw["screw_diameter_mm"] + comp          # screw_pilot_ratio's default
    s_clear = hw["screw_diameter_mm"] + 2 * cl + comp
    tendon = hw["tendon_diameter_mm"] + 2 * cl             # a clearance channel: not compensated
    bw = hw["bearing"]["width_mm"]
    H = max(3 * hw["screw_diameter_mm"], bw, hw["magnet"]["thickness_mm"] + pr["magnet_clearance_mm"]) + 1.0
    W = seat + 2 * doc["palm"]["wall_mm"]
    return {
        "bearing_seat": (seat, bw, True), "axle_clearance": (a_clear, H - bw, True),
        "axle_press": (a_press, H, True),
        "magnet_pocket": (magnet, hw["magnet"]["thickness_mm"] + pr["magnet_clearance_mm"], True),
        "screw_pilot": (pilot, 3 * hw["screw_diameter_mm"], True), "screw_clearance": (s_clear, H, True),
        "tendon_channel": (tendon, H, True),
        "bearing_seat_h": (seat, bw, False), "axle_clearance_h": (a_clear, W - bw, False),
        "axle_press_h": (a_press, W, False), "tendon_channel_h": (tendon, W, False),
    }, H, W


def _expected(doc):
    holes, H, W = _holes(doc)
    g = doc["palm"]["wall_mm"]
    plate = [holes[k][0] for k in ("bearing_seat", "axle_press", "magnet_pocket", "screw_pilot",
                                   "screw_clearance", "tendon_channel")]
    block = [holes[k][0] for k in ("bearing_seat_h", "axle_press_h", "tendon_channel_h")]
    Lp = sum(plate) + (len(plate) + 1) * g
    Lb = sum(block) + (len(block) + 1) * g
    Hb = holes["bearing_seat"][0] + 2 * g
    volume = Lp * W * H + Lb * W * Hb - sum(math.pi * d * d / 4 * depth for d, depth, _ in holes.values())
    return holes, (Lp + Lb, W, max(H, Hb)), volume


@pytest.fixture(scope="module")
def coupon(params):
    from phantom_cad.cad.coupon import FitCoupon

    c = FitCoupon(params)
    return c, c.build()


def test_coupon_volume_and_size_by_hand(coupon, document):
    c, shape = coupon
    _, size, volume = _expected(document)
    rep = measure.solid_report(shape)
    assert rep["n_solids"] == 1 and rep["valid"]
    assert shape.volume == pytest.approx(volume, rel=1e-9)
    assert rep["bbox_max"] - rep["bbox_min"] == pytest.approx(size, abs=1e-6)
    assert rep["bbox_min"][2] == pytest.approx(0.0, abs=1e-9)        # flat on the bed


def test_every_hole_measured_on_the_coupon(coupon, document):
    c, shape = coupon
    holes, _, _ = _expected(document)
    cyl = measure.cylinders(shape)
    by_key = {f.key: f for f in c.features}
    assert set(by_key) == set(holes)
    for key, (d, depth, vertical) in holes.items():
        f = by_key[key]
        hits = [x for x in cyl if abs(x["radius"] - d / 2) < 1e-6 and measure.coaxial(x, f.opening, f.axis, 1e-6)]
        assert hits, key
        axis = np.array([0, 0, 1.0]) if vertical else np.array([0, 1.0, 0])
        assert all(abs(abs(x["direction"] @ axis) - 1) < 1e-9 for x in hits), key
        assert max(x["s_max"] for x in hits) - min(x["s_min"] for x in hits) == pytest.approx(depth, abs=1e-6), key
    # the blind holes are pockets that open upward (vertical) or toward -y (horizontal)
    for key in ("magnet_pocket", "screw_pilot"):
        pk = measure.circular_pockets(shape, holes[key][0] / 2)
        assert [tuple(np.round(p["facing"], 9)) for p in pk] == [(0.0, 0.0, 1.0)], key
        assert pk[0]["depth"] == pytest.approx(holes[key][1], abs=1e-6)
    assert c.verify(shape) == []


def test_the_coupon_holes_are_the_hands(coupon, built):
    """Every hole of the coupon is a hole of the hand: some part has a bore of that radius."""
    c, _ = coupon
    radii = {round(x["radius"], 6) for b in built.values() for x in measure.cylinders(b.shape)}
    missing = [f.key for f in c.features if round(f.diameter / 2, 6) not in radii]
    assert missing == []


@pytest.mark.slow
def test_hole_compensation_moves_the_hand_and_the_coupon(variant, document):
    """0.3 mm of compensation: the finger's bearing seat and axle bore, and the coupon's, grow by
    0.05 mm in radius over the default; the tendon channel does not."""
    from phantom_cad.cad.coupon import FitCoupon
    from phantom_cad.cad.registry import part

    p = variant(lambda d: d["print"].__setitem__("hole_compensation_mm", 0.3))
    hw, pr = document["hardware"], document["print"]
    seat = (hw["bearing"]["outer_mm"] - pr["press_fit_interference_mm"] + 0.3) / 2
    clear = (hw["axle_diameter_mm"] + 2 * pr["hole_clearance_mm"] + 0.3) / 2
    tendon = (hw["tendon_diameter_mm"] + 2 * pr["hole_clearance_mm"]) / 2
    phalanx = {round(x["radius"], 6) for x in measure.cylinders(part(p, "index_proximal").build())}
    assert round(seat, 6) in phalanx and round(clear, 6) in phalanx
    cp = {round(x["radius"], 6) for x in measure.cylinders(FitCoupon(p).build())}
    assert {round(seat, 6), round(clear, 6), round(tendon, 6)} <= cp
    default_seat = (hw["bearing"]["outer_mm"] - pr["press_fit_interference_mm"] + 0.2) / 2
    assert round(default_seat, 6) not in cp
