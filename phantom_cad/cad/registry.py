"""The part registry: which family makes the part of each topology link.

Every link of ``topology.LINKS`` is one printed part, named after its link; each family
(:class:`~phantom_cad.cad.parts.base.Part`) claims the links of its ``SEGMENTS``. Adding a
part is one class in ``cad/parts/`` and one entry in :data:`FAMILIES`. numpy only.
"""

from __future__ import annotations


from ..kinematics.hand_params import HandParams
from ..kinematics.topology import LINKS, link
from .parts.base import Part
from .parts.finger_base import FingerBase
from .parts.forearm import Forearm
from .parts.palm import Palm
from .parts.phalanx import Phalanx
from .parts.pulley import CMCPulley, ServoPulley
from .parts.thumb import ThumbCMCBase


#: the part families
FAMILIES: tuple[type[Part], ...] = (Palm, Forearm, FingerBase, Phalanx, ThumbCMCBase, CMCPulley, ServoPulley)

#: link name -> the family that makes it, in topology order
FAMILY: dict[str, type[Part]] = {ln.name: fam for ln in LINKS for fam in FAMILIES if ln in fam.links()}

#: the part names, in topology (build) order
PART_NAMES: tuple[str, ...] = tuple(FAMILY)


def _check() -> None:
    claimed = [ln.name for fam in FAMILIES for ln in fam.links()]
    twice = sorted({n for n in claimed if claimed.count(n) > 1})
    if twice:
        raise RuntimeError(f"links claimed by more than one part family: {twice}")


_check()


def part(params: HandParams, name: str) -> Part:
    """The part ``name`` of the hand ``params`` (its dimension object; ``.build()`` makes the
    right-hand solid). KeyError for a name that is no part."""
    fam = FAMILY.get(name)
    if fam is None:
        raise KeyError(f"unknown part {name!r} (known: {', '.join(PART_NAMES)})")
    return fam.for_link(params, link(name))
