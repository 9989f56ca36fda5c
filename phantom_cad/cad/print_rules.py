"""What the printer asks of a part's shape: the extrusion width and the angle from the vertical at
which a hole's roof prints without support (the digits' teardrop channels). Pure arithmetic, SI."""

from __future__ import annotations

import math

from .. import units

#: the extrusion width of a 0.4 mm nozzle (PrusaSlicer's automatic width, 1.125 x the nozzle), m
EXTRUSION_WIDTH = 0.45e-3
#: how much steeper than the printer's limit a roof is made (rad): PrusaSlicer supports a 45 deg
#: roof at 0.2 mm layers (its limit there, 48.4 deg) where the roof's ridge climbs across layers
#: in a channel that is not level (tests/cad/test_teardrop.py)
ROOF_MARGIN = units.rad(8.0)
#: the steepest roof made (rad)
ROOF_MAX = units.rad(40.0)


def roof_angle(layer_height: float) -> float:
    """The angle (rad) from the vertical at which a hole's roof prints without support at
    ``layer_height`` (m): a layer may reach past the one below by half an extrusion width
    (PrusaSlicer's automatic support threshold), atan(w / 2h), less :data:`ROOF_MARGIN`, at most
    :data:`ROOF_MAX`. 40 deg at 0.2 mm layers, 28.9 deg at 0.3 mm."""
    return min(ROOF_MAX, math.atan(EXTRUSION_WIDTH / (2.0 * layer_height)) - ROOF_MARGIN)
