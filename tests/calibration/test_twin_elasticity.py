"""diagnose finds the tendon stretch where the MuJoCo twin has it.

The measurements are written by the twin of the default export (its MJCF, gravity and contacts
off), not by the project's model: the twin's strands (drives and coupling loops) made 0.5x-2x as
stiff, or its return cords 0.5x-2x as stiff, each servo swept over its travel with the other digits'
servos at the bottom (one servo of each digit at a time: the digits do not interact), flexing then
extending, the twin brought to rest at every step (``export.twin.settle``) and its joints read,
the servo column the angle the twin's servo reached; Gaussian noise on every recorded angle; the
measurement CSV format, written and read back.

With gravity off only k_s / EA shows in the joint angles, so strands s times as stiff are a
compliance ratio of 1 / s and return cords c times as stiff one of c. Criteria: ``diagnose``
selects a hand-side elasticity effect (not a camera scale, not slack or a radius error), says
``explained`` (at the noise floor); ``fit`` of that effect recovers the ratio within 5 %; the
calibrated file's ``forward`` is within 0.1 degree MAE of the twin's noise-free angles, and its
control law ``inverse`` brings the calibrated model back to the twin's poses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad import load_hand
from phantom_cad.calibration.data import read_measurements, write_measurements
from phantom_cad.calibration.diagnose import diagnose
from phantom_cad.export import twin
from phantom_cad.kinematics.topology import CHAINS, JOINTS, N_JOINTS, N_SERVOS, SERVOS, U_COLUMNS, servo_joints
from tests.support import shared

mujoco = pytest.importorskip("mujoco")

#: steps per direction of each servo's sweep
POINTS = 25
#: at rest: no joint faster than this (rad/s), as in tests/export/test_twin_model.py
REST = 2e-4
#: (name, strands' stiffness factor, return cords' stiffness factor, noise sd in degrees), each
#: factor one for the hand or {digit: factor} (1 for the digits not named); the compliance ratio
#: the fit must find is the return cord's factor over the strands'
CASES = (
    ("strands 0.5x", 0.5, 1.0, 0.1),
    ("strands 2x", 2.0, 1.0, 0.1),
    ("strands 0.625x", 0.625, 1.0, 0.1),
    ("returns 1.8x", 1.0, 1.8, 0.1),
    ("returns 0.5x", 1.0, 0.5, 0.1),
    ("returns 2x, noise 0.2", 1.0, 2.0, 0.2),
    ("strands 1.25x, returns 1.5x", 1.25, 1.5, 0.1),
    ("index strands 0.5x, ring return 1.6x", {"index": 0.5}, {"ring": 1.6}, 0.1),
)
DIGITS = tuple(c.digit for c in CHAINS)
HAND_ELASTICITY = {"routed_elasticity", "routed_elasticity_per_finger"}


def factors(value) -> dict[str, float]:
    """{digit: factor} of a case's factor (one for the hand, or per digit, 1 where not named)."""
    return {d: value.get(d, 1.0) for d in DIGITS} if isinstance(value, dict) else dict.fromkeys(DIGITS, value)


def ratios(strands, returns) -> np.ndarray:
    """The compliance ratio of each tendon chain (servo order): its return cord's factor over its strands'."""
    s, r = factors(strands), factors(returns)
    return np.array([r[d] / s[d] for d in DIGITS])


def twin_model(scene, strands, returns):
    """The export's MJCF (gravity and contacts off) with each digit's strands' stiffness (and
    damping: their time constant kept) times its ``strands`` factor and its return cord's times its
    ``returns`` factor (:func:`factors`). The CMC's loop carries no load here: left as it is."""
    m = mujoco.MjModel.from_xml_path(str(scene))
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    s, r = factors(strands), factors(returns)
    for t in range(m.ntendon):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t)
        digit = name.split("_")[0]
        if digit not in DIGITS or name.startswith("thumb_cmc"):
            continue
        f = r[digit] if name.endswith("_return") else s[digit]
        m.tendon_stiffness[t] *= f
        m.tendon_damping[t] *= f
    return m


def rounds() -> list[list[int]]:
    """The servos swept at once: one servo of each digit per round (the thumb's flexion and its
    CMC in two). Gravity and contacts off, the digits share no tendon and no body but the palm,
    which is fixed: each reads as if swept alone (:func:`test_the_digits_sweep_as_if_alone`), and
    every step of the simulation moves the whole hand anyway."""
    by_digit: dict[str, list[int]] = {}
    for s in SERVOS:
        by_digit.setdefault(s.digit, []).append(s.index)
    return [[ks[r] for ks in by_digit.values() if r < len(ks)] for r in range(max(map(len, by_digit.values())))]


