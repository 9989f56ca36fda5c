"""The part protocol: what every printable part family declares.

One class per part family (bd_warehouse style): the constructor takes the validated
parameters and the family's own arguments and refuses impossible ones; the derived
dimensions are plain properties in mm (numpy only, testable without OCP); ``build()``
imports build123d lazily. A family declares:

* ``SEGMENTS``: the topology link segments it makes (``topology.Link.segment``), so the
  links, and the part names (a part is named after its link), come from the topology;
* ``for_link(params, link)``: the part of one of those links;
* ``link`` (the topology ``Link`` record), ``name``, ``digit``, ``color``, ``print_rotation``;
* ``build()``: the right-hand solid in its link frame (mm);
* optionally ``collision_solids()``: the convex solids whose union is its collision shape in the
  robot description (default: none, the hull of the built solid);
* optionally ``support_blockers()``: regions (``tendons.Blocker``, link frame) where a slicer must
  not put support, because every overhang in them bridges between close walls (the tendon
  grooves, pilots and channels); the export writes them into the part's PrusaSlicer project;
* ``inputs()``: the plain parameter values the solid depends on (a superset, never a
  subset): the part cache's key; ``tests/cad/test_part_contract.py`` checks that every
  parameter a part reads while it is made, measured and built is in it;
* ``verify(shape)``: what a built solid must measure (groove radius, guides, pockets...),
  as a list of problems; an empty list means the part is sound (default: none);
* ``pad()``: a fingertip's contact pad frame (the robot description's tip frames); only a family
  that makes a digit's last link has one, the others refuse.

:class:`Part` is an abstract base class: ``for_link``, ``build`` and ``inputs`` are abstract, so a
family that lacks one cannot be made (TypeError when the registry makes one of its parts).

The registry of families is :mod:`phantom_cad.cad.registry`: adding a part is one class here
and one entry there.
"""

from __future__ import annotations

import abc
import math

import numpy as np

from ... import canon
from ...kinematics import frames as F
from ...kinematics.hand_params import HandParams
from ...kinematics.topology import DIGITS, JOINTS, LINKS, Joint, Link, joint


#: display colours (RGB 0..1) of the digit links, one per digit in topology.DIGITS order
DIGIT_COLORS = dict(zip(DIGITS, (
    (0.90, 0.55, 0.25),
    (0.25, 0.55, 0.85),
    (0.30, 0.70, 0.45),
    (0.80, 0.35, 0.40),
    (0.60, 0.45, 0.80),
), strict=True))

#: a part lying on its flat +x side (the default)
SIDE_DOWN = F.rot_y(math.pi / 2.0)[:3, :3]
#: a phalanx on its dorsal face (+z of the link down): its joint axes lie flat, its clevis slots
#: and grooves stand in vertical planes
DORSAL_DOWN = F.rot_x(math.pi)[:3, :3]
#: on the palmar face (-z of the link down, the link's frame as it is): the thumb CMC base, its
#: MP axis flat and its column upright
PALMAR_DOWN = np.eye(3)
#: a finger base on its magnet face (-y of the link down)
MAGNET_DOWN = F.rot_x(math.pi / 2.0)[:3, :3]


def parent_joint(ln: Link) -> Joint | None:
    """The joint at a link's origin (None for a link fixed to its parent)."""
    return joint(ln.parent_joint) if ln.parent_joint else None


def child_joint(ln: Link) -> Joint | None:
    """The joint at a link's far end, to its digit's next link (None at a fingertip)."""
    return next((j for j in JOINTS if j.parent == ln.name and j.digit == ln.digit), None)


class Part(abc.ABC):
    """Base of the part families (see the module doc)."""

    #: topology link segments this family makes
    SEGMENTS: tuple[str, ...] = ()
    #: display colour; None = the digit's colour
    COLOR: tuple[float, float, float] | None = None

    #: the hand this part belongs to (set by each family's constructor)
    params: HandParams
    link: Link

    @classmethod
    def links(cls) -> tuple[Link, ...]:
        """The topology links this family makes, in topology order."""
        return tuple(ln for ln in LINKS if ln.segment in cls.SEGMENTS)

    @classmethod
    @abc.abstractmethod
    def for_link(cls, params: HandParams, link: Link) -> "Part":
        """The part of ``link`` (one of the family's ``links()``) of the hand ``params``."""

    # -- what a part declares ------------------------------------------------
    @property
    def name(self) -> str:
        return self.link.name

    @property
    def digit(self) -> str | None:
        return self.link.digit

    @property
    def color(self) -> tuple[float, float, float]:
        return self.COLOR if self.COLOR is not None else DIGIT_COLORS[self.digit]

    @property
    def print_rotation(self) -> np.ndarray:
        """3x3: lays the part on its preferred face for printing (z up); the export keeps it unless
        an axis-aligned orientation has less overhang (``export.orient``)."""
        return SIDE_DOWN

    @property
    def print_up(self) -> np.ndarray:
        """The printer's +z in the link frame, for the declared ``print_rotation``: the way a hole's
        roof must point to print without support (``common.teardrop``)."""
        return np.asarray(self.print_rotation, float)[2].copy()

    @abc.abstractmethod
    def build(self):
        """The right-hand solid (build123d) in the link frame, mm."""

    def collision_solids(self) -> list:
        """Convex solids (link frame, mm) whose union is the part's collision shape in the robot
        description: a part with concavities that matter for contact (the palm's stepped sockets and
        thenar) names the convex solids it is fused from, before its cuts. Empty: the convex hull
        of the built part."""
        return []

    def support_blockers(self) -> list:
        """Where a slicer must not put support (``tendons.Blocker`` meshes, link frame, mm):
        default none."""
        return []

    @abc.abstractmethod
    def inputs(self) -> dict:
        """The plain parameter values the solid depends on (the part cache's key)."""

    def verify(self, shape) -> list[str]:
        """Problems of a built solid (one line each); default: none to measure."""
        return []

    def pad(self) -> np.ndarray:
        """T_link_pad (mm) of a fingertip's contact pad: only a digit's last link has one."""
        raise ValueError(f"{self.name} is not a fingertip")

    # -- helpers ---------------------------------------------------------------
    def common_inputs(self) -> dict:
        """The values every part depends on: side, hand length, hardware, print, cad, palm wall."""
        doc = self.params.document
        return {
            "side": doc["hand"]["side"],
            "hand_length_mm": doc["hand"]["hand_length_mm"],
            "hardware": canon.plain(doc["hardware"]),
            "print": canon.plain(doc["print"]),
            "cad": canon.plain(doc["cad"]),
            "palm_wall_mm": doc["palm"]["wall_mm"],
        }

    def whole_hand_inputs(self) -> dict:
        """Every parameter but the model's mechanics and effects: for a part placed by every
        socket and servo (the palm, the forearm module)."""
        doc = self.params.document
        out = {k: canon.plain(v) for k, v in doc.items() if k not in ("mechanics", "effects", "hand")}
        out["side"] = doc["hand"]["side"]
        out["hand_length_mm"] = doc["hand"]["hand_length_mm"]
        return out

    def expect(self, problems: list[str], what: str, measured: float | None, wanted: float,
               eps: float = 1e-3) -> None:
        """Append a problem when ``measured`` (mm) is missing or off ``wanted`` by more than eps."""
        if measured is None or abs(measured - wanted) > eps:
            got = "nothing" if measured is None else f"{measured:.4f}"
            problems.append(f"{self.name}: {what} measures {got}, expected {wanted:.4f} mm")

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r})"
