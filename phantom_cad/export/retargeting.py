"""The description package's retargeting configurations: ``config/retargeting/`` holds
`dex-retargeting <https://pypi.org/project/dex-retargeting/>`_ configs that map 21 human hand
keypoints (MediaPipe's order) onto the hand's 15 joints, for the package's side::

    <hand>_<side>_vector.yml    teleoperation: the vectors from the index MCP to each digit's
                                second joint and fingertip (type vector)
    <hand>_<side>_position.yml  offline: every digit joint and fingertip at its keypoint (type
                                position; the palm fixed, the keypoints put in its frame)

Each is dex-retargeting's ``retargeting:`` table (``urdf_path`` relative to the package folder:
``RetargetingConfig.set_default_urdf_dir(<package>)``) and a ``frame:`` table that dex-retargeting
does not read: how keypoints in its operator frame (its MediaPipe detector's wrist frame, the MANO
convention) are put into the hand's root frame before retargeting. Every link comes from the
topology and the fingertip frames; docs/retargeting.md.

The joints retarget independently (``ignore_mimic_joint``): the hand's coupling is the routed
tendons', which the URDF's linear ``<mimic>`` only approximates; ``phantom-cad retarget`` projects the
15 angles through the coupling and the control law onto the six servos (:mod:`phantom_cad.retargeting`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..kinematics.topology import DIGITS, FINGERS, LINKS, digit_links
from .robot import RobotModel

#: the package folder of the configs
FOLDER = "config/retargeting"
METHODS = ("vector", "position")
#: MediaPipe's 21 hand landmarks: the wrist, then four a digit in the topology's digit order (thumb
#: CMC, MCP, IP, tip; a finger's MCP, PIP, DIP, tip)
KEYPOINTS = 21
WRIST = 0
PER_DIGIT = 4
#: the root link's frame (the palm's: x ulnar for a right hand, y distal, z dorsal; docs/frames.md)
#: from dex-retargeting's operator frame (x palmar, y radial for a right hand and ulnar for a left,
#: z distal: its detector's wrist frame times OPERATOR2MANO): p_root = ROOT_FROM_OPERATOR p_operator.
#: The same for both sides, as the left hand's palm frame is the mirror image of the right's.
ROOT_FROM_OPERATOR = np.array([[0.0, -1.0, 0.0],
                               [0.0, 0.0, 1.0],
                               [-1.0, 0.0, 0.0]])
#: what each method retargets: per digit, the indices (0 its first joint's child link .. 3 its tip)
#: of the points it matches
POINTS = {"vector": (1, 3), "position": (0, 1, 2, 3)}
#: dex-retargeting's low-pass filter of each method (1: none), as its own configs of other hands
LOW_PASS = {"vector": 0.2, "position": 1.0}
#: its regularisation toward the last frame's joints and its Huber loss's quadratic zone (m): a
#: tenth of its defaults (4e-3, 2e-2), made for hands 1.2-1.6 times a human's, with which the
#: human-sized hand's distal joints stay near the last frame's angles (docs/retargeting.md)
NORMAL_DELTA = 4e-4
HUBER_DELTA = 2e-3


def digit_keypoints(digit: str) -> tuple[int, ...]:
    """The MediaPipe keypoints of ``digit``, proximal first (its last the tip)."""
    start = WRIST + 1 + PER_DIGIT * DIGITS.index(digit)
    return tuple(range(start, start + PER_DIGIT))


def keypoint_links(model: RobotModel) -> dict[int, str]:
    """MediaPipe keypoint -> the link or fingertip frame whose origin is that point: per digit, the
    child links of its joints, proximal first (the thumb's CMC base, a finger's proximal phalanx on
    its MCP), then its fingertip frame."""
    tip_of = {j.parent: j.child for j in model.joints if j.type == "fixed" and j.child not in {ln.name for ln in LINKS}}
    out = {}
    for digit in DIGITS:
        links = [ln.name for ln in digit_links(digit) if ln.parent_joint is not None]
        points = [*links, tip_of[links[-1]]]
        if len(points) != PER_DIGIT:
            raise ValueError(f"{digit}: {len(points)} points, MediaPipe has {PER_DIGIT} a digit")
        out.update(zip(digit_keypoints(digit), points))
    return out


def origin_keypoint(model: RobotModel) -> int:
    """The keypoint at the root frame's origin: the index MCP (docs/frames.md), the origin of the
    index finger's first jointed link."""
    first = next(ln.name for ln in digit_links(FINGERS[0]) if ln.parent_joint is not None)
    return {name: k for k, name in keypoint_links(model).items()}[first]


def _points(model: RobotModel, method: str) -> list[tuple[int, str]]:
    """(keypoint, link) of what ``method`` matches: the POINTS of each digit, by point then digit."""
    links = keypoint_links(model)
    return sorted(((k, name) for k, name in links.items() if (k - WRIST - 1) % PER_DIGIT in POINTS[method]),
                  key=lambda kn: ((kn[0] - WRIST - 1) % PER_DIGIT, kn[0]))


def config(model: RobotModel, method: str, urdf_path: str) -> dict:
    """The config document of ``method`` ("vector" or "position") for ``model``'s URDF at
    ``urdf_path``: dex-retargeting's ``retargeting`` table and the ``frame`` table."""
    points = _points(model, method)
    origin = origin_keypoint(model)
    table = {"type": method, "urdf_path": urdf_path}
    if method == "vector":
        table.update({
            "target_origin_link_names": [keypoint_links(model)[origin]] * len(points),
            "target_task_link_names": [name for _, name in points],
            "target_link_human_indices": [[origin] * len(points), [k for k, _ in points]],
            "scaling_factor": 1.0,
        })
    elif method == "position":
        table.update({
            "target_link_names": [name for _, name in points],
            "target_link_human_indices": [k for k, _ in points],
        })
    else:
        raise ValueError(f"unknown retargeting method {method!r} (known: {', '.join(METHODS)})")
    table.update({"normal_delta": NORMAL_DELTA, "huber_delta": HUBER_DELTA, "ignore_mimic_joint": True,
                  "low_pass_alpha": LOW_PASS[method]})
    frame = {"keypoints": f"MediaPipe's {KEYPOINTS} hand landmarks, in dex-retargeting's operator frame",
             "root_link": next(ln.name for ln in LINKS if ln.parent is None),
             "root_from_operator": ROOT_FROM_OPERATOR.astype(int).tolist(),
             "origin_keypoint": origin}
    return {"retargeting": table, "frame": frame}


def config_yaml(doc: dict, model: RobotModel, method: str) -> str:
    import yaml

    head = (f"# dex-retargeting config ({method}) of the {model.name} hand ({model.side}), generated by "
            "phantom_cad; do not edit.\n"
            "# RetargetingConfig.set_default_urdf_dir(<this package>) before load_from_file; the frame table:\n"
            "# keypoints p (operator frame) -> root_from_operator (p - p[origin_keypoint]). docs/retargeting.md\n")
    return head + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=1 << 16)


def config_files(model: RobotModel) -> list[str]:
    """The configs of the package, relative to its folder."""
    return [f"{FOLDER}/{model.name}_{model.side}_{m}.yml" for m in METHODS]


def write_configs(folder: Path, model: RobotModel, urdf_path: str) -> None:
    """The configs into the package folder ``folder``; ``urdf_path`` relative to it."""
    (folder / FOLDER).mkdir(parents=True, exist_ok=True)
    for method, rel in zip(METHODS, config_files(model)):
        (folder / rel).write_text(config_yaml(config(model, method, urdf_path), model, method), encoding="utf-8")
