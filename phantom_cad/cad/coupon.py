"""The fit-test coupon: a small print that carries the hand's fits at the current tolerances, so a
maker tunes ``[print]`` before printing the hand (docs/parts.md, "Fit-test coupon").

It is not a link of the hand (no part family, no description); ``phantom-cad build`` exports it
beside the parts (``coupon/``). Every hole is made by the same :class:`Tolerances` properties
the parts use, so the coupon's holes are the hand's, byte for byte in diameter:

* a plate, printed flat, with the holes the palm and forearm print vertically: a bearing seat over
  an axle clearance bore (a tongue's joint), an axle press bore (a clevis cheek), a magnet pocket,
  a screw pilot, a screw clearance hole and a tendon channel;
* a block at its end with the holes the digits print horizontally (their joint bores lie flat
  in the exported orientation, docs/parts.md): the bearing seat over the clearance bore, the
  press bore and a tendon channel, through the block along y.

Frame: mm, z up (the print orientation; the plate's underside on the bed at z = 0), x along the
coupon. Dimensions are plain properties (numpy only); :meth:`FitCoupon.build` imports build123d.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..canon import plain
from ..kinematics.hand_params import HandParams
from .parts.common import Tolerances, as_solid, box, cylinder
from .print_aid import PrintAid


#: the coupon's name (its files: coupon/fit_coupon.step, .stl, .md)
NAME = "fit_coupon"
#: floor under the deepest blind hole, and the plate's and block's walls around every hole (mm)
FLOOR = 1.0
#: display colour
COLOR = (0.85, 0.75, 0.35)


@dataclass(frozen=True)
class Feature:
    """One hole of the coupon (mm, coupon frame)."""

    key: str
    what: str             # the hardware it takes and the fit
    fit: float            # the diameter the printed hole should measure
    diameter: float       # the modelled diameter (fit + hole compensation for hardware holes)
    depth: float          # along the axis from the opening; the body's extent for a through hole
    opening: tuple        # centre of the opening
    axis: tuple           # unit vector from the opening into the material
    printed: str          # "vertical" or "horizontal" (its axis in the print)
    through: bool
    check: str            # what the maker checks with the hardware
    tune: str             # the parameter that moves this fit

    def as_dict(self) -> dict:
        return {"key": self.key, "what": self.what, "fit_mm": round(self.fit, 6),
                "modelled_mm": round(self.diameter, 6), "depth_mm": round(self.depth, 6),
                "opening_mm": [round(float(v), 6) for v in self.opening],
                "axis": [round(float(v), 6) for v in self.axis], "printed": self.printed,
                "through": self.through, "check": self.check, "tune": self.tune}


class FitCoupon(PrintAid):
    """The fit-test coupon of a hand's parameters (see the module doc)."""

    kind = "coupon"
    name = NAME
    title = "the fit-test coupon"
    color = COLOR
    listed = ("features",)

    def __init__(self, params: HandParams):
        super().__init__(params)
        self.tol = Tolerances(params)

    @staticmethod
    def inputs(params: HandParams) -> dict:
        """The print settings, the hardware and the wall it is made of."""
        doc = params.document
        return {"print": plain(doc["print"]), "hardware": plain(doc["hardware"]),
                "palm_wall_mm": doc["palm"]["wall_mm"], "name": params.name}

    def subtitle(self) -> str:
        return f"{len(self.features)} holes at the hand's tolerances; see {NAME}.md"

    def meta(self) -> dict:
        return {"features": [ft.as_dict() for ft in self.features]}

    # -- dimensions (mm) --------------------------------------------------------
    @property
    def gap(self) -> float:
        """Material between two holes and between a hole and the outside: the palm's wall."""
        return self.tol.wall

    @property
    def plate_height(self) -> float:
        """The deepest blind vertical hole (the screw pilot's thread engagement) and a floor."""
        t = self.tol
        return max(t.screw_engagement, t.bearing_width, t.magnet_pocket_depth) + FLOOR

    @property
    def width(self) -> float:
        """Along y: the widest hole and a wall each side (the horizontal bores run this long)."""
        return self.tol.bearing_seat + 2.0 * self.gap

    @property
    def block_height(self) -> float:
        """The block of the horizontal holes: the bearing seat and a wall above and below."""
        return self.tol.bearing_seat + 2.0 * self.gap

    def _row(self, diameters: list[float], x0: float) -> tuple[list[float], float]:
        """Centres along x of holes of ``diameters`` from x0, a gap before each; the end x (with
        the last gap)."""
        xs, x = [], x0
        for d in diameters:
            x += self.gap + d / 2.0
            xs.append(x)
            x += d / 2.0
        return xs, x + self.gap

    @cached_property
    def features(self) -> list[Feature]:
        t = self.tol
        H, W = self.plate_height, self.width
        down, along = (0.0, 0.0, -1.0), (0.0, 1.0, 0.0)
        tune_press = "print.hole_compensation_mm (all holes), print.press_fit_interference_mm (press fits)"
        tune_clear = "print.hole_compensation_mm (all holes), print.hole_clearance_mm (clearance fits)"
        bearing = (f"{t.bearing_outer:g} mm bearing outer ring, press fit "
                   f"({t.interference:g} mm interference)")
        seat_check = "the bearing presses in with a thumb, sits flush and does not fall out upside down"
        clear_check = "the axle slides through and turns freely with no visible play"
        press_check = "the axle presses in (a vice or a light tap) and cannot be turned by hand"
        channel = (f"{t.tendon:g} mm tendon, clearance channel "
                   f"(not compensated)")
        channel_check = "the tendon pulls through with no felt drag; a burr or a sagging roof catches it"
        vertical = [
            ("bearing_seat", bearing, t.fit("bearing_seat"), t.bearing_seat, t.bearing_width,
             False, seat_check, tune_press),
            ("axle_clearance", f"{t.axle:g} mm axle, clearance bore ({t.clearance:g} mm a side) under the "
             "bearing seat", t.fit("axle_clear"), t.axle_clear, H - t.bearing_width, True,
             clear_check, tune_clear),
            ("axle_press", f"{t.axle:g} mm axle, press bore ({t.interference:g} mm interference)",
             t.fit("axle_press"), t.axle_press, H, True, press_check, tune_press),
            ("magnet_pocket", f"{t.magnet_d:g} x {t.magnet_t:g} mm magnet pocket ({t.magnet_clearance:g} mm "
             "clearance)", t.fit("magnet_pocket_d"), t.magnet_pocket_d, t.magnet_pocket_depth,
             False, "the magnet drops in and seats flush or just below the face (it is glued)",
             "print.hole_compensation_mm, print.magnet_clearance_mm"),
            ("screw_pilot", f"M{t.screw:g} thread-forming pilot ({t.pilot_ratio:g} of the diameter)",
             t.fit("screw_pilot"), t.screw_pilot, t.screw_engagement, False,
             f"an M{t.screw:g} screw cuts its thread with firm torque and holds; it must not strip or split the wall",
             "print.hole_compensation_mm, print.screw_pilot_ratio"),
            ("screw_clearance", f"M{t.screw:g} clearance hole", t.fit("screw_clear"), t.screw_clear, H,
             True, "the screw drops through", tune_clear),
            ("tendon_channel", channel, t.tendon_hole, t.tendon_hole, H, True, channel_check,
             "print.hole_clearance_mm"),
        ]
        out: list[Feature] = []
        # the plate: the bearing seat and its clearance bore share one column
        xs, _ = self._plate_row
        col_of = {"bearing_seat": 0, "axle_clearance": 0, "axle_press": 1, "magnet_pocket": 2,
                  "screw_pilot": 3, "screw_clearance": 4, "tendon_channel": 5}
        for key, what, fit, dia, depth, through, check, tune in vertical:
            z0 = H - t.bearing_width if key == "axle_clearance" else H
            out.append(Feature(key, what, fit, dia, depth, (xs[col_of[key]], 0.0, z0), down, "vertical",
                               through, check, tune))
        # the block: the same joint fits and a channel, horizontal, through the block along y
        bx, _ = self._block_row
        zc = self.block_height / 2.0
        y0 = -W / 2.0
        out += [
            Feature("bearing_seat_h", bearing, t.fit("bearing_seat"), t.bearing_seat,
                    t.bearing_width, (bx[0], y0, zc), along, "horizontal", False, seat_check, tune_press),
            Feature("axle_clearance_h", f"{t.axle:g} mm axle, clearance bore under the bearing seat",
                    t.fit("axle_clear"), t.axle_clear, W - t.bearing_width,
                    (bx[0], y0 + t.bearing_width, zc), along, "horizontal", True, clear_check, tune_clear),
            Feature("axle_press_h", f"{t.axle:g} mm axle, press bore", t.fit("axle_press"), t.axle_press,
                    W, (bx[1], y0, zc), along, "horizontal", True, press_check, tune_press),
            Feature("tendon_channel_h", channel, t.tendon_hole, t.tendon_hole, W, (bx[2], y0, zc), along,
                    "horizontal", True, channel_check, "print.hole_clearance_mm"),
        ]
        return out

    @cached_property
    def _plate_row(self) -> tuple[list[float], float]:
        """The plate's hole columns, from x = 0: bearing seat (over its clearance bore), axle press
        bore, magnet pocket, screw pilot, screw clearance hole, tendon channel."""
        t = self.tol
        return self._row([t.bearing_seat, t.axle_press, t.magnet_pocket_d, t.screw_pilot, t.screw_clear,
                          t.tendon_hole], 0.0)

    @cached_property
    def _block_row(self) -> tuple[list[float], float]:
        """The block's hole columns, after the plate: bearing seat, axle press bore, tendon channel."""
        t = self.tol
        return self._row([t.bearing_seat, t.axle_press, t.tendon_hole], self.plate_length)

    @property
    def plate_length(self) -> float:
        return self._plate_row[1]

    @property
    def length(self) -> float:
        return self._block_row[1]

    def boxes(self) -> list[tuple[float, float, float, float, float, float]]:
        """The plate and the block, (x0, x1, y0, y1, z0, z1)."""
        W = self.width
        return [(0.0, self.plate_length, -W / 2.0, W / 2.0, 0.0, self.plate_height),
                (self.plate_length, self.length, -W / 2.0, W / 2.0, 0.0, self.block_height)]

    # -- solid --------------------------------------------------------------------
    def build(self):
        """The coupon's solid (mm, print orientation)."""
        body = None
        for b in self.boxes():
            s = box(*b)
            body = s if body is None else body.fuse(s)
        tools = []
        for f in self.features:
            a = np.asarray(f.axis, float)
            o = np.asarray(f.opening, float)
            # through holes overshoot both faces; blind ones overshoot their opening only
            far = o + a * (f.depth + (1.0 if f.through else 0.0))
            tools.append(cylinder(o - a, far, f.diameter / 2.0))
        shape = body
        for tool in tools:
            shape = shape.cut(tool)
        return as_solid(shape.clean())

    def verify(self, shape) -> list[str]:
        """Each feature measured on the solid: a cylindrical face of its modelled radius on its axis,
        as long as its depth."""
        from .measure import coaxial, cylinders

        cyl = cylinders(shape)
        out = []
        for f in self.features:
            hits = [c for c in cyl if abs(c["radius"] - f.diameter / 2.0) < 1e-6
                    and coaxial(c, f.opening, f.axis, 1e-6)]
            if not hits:
                out.append(f"{NAME}: no {f.key} of diameter {f.diameter:.4f} mm on its axis")
                continue
            length = max(c["s_max"] for c in hits) - min(c["s_min"] for c in hits)
            if abs(length - f.depth) > 1e-4:
                out.append(f"{NAME}: {f.key} measures {length:.4f} mm deep, expected {f.depth:.4f} mm")
        return out

    def volume(self) -> float:
        """Closed form: the boxes less every hole (the holes do not overlap)."""
        v = sum((b[1] - b[0]) * (b[3] - b[2]) * (b[5] - b[4]) for b in self.boxes())
        return v - sum(math.pi * f.diameter ** 2 / 4.0 * f.depth for f in self.features)

    def table(self) -> str:
        """coupon/fit_coupon.md: the maker's sheet (what each hole is, what to check, what to tune)."""
        t = self.tol
        rows = ["| hole | printed | takes | should measure (mm) | modelled (mm) | check | if not, tune |",
                "|---|---|---|---|---|---|---|"]
        for f in self.features:
            rows.append(f"| {f.key} | {f.printed} | {f.what} | {f.fit:.3f} | {f.diameter:.3f} | {f.check} | "
                        f"{f.tune} |")
        return "\n".join([
            f"# Fit-test coupon of {self.params.name}",
            "",
            f"Print `fit_coupon.stl` as exported (flat side down) with the settings of the hand, before the "
            f"hand. It is {self.length:.1f} x {self.width:.1f} mm. Holes are listed left to right: the plate "
            "holds them vertical (as the palm and forearm print them), the block at the end holds them "
            "horizontal along y (as the digits print their joint bores).",
            "",
            f"Every hole that takes hardware is modelled `print.hole_compensation_mm` = {t.compensation:g} mm "
            "wider than the fit it should print at. Measure a hole with a pin gauge or the hardware itself. "
            "If all the holes come out small (or large) by the same amount, change `hole_compensation_mm` by "
            "it; if one kind of fit is off, change its own parameter. Then build again: the hand's holes "
            "change with the coupon's.",
            "",
            *rows,
            "",
        ])
