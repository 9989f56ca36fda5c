"""No tendon passes through material: points sampled every 0.25 mm along every strand of the routing
model, with the hand posed at 0, 25, 50, 75 and 100 % of every travel, classified by OpenCascade
against the built solids (cad.clearance). Default hand, left hand, slender.toml.

Known answers: nothing inside any solid; and the check sees a tendon in material when a part is
built without the channels cut for it (the check can fail).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from phantom_cad import load_params
from phantom_cad.cad import assembly, clearance, registry
from phantom_cad.params import parse

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def right_solids(built, params):
    """The default hand's right-handed solids in their link frames (as the parts build them)."""
    assert params.side == "right"
    return {n: b.shape for n, b in built.items()}


def _fmt(hits):
    return [f"{h.strand} at {h.fraction:.0%} in {h.part} ({h.n_points} points, first at {h.point_mm} mm)" for h in hits]


def test_no_tendon_passes_through_material(params, right_solids):
    assert _fmt(clearance.tendon_hits(params, right_solids)) == []


def test_left_hand_tendons_pass_through_no_material(document, right_solids):
    """A left hand's parts are the right hand's mirrored (test_parts checks that): its routes,
    mirrored back into the parts' frames, must clear the same solids."""
    doc = dict(document)
    doc["hand"] = {**document["hand"], "side": "left"}
    left = parse(doc)
    assert left.side == "left"
    assert _fmt(clearance.tendon_hits(left, right_solids)) == []


def test_slender_hand_tendons_pass_through_no_material():
    p = load_params(ROOT / "params" / "examples" / "slender.toml")
    solids = {n: registry.part(p, n).build() for n in assembly.part_names(p)}
    assert _fmt(clearance.tendon_hits(p, solids)) == []


def test_a_part_without_its_channels_is_caught(params, monkeypatch):
    """Build the index proximal phalanx without the loop and return channels the routing model asks
    for: the check finds those strands inside it."""
    from phantom_cad.cad.parts import phalanx
    monkeypatch.setattr(phalanx, "channel_tools", lambda lt, extend=None: [])
    shape = registry.part(params, "index_proximal").build()
    hits = clearance.tendon_hits(params, {"index_proximal": shape}, fractions=(0.0,))
    assert {h.strand for h in hits} >= {"index_mcp_pip_a", "index_mcp_pip_b", "index_return"}
    assert all(h.part == "index_proximal" for h in hits)
