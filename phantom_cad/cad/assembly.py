"""The printable parts of one hand, placed: the interface the export pipeline codes against.

``part_names``, ``part_inputs``, ``designed_contacts``, ``bill_of_materials`` and
``pose_transforms`` are numpy only; ``build_part`` imports build123d (lazily, through the
part modules). Units: millimetres. Each part is modelled in its own link frame
(docs/frames.md); ``T_hand_link`` places it in the palm frame at the rest pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..kinematics import frames as F
from ..kinematics.topology import FINGERS, N_JOINTS, N_SERVOS

FINGER_SEGMENTS = ("base", "proximal", "middle", "distal")
THUMB_PARTS = ("thumb_cmc_base", "thumb_proximal", "thumb_distal")

#: display colours (RGB 0..1): one per digit, palm and pulleys neutral
COLORS = {
    "palm": (0.55, 0.57, 0.60),
    "thumb": (0.90, 0.55, 0.25),
    "index": (0.25, 0.55, 0.85),
    "middle": (0.30, 0.70, 0.45),
    "ring": (0.80, 0.35, 0.40),
    "pinky": (0.60, 0.45, 0.80),
    "pulley": (0.20, 0.20, 0.22),
}


@dataclass(frozen=True)
class Built:
    name: str                    # unique, file-name safe
    shape: Any                   # build123d.Solid: ONE valid solid, in its link frame, mm
    T_hand_link: np.ndarray      # 4x4, mm: the link frame in the hand (palm) frame at rest
    color: tuple[float, float, float]
    print_rotation: np.ndarray   # 3x3: lays the part on its best face for printing (z up)
    digit: str | None


def part_names(params) -> list[str]:
    names = ["palm"]
    for f in FINGERS:
        names += [f"{f}_{s}" for s in FINGER_SEGMENTS]
    names += list(THUMB_PARTS)
    names += [f"servo_pulley_{k}" for k in range(1, N_SERVOS + 1)]
    return names


def _digit(name: str) -> str | None:
    head = name.split("_")[0]
    return head if head in FINGERS or head == "thumb" else None


def _check_name(params, name: str) -> None:
    if name not in part_names(params):
        raise KeyError(f"unknown part {name!r} (known: {', '.join(part_names(params))})")


def _plain(x):
    from ..params.schema import _plain as plain
    return plain(x)


def part_inputs(params, name: str) -> dict:
    """The plain parameter values ``name`` depends on (a superset, never a subset)."""
    _check_name(params, name)
    doc = params.document
    common = {
        "side": doc["hand"]["side"],
        "hand_length_mm": doc["hand"]["hand_length_mm"],
        "hardware": _plain(doc["hardware"]),
        "print": _plain(doc["print"]),
        "cad": _plain(doc["cad"]),
        "palm_wall_mm": doc["palm"]["wall_mm"],
    }
    if name == "palm":
        out = {k: _plain(v) for k, v in doc.items() if k not in ("mechanics", "effects", "hand")}
        out["side"] = common["side"]
        out["hand_length_mm"] = common["hand_length_mm"]
        return out
    if name.startswith("servo_pulley_"):
        k = int(name.rsplit("_", 1)[1])
        if k == 6:
            src = {"cmc_horn_radius_mm": doc["thumb"]["cmc_horn_radius_mm"]}
        elif k == 1:
            src = {"servo_pulley_radius_mm": doc["thumb"]["servo_pulley_radius_mm"]}
        else:
            src = {"servo_pulley_radius_mm": doc["fingers"][FINGERS[k - 2]]["servo_pulley_radius_mm"]}
        return {**common, "servo": k, **src}
    digit = _digit(name)
    if digit == "thumb":
        return {**common, "thumb": _plain(doc["thumb"])}
    out = {**common, "finger": _plain(doc["fingers"][digit])}
    if name.endswith("_base"):
        # the tendon height at the magnet face follows the thinnest finger
        out["thicknesses_mm"] = {f: doc["fingers"][f]["thickness_mm"] for f in FINGERS}
    return out


def pose_transforms(params, q=None) -> dict[str, np.ndarray]:
    """T_hand_link (mm) of every part at joint angles q (15,), None = rest."""
    if q is not None:
        q = np.asarray(q, float)
        if q.shape != (N_JOINTS,):
            raise ValueError(f"q must have shape ({N_JOINTS},), got {q.shape}")
    links = F.link_transforms(params, q)
    return {n: F.to_mm(links[n]) for n in part_names(params)}


def _print_rotation(name: str) -> np.ndarray:
    if name == "palm":
        return F.rot_x(math.pi)[:3, :3]            # on its dorsal face
    if name.startswith("servo_pulley_"):
        return np.eye(3)                           # on a flange face
    return F.rot_y(math.pi / 2.0)[:3, :3]          # digit links: on their flat +x side


def _make(params, name: str):
    from .parts.finger_base import FingerBase
    from .parts.palm import Palm
    from .parts.phalanx import Phalanx
    from .parts.pulley import ServoPulley
    from .parts.thumb import ThumbCMCBase

    if name == "palm":
        return Palm(params)
    if name.startswith("servo_pulley_"):
        return ServoPulley(params, int(name.rsplit("_", 1)[1]))
    if name == "thumb_cmc_base":
        return ThumbCMCBase(params)
    digit, segment = name.split("_", 1)
    if segment == "base":
        return FingerBase(params, digit)
    return Phalanx(params, digit, segment)


def part_object(params, name: str):
    """The part's dimension object (mm properties; ``.build()`` makes the right-hand solid)."""
    _check_name(params, name)
    return _make(params, name)