def twin_sweeps(m, points: int = POINTS, servos=None):
    """(u (N, 6) the servos reached, q (N, 15), sweep code (N,)): each servo from the bottom of its
    range to the top in ``points`` steps and back in ``points``, the other digits' servos at the
    bottom, in servo order; the twin at rest before each reading, each round (:func:`rounds`) from
    the rest keyframe. A row holds its servo's reading and its digit's joints; the other digits'
    columns are their rest readings (their servos at the bottom). ``servos``: sweep only these, each
    alone."""
    d = mujoco.MjData(m)
    q_adr, u_adr = twin.addresses(mujoco, m)
    lo, hi = m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1]
    mujoco.mj_resetDataKeyframe(m, d, 0)
    d.ctrl[:] = lo
    twin.settle(mujoco, m, d, REST, 20.0)
    u_rest, q_rest = d.qpos[u_adr].copy(), d.qpos[q_adr].copy()
    rows: dict[int, list] = {}
    for group in (rounds() if servos is None else [[k] for k in servos]):
        mujoco.mj_resetDataKeyframe(m, d, 0)
        paths = {k: np.concatenate([np.linspace(lo[k], hi[k], points), np.linspace(hi[k], lo[k], points + 1)[1:]])
                 for k in group}
        for i in range(2 * points):
            d.ctrl[:] = lo
            for k in group:
                d.ctrl[k] = paths[k][i]
            twin.settle(mujoco, m, d, REST, 20.0)
            assert np.abs(d.qvel).max() < REST, "the twin did not come to rest"
            for k in group:
                u, q = u_rest.copy(), q_rest.copy()
                u[k] = d.qpos[u_adr[k]]
                mine = [j.index for j in JOINTS if j.digit == SERVOS[k].digit]
                q[mine] = d.qpos[np.asarray(q_adr)[mine]]
                rows.setdefault(k, []).append((u, q))
    order = sorted(rows)
    return (np.array([u for k in order for u, _ in rows[k]]), np.array([q for k in order for _, q in rows[k]]),
            np.array([k for k in order for _ in rows[k]]))


@pytest.fixture(scope="module")
def scene(hand_export):
    return hand_export("default").out_dir / "description" / "mjcf" / "scene.xml"


@pytest.fixture(scope="module")
def twin_data(scene, shared_root):
    """{case name: (u, q, sweep)} of every case, made once per test run."""

    def make():
        return {name: twin_sweeps(twin_model(scene, s, r)) for name, s, r, _ in CASES}
    return shared.once(shared_root, "twin-elasticity-sweeps", make)


@pytest.mark.slow
def test_the_digits_sweep_as_if_alone(twin_data, scene):
    """A servo swept alone (the others at the bottom) reads as it does swept with one servo of each
    other digit (:func:`rounds`): the thumb's flexion, which shares its digit with the CMC, and the
    index, within 0.001 degree (the twin at rest to 2e-4 rad/s; the cases' noise is 0.1 degree)."""
    name, strands, returns, _ = CASES[0]
    u_all, q_all, sweep = twin_data[name]
    u, q, alone = twin_sweeps(twin_model(scene, strands, returns), servos=[0, 1])
    rows = np.isin(sweep, [0, 1])
    assert np.array_equal(sweep[rows], alone)
    assert math.degrees(np.abs(u_all[rows] - u).max()) < 1e-3
    assert math.degrees(np.abs(q_all[rows] - q).max()) < 1e-3


def write_case(path, u, q, sweep, noise_deg: float, seed: int):
    """The measurement file of one case: each sweep records its own servo's joints, with noise."""
    rng = np.random.default_rng(seed)
    recorded = np.full(q.shape, np.nan)
    for k in range(N_SERVOS):
        rows = sweep == k
        for j in servo_joints(k):
            recorded[rows, j] = q[rows, j] + np.radians(rng.normal(0.0, noise_deg, rows.sum()))
    write_measurements(path, u, recorded, [U_COLUMNS[k] for k in sweep],
                       comments=[f"the MuJoCo twin, noise {noise_deg} deg"])


