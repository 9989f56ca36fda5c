"""Twin = model: the MJCF twin of an export, settled under its six servos (gravity and contacts
off), against ``hand.forward(u, compensated=True)`` (the routed compensation) evaluated at the
servo angles the twin reached, every joint within 0.1 degree: each servo swept alone over its
travel and all together, on the default, left and 170 mm hands and a hand `phantom-cad size`
made; and with the loop preload and EA at the ends of their ranges (20 N; EA = 50 N, just above
the 45 N below which the routed statics leave the middle DIP no coupling), whose twins are the
exported MJCF with its tendons' stiffness, damping and spring length set from the export's own
strand records (``export.robot.transmissions`` of the changed parameters: what the writer would
put there).

The known answer is MuJoCo's equilibrium of the routed strands; the model never sees the MJCF.
The paper's eq. (11)-(14) miss it by degrees (docs/transmission.md), which the same loop shows.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.export import twin
from phantom_cad.kinematics.model import Hand
from phantom_cad.kinematics.topology import JOINTS
from phantom_cad.params import parse
from tests.support.hands import HANDS, hand_document

mujoco = pytest.importorskip("mujoco")

TOL = math.radians(0.1)
#: at rest: no joint faster than this (rad/s). A preloaded twin's unloaded fingers keep a
#: jitter of up to 1e-4 rad/s (two opposed strands under tension), a few microradians in amplitude
REST = 2e-4


def _twin(result):
    m = mujoco.MjModel.from_xml_path(str(result.out_dir / "description" / "mjcf" / "scene.xml"))
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    return m


def _errors(m, hand, fractions=(0.25, 0.5, 0.75, 1.0), together=(0.3, 0.6, 1.0), seconds=10.0) -> np.ndarray:
    """Max |twin - model| (rad) per joint over each servo alone at ``fractions`` of its travel
    and all servos together at ``together``; the twin at rest (:data:`REST`, within ``seconds``
    of simulated time) before it is read."""
    d = mujoco.MjData(m)
    q_adr, u_adr = twin.addresses(mujoco, m)
    err = np.zeros(len(JOINTS))
    for u in twin.sweep(m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1], fractions, together):
        mujoco.mj_resetDataKeyframe(m, d, 0)
        d.ctrl[:] = u
        twin.settle(mujoco, m, d, REST, seconds)
        assert np.abs(d.qvel).max() < REST, "the twin did not come to rest"
        err = np.maximum(err, np.abs(d.qpos[q_adr] - hand.forward(d.qpos[u_adr], compensated=True)))
    return err


@pytest.mark.slow
@pytest.mark.parametrize("kind", HANDS)
def test_the_twin_sits_on_the_routed_compensation(hand_export, kind):
    result = hand_export(kind)
    params = parse(hand_document(kind))
    m = _twin(result)
    err = _errors(m, Hand(params))
    worst = int(np.argmax(err))
    assert err[worst] < TOL, (kind, JOINTS[worst].name, math.degrees(err[worst]))
    # the paper's lumped form is not the printed hand's statics: degrees off on the fingers
    paper = _errors(m, Hand(params, compensation="paper"), fractions=(1.0,), together=())
    assert math.degrees(paper.max()) > 2.0


@pytest.mark.slow
def test_the_twin_of_a_sized_hand_sits_on_the_routed_compensation(sized_hand):
    """The hand ``phantom-cad size`` makes for 160 x 72 mm (tests/conftest.py)."""
    doc, result = sized_hand
    err = _errors(_twin(result), Hand(parse(doc)))
    worst = int(np.argmax(err))
    assert err[worst] < TOL, (JOINTS[worst].name, math.degrees(err[worst]))


@pytest.mark.slow
@pytest.mark.parametrize("mechanics", [{"loop_preload_N": 20.0}, {"loop_preload_N": 1.5},
                                       {"tendon_EA_N": 50.0}])
def test_the_twin_sits_on_the_routed_compensation_across_the_ranges(hand_export, mechanics):
    """1.5 N: the loops go one-sided inside the travel (the piecewise statics)."""
    from phantom_cad.export.robot import transmissions

    doc = hand_document("default")
    doc["mechanics"].update(mechanics)
    params = parse(doc)
    m = _twin(hand_export("default"))
    for st in transmissions(params)[1]:
        t = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, st.name)
        m.tendon_stiffness[t], m.tendon_damping[t] = st.stiffness, st.damping
        m.tendon_lengthspring[t] = [0.0, st.slack_length]
    # soft strands settle slowly: at EA = 50 N every servo at full travel takes about 25 s
    err = _errors(m, Hand(params), fractions=(0.5, 1.0), together=(1.0,), seconds=40.0)
    worst = int(np.argmax(err))
    assert err[worst] < TOL, (mechanics, JOINTS[worst].name, math.degrees(err[worst]))