def build_part(params, name: str) -> Built:
    _check_name(params, name)
    shape = _make(params, name).build()
    if params.side == "left":
        import build123d as bd
        shape = shape.mirror(bd.Plane.YZ)
    digit = _digit(name)
    color = COLORS["palm" if name == "palm" else "pulley" if digit is None else digit]
    return Built(name=name, shape=shape, T_hand_link=pose_transforms(params)[name], color=color,
                 print_rotation=_print_rotation(name), digit=digit)


def designed_contacts(params) -> list[tuple[str, str, str]]:
    out = []
    for f in FINGERS:
        out.append((f"{f}_base", "palm", "magnet face seated on its palm socket"))
        out.append((f"{f}_base", f"{f}_proximal", "MCP joint: tongue heel on the extension stop"))
        out.append((f"{f}_proximal", f"{f}_middle", "PIP joint: tongue heel on the extension stop"))
        out.append((f"{f}_middle", f"{f}_distal", "DIP joint: tongue heel on the extension stop"))
    out.append(("thumb_cmc_base", "thumb_proximal", "MP joint: tongue heel on the extension stop"))
    out.append(("thumb_proximal", "thumb_distal", "IP joint: tongue heel on the extension stop"))
    out.append(("thumb_cmc_base", "servo_pulley_6", "CMC base screwed onto the servo-6 hub"))
    return out


def _tendon_lengths(params) -> dict[str, float]:
    """Cut length (mm) of each tendon: servo pulley tangent -> palm -> finger base -> guides ->
    along the phalanges to the distal anchor, plus the length wound on the servo pulley over
    its full travel."""
    out = {}
    mm = 1000.0
    for k, f in enumerate(FINGERS):
        fp = params.fingers[f]
        chain = fp.chain
        exit_ = F.socket_tendon_point(params, f)
        Ts = F.T_palm_servo(params, k + 1)
        tangent = (Ts @ np.array([-chain.servo_radius, 0, 0, 1.0]))[:3]
        palm = np.linalg.norm(exit_ - tangent)
        base = params.cad.finger_base_length
        run = palm + base + chain.guide.L0 + fp.proximal + fp.middle + fp.distal / 2.0
        wrap = chain.servo_radius * chain.travel[1]
        out[f] = (run + wrap) * mm
    th = params.thumb
    from .parts.palm import Palm   # numpy only until build()
    palm = Palm(params)
    path = palm.thumb_tendon_path()             # mm: servo 1 -> palm exit -> post -> arch -> CMC axis
    run = sum(float(np.linalg.norm(b - a)) for a, b in zip(path, path[1:])) / mm
    run += palm.cmc_arch()["z_lo"] / mm         # down the CMC axis to the CMC base's mid-plane
    run += th.metacarpal + th.chain.guide.L0 + th.proximal + th.distal / 2.0
    out["thumb"] = (run + th.chain.servo_radius * th.chain.travel[1]) * mm
    return out


