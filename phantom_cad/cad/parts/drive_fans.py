"""The slots a digit's drive chord sweeps through a link over the travel (a fan about the end fixed
there), cut as tools; a flexion stop's wedge kept clear of them; where a guide's channel ends.
numpy only (build123d through ``common``'s helpers, inside the functions); link frame, mm."""

from __future__ import annotations

import math

import numpy as np

from ... import units
from ...kinematics.dimensions import FLANK
from .tendons import LinkTendons, cutter

#: a drive chord's fan reaches this far (rad) beyond the extreme chords it holds
FAN_PAD = units.rad(4.0)


def drive_fan_outlines(lt: LinkTendons, sec, start: float) -> list[tuple[list, float, float]]:
    """(y-z outline, x0, x1) of each slot a drive chord sweeps through this link over the travel:
    a fan from the end fixed here (from ``start`` mm along the chord, past the eyelet) to the other
    end's positions, a clearance diameter wide about the chord's plane."""
    out = []
    w = sec.tol.tendon_hole
    for fixed, moving in lt.drive_sweeps:
        rays = {}
        for m in moving:
            v = (m - fixed)[1:]
            L = float(np.linalg.norm(v))
            if L <= start:
                continue
            u = v / L
            a = round(math.atan2(u[1], u[0]), 9)
            rays[a] = max(rays.get(a, 0.0), L + 1.0)
        if len(rays) < 2:
            continue
        # star-shaped about the fixed end: the rays in angular order (unwrapped about the first)
        a0 = next(iter(rays))
        order = sorted(rays, key=lambda a: ((a - a0 + math.pi) % (2 * math.pi)))
        # a clearance's worth of angle beyond the two extreme chords, which would lie on its edges
        first, last = order[0], order[-1]
        pad = FAN_PAD
        rays[first - pad], rays[last + pad] = rays[first], rays[last]
        order = [first - pad] + order + [last + pad]
        c = fixed[1:]
        near = [c + start * np.array([math.cos(a), math.sin(a)]) for a in order]
        far = [c + rays[a] * np.array([math.cos(a), math.sin(a)]) for a in order]
        poly = _simple([tuple(p) for p in near] + [tuple(p) for p in reversed(far)])
        out.append((poly, fixed[0] - w / 2.0, fixed[0] + w / 2.0))
    return out


def drive_fan_tools(lt: LinkTendons, sec, start: float, flanks: tuple = (), span: tuple | None = None) -> list:
    """The drive's fans (:func:`drive_fan_outlines`) as cutting tools. ``flanks``: the x of the
    faces of grooves the fan passes beside within ``span`` = (y0, y1) (a joint's tongue); where one
    lies less than a flank (``dimensions.FLANK``) beside the fan, the fan is widened to it there (a
    0.4 mm fin stood between the drive's fan and the return cord's groove on the proximal
    phalanges)."""
    from .common import box, prism_x
    out = []
    for poly, x0, x1 in drive_fan_outlines(lt, sec, start):
        out.append(prism_x(poly, x0, x1))
        for face in flanks:
            for edge, side in ((x0, -1.0), (x1, 1.0)):
                if 0.0 < side * (face - edge) < units.mm(FLANK):
                    # to the face and 0.05 mm into the groove beyond it (no coplanar faces)
                    a, b = sorted((edge, face + side * 0.05))
                    big = max(abs(v) for p in poly for v in p) + 1.0
                    out.append(cutter(prism_x(poly, a, b).intersect(box(a - 1.0, b + 1.0, *span, -big, big))))
    return out


def clear_of_fans(lt: LinkTendons, sec, start: float, wedge) -> list:
    """A flexion stop's wedge (``DigitSection.stop_polygon``: a (y, z) triangle on the palmar face,
    its edge at the face) where a drive's fan (:func:`drive_fan_outlines`) passes under it: cut
    back, square to the face, to where the wedge stands a flank (``dimensions.FLANK``) above the
    fan's top. Its edge left a web over the fan (0.14 mm on a 170 mm hand's middle finger base)."""
    if len(wedge) != 3:
        return list(wedge)
    (y0, z0), (y1, _), (_, z2) = wedge          # (back, face), (edge, face), (back, top)
    top = None
    t = np.linspace(0.0, 1.0, 9)[:, None]
    for poly, _, _ in drive_fan_outlines(lt, sec, start):
        ring = np.asarray(poly, float)
        pts = np.vstack([a + t * (b - a) for a, b in zip(ring, np.roll(ring, -1, axis=0))])
        zs = [z for y, z in pts if min(y0, y1) <= y <= max(y0, y1)]
        if zs and max(zs) > z0:
            top = max(zs) if top is None else max(top, max(zs))
    if top is None:
        return list(wedge)
    z = top + units.mm(FLANK)
    if z >= z2:
        return list(wedge)
    y = y1 + (y0 - y1) * (z - z0) / (z2 - z0)   # on the wedge's slope at height z
    if (y - y1) * (y0 - y1) <= 0.0:
        return list(wedge)
    return [(y0, z0), (y, z0), (y, z), (y0, z2)]


def guide_entry(start, guide, relief_centre) -> np.ndarray:
    """Where a channel along the line from ``start`` through a guide point should end: the point of
    that line nearest the eyelet's far relief sphere's centre (inside the sphere, so the channel's
    rim never reaches the eyelet's hole)."""
    a, g, c = (np.asarray(v, float) for v in (start, guide, relief_centre))
    u = (g - a) / np.linalg.norm(g - a)
    return a + float((c - a) @ u) * u


def _simple(poly):
    """Drop consecutive duplicates (a fan whose near edge has not moved)."""
    out = []
    for p in poly:
        if not out or math.hypot(p[0] - out[-1][0], p[1] - out[-1][1]) > 1e-6:
            out.append(p)
    if math.hypot(out[0][0] - out[-1][0], out[0][1] - out[-1][1]) < 1e-6:
        out.pop()
    return out
