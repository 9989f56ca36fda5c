"""The posture library on the MJCF twin of the default hand: each posture's commands
(``phantom-cad pose``) settle, gravity and contacts off, within 1 degree of the model's joint angles
at those commands on every joint; with contacts on, each opposition posture's thumb tip touches the
fingertip it is for and no other.

The known answer is MuJoCo's equilibrium of the exported strands; the model never sees the MJCF.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad import postures as P
from phantom_cad.export import twin
from phantom_cad.kinematics.model import Hand
from phantom_cad.kinematics.topology import FINGERS, JOINTS, digit_links
from phantom_cad.params import parse
from tests.support.hands import hand_document

mujoco = pytest.importorskip("mujoco")

TOL = math.radians(1.0)
#: at rest: no joint faster than this (rad/s), as in tests/export/test_twin_model.py
REST = 2e-4


def _model(result, contacts: bool):
    m = mujoco.MjModel.from_xml_path(str(result.out_dir / "description" / "mjcf" / "scene.xml"))
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_GRAVITY
    if not contacts:
        m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    return m


def settled(m, u, rest: bool = True):
    """The twin under the commands u from its rest keyframe, brought to rest (``rest``) or run for
    10 s (two pads pressed together keep a jitter above :data:`REST`)."""
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    d.ctrl[:] = u
    assert twin.settle(mujoco, m, d, REST, 10.0) or not rest, "the twin did not come to rest"
    return d


def postures_errors(m, hand) -> dict[str, np.ndarray]:
    """Per library posture, |twin - model| (rad) per joint at the posture's commands."""
    q_adr, _ = twin.addresses(mujoco, m)
    out = {}
    for name, posture in P.load(hand).items():
        r = P.pose(hand, posture)
        out[name] = np.abs(settled(m, r.u).qpos[q_adr] - r.q)
    return out


@pytest.mark.slow
def test_every_posture_settles_on_the_model(hand_export):
    hand = Hand(parse(hand_document("default")))
    for name, err in postures_errors(_model(hand_export("default"), contacts=False), hand).items():
        worst = int(np.argmax(err))
        assert err[worst] < TOL, (name, JOINTS[worst].name, math.degrees(err[worst]))


@pytest.mark.slow
def test_the_opposition_postures_touch_their_finger(hand_export):
    hand = Hand(parse(hand_document("default")))
    m = _model(hand_export("default"), contacts=True)
    distal = {d: digit_links(d)[-1].name for d in ("thumb", *FINGERS)}
    for name, posture in P.load(hand).items():
        if posture.finger is None:
            continue
        d = settled(m, P.pose(hand, posture).u, rest=False)
        pairs = {frozenset(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, m.geom_bodyid[g]) for g in (c.geom1, c.geom2))
                 for c in d.contact[:d.ncon]}
        thumb = {p for p in pairs if distal["thumb"] in p}
        assert thumb == {frozenset((distal["thumb"], distal[posture.finger]))}, (name, pairs)
