"""The routed elasticity effects against the model they scale: at scale 1 the pipeline is the plain
hand's routed compensation (which tests/export/test_twin_model.py holds to the MuJoCo twin), at 0
the analytic model, at c the routed compensation of a file whose EA is EA / c; a calibrated file
with one is a routed hand whose control law inverts its forward, a loop preload's piecewise statics
included."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import tomli_w

from phantom_cad import load_hand, load_params
from phantom_cad.calibration.effects import get_effect, run_pipeline
from phantom_cad.canon import plain
from phantom_cad.kinematics.model import Hand
from phantom_cad.params import parse


def _grid(hand, n=9):
    """Each servo alone over its travel, then all together."""
    rows = []
    for k in range(6):
        for f in np.linspace(0.0, 1.0, n):
            u = hand.u_min.copy()
            u[k] += f * (hand.u_max[k] - hand.u_min[k])
            rows.append(u)
    rows += [hand.u_min + f * (hand.u_max - hand.u_min) for f in np.linspace(0.0, 1.0, n)]
    return np.array(rows)


def _mechanics(document, **changes):
    doc = copy.deepcopy(document)
    doc["mechanics"].update(changes)
    return parse(doc)


def test_scale_one_is_the_routed_compensation_zero_the_analytic_model(hand):
    u = _grid(hand)
    routed = get_effect("routed_elasticity")
    assert np.abs(run_pipeline(hand, [(routed, np.array([1.0]))], u) - hand.forward(u, compensated=True)).max() < 1e-10
    assert np.abs(run_pipeline(hand, [(routed, np.array([0.0]))], u) - hand.forward(u)).max() < 1e-12


@pytest.mark.parametrize("scale", [0.5, 2.0])
def test_a_scale_is_the_file_with_ea_over_it(hand, document, scale):
    u = _grid(hand)
    soft = Hand(_mechanics(document, tendon_EA_N=document["mechanics"]["tendon_EA_N"] / scale))
    got = run_pipeline(hand, [(get_effect("routed_elasticity"), np.array([scale]))], u)
    assert np.abs(got - soft.forward(u, compensated=True)).max() < 1e-10
    # per finger: the index alone, the other chains at the file's
    x = np.ones(5)
    x[1] = scale
    per = run_pipeline(hand, [(get_effect("routed_elasticity_per_finger"), x)], u)
    index = list(range(2, 5))
    assert np.abs(per[:, index] - got[:, index]).max() < 1e-10
    others = [j for j in range(15) if j not in index]
    assert np.abs(per[:, others] - hand.forward(u, compensated=True)[:, others]).max() < 1e-10


def _calibrated(tmp_path, params, effects):
    doc = plain(params.document)
    doc["effects"] = effects
    path = tmp_path / "calibrated.toml"
    path.write_text(tomli_w.dumps(doc))
    return load_hand(path)


@pytest.mark.parametrize("preload", [0.0, 1.5])
def test_a_calibrated_routed_hand_inverts_its_forward(tmp_path, document, preload):
    """With a 1.5 N loop preload the loops go one-sided inside the travel: the piecewise statics."""
    params = _mechanics(document, loop_preload_N=preload)
    cal = _calibrated(tmp_path, params, {"routed_elasticity": {"compliance_scale": 1.7},
                                         "tendon_elasticity": {"compliance_per_m": 0.0}})
    assert cal.compensation == "routed"
    u = _grid(cal)
    q = cal.forward(u, compensated=True)
    soft = Hand(_mechanics(document, loop_preload_N=preload, tendon_EA_N=document["mechanics"]["tendon_EA_N"] / 1.7))
    assert np.abs(q - soft.forward(u, compensated=True)).max() < 1e-10
    assert np.abs(cal.inverse(q) - u).max() < 1e-9
    # compensated=False leaves the stretch out, as it does the paper's
    assert np.abs(cal.forward(u, compensated=False) - cal.forward(u, compensated=True)).max() > math.radians(1.0)
    assert np.abs(cal.forward(u, compensated=False) - Hand(params).forward(u)).max() < 1e-12
    with pytest.raises(ValueError, match="routed compensation"):
        Hand(params, cal.effects, compensation="paper")


def test_with_other_effects_the_control_law_still_inverts(tmp_path):
    """Per-finger routed scales with radius errors and a slack: inverse(forward(u)) == u beyond the
    dead band."""
    params = load_params()
    cal = _calibrated(tmp_path, params, {
        "routed_elasticity_per_finger": {"thumb_scale": 0.8, "index_scale": 1.5, "middle_scale": 1.0,
                                         "ring_scale": 2.0, "pinky_scale": 0.6},
        "pulley_radius_error": {"u2_relative": 0.03, "u4_relative": -0.02},
        "tendon_slack": {"u3_deg": 2.0},
        "tendon_elasticity": {"compliance_per_m": 0.0}})
    u = _grid(cal)
    u = u[u[:, 2] - cal.u_min[2] > math.radians(2.5)]
    assert np.abs(cal.inverse(cal.forward(u, compensated=True)) - u).max() < 1e-9