@pytest.mark.slow
@pytest.mark.parametrize("case", range(len(CASES)), ids=[c[0] for c in CASES])
def test_diagnose_finds_the_twins_stretch(twin_data, tmp_path, case):
    import tomllib

    from typer.testing import CliRunner

    from phantom_cad.cli import app

    name, strands, returns, noise = CASES[case]
    ratio = ratios(strands, returns)
    # one compliance for the hand, or one per finger where the fingers differ
    effect = "routed_elasticity" if np.all(ratio == ratio[0]) else "routed_elasticity_per_finger"
    u, q, sweep = twin_data[name]
    path = tmp_path / "twin.csv"
    write_case(path, u, q, sweep, noise, seed=case)
    m = read_measurements(path)
    d = diagnose(load_hand(), m, jobs=1)
    out = d.to_json()
    assert out["selected"] == [effect], (name, out["selected"], out["notes"])
    assert out["explained"] is True, (name, out["verdict"])
    assert out["mae_deg_after"] <= 1.5 * out["noise_floor_deg"], name

    # fit writes a calibrated file: its ratios within 5 %, its forward on the twin's noise-free angles
    cal = tmp_path / "calibrated.toml"
    res = CliRunner().invoke(app, ["fit", str(path), "--effects", effect, "--out", str(cal)])
    assert res.exit_code == 0, res.output
    table = tomllib.loads(cal.read_text())["effects"][effect]
    fitted = (np.full(len(DIGITS), table["compliance_scale"]) if effect == "routed_elasticity" else
              np.array([table[f"{digit}_scale"] for digit in DIGITS]))
    assert np.all(np.abs(fitted / ratio - 1.0) < 0.05), (name, fitted, ratio)
    calibrated = load_hand(cal)
    assert calibrated.compensation == "routed"
    measured = np.isfinite(m.q)
    model = calibrated.forward(u, compensated=True)
    assert math.degrees(np.mean(np.abs(model - q)[measured])) < 0.1, name
    # the uncalibrated routed model is off wherever the ratio is: the calibration is what brings it there
    before = load_hand().forward(u, compensated=True)
    if np.abs(ratio - 1.0).max() >= 0.2:
        assert np.mean(np.abs(model - q)[measured]) < 0.5 * np.mean(np.abs(before - q)[measured]), name
    # the calibrated control law inverts its forward (at the twin's servo angles, within the travel:
    # at rest the twin's servos stand a few nanoradians below it)
    poses = calibrated.forward(np.clip(u, calibrated.u_min, calibrated.u_max), compensated=True)
    assert np.abs(calibrated.forward(calibrated.inverse(poses), compensated=True) - poses).max() < 1e-9


@pytest.mark.slow
def test_softer_strands_and_a_stiffer_return_cord_are_one_ratio_on_the_twin(twin_data):
    """Strands half as stiff and return cords twice as stiff: on the twin both sit on the routed
    statics with compliance ratio 2 (each at the servo angles it reached: the stiffer return cord
    loads the servo more), within 0.01 degree; the file's ratio misses them by degrees."""
    from phantom_cad.calibration.effects import get_effect, run_pipeline

    hand = load_hand()
    routed = get_effect("routed_elasticity")
    for name in ("strands 0.5x", "returns 2x, noise 0.2"):
        u, q, _ = twin_data[name]
        model = run_pipeline(hand, [(routed, np.array([2.0]))], u, None, 0.0)
        assert math.degrees(np.abs(model - q).max()) < 0.01, name
        assert math.degrees(np.abs(hand.forward(u, compensated=True) - q).max()) > 1.0, name


def test_the_ratio_not_the_stiffness_is_seen():
    """Softer strands and a stiffer return cord by the same factor are the same compliance (the
    routed statics scale with k_s / EA alone, gravity off): so the cases name only the ratio."""
    import copy
    import tomllib
    from pathlib import Path

    from phantom_cad.kinematics.model import Hand
    from phantom_cad.params import parse

    doc = tomllib.loads((Path(__file__).resolve().parents[2] / "params" / "phantom.toml").read_text())
    hand = load_hand()
    u = np.linspace(hand.u_min, hand.u_max, 7)
    soft, stiff = copy.deepcopy(doc), copy.deepcopy(doc)
    soft["mechanics"]["tendon_EA_N"] = doc["mechanics"]["tendon_EA_N"] / 2.0
    stiff["mechanics"]["spring_k_N_per_m"] = doc["mechanics"]["spring_k_N_per_m"] * 2.0
    a = Hand(parse(soft)).forward(u, compensated=True)
    b = Hand(parse(stiff)).forward(u, compensated=True)
    assert np.abs(a - b).max() < 1e-12
    assert np.abs(a - hand.forward(u, compensated=True)).max() > math.radians(1.0)
    assert a.shape == (7, N_JOINTS)
