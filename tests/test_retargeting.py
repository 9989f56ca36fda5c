"""Retargeting from a human hand (phantom_cad/retargeting.py, export/retargeting.py,
``phantom-cad retarget``; docs/retargeting.md).

Known answers from elsewhere: the keypoints come from a human hand model of its own
(tests/support/human_hand.py: Buchholz et al.'s segment ratios, a 180 mm hand, not this hand's
kinematics) with noise, in a random camera frame; the palm frame's axes are docs/frames.md's;
dex-retargeting itself does the retargeting; the gestures say which way the fingers must go
(a fist flexes every finger more than an open hand, pointing keeps the index open).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from tests.support import human_hand as H

pytest.importorskip("dex_retargeting", reason="dex-retargeting not installed (pip install dex-retargeting torch)")

GESTURES = ["open", "fist", "open", "pinch", "point"]
#: a finger's servo, fist against open, closes by at least this much (deg): most of its travel
CLOSING_DEG = 45.0


@pytest.fixture(scope="module")
def hands():
    from phantom_cad import make_hand
    from phantom_cad.retargeting import load_params

    return {side: make_hand(load_params(None, side)) for side in ("right", "left")}


def _model(hand):
    from phantom_cad.cad.assembly import tip_frames
    from phantom_cad.export.robot import kinematic_model

    return kinematic_model(hand.params, tip_frames(hand.params))


def test_config_points_are_the_trees_links(hands):
    from phantom_cad.export import retargeting as RC
    from phantom_cad.kinematics.topology import DIGITS

    model = _model(hands["right"])
    links = RC.keypoint_links(model)
    names = {ln.name for ln in model.links}
    assert sorted(links) == list(range(1, RC.KEYPOINTS)) and set(links.values()) <= names
    # a digit's last keypoint is its fingertip frame, on its distal link
    tips = {j.child: j.parent for j in model.joints if j.child in links.values() and j.type == "fixed"}
    assert {links[RC.digit_keypoints(d)[-1]] for d in DIGITS} == set(tips)
    vector = RC.config(model, "vector", "x.urdf")["retargeting"]
    assert set(vector["target_origin_link_names"]) == {links[RC.origin_keypoint(model)]}
    assert [links[k] for k in vector["target_link_human_indices"][1]] == vector["target_task_link_names"]
    position = RC.config(model, "position", "x.urdf")["retargeting"]
    assert [links[k] for k in position["target_link_human_indices"]] == position["target_link_names"]
    assert len(position["target_link_names"]) == 20


def test_the_origin_keypoint_is_the_palm_frames_origin(hands):
    """docs/frames.md: the palm frame's origin is on the index MCP axis."""
    import tempfile
    from pathlib import Path

    import pinocchio as pin

    from phantom_cad.export import retargeting as RC
    from phantom_cad.export.urdf import urdf_bytes

    for side, hand in hands.items():
        model = _model(hand)
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "h.urdf"
            path.write_bytes(urdf_bytes(model, None))
            pm = pin.buildModelFromUrdf(str(path))
        data = pm.createData()
        pin.framesForwardKinematics(pm, data, pin.neutral(pm))
        origin = RC.keypoint_links(model)[RC.origin_keypoint(model)]
        assert np.allclose(data.oMf[pm.getFrameId(origin)].translation, 0.0, atol=1e-12), side


@pytest.mark.parametrize("side", ["right", "left"])
def test_keypoints_enter_the_palm_frame(side):
    """Whatever the camera, an open hand's fingers point along the palm frame's y, the little
    finger lies toward +x of the index on a right hand (-x on a left: the mirror image) and a fist's
    fingertips go palmar (-z)."""
    from phantom_cad import retargeting as R

    pts, labels = H.sequence(["open", "fist"], frames_each=1, noise_mm=0.0, seed=3, side=side)
    p = R.root_frame(pts, side, 5) * 1e3          # MediaPipe: 5 the index MCP, 8 12 16 20 the fingertips
    open_, fist = p[0], p[1]
    sign = 1.0 if side == "right" else -1.0
    assert np.allclose(open_[5], 0.0)
    middle_tip, index_tip, pinky_tip = open_[12], open_[8], open_[20]
    assert middle_tip[1] > 80.0 and abs(middle_tip[0]) < 30.0
    assert sign * (pinky_tip[0] - index_tip[0]) > 40.0
    assert all(fist[k][2] < -20.0 for k in (8, 12, 16, 20))
    assert all(fist[k][1] < open_[k][1] - 60.0 for k in (8, 12, 16, 20))


def _frames(labels, name):
    return [i for i, n in enumerate(labels) if n == name]


