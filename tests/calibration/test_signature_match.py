"""Each library effect declares the signature it leaves (Effect.leaves, an effects.Signature); the
report compares the measured residual's features with the best candidate's declaration and says
which match and which do not. The data: closed-form cosine law and hidden physics written out here
in numpy (test_noise_floor, test_plugin), never simulate or the effect classes."""

import math

import numpy as np
import pytest

from phantom_cad.calibration.diagnose import diagnose
from phantom_cad.calibration.effects import REGISTRY, Signature
from phantom_cad.calibration.signature import compare_features
from phantom_cad.calibration.diagnosis_text import diagnosis_text

from .test_noise_floor import OFFSETS, analytic, eccentric_data, measure, sweeps
from .test_plugin import compliant

LIBRARY = ("tendon_slack", "pulley_radius_error", "tendon_elasticity", "tendon_elasticity_per_finger",
           "friction_hysteresis", "joint_offset", "camera_scale", "backlash", "drive_friction", "routed_elasticity",
           "routed_elasticity_per_finger")
PERIODIC = ("the residual is periodic in u with period 40 deg: no library effect predicts that; "
            "look at the servo horn / pulley eccentricity")


def test_every_library_effect_declares_its_signature():
    for name in LIBRARY:
        leaves = REGISTRY[name].leaves
        assert isinstance(leaves, Signature), name
        assert leaves.periodic is False
    assert REGISTRY["friction_hysteresis"].leaves.direction == "flips"
    assert REGISTRY["tendon_elasticity"].leaves.joints == "distal"
    assert REGISTRY["joint_offset"].leaves.at_rest == "nonzero"
    with pytest.raises(ValueError, match="direction"):
        Signature(direction="sideways")


def test_compare_features_known_answer():
    measured = {"direction": "flips", "at_rest": "zero", "trend": "flat", "joints": "all", "periodic": False,
                "reversal": "unknown", "digits": "one"}
    declared = Signature(direction="flips", at_rest="any", trend="grows", joints="distal", reversal="jump",
                         digits="all")
    out = compare_features(measured, declared)
    assert out["matches"] == ["direction", "at_rest", "periodic"]
    assert out["mismatches"] == ["trend", "joints", "digits"]
    assert out["unknown"] == ["reversal"]
    # a feature the measurement does not give is unknown
    del measured["digits"]
    assert compare_features(measured, declared)["unknown"] == ["reversal", "digits"]
    assert compare_features(measured, None)["declared"] is None


@pytest.fixture(scope="module")
def eccentric(hand):
    d = diagnose(hand, eccentric_data(hand))
    return d, d.to_json()


def test_eccentricity_is_reported_unexplained_with_its_period_named(eccentric):
    d, out = eccentric
    assert out["explained"] is False
    for key in ("before", "after"):
        sm = out["signature_match"][key]
        assert sm["measured"]["periodic"] is True
        assert sm["details"]["period_deg"] == pytest.approx(40.0, abs=2.0)
        # a sinusoid on every joint of two chains, the same both ways, zero at u = 0, no jump
        assert sm["measured"]["direction"] == "same" and sm["measured"]["joints"] == "all"
        assert sm["measured"]["reversal"] == "none"
        assert "periodic" in sm["mismatches"]
        assert sm["effects_with_this_signature"] == []
        assert sm["best_candidate"] in LIBRARY
        assert any(PERIODIC in t for t in sm["sentences"])
        assert "no single library effect leaves this signature (two effects at once, or one outside the library)" in sm["sentences"]
    text = "\n".join(diagnosis_text(d, out))
    assert PERIODIC in text and "explained: no" in text


def test_nothing_hidden_is_explained_and_has_no_signature_to_match(hand):
    u, sweep, cj = sweeps(hand)
    out = diagnose(hand, measure(hand, u, sweep, cj, analytic(hand, u), seed=4)).to_json()
    assert out["explained"] is True and out["selected"] == []
    assert out["signature_match"] == {"before": None}


def test_hand_written_offsets_match_joint_offset_only(hand):
    u, sweep, cj = sweeps(hand)
    q = analytic(hand, u)
    for j, o in OFFSETS.items():
        q[:, j] += math.radians(o)
    out = diagnose(hand, measure(hand, u, sweep, cj, q, seed=6)).to_json()
    sm = out["signature_match"]["before"]
    assert sm["details"]["joints_used"] == ["q4", "q9", "q13"]
    # the offsets sit on PIP joints only: "distal" (joint_offset declares any joints)
    # q4, q9, q13: the index, ring and pinky of the five tendon-driven digits
    assert sm["measured"] == {"direction": "same", "at_rest": "nonzero", "trend": "flat", "joints": "distal",
                              "periodic": False, "reversal": "none", "digits": "some"}
    assert sm["best_candidate"] == "joint_offset" and sm["mismatches"] == []
    assert sm["effects_with_this_signature"] == ["joint_offset"]
    assert sm["sentences"][0].startswith("matches joint_offset: it is the same in both directions; it is present at rest")
    assert "after" not in out["signature_match"] and out["explained"] is True


