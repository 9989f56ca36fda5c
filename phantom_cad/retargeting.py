"""Retargeting from a human hand: 21 hand keypoints a frame (MediaPipe's order) onto the 15 joints
with dex-retargeting (the description package's configs, ``export.retargeting``), then through
the coupling and the control law onto the six servos (``postures.command``), with the joint error
the coupling cannot follow (docs/retargeting.md). Builds no geometry: the URDF it retargets on is
the robot model's kinematic tree (``export.robot.kinematic_model``), written without meshes.

Keypoints in any frame (a camera's, MediaPipe's world landmarks): each frame is put into
dex-retargeting's operator frame as its MediaPipe detector does (the wrist at the origin; the
plane of the wrist, index MCP and middle MCP; OPERATOR2MANO of the hand's side), then into the
hand's root frame (``frame.root_from_operator`` of the configs, the index MCP at the origin).
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import UserError, one_line
from .export import retargeting as RC
from .kinematics.topology import FINGERS, JOINT_NAMES, N_JOINTS

#: the keypoints that fix the wrist frame: the wrist, the index MCP and the middle MCP
FRAME_KEYPOINTS = (RC.WRIST, RC.digit_keypoints(FINGERS[0])[0], RC.digit_keypoints(FINGERS[1])[0])
#: the wrist to the middle MCP of a human hand, m (about 0.07 for an adult's): keypoints outside
#: are not in metres
PALM_LENGTH = (0.02, 0.3)
#: a frame whose wrist, index MCP and middle MCP span a triangle of sides shorter than this (m,
#: about: the square root of twice its area) has no palm plane and is refused
DEGENERATE = 1e-6


@dataclass(frozen=True)
class Retargeted:
    """What :func:`retarget` makes of a keypoint sequence (T frames)."""
    method: str
    side: str
    q_target: np.ndarray        # (T, 15) rad: dex-retargeting's joint angles, the joints independent
    u: np.ndarray               # (T, 6) rad: the control law's commands, within the travel
    q: np.ndarray               # (T, 15) rad: the hand's joint angles at u (hand.forward(u, compensated=True))

    @property
    def error(self) -> np.ndarray:
        """(T, 15) rad: what the coupling cannot follow, q - q_target."""
        return self.q - self.q_target

    @property
    def max_error(self) -> np.ndarray:
        return np.abs(self.error).max(axis=1)


def load_params(path=None, side: str | None = None):
    """The parameters of ``path`` (default: params/phantom.toml) with the calibration layer's
    effect library, as ``phantom_cad.load_params`` reads them; ``side`` overrides ``hand.side`` (the
    human hand's: a left hand retargets onto the mirrored hand)."""
    import copy

    from .calibration.pipeline import PARAMS_EFFECTS
    from .params import ParamError
    from .params.io import DEFAULT_PARAMS, load_document
    from .params.schema import parse

    path = Path(path) if path is not None else DEFAULT_PARAMS
    document = load_document(path)
    if side is not None:
        document = copy.deepcopy(document)
        if not isinstance(document.get("hand"), dict):
            raise ParamError("hand", document.get("hand"), "must be a table", str(path))
        document["hand"]["side"] = side
    return parse(document, source=str(path), effects=PARAMS_EFFECTS)


def write_commands(path, result: Retargeted, times=None, comment: str = "") -> None:
    """U.csv, atomically: per frame (``frame``, ``t`` when the keypoints had times) the servo
    commands u1..u6 (deg), the largest joint error the coupling leaves and each joint's (deg)."""
    from .calibration.data import write_table
    from .kinematics.topology import JOINTS, U_COLUMNS
    from .units import deg

    cols = {"frame": np.arange(len(result.u))}
    if times is not None:
        cols["t"] = np.asarray(times, float)
    cols.update({c: result.u[:, i] for i, c in enumerate(U_COLUMNS)})
    cols["max_error_deg"] = deg(result.max_error)
    cols.update({f"{j.name}_error_deg": deg(result.error[:, j.index]) for j in JOINTS})
    write_table(path, cols, comments=[comment] if comment else (), degrees=True)


def read_keypoints(path) -> tuple[np.ndarray, np.ndarray | None]:
    """(keypoints (T, 21, 3), times (T,) or None) of a ``.npy`` file of shape (T, 21, 3) or a CSV of
    63 columns (x, y, z of keypoint 0, then 1, ...) or 64 (a time first); a first line that is not
    numbers is a header. Any problem: one :class:`UserError`."""
    path = Path(path)
    if not path.exists():
        raise UserError(f"{path}: no such file")
    if not path.is_file():
        raise UserError(f"{path}: not a file")
    n = RC.KEYPOINTS
    times = None
    if path.suffix.lower() == ".npy":
        try:
            data = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise UserError(f"{path}: not a NumPy .npy file ({one_line(exc)})") from None
        if data.ndim != 3 or data.shape[1:] != (n, 3) or not len(data) or data.dtype.kind not in "fiu":
            raise UserError(f"{path}: keypoints of shape {data.shape}, expected (frames, {n}, 3) numbers")
        points = np.asarray(data, float)
    else:
        rows, first = _csv_rows(path)
        width = {len(r) for r in rows}
        if len(width) != 1 or width.pop() not in (3 * n, 3 * n + 1):
            widths = sorted({len(r) for r in rows})
            raise UserError(f"{path}: rows of {', '.join(map(str, widths))} columns, expected {3 * n} "
                            f"(x, y, z of the {n} keypoints) or {3 * n + 1} (a time first)")
        try:
            table = np.array([[float(v) if v.strip() else math.nan for v in r] for r in rows])
        except ValueError as exc:
            raise UserError(f"{path}: {one_line(exc)} (from line {first})") from None
        if table.shape[1] == 3 * n + 1:
            times, table = table[:, 0], table[:, 1:]
        points = table.reshape(len(table), n, 3)
    bad = np.flatnonzero(~np.isfinite(points).all(axis=(1, 2)))
    if len(bad):
        frames = ", ".join(map(str, bad[:5])) + (", ..." if len(bad) > 5 else "")
        raise UserError(f"{path}: {len(bad)} of {len(points)} frames have NaN or infinite keypoints "
                        f"(frames {frames}, counted from 0)")
    if times is not None and not np.isfinite(times).all():
        raise UserError(f"{path}: a time that is not a number")
    return points, times


def _csv_rows(path: Path) -> tuple[list[list[str]], int]:
    import csv

    try:
        with open(path, newline="", encoding="utf-8") as fh:
            lines = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
    except (UnicodeDecodeError, csv.Error) as exc:
        raise UserError(f"{path}: not a CSV text file ({one_line(exc)})") from None
    first = 1
    if lines:
        try:
            [float(v) for v in lines[0] if v.strip()]
        except ValueError:
            lines, first = lines[1:], 2      # a header
    if not lines:
        raise UserError(f"{path}: no keypoint rows")
    return lines, first


def operator_frame(points: np.ndarray, side: str) -> np.ndarray:
    """Keypoints (T, 21, 3) in dex-retargeting's operator frame, as its MediaPipe detector puts
    them: the wrist at the origin; x from the middle MCP to the wrist and y the normal of the plane
    of the wrist, index MCP and middle MCP, signed so that x cross y points toward the index; then
    OPERATOR2MANO of ``side``."""
    from dex_retargeting.constants import OPERATOR2MANO, HandType

    p = points - points[:, RC.WRIST:RC.WRIST + 1]
    w, i, m = (p[:, k] for k in FRAME_KEYPOINTS)
    flat = np.flatnonzero(np.linalg.norm(np.cross(i - w, m - w), axis=1) < DEGENERATE ** 2)
    if len(flat):
        raise UserError(f"frame {int(flat[0])}: the wrist, index MCP and middle MCP keypoints lie on a line "
                        "(no palm plane)")
    tri = np.stack([w, i, m], axis=1)
    normal = np.linalg.svd(tri - tri.mean(axis=1, keepdims=True))[2][:, 2]
    x = w - m
    x = x - np.sum(x * normal, axis=1, keepdims=True) * normal
    length = np.linalg.norm(x, axis=1)
    x = x / length[:, None]
    z = np.cross(x, normal)
    flip = np.sum(z * (i - m), axis=1) < 0
    normal[flip] *= -1.0
    z[flip] *= -1.0
    wrist = np.stack([x, normal, z], axis=2)            # columns: the wrist frame's axes
    return p @ wrist @ OPERATOR2MANO[HandType[side]]


def root_frame(points: np.ndarray, side: str, origin: int) -> np.ndarray:
    """Keypoints (T, 21, 3) in the hand's root frame: the operator frame's, turned by
    ``ROOT_FROM_OPERATOR`` and moved so that keypoint ``origin`` (the index MCP) is at the origin."""
    p = operator_frame(points, side) @ RC.ROOT_FROM_OPERATOR.T
    return p - p[:, origin:origin + 1]


def _build(config, folder: str):
    """``config.build()`` with its scratch files inside ``folder``: dex-retargeting writes its copy
    of the URDF to a ``tempfile.mkdtemp`` it never removes, one folder per call."""
    saved = tempfile.tempdir
    tempfile.tempdir = folder
    try:
        return config.build()
    finally:
        tempfile.tempdir = saved


def retarget(hand, points: np.ndarray, method: str = "vector") -> Retargeted:
    """Retarget keypoints (T, 21, 3) onto ``hand`` (the kinematic model, ``phantom_cad.make_hand``;
    its side: the human hand's) with ``method`` ("vector" or "position"), each frame warm-started
    from the last, unfiltered."""
    from .cad.assembly import tip_frames
    from .export.robot import kinematic_model
    from .export.urdf import urdf_bytes
    from .postures import command

    if method not in RC.METHODS:
        raise UserError(f"unknown retargeting method {method!r} (known: {', '.join(RC.METHODS)})")
    try:
        from dex_retargeting.retargeting_config import RetargetingConfig
    except ImportError as exc:
        raise UserError(f"retarget needs dex-retargeting and torch ({one_line(exc)}; pip install "
                        "dex-retargeting==0.5.0 torch)") from None
    params = hand.params
    model = kinematic_model(params, tip_frames(params))
    p = root_frame(np.asarray(points, float), params.side, RC.origin_keypoint(model))
    palm = np.median(np.linalg.norm(p[:, FRAME_KEYPOINTS[2]] - p[:, RC.WRIST], axis=1))
    if not PALM_LENGTH[0] <= palm <= PALM_LENGTH[1]:
        raise UserError(f"keypoints: the wrist to the middle MCP is {palm:.4g} (median of the frames): keypoints "
                        f"are in metres, where it is {PALM_LENGTH[0]:g}-{PALM_LENGTH[1]:g}")
    with tempfile.TemporaryDirectory(prefix="phantom-retarget-") as tmp:
        urdf = Path(tmp) / f"{model.name}.urdf"
        urdf.write_bytes(urdf_bytes(model, None, f"{model.name} hand ({model.side}), kinematics only"))
        doc = RC.config(model, method, str(urdf))
        table = dict(doc["retargeting"], low_pass_alpha=1.0)   # each frame's own result, unfiltered
        retargeting = _build(RetargetingConfig.from_dict(table), tmp)
    indices = np.asarray(retargeting.optimizer.target_link_human_indices)
    names = list(retargeting.joint_names)
    order = [names.index(n) for n in JOINT_NAMES]
    q_target = np.empty((len(p), N_JOINTS))
    for t, frame in enumerate(p):
        ref = frame[indices] if method == "position" else frame[indices[1]] - frame[indices[0]]
        q_target[t] = np.asarray(retargeting.retarget(ref), float)[order]
    _, u = command(hand, q_target)
    return Retargeted(method, params.side, q_target, u, hand.forward(u, compensated=True))