@pytest.mark.slow
@pytest.mark.parametrize("side", ["right", "left"])
def test_vector_retargeting_follows_the_gestures(hands, side):
    from phantom_cad import retargeting as R
    from phantom_cad.kinematics.topology import FINGERS, SERVOS
    from phantom_cad.units import deg

    hand = hands[side]
    pts, labels = H.sequence(GESTURES, frames_each=2, noise_mm=1.5, seed=1, side=side)
    r = R.retarget(hand, pts, "vector")
    assert r.u.shape == (len(pts), 6) and np.isfinite(r.u).all()
    assert (r.u >= hand.u_min - 1e-12).all() and (r.u <= hand.u_max + 1e-12).all()
    # the error is what the hand does at the commands less dex-retargeting's angles
    assert np.allclose(r.error, hand.forward(r.u, compensated=True) - r.q_target)
    finger_servos = [s.index for s in SERVOS if s.digit in FINGERS]
    u = deg(r.u)
    open_ = u[_frames(labels, "open")].max(axis=0)
    fist = u[_frames(labels, "fist")].min(axis=0)
    assert (fist[finger_servos] > open_[finger_servos] + CLOSING_DEG).all(), (open_, fist)
    point = u[_frames(labels, "point")]
    index, others = finger_servos[0], finger_servos[1:]
    assert (point[:, index] < open_[index] + 10.0).all() and (point[:, others] > fist[others] - 15.0).all()
    pinch = u[_frames(labels, "pinch")]
    assert (pinch[:, index] > open_[index] + 10.0).all() and (pinch[:, index] < fist[index] - 10.0).all()


def test_position_retargeting_closes_the_fist(hands):
    from phantom_cad import retargeting as R
    from phantom_cad.kinematics.topology import FINGERS, SERVOS

    hand = hands["right"]
    pts, labels = H.sequence(["open", "fist"], frames_each=2, noise_mm=1.5, seed=2)
    r = R.retarget(hand, pts, "position")
    assert (r.u >= hand.u_min - 1e-12).all() and (r.u <= hand.u_max + 1e-12).all()
    fingers = [s.index for s in SERVOS if s.digit in FINGERS]
    assert (np.degrees(r.u[2:, fingers]).min(axis=0) > np.degrees(r.u[:2, fingers]).max(axis=0) + CLOSING_DEG).all()



