"""Prints that are not links of the hand: the maker prints them beside it (the fit-test coupon
before the hand, the angle gauge before calibrating it). ``phantom-cad build`` makes, verifies,
caches and exports each one the same way (``export.pool.aid_worker``, ``export.exporters.PrintAidFiles``):
its folder ``<kind>/`` holds ``<name>.step``, ``.stl`` (as built: it prints flat side down),
``.md`` (the maker's sheet) and ``.png``; the manifest lists it under ``<kind>``. numpy only;
:meth:`PrintAid.build` imports build123d.
"""

from __future__ import annotations

import abc
from typing import Any, ClassVar

from ..kinematics.hand_params import HandParams


class PrintAid(abc.ABC):
    """One print aid of a hand's parameters; the constructor refuses parameters it cannot be made
    from (ParamError)."""

    #: its folder in the export and in the part cache
    kind: ClassVar[str]
    #: its files' stem and its STEP label
    name: ClassVar[str]
    #: what it is, in a few words (logs, errors)
    title: ClassVar[str]
    #: display colour
    color: ClassVar[tuple[float, float, float]]
    #: the keys of :meth:`meta` the manifest lists, in order
    listed: ClassVar[tuple[str, ...]]

    def __init__(self, params: HandParams):
        self.params = params

    @staticmethod
    @abc.abstractmethod
    def inputs(params: HandParams) -> dict[str, Any]:
        """Everything of the parameters it reads (its cache key)."""

    @abc.abstractmethod
    def build(self):
        """The solid (mm, print orientation)."""

    @abc.abstractmethod
    def verify(self, shape) -> list[str]:
        """What the solid lacks of its design, measured on it (empty: nothing)."""

    @abc.abstractmethod
    def volume(self) -> float:
        """Its volume in closed form (mm^3), which the solid's must equal."""

    @abc.abstractmethod
    def table(self) -> str:
        """The maker's sheet (markdown)."""

    @abc.abstractmethod
    def subtitle(self) -> str:
        """Its picture's subtitle."""

    @abc.abstractmethod
    def meta(self) -> dict[str, Any]:
        """What its cache entry records besides its volume, mass, box and STL (JSON values)."""
