"""The printable parts of one hand, placed: the interface the export pipeline codes against.

An *assembly interface* is a module with these functions (``phantom_cad.export.interface``
names the module the pipeline uses; its tests install a stand-in with the same functions):

* ``part_names(params) -> list[str]``: unique, file-name safe, in build order;
* ``part_inputs(params, name) -> dict``: the plain values the part depends on (its cache key);
* ``build_part(params, name) -> Built``: the solid and what the exports need to know of it
  (optionally the convex solids of its collision shape);
* ``pose_transforms(params, q=None) -> {name: 4x4}``: T_hand_link (mm) at joint angles q;
* ``designed_contacts(params) -> [(a, b, why)]``: pairs that touch by design;
* ``bill_of_materials(params) -> [row]``: rows with item, spec, quantity, used_in;
* optionally ``verify_part(params, name, shape) -> [problem]``: measured verification;
* optionally ``tip_frames(params) -> {frame: (link, T_link_frame)}`` (metres): the fingertip pad
  frames of the robot description (an interface without it gets no description).

Everything but ``build_part`` is numpy only; ``build_part`` imports build123d (lazily,
through the part families). Units: millimetres. Each part is modelled in its own link frame
(docs/frames.md); ``T_hand_link`` places it in the palm frame at the rest pose. The parts
come from :mod:`phantom_cad.cad.registry`, one per topology link.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..kinematics import frames as F
from ..kinematics import link_frames as LF
from ..kinematics.hand_params import HandParams
from ..kinematics.topology import CMC_PULLEY, CMC_Q, DIGITS, JOINTS, LINKS, N_JOINTS, digit_links
from . import registry, verify
from .materials import bill_of_materials  # noqa: F401  (part of the interface)


@dataclass(frozen=True)
class Built:
    name: str                    # unique, file-name safe
    shape: Any                   # build123d.Solid: ONE valid solid, in its link frame, mm
    T_hand_link: np.ndarray      # 4x4, mm: the link frame in the hand (palm) frame at rest
    color: tuple[float, float, float]
    print_rotation: np.ndarray   # 3x3: lays the part on its best face for printing (z up)
    digit: str | None
    #: convex solids (link frame, mm) whose union is the collision shape; empty: the shape's hull
    collision: tuple = ()
    #: ``tendons.Blocker`` meshes (link frame, mm) where a slicer must not put support
    #: (``Part.support_blockers``)
    blockers: tuple = ()


#: the left hand's mirror (x -> -x)
MIRROR = np.array([-1.0, 1.0, 1.0])


def part_names(params: HandParams) -> list[str]:
    return list(registry.PART_NAMES)


def part_inputs(params: HandParams, name: str) -> dict:
    """The plain parameter values ``name`` depends on (a superset, never a subset)."""
    return registry.part(params, name).inputs()


def part_object(params: HandParams, name: str):
    """The part's dimension object (mm properties; ``.build()`` makes the right-hand solid)."""
    return registry.part(params, name)


def pose_transforms(params: HandParams, q=None) -> dict[str, np.ndarray]:
    """T_hand_link (mm) of every part at joint angles q (15,), None = rest."""
    if q is not None:
        q = np.asarray(q, float)
        if q.shape != (N_JOINTS,):
            raise ValueError(f"q must have shape ({N_JOINTS},), got {q.shape}")
    links = LF.link_transforms(params, q)
    return {n: F.to_mm(links[n]) for n in part_names(params)}


def tip_frames(params: HandParams) -> dict[str, tuple[str, np.ndarray]]:
    """``<digit>_tip`` -> (its distal link, T_link_tip in metres): the centre of each fingertip pad,
    z along the pad normal (what retargeting and grasp tools look for); mirrored for a left hand."""
    out = {}
    for d in DIGITS:
        distal = digit_links(d)[-1]
        T = registry.part(params, distal.name).pad()
        T = F.mirror(F.from_mm(T)) if params.side == "left" else F.from_mm(T)
        out[f"{d}_tip"] = (distal.name, T)
    return out


def build_part(params: HandParams, name: str, shape=None) -> Built:
    """The part ``name`` of this hand, built; or, given ``shape`` (its solid for this side, built
    before: the export's part cache keeps it as BREP), everything else about it made around that
    solid (the convex collision solids and the support blockers are small)."""
    import build123d as bd

    part = registry.part(params, name)
    if shape is None:
        shape = part.build()
        if params.side == "left":
            shape = shape.mirror(bd.Plane.YZ)
    collision = tuple(part.collision_solids())
    blockers = tuple(part.support_blockers())
    if params.side == "left":
        collision = tuple(s.mirror(bd.Plane.YZ) for s in collision)
        # the mirror x -> -x, its faces turned back outward
        blockers = tuple(replace(b, vertices=b.vertices * MIRROR, faces=b.faces[:, ::-1].copy(),
                                 flat=None if b.flat is None else tuple(np.multiply(b.flat, MIRROR)))
                         for b in blockers)
    return Built(name=name, shape=shape, T_hand_link=pose_transforms(params)[name], color=part.color,
                 print_rotation=part.print_rotation, digit=part.digit, collision=collision, blockers=blockers)


def verify_part(params: HandParams, name: str, shape) -> list[str]:
    """Problems of a built part (``phantom_cad.cad.verify.verify_part``)."""
    return verify.verify_part(params, name, shape)


def designed_contacts(params: HandParams) -> list[tuple[str, str, str]]:
    """Pairs of parts that touch at rest by design: every finger base on its palm socket, every
    tendon-driven joint's tongue heel on its extension stop, the CMC pulley on the CMC base's
    column."""
    out = []
    for ln in LINKS:
        if ln.segment == "base" and ln.parent_joint is None:
            out.append((ln.name, ln.parent, "magnet face seated on its palm socket"))
        for j in JOINTS:
            if j.parent == ln.name and j.index != CMC_Q:
                out.append((j.parent, j.child, f"{j.key.upper()} joint: tongue heel on the extension stop"))
    out.append((JOINTS[CMC_Q].child, CMC_PULLEY, "CMC pulley on the CMC base's keyed column (the flats touch)"))
    return out