def test_retargeting_leaves_no_scratch_files(hands, tmp_path, monkeypatch):
    """dex-retargeting copies the URDF into a folder of its own at each build; a retarget leaves
    the temporary folder as it found it."""
    import tempfile

    from phantom_cad import retargeting as R

    pts, _ = H.sequence(["open"], frames_each=1, noise_mm=0.0, seed=4)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    R.retarget(hands["right"], pts, "vector")
    assert tempfile.tempdir == str(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == []

# -- the command line: bad input ---------------------------------------------------

def _run(argv, capsys):
    from phantom_cad.cli import main

    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    return exc.value.code, err


@pytest.mark.parametrize("make, says", [
    (lambda p: np.save(p.with_suffix(".npy"), np.zeros((4, 20, 3))), "shape (4, 20, 3)"),
    (lambda p: np.save(p.with_suffix(".npy"), np.zeros((21, 3))), "shape (21, 3)"),
    (lambda p: np.save(p.with_suffix(".npy"), _with_nan()), "2 of 6 frames have NaN"),
    (lambda p: p.with_suffix(".csv").write_text("1,2,3\n"), "rows of 3 columns"),
    (lambda p: p.with_suffix(".csv").write_text(",".join(["0"] * 62 + [""]) + "\n"), "1 of 1 frames have NaN"),
    (lambda p: p.with_suffix(".csv").write_text(",".join(["x"] * 63) + "\n"), "no keypoint rows"),
    (lambda p: np.save(p.with_suffix(".npy"), np.zeros((2, 21, 3))), "lie on a line (no palm plane)"),
    (lambda p: np.save(p.with_suffix(".npy"), 1000.0 * H.sequence(["open"])[0]), "keypoints are in metres"),
])
def test_bad_keypoint_files_fail_in_one_line(tmp_path, capsys, make, says):
    make(tmp_path / "kp")
    path = next(tmp_path.glob("kp.*"))
    code, err = _run(["retarget", str(path), "--out", str(tmp_path / "U.csv")], capsys)
    assert code == 2 and err.count("\n") == 1 and err.startswith("error: ") and says in err, err
    assert not (tmp_path / "U.csv").exists()


def _with_nan():
    pts, _ = H.sequence(["open", "fist"], frames_each=3, seed=0)
    pts[1, 4, 0] = np.nan
    pts[4, 0, 2] = np.inf
    return pts


def test_missing_file_and_bad_options_fail_in_one_line(tmp_path, capsys):
    pts, _ = H.sequence(["open"], frames_each=1)
    np.save(tmp_path / "kp.npy", pts)
    for argv, says in ((["retarget", str(tmp_path / "none.npy")], "no such file"),
                       (["retarget", str(tmp_path / "kp.npy"), "--method", "dexpilot"], "must be one of vector, position"),
                       (["retarget", str(tmp_path / "kp.npy"), "--side", "up"], "must be right or left")):
        code, err = _run([*argv, "--out", str(tmp_path / "U.csv")], capsys)
        assert code == 2 and err.count("\n") == 1 and says in err, err


# -- the command line: a sequence, in a process of its own ---------------------------

@pytest.mark.slow
def test_retarget_command_writes_commands_within_the_travel(tmp_path, hands):
    from phantom_cad.kinematics.topology import JOINTS, U_COLUMNS

    pts, labels = H.sequence(GESTURES, frames_each=2, seed=4)
    times = 0.05 * np.arange(len(pts))
    np.savetxt(tmp_path / "kp.csv", np.column_stack([times, pts.reshape(len(pts), -1)]), delimiter=",",
               header="t," + ",".join(f"k{i}_{a}" for i in range(21) for a in "xyz"), comments="")
    probe = ("import sys; from phantom_cad.cli import main\n"
             "try:\n    main(sys.argv[1:])\nfinally:\n"
             "    print('cad:', sorted(m for m in ('build123d', 'cadquery', 'OCP') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", probe, "retarget", str(tmp_path / "kp.csv"), "--out",
                           str(tmp_path / "U.csv")], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "cad: []" in proc.stdout and f"wrote {len(pts)} frames" in proc.stdout
    lines = (tmp_path / "U.csv").read_text().splitlines()
    assert lines[0].startswith("# phantom-cad retarget --method vector")
    header = lines[1].split(",")
    assert header[:2] == ["frame", "t"] and header[2:8] == list(U_COLUMNS)
    assert header[8:] == ["max_error_deg"] + [f"{j.name}_error_deg" for j in JOINTS]
    table = np.array([[float(v) for v in line.split(",")] for line in lines[2:]])
    assert len(table) == len(pts) and np.allclose(table[:, 1], times)
    hand = hands["right"]
    u = np.radians(table[:, 2:8])
    assert (u >= hand.u_min - 1e-9).all() and (u <= hand.u_max + 1e-9).all()
    assert np.allclose(table[:, 8], np.abs(table[:, 9:]).max(axis=1))


# -- the shipped configs, loaded by dex-retargeting from an export -------------------------

@pytest.mark.parametrize("kind", ["default", "left"])
def test_dex_retargeting_loads_the_shipped_configs(hand_export, kind, tmp_path, monkeypatch):
    import tempfile

    import yaml
    from dex_retargeting.retargeting_config import RetargetingConfig

    from phantom_cad import make_hand
    from phantom_cad import retargeting as R
    from phantom_cad.kinematics.topology import FINGERS, JOINT_NAMES, SERVOS
    from phantom_cad.postures import command
    from phantom_cad.units import deg

    result = hand_export(kind)
    pkg = result.out_dir / "description"
    configs = sorted((pkg / "config" / "retargeting").glob("*.yml"))
    assert [c.name for c in configs] == [f"{result.hand}_{result.side}_{m}.yml" for m in ("position", "vector")]
    hand = make_hand(R.load_params(None, result.side))
    pts, labels = H.sequence(["open", "fist", "point"], frames_each=1, seed=5, side=result.side)
    RetargetingConfig.set_default_urdf_dir(str(pkg))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))   # build() leaves a copy of the URDF there
    for path in configs:
        doc = yaml.safe_load(path.read_text())
        retargeting = RetargetingConfig.load_from_file(path, override={"low_pass_alpha": 1.0}).build()
        # the frame table: operator frame -> root frame, the origin keypoint at the origin
        frame = doc["frame"]
        p = R.operator_frame(pts, result.side) @ np.array(frame["root_from_operator"], float).T
        p -= p[:, frame["origin_keypoint"]:frame["origin_keypoint"] + 1]
        idx = np.asarray(retargeting.optimizer.target_link_human_indices)
        names = list(retargeting.joint_names)
        q = np.array([np.asarray(retargeting.retarget(f[idx] if doc["retargeting"]["type"] == "position"
                                                      else f[idx[1]] - f[idx[0]]))[[names.index(n) for n in JOINT_NAMES]]
                      for f in p])
        _, u = command(hand, q)
        assert (u >= hand.u_min - 1e-12).all() and (u <= hand.u_max + 1e-12).all()
        fingers = [s.index for s in SERVOS if s.digit in FINGERS]
        assert (deg(u[1, fingers]) > deg(u[0, fingers]) + CLOSING_DEG).all(), path.name
