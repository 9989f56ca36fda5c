"""A human hand's 21 keypoints (MediaPipe's order) for the retargeting tests: a simple model of a
person's hand, independent of the robot hand's kinematics.

Segment lengths are fractions of the hand length (wrist crease to the middle fingertip) from
Buchholz B., Armstrong T.J., Goldstein S.A., "Anthropometric data for describing the kinematics of
the human hand", Ergonomics 35(3):261-273, 1992, Table 1; the metacarpals fan out from the carpus
(bases 8-10 mm apart, a few degrees between neighbours), the thumb's metacarpal leaves the carpus
radially at 40 degrees and swings palmar in opposition. Each finger flexes in its own plane; the
thumb's MCP and IP flex toward the ulnar-palmar side. Hand frame: origin at the wrist, x radial
(toward the thumb) for a right hand, y distal, z palmar; a left hand is its mirror image in x.
"""

from __future__ import annotations

import math

import numpy as np

#: Buchholz et al. 1992, Table 1: metacarpal, proximal, middle, distal (thumb: metacarpal,
#: proximal, distal) / hand length
LENGTHS = {"thumb": (0.251, 0.196, 0.158), "index": (0.374, 0.245, 0.143, 0.097),
           "middle": (0.373, 0.266, 0.170, 0.108), "ring": (0.336, 0.244, 0.165, 0.107),
           "pinky": (0.295, 0.204, 0.117, 0.093)}
#: where each finger's metacarpal leaves the carpus (x, mm at a 180 mm hand) and its angle (deg,
#: radial positive) from the middle finger's axis
CARPUS = {"index": (11.0, 6.0), "middle": (1.0, 0.0), "ring": (-8.0, -6.0), "pinky": (-16.0, -13.0)}
#: the thumb's CMC (x, y, z mm at a 180 mm hand) and its metacarpal's angle from distal (deg, radial)
THUMB_CMC = (14.0, 12.0, 6.0)
THUMB_ANGLE = 40.0
FINGERS = ("index", "middle", "ring", "pinky")


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def keypoints(pose: dict, length_mm: float = 180.0, side: str = "right") -> np.ndarray:
    """(21, 3) keypoints, metres, of a hand of ``length_mm`` in ``pose``: per finger
    (mcp, pip, dip) flexion in degrees, and "thumb": (opposition, mcp, ip) in degrees."""
    s = length_mm / 180.0
    L = length_mm * 1e-3
    out = np.zeros((21, 3))
    palmar = np.array([0.0, 0.0, 1.0])
    # the thumb: metacarpal from the CMC, swung palmar by the opposition angle
    opp, f_mcp, f_ip = (math.radians(a) for a in pose.get("thumb", (0.0, 0.0, 0.0)))
    a = math.radians(THUMB_ANGLE)
    rest = np.array([math.sin(a), math.cos(a), 0.0])
    meta = _unit(math.cos(opp) * rest + math.sin(opp) * palmar)
    # it flexes toward the ulnar-palmar side, turned with the opposition
    bend = np.array([-math.sin(opp), 0.0, math.cos(opp)]) + np.array([-0.3, 0.0, 0.0])
    bend = _unit(bend - (bend @ meta) * meta)
    cmc = np.array(THUMB_CMC) * s * 1e-3
    points = [cmc, cmc + LENGTHS["thumb"][0] * L * meta]
    angle = 0.0
    for seg, flex in zip(LENGTHS["thumb"][1:], (f_mcp, f_ip)):
        angle += flex
        d = math.cos(angle) * meta + math.sin(angle) * bend
        points.append(points[-1] + seg * L * d)
    out[1:5] = points
    for k, f in enumerate(FINGERS):
        x0, deg = CARPUS[f]
        c = math.radians(deg)
        axis = np.array([math.sin(c), math.cos(c), 0.0])
        base = np.array([x0 * s * 1e-3, 0.0, 0.0])
        mcp = base + LENGTHS[f][0] * L * axis
        points = [mcp]
        angle = 0.0
        for seg, flex in zip(LENGTHS[f][1:], pose.get(f, (0.0, 0.0, 0.0))):
            angle += math.radians(flex)
            points.append(points[-1] + seg * L * (math.cos(angle) * axis + math.sin(angle) * palmar))
        out[5 + 4 * k:9 + 4 * k] = points
    if side == "left":
        out[:, 0] *= -1.0
    return out


def gesture(name: str) -> dict:
    """Joint angles (deg) of a named gesture: open, fist, point (the index extended), pinch (the
    thumb's tip on the index tip: :func:`pinch`)."""
    curled = (80.0, 95.0, 55.0)
    if name == "open":
        return {f: (5.0, 5.0, 3.0) for f in FINGERS} | {"thumb": (5.0, 5.0, 5.0)}
    if name == "fist":
        return {f: curled for f in FINGERS} | {"thumb": (55.0, 45.0, 40.0)}
    if name == "point":
        return {f: curled for f in FINGERS[1:]} | {"index": (0.0, 0.0, 0.0), "thumb": (50.0, 40.0, 35.0)}
    if name == "pinch":
        return pinch()
    raise KeyError(name)


def pinch(length_mm: float = 180.0) -> dict:
    """The index flexed half way and the thumb's three angles that put its tip on the index tip."""
    from scipy.optimize import least_squares

    pose = {f: (30.0, 35.0, 20.0) for f in FINGERS[1:]} | {"index": (40.0, 45.0, 25.0)}

    def gap(x):
        p = keypoints(pose | {"thumb": tuple(x)}, length_mm)
        return p[4] - p[8]

    fit = least_squares(gap, x0=[40.0, 20.0, 20.0], bounds=([0, 0, 0], [80, 80, 80]))
    return pose | {"thumb": tuple(float(v) for v in fit.x)}


def sequence(names, frames_each: int = 3, noise_mm: float = 1.5, seed: int = 0, length_mm: float = 180.0,
             side: str = "right") -> tuple[np.ndarray, list[str]]:
    """(T, 21, 3) keypoints of the gestures ``names``, ``frames_each`` noisy frames each, the whole
    hand turned and moved by one random rigid motion (a camera's frame); and each frame's gesture."""
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    R = q * np.sign(np.linalg.det(q))
    shift = rng.normal(scale=0.3, size=3)
    frames, labels = [], []
    for name in names:
        clean = keypoints(gesture(name), length_mm, side)
        for _ in range(frames_each):
            frames.append((clean + rng.normal(scale=noise_mm * 1e-3, size=clean.shape)) @ R.T + shift)
            labels.append(name)
    return np.array(frames), labels
