"""The print aids a build makes beside the parts (:class:`~phantom_cad.cad.print_aid.PrintAid`):
adding one is one class and one entry in :data:`AIDS`. numpy only."""

from __future__ import annotations

from .coupon import FitCoupon
from .gauge import AngleGauge
from .print_aid import PrintAid

#: every print aid, in the order a build makes, exports and lists them
AIDS: tuple[type[PrintAid], ...] = (FitCoupon, AngleGauge)

#: kind -> its class
BY_KIND: dict[str, type[PrintAid]] = {a.kind: a for a in AIDS}
