"""Unit conversions, the one place: SI inside the library (metres, radians, kg/m^3), millimetres
in the CAD layer and the parameter file's key names, degrees where people read angles.

Plain Python and numpy arrays alike (the functions only multiply).
"""

from __future__ import annotations

import math

#: metres per millimetre (a value in mm times MM is in metres)
MM = 1e-3
#: radians per degree (a value in degrees times DEG is in radians)
DEG = math.pi / 180.0
#: degrees per radian (a value in radians times DEG_PER_RAD is in degrees)
DEG_PER_RAD = 180.0 / math.pi
#: cm^3 per mm^3
CM3_PER_MM3 = 1e-3
#: kg/m^3 per g/cm^3
G_PER_CM3 = 1000.0
#: kilograms per gram
KG_PER_G = 1e-3


def mm(metres):
    """Metres -> millimetres."""
    return metres * 1000.0


def m(millimetres):
    """Millimetres -> metres."""
    return millimetres * MM


def deg(radians):
    """Radians -> degrees."""
    return radians * DEG_PER_RAD


def rad(degrees):
    """Degrees -> radians."""
    return degrees * DEG


def cm3(mm3):
    """Cubic millimetres -> cubic centimetres."""
    return mm3 * CM3_PER_MM3
