"""The typed, frozen parameters of one hand, SI units (metres, radians, N/m, N): what
``phantom_cad.params.parse`` returns and what the kinematics and the CAD read.

The records only hold values and what follows from them (a chain's coupling, the palm's arc
radius, the document's digest); the params layer builds and validates them. A foundation module
(docs/architecture.md): it imports only other foundation modules, so every layer, the params layer
included, can name these types.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from .. import canon
from ..units import DEG
from . import closed_form as cf
from . import topology
from .dimensions import digit_entry

__all__ = ["Guide", "ChainParams", "Finger", "Thumb", "Mechanics", "Palm", "ServoBody", "Hardware",
           "Print", "Cad", "HandParams"]


@dataclass(frozen=True)
class Guide:
    """MCP (or thumb MP) tendon guides: distances d1 (metacarpal side), d2 (phalanx side)
    from the joint axis, and their included angle alpha at full extension."""

    d1: float
    d2: float
    alpha: float

    @property
    def L0(self) -> float:
        """Eq. (4): chord between the guides at full extension."""
        return float(cf.chord_rest(self.d1, self.d2, self.alpha))

    @property
    def chord_range(self) -> tuple[float, float]:
        """Chord lengths the cosine law admits: [|d1 - d2|, d1 + d2]."""
        return abs(self.d1 - self.d2), self.d1 + self.d2


@dataclass(frozen=True)
class ChainParams:
    """What the model needs of one tendon-driven digit (reference joint first), with its
    topology entry ``spec`` (servo, q indices, joint keys)."""

    spec: topology.Chain
    radii: tuple[float, ...]           # joint pulley radii R, same order
    path_lengths: tuple[float, ...]    # tendon path between consecutive joints
    limits: tuple[tuple[float, float], ...]
    guide: Guide
    servo_radius: float                # r_j
    travel: tuple[float, float]        # servo travel (rad)

    @property
    def digit(self) -> str:
        return self.spec.digit

    @property
    def joints(self) -> tuple[str, ...]:
        """Joint keys, reference first: ("mcp", "pip", "dip") or ("mp", "ip")."""
        return self.spec.keys

    @property
    def ideal_coupling(self) -> np.ndarray:
        """A: q_i = A_i q_ref from the radii (eq. 2; the thumb erratum is fixed by construction)."""
        return cf.ideal_coupling(self.radii)


@dataclass(frozen=True)
class Finger:
    name: str
    metacarpal: float
    proximal: float
    middle: float
    distal: float
    width: float
    thickness: float
    chain: ChainParams


@dataclass(frozen=True)
class Thumb:
    metacarpal: float
    proximal: float
    distal: float
    width: float
    thickness: float
    chain: ChainParams
    cmc_gain: float
    cmc_limits: tuple[float, float]
    cmc_travel: tuple[float, float]
    cmc_pulley_radius: float     # r6: servo 6's pulley and the CMC pulley (a 1:1 cable loop)
    # the MP joint's fixed turn (rad) about the metacarpal's length (its y), a pronation: the MP and
    # IP axes and the pad turn with it; 0 lays the thumb's flexion axes across the CMC axis
    twist: float = 0.0


@dataclass(frozen=True)
class Mechanics:
    spring_k: float   # k_s, N/m
    tendon_EA: float  # EA, N
    #: tension (N) both strands of every coupling loop are tied with: they share the load until
    #: one goes slack (kinematics.statics)
    loop_preload: float = 0.0


@dataclass(frozen=True)
class Palm:
    arc_offset: float        # rad between adjacent fingers
    finger_pitch: float      # m
    thickness: float
    wall: float
    thumb_cmc_offset: tuple[float, float, float]
    thumb_cmc_axis: tuple[float, float, float]   # roll, pitch, yaw (rad)
    heel_height: float = 0.0     # m below the palmar face (0: a flat palm)
    heel_length: float = 0.0     # m from the palm's back face distally
    magnet_lift: float = 0.0     # m the magnet pockets sit dorsal of the magnet face's centre

    @property
    def arc_radius(self) -> float:
        """Radius of the arc on which adjacent MCPs, finger_pitch apart, turn by arc_offset
        (infinite for parallel fingers, arc_offset = 0)."""
        if self.arc_offset == 0.0:
            return math.inf
        return self.finger_pitch / (2.0 * math.sin(self.arc_offset / 2.0))


@dataclass(frozen=True)
class ServoBody:
    """The servo model's body: length, width, height (m), flange span and screw."""

    body: tuple[float, float, float]
    flange_span: float
    screw_diameter: float
    #: stall torque (N m) and no-load speed (rad/s) at the output: joint efforts and velocities
    stall_torque: float
    speed: float
    #: position error (rad) at which the servo's controller gives its stall torque: the
    #: simulation's position gain kp = stall_torque / stall_error
    stall_error: float = 1.0 * DEG
    #: the catalogue servo the file names (``[servo] model``), or None: the file's own numbers
    model: str | None = None