def _spring_lengths(params) -> dict[str, float]:
    """Free length (mm) of each dorsal cable spring, anchor to anchor at full extension."""
    out = {}
    for f in FINGERS:
        fp = params.fingers[f]
        out[f] = (params.cad.finger_base_length + fp.proximal + fp.middle + fp.distal / 2.0) * 1000.0
    th = params.thumb
    out["thumb"] = (th.metacarpal + th.proximal + th.distal / 2.0) * 1000.0
    return out


def bill_of_materials(params) -> list[dict]:
    hw = params.hardware
    mm = 1000.0
    g = lambda v: f"{v * mm:g}"  # noqa: E731
    n_joints = {f: 3 for f in FINGERS}
    n_joints["thumb"] = 2
    bom = [{
        "item": "bearing",
        "spec": f"{g(hw.bearing_bore)} x {g(hw.bearing_outer)} x {g(hw.bearing_width)} mm (683ZZ class)",
        "quantity": 2 * sum(n_joints.values()),
        "used_in": "two per joint, in the child link's tongue: " + ", ".join(
            f"{d} x{n}" for d, n in n_joints.items()),
    }]
    for d in ("thumb",) + FINGERS:
        width = (params.thumb.width if d == "thumb" else params.fingers[d].width) * mm
        bom.append({"item": "axle", "spec": f"{g(hw.axle_diameter)} mm steel pin, {width:g} mm long",
                    "quantity": n_joints[d], "used_in": f"{d} joints (pressed into the clevis cheeks)"})
    bom.append({"item": "magnet", "spec": f"disc {g(hw.magnet_diameter)} x {g(hw.magnet_thickness)} mm (N52)",
                "quantity": 4 * len(FINGERS),
                "used_in": "two per finger base and two per palm socket"})
    from .parts.common import Tolerances   # numpy only
    engage = Tolerances(params).screw_engagement / 1000.0
    bom.append({"item": "screw",
                "spec": f"M{g(hw.screw_diameter)} self-tapping, {g(engage)} mm thread engagement + servo flange",
                "quantity": 2 * N_SERVOS, "used_in": "servo flanges into the palm's pilot holes"})
    bom.append({"item": "screw", "spec": f"M{g(hw.screw_diameter)} horn screw (servo accessory)",
                "quantity": 2 * N_SERVOS, "used_in": "servo pulleys 1-6 to their horns"})
    cmc = params.thumb.thickness + params.print.hole_clearance + engage
    bom.append({"item": "screw", "spec": f"M{g(hw.screw_diameter)} x {cmc * 1000.0:.0f} self-tapping",
                "quantity": 2, "used_in": "thumb_cmc_base through its hub into servo_pulley_6"})
    for d, L in _tendon_lengths(params).items():
        bom.append({"item": "tendon", "spec": f"{g(hw.tendon_diameter)} mm braided UHMWPE, {L:.0f} mm",
                    "quantity": 1, "used_in": f"{d}: servo pulley to distal anchor"})
    for d, L in _spring_lengths(params).items():
        bom.append({"item": "cable spring",
                    "spec": f"{g(params.cad.spring_diameter)} mm elastic cord, {L:.0f} mm free length",
                    "quantity": 2, "used_in": f"{d}: dorsal return path, base anchor to distal anchor"})
    sv = params.servo
    bom.append({"item": "servo",
                "spec": "micro servo, body " + " x ".join(g(v) for v in sv.body) + " mm (SCS0009 class)",
                "quantity": N_SERVOS, "used_in": "palm: u1 thumb flexion, u2-u5 fingers, u6 thumb CMC"})
    return bom
