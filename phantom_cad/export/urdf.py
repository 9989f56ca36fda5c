"""URDF from the format-neutral robot model (``export.robot``), written with an XML library.

Deterministic: elements in topology order, numbers with 10 significant digits (no ``-0``),
attributes in a fixed order. ``mesh_uri(kind, stem)`` chooses where the meshes are found:
``package://<pkg>/meshes/...`` for ROS, or a path relative to the URDF for yourdfpy, PyBullet,
MuJoCo and Pinocchio.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Callable

import numpy as np

from .robot import RobotJoint, RobotLink, RobotModel


def num(x: float) -> str:
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"not a finite number: {x}")
    s = f"{x:.10g}"
    return "0" if s in ("-0", "0") else s


def nums(v) -> str:
    return " ".join(num(x) for x in v)


def rpy(R: np.ndarray) -> tuple[float, float, float]:
    """URDF roll, pitch, yaw (fixed axes x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll)) of a rotation."""
    R = np.asarray(R, float)
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if abs(math.cos(pitch)) > 1e-9:
        roll = math.atan2(R[2, 1], R[2, 2])
        yaw = math.atan2(R[1, 0], R[0, 0])
    else:                         # gimbal lock: put the whole turn in roll
        yaw = 0.0
        roll = math.atan2(-R[1, 2], R[1, 1])
    return roll, pitch, yaw


def _origin(parent: ET.Element, T: np.ndarray) -> None:
    T = np.asarray(T, float)
    ET.SubElement(parent, "origin", {"xyz": nums(T[:3, 3]), "rpy": nums(rpy(T[:3, :3]))})


def _link(ln: RobotLink, mesh_uri: Callable[[str, str], str]) -> ET.Element:
    e = ET.Element("link", {"name": ln.name})
    if ln.inertial is not None:
        i = ln.inertial
        ine = ET.SubElement(e, "inertial")
        ET.SubElement(ine, "origin", {"xyz": nums(i.com), "rpy": "0 0 0"})
        ET.SubElement(ine, "mass", {"value": num(i.mass)})
        ET.SubElement(ine, "inertia", dict(zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
                                               (num(v) for v in i.inertia))))
    if ln.mesh is not None:
        shapes = [("visual", f"{ln.name}_visual", ln.mesh)]
        shapes += [("collision", f"{stem}_collision", stem) for stem in ln.collision]
        for kind, name, stem in shapes:
            g = ET.SubElement(e, kind, {"name": name})
            ET.SubElement(g, "origin", {"xyz": "0 0 0", "rpy": "0 0 0"})
            geo = ET.SubElement(g, "geometry")
            ET.SubElement(geo, "mesh", {"filename": mesh_uri(kind, stem)})
            if kind == "visual":
                mat = ET.SubElement(g, "material", {"name": f"{ln.name}_color"})
                ET.SubElement(mat, "color", {"rgba": nums((*ln.color, 1.0))})
    return e


def _joint(j: RobotJoint) -> ET.Element:
    e = ET.Element("joint", {"name": j.name, "type": j.type})
    ET.SubElement(e, "parent", {"link": j.parent})
    ET.SubElement(e, "child", {"link": j.child})
    _origin(e, j.origin)
    if j.type != "fixed":
        ET.SubElement(e, "axis", {"xyz": nums(j.axis)})
        ET.SubElement(e, "limit", {"lower": num(j.lower), "upper": num(j.upper),
                                   "effort": num(j.effort), "velocity": num(j.velocity)})
        if j.mimic is not None:
            ET.SubElement(e, "mimic", {"joint": j.mimic.joint, "multiplier": num(j.mimic.multiplier),
                                       "offset": num(j.mimic.offset)})
    return e


def urdf_bytes(model: RobotModel, mesh_uri: Callable[[str, str], str], comment: str = "") -> bytes:
    """The URDF document of ``model``; ``mesh_uri(kind, stem)`` with kind "visual" or "collision"."""
    root = ET.Element("robot", {"name": model.name})
    if comment:
        root.append(ET.Comment(f" {comment} "))
    # MuJoCo's URDF import: keep the mesh paths, the fixed links (servo pulleys, tip frames) and
    # the visual geoms; other URDF readers ignore the element
    mj = ET.SubElement(root, "mujoco")
    ET.SubElement(mj, "compiler", {"strippath": "false", "fusestatic": "false", "discardvisual": "false"})
    for ln in model.links:
        root.append(_link(ln, mesh_uri))
    for j in model.joints:
        root.append(_joint(j))
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"