@dataclass(frozen=True)
class Hardware:
    bearing_bore: float
    bearing_outer: float
    bearing_width: float
    axle_diameter: float
    magnet_diameter: float
    magnet_thickness: float
    screw_diameter: float
    tendon_diameter: float
    #: the crimped stop that ends each finger drive's palm strand at the magnet face (the drive's
    #: split: docs/transmission.md)
    stop_diameter: float = 2.0e-3
    stop_length: float = 3.0e-3


@dataclass(frozen=True)
class Print:
    hole_clearance: float
    press_fit_interference: float
    magnet_clearance: float
    stl_tolerance: float
    density: float      # kg/m^3
    infill: float
    #: a thread-forming screw's pilot hole, as a fraction of the screw's diameter
    screw_pilot_ratio: float = 0.8
    #: added to the diameter of every round hole that takes hardware (bearing seats, axle bores,
    #: screw holes, magnet pockets): FDM prints holes this much small (kinematics.dimensions.printed_hole)
    hole_compensation: float = 0.2e-3
    #: the slicer's layer height (m): the build's slicing, and the roofs of the tendon channels
    #: (cad.print_rules.roof_angle)
    layer_height: float = 0.2e-3


@dataclass(frozen=True)
class Cad:
    """Dimensions only the printable parts use (params/phantom.toml [cad]); metres, radians."""

    finger_base_length: float    # finger base: magnet face to MCP axis
    cheek: float                 # clevis cheek wall beside each joint tongue
    eyelet_length: float         # MCP / thumb MP guide eyelet length along the tendon
    spring_diameter: float       # dorsal cable-spring channel diameter
    servo_pulley_width: float    # servo pulley axial width
    horn_hole_radius: float      # servo horn screw circle radius
    servo_shaft_offset: float    # servo output shaft from the body centre along its length
    module_stop_margin: float    # finger module's own MCP stop beyond the palm's (operational) limit, rad
    servo_ear_offset: float      # servo output face to the flange ears' top face
    servo_ear_thickness: float   # servo flange ear thickness
    cmc_column_radius: float     # the CMC base's column, which the palm's journal holds


@dataclass(frozen=True)
class HandParams:
    name: str
    side: str
    hand_length: float
    fingers: Mapping[str, Finger]
    thumb: Thumb
    mechanics: Mechanics
    palm: Palm
    servo: ServoBody
    hardware: Hardware
    print: Print
    cad: Cad
    #: fitted effect parameters, ``{effect_name: {param: value}}`` (see phantom_cad.calibration)
    effects: Mapping[str, Mapping[str, Any]]
    #: the validated document, as parsed (units as in the file); dump() writes it back
    document: Mapping[str, Any] = field(repr=False)
    source: str | None = None
    #: effect plugin files as written (relative to the file's folder); see ``phantom_cad.params.schema.plugin_paths``
    plugins: tuple[str, ...] = ()

    @property
    def chains(self) -> tuple[ChainParams, ...]:
        """The five tendon chains in servo order: thumb, index, middle, ring, pinky."""
        return tuple(self.digit(c.digit).chain for c in topology.CHAINS)

    def digit(self, name: str) -> Finger | Thumb:
        """The :class:`Thumb` or the :class:`Finger` named ``name``."""
        return digit_entry(self, name)

    @functools.cached_property
    def digest(self) -> str:
        """SHA-256 of the canonical document: same parameters, same digest (computed once: the
        document is never changed after parsing)."""
        return canon.digest(self.document)
