"""The servo catalogue: hobby and bus servos a parameter file can name (``[servo] model = "..."``),
with their datasheet numbers (docs/force.md cites the datasheets).

A file that names a model takes from here every ``[servo]`` number it does not write itself
(a number it writes, e.g. a torque measured on the bench, wins). The default file names none:
it writes the SCS0009's numbers out, which :data:`DEFAULT` names.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CatalogueServo:
    """One servo's datasheet: in the parameter file's units (mm, N m, deg/s, V)."""

    title: str
    #: stall torque (N m) and no-load speed (deg/s) at ``voltage`` (V)
    stall_torque_Nm: float
    speed_deg_s: float
    voltage: float
    #: body length, width, height (mm): the printed pockets' size
    body_mm: tuple[float, float, float]
    #: the mounting ears: span across them and their screw (mm); None: the servo has no ears
    #: (a file that names it writes its own)
    flange_span_mm: float | None
    screw_diameter_mm: float | None
    #: what the datasheet says, briefly (where the numbers come from)
    source: str
    #: the bus the servo is driven over: "feetech-scs" (half-duplex TTL serial bus), "dynamixel-ttl"
    #: (ROBOTIS TTL multidrop bus) or "pwm" (a hobby servo's pulse input); the BOM's electronics
    #: follow it (``cad.purchase``)
    bus: str
    #: stall current (A) at ``voltage``: sizes the power supply; and where it comes from
    stall_current_A: float
    current_source: str

    def values(self) -> dict[str, object]:
        """The ``[servo]`` numbers this entry gives a file that names it (the ones it has)."""
        out = {"body_mm": list(self.body_mm), "stall_torque_Nm": self.stall_torque_Nm,
               "speed_deg_s": self.speed_deg_s}
        if self.flange_span_mm is not None:
            out["flange_span_mm"] = self.flange_span_mm
        if self.screw_diameter_mm is not None:
            out["screw_diameter_mm"] = self.screw_diameter_mm
        return out


#: kgf cm -> N m
KGF_CM = 0.0980665

CATALOGUE: dict[str, CatalogueServo] = {
    "scs0009": CatalogueServo(
        "Feetech SCS0009", 0.226, 600.0, 6.0, (23.2, 12.1, 25.3), 32.3, 2.0,
        "Feetech SCS0009 datasheet: 2.3 kgf cm stall, 0.10 s / 60 deg no-load, at 6 V (4.8-6 V)",
        bus="feetech-scs", stall_current_A=1.0,
        current_source="[assumed] the datasheet gives no stall current: 1.0 A taken for a 2.3 kgf cm micro "
                       "servo at 6 V; measure yours"),
    "mg90s": CatalogueServo(
        "TowerPro MG90S", round(2.2 * KGF_CM, 4), 750.0, 6.0, (22.8, 12.2, 28.5), 32.5, 2.0,
        "TowerPro MG90S datasheet: 2.2 kgf cm stall, 0.08 s / 60 deg no-load, at 6 V "
        "(1.8 kgf cm and 0.10 s / 60 deg at 4.8 V); 22.8 x 12.2 x 28.5 mm",
        bus="pwm", stall_current_A=1.0,
        current_source="[assumed] the datasheet gives no stall current: 1.0 A taken for a 2.2 kgf cm micro "
                       "servo at 6 V; measure yours"),
    "xl330-m288": CatalogueServo(
        "ROBOTIS Dynamixel XL330-M288-T", 0.52, 618.0, 5.0, (34.0, 20.0, 26.0), None, None,
        "ROBOTIS e-Manual, XL330-M288-T: 0.52 N m stall and 103 rev/min no-load at 5.0 V "
        "(0.60 N m, 123 rev/min at 6 V); 20 x 34 x 26 mm; mounted by the case's screw holes, no ears",
        bus="dynamixel-ttl", stall_current_A=1.47,
        current_source="ROBOTIS e-Manual, XL330-M288-T: 0.52 N m at 5.0 V, 1.47 A"),
}

#: the servo params/phantom.toml's numbers are (it writes them out rather than naming it)
DEFAULT = "scs0009"


@dataclass(frozen=True)
class BusFamily:
    """A serial-bus servo family as ``phantom_cad.drive`` speaks to it: the Feetech protocol's
    packets are the same for the families; the word order and the position resolution are not."""

    title: str
    #: two-byte registers: high byte first (SCS) or low byte first (STS)
    big_endian: bool
    #: position counts over ``span_deg`` of output rotation, counted from 0
    counts: int
    span_deg: float
    #: the factory baud rate and ID of a new servo
    baud: int
    factory_id: int
    #: whether the family answers SYNC_READ (one packet for every servo's registers)
    sync_read: bool
    source: str


#: by the catalogue's ``bus``: the buses ``phantom-cad drive`` speaks (a PWM or Dynamixel servo has none)
BUS_FAMILIES: dict[str, BusFamily] = {
    "feetech-scs": BusFamily("Feetech SCS", True, 1024, 300.0, 1_000_000, 1, False,
                     "Feetech SCS series memory table (SCSCL): 10-bit position over 300 deg, big-endian words"),
    "feetech-sts": BusFamily("Feetech STS/SMS", False, 4096, 360.0, 1_000_000, 1, True,
                     "Feetech STS series memory table (SMS_STS): 12-bit position over 360 deg, little-endian words"),
}



def bus_family(name: str | None) -> str | None:
    """The bus family (a :data:`BUS_FAMILIES` key) of catalogue servo ``name``; None when it has
    none ``phantom-cad drive`` speaks, or for a servo of the file's own."""
    bus = CATALOGUE[name].bus if name in CATALOGUE else None
    return bus if bus in BUS_FAMILIES else None


def names() -> tuple[str, ...]:
    return tuple(CATALOGUE)


def named(servo) -> str | None:
    """The catalogue name of a parsed servo (``HandParams.servo``): the one it names, or the one
    whose datasheet numbers it writes out; None for a servo of the file's own."""
    if servo.model is not None:
        return servo.model
    for name, entry in CATALOGUE.items():
        if (entry.flange_span_mm is not None and abs(servo.stall_torque - entry.stall_torque_Nm) < 1e-9
                and all(abs(a * 1e3 - b) < 1e-9 for a, b in zip(servo.body, entry.body_mm))
                and abs(servo.flange_span * 1e3 - entry.flange_span_mm) < 1e-9):
            return name
    return None
