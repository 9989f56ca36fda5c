"""Twin = force model: each fingertip of the MJCF twin pressing a plate at its pad, its servo
commanded to the end of its travel (``export.twin.press``), against ``kinematics.force`` at the
posture where the pads met the plates, every servo at half its travel (``phantom-cad force``'s
default): within 10 % on every digit, on the default hand and the hand `phantom-cad size` makes.

The known answer is MuJoCo's contact force on the routed strands' equilibrium; the model never
sees the MJCF. docs/force.md has the table and why the thumb reads higher in the twin.
"""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.export import twin
from phantom_cad.kinematics.force import fingertip_forces
from phantom_cad.kinematics.model import Hand
from phantom_cad.params import parse
from tests.support.hands import hand_document

mujoco = pytest.importorskip("mujoco")

TOL = 0.10


def _check(result, params):
    hand = Hand(params)
    u = (hand.u_min + hand.u_max) / 2.0
    got = twin.press(mujoco, result.out_dir / "description" / "mjcf" / "scene.xml", u)
    assert got["rested"], "the twin did not come to rest"
    # the five tendon servos at their stall torque: the plate took what they give
    assert np.all(got["torque"][:5] >= got["stall"][:5] * (1.0 - 1e-9)), got["torque"]
    # the pads met the plates where the model puts them at the servo angles reached (the routed
    # compensation, within 0.1 deg: tests/export/test_twin_model.py)
    contact = hand.forward(got["u0"], compensated=True)
    assert np.abs(got["q0"] - contact).max() < np.radians(0.1)
    model = {f.digit: f.force for f in fingertip_forces(params, contact)}
    off = {d: got["force"][d] / model[d] - 1.0 for d in model}
    assert all(abs(v) < TOL for v in off.values()), {d: f"{100 * v:+.1f} %" for d, v in off.items()}


@pytest.mark.slow
def test_the_twin_presses_as_the_force_model_says(hand_export):
    _check(hand_export("default"), parse(hand_document("default")))


@pytest.mark.slow
def test_a_sized_hand_presses_as_the_force_model_says(sized_hand):
    doc, result = sized_hand
    _check(result, parse(doc))