def test_per_finger_compliance_matches_tendon_elasticity(hand):
    """Tendon stretch with a different compliance per finger (eq. 13 by hand): the distal joints lag
    in proportion to flexion, the MCP does not: the signature tendon_elasticity declares."""
    u, sweep, cj = sweeps(hand)
    out = diagnose(hand, measure(hand, u, sweep, cj, compliant(hand, u), seed=12)).to_json()
    sm = out["signature_match"]["before"]
    assert sm["measured"] == {"direction": "same", "at_rest": "zero", "trend": "grows", "joints": "distal",
                              "periodic": False, "reversal": "none", "digits": "all"}
    # the per-finger variant and a per-joint scale of the measurement leave the same features
    assert sm["effects_with_this_signature"] == ["tendon_elasticity", "tendon_elasticity_per_finger",
                                                 "camera_scale"]
    # the per-finger compliance is the best candidate (5 parameters fit what 15 scales only approach)
    assert sm["best_candidate"] == "tendon_elasticity_per_finger" and sm["mismatches"] == []
    assert out["selected"] == ["tendon_elasticity_per_finger"] and out["explained"] is True


@pytest.mark.slow
def test_a_friction_band_on_the_drive_matches_drive_friction(hand):
    """The drive tendon's friction band (written row by row in hidden.friction_band, 1.5 deg at rest,
    3 deg more at full flexion): a band between the branches on the MCP as on the distal joints, a
    jump after each reversal, on every digit. Its width triples, yet the trend measures "flat" (the
    upper half of the travel carries 1.7x the lower half's, not 2x): backlash's signature too, and
    the fit, not the signature, picks drive_friction (widths 1.51 and 2.99 deg fitted)."""
    from .hidden import truth

    u, sweep, cj = sweeps(hand)
    q = truth(hand, u, sweep, {"drive_friction": np.array([1.5, 3.0])})
    out = diagnose(hand, measure(hand, u, sweep, cj, q, seed=14)).to_json()
    sm = out["signature_match"]["before"]
    m = sm["measured"]
    assert (m["direction"], m["joints"], m["reversal"], m["digits"]) == ("flips", "all", "jump", "all"), m
    assert sm["best_candidate"] == "drive_friction" and sm["mismatches"] == [], sm
    assert sm["effects_with_this_signature"] == ["backlash", "drive_friction"]
    assert out["selected"] == ["drive_friction"] and out["explained"] is True
    fitted = out["effects"]["drive_friction"]["parameters"]
    assert fitted["width_at_rest_deg"]["value"] == pytest.approx(1.5, abs=0.05)
    assert fitted["width_growth_deg"]["value"] == pytest.approx(3.0, abs=0.1)


def test_the_spread_across_digits(hand, monkeypatch):
    """The index tendon alone is compliant (eq. 13 written out in test_plugin.compliant): the
    residual is on one digit, which the hand-wide tendon_elasticity (digits "all") does not leave and
    the per-digit effects (digits "any") do; with every tendon compliant it is on every digit."""
    from . import test_plugin

    u, sweep, cj = sweeps(hand)
    for digit in test_plugin.HIDDEN:
        monkeypatch.setitem(test_plugin.HIDDEN, digit, 0.6 if digit == "index" else 0.0)
    d = diagnose(hand, measure(hand, u, sweep, cj, test_plugin.compliant(hand, u), seed=4),
                 candidates=["tendon_elasticity"])
    before = d.to_json()["signature_match"]["before"]
    assert before["measured"]["digits"] == "one"
    assert before["best_candidate"] == "tendon_elasticity" and "digits" in before["mismatches"]
    assert any(s.startswith("does not match tendon_elasticity, whose residual is on every digit measured: "
                            "it is on one digit only (index)") and "tendon_elasticity_per_finger" in s
               for s in before["sentences"])
    for digit in test_plugin.HIDDEN:
        monkeypatch.setitem(test_plugin.HIDDEN, digit, 0.3)
    d = diagnose(hand, measure(hand, u, sweep, cj, test_plugin.compliant(hand, u), seed=4),
                 candidates=["joint_offset"])
    assert d.to_json()["signature_match"]["before"]["measured"]["digits"] == "all"
