"""A small stand-in for phantom_cad.cad.assembly, used by the export tests that need parts
with known geometry or deliberately broken parts.

Three parts sized from the parameters: a palm plate with a through hole, an index
proximal phalanx (filleted bar), a servo pulley (cylinder). Same assembly interface as
phantom_cad.cad.assembly (part_names, part_inputs, build_part, pose_transforms,
designed_contacts, bill_of_materials; see phantom_cad.export.interface), without the
optional verify_part. Known volumes are computed here from textbook formulas.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MM = 1000.0
#: set by tests to make a part fail: {"part": name, "kind": "param" | "crash" | "two_solids"}
FAULT: dict = {}
#: set by tests to push the pulley into the palm
OVERLAP: dict = {}


@dataclass(frozen=True)
class Built:
    name: str
    shape: object
    T_hand_link: np.ndarray
    color: tuple
    print_rotation: np.ndarray
    digit: str | None


def part_names(params):
    return ["palm", "index_proximal", "servo_pulley_2"]


def dims(params):
    """The stand-in dimensions (mm)."""
    f = params.fingers["index"]
    return {
        "palm": (4 * params.palm.finger_pitch * MM, 0.4 * params.hand_length * MM, params.palm.thickness * MM),
        "hole_r": params.hardware.axle_diameter * MM,
        "index_proximal": (f.width * MM, f.thickness * MM, f.proximal * MM),
        "pulley_r": f.chain.servo_radius * MM,
        "pulley_h": params.hardware.bearing_width * MM,
    }


def known_volume(params, name):
    d = dims(params)
    if name == "palm":
        a, b, c = d["palm"]
        return a * b * c - math.pi * d["hole_r"] ** 2 * c
    if name == "index_proximal":
        a, b, c = d["index_proximal"]
        return a * b * c
    return math.pi * d["pulley_r"] ** 2 * d["pulley_h"]


def part_inputs(params, name):
    doc = params.document
    if name == "palm":
        return {"palm": doc["palm"], "hand_length_mm": doc["hand"]["hand_length_mm"],
                "axle": doc["hardware"]["axle_diameter_mm"]}
    if name == "index_proximal":
        return {"finger": doc["fingers"]["index"], "hand_length_mm": doc["hand"]["hand_length_mm"]}
    return {"finger": doc["fingers"]["index"], "hardware": doc["hardware"]}


def build_part(params, name):
    from build123d import Box, Cylinder, Pos

    from phantom_cad.params import ParamError

    if FAULT.get("part") == name:
        if FAULT["kind"] == "param":
            raise ParamError("fingers.index.width_mm", 18.0, "too narrow for the stand-in bearing")
        if FAULT["kind"] == "crash":
            raise RuntimeError("BRep_API: command not done")
    d = dims(params)
    R = np.eye(3)
    if name == "palm":
        a, b, c = d["palm"]
        shape = Box(a, b, c) - Cylinder(d["hole_r"], 2 * c)
        color, digit = (0.8, 0.8, 0.85), None
    elif name == "index_proximal":
        a, b, c = d["index_proximal"]
        shape = Box(a, b, c)
        if FAULT.get("part") == name and FAULT["kind"] == "two_solids":
            shape = shape + Pos(3 * a, 0, 0) * Box(a, b, c)
        color, digit = (0.9, 0.5, 0.2), "index"
        # print lying on its side: rotate +90 deg about x
        R = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float)
    else:
        shape = Cylinder(d["pulley_r"], d["pulley_h"])
        color, digit = (0.2, 0.4, 0.9), None
    return Built(name, shape, _T(params, name), color, R, digit)


def designed_contacts(params):
    return [("palm", "index_proximal", "magnetic finger mount (stand-in)")]


def bill_of_materials(params):
    return [
        {"item": "bearing", "spec": f"{params.hardware.bearing_bore * MM:g}x{params.hardware.bearing_outer * MM:g}",
         "quantity": 2, "used_in": "index_proximal"},
        {"item": "servo", "spec": "stand-in", "quantity": 1, "used_in": "palm"},
    ]


def pose_transforms(params, q=None):
    return {n: _T(params, n) for n in part_names(params)}


def _T(params, name):
    d = dims(params)
    T = np.eye(4)
    if name == "index_proximal":
        c = d["index_proximal"][2]
        T[:3, 3] = (0, d["palm"][1] / 2 + c / 2 + 2, 0)
        T[:3, :3] = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float).T
    elif name == "servo_pulley_2":
        T[:3, 3] = (0, 0, d["palm"][2] / 2 + d["pulley_h"] / 2 + 1 - OVERLAP.get("depth", 0.0))
    return T

