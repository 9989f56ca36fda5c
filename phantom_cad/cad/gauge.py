"""The angle gauge: a printed plate whose edges are reference faces at known angles, photographed
with the camera that measures the hand so that the camera's angle scale is known before the hand
is diagnosed (docs/calibration.md, "Calibrate the camera on the angle gauge first"; docs/parts.md).

It is not a link of the hand (no part family, no description); ``phantom-cad build`` exports it
beside the fit-test coupon (``gauge/``). The plate's outline, seen from above:

* the datum face along x from the origin, then one reference face per angle of
  ``angles_deg`` (0, 15, 30, ... degrees from the datum, up to the largest joint limit of the
  parameter file's Table I ranges rounded up to a step), each ``face_length`` long: every face
  turns by one step from the one before, so the corners lie on a circle of ``radius`` (the
  longest finger's length beyond its MCP: the gauge spans the image a finger does);
* two radii of that circle close the outline (a slice of it; they are not reference faces): the
  corners next to them stay 82.5 degrees wide, so the marks keep clear of them.

Each reference face but the datum carries its angle as marks engraved in the top face: one
dimple per step (15 degrees: one, 90 degrees: six), in a row along the face's middle, 3 mm apart
or closer on a small hand's shorter faces (``mark_pitch``).

Frame: mm, z up (the print orientation: the plate flat on the bed at z = 0). Dimensions are
plain properties (numpy only); :meth:`AngleGauge.build` imports build123d.
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ..canon import plain
from ..errors import ParamError
from ..kinematics.hand_params import HandParams
from ..kinematics.topology import FINGERS
from .parts.common import as_solid, bd, cylinder, mm
from .print_aid import PrintAid

#: the gauge's name (its files: gauge/angle_gauge.step, .stl, .md)
NAME = "angle_gauge"
#: degrees between neighbouring reference faces
STEP_DEG = 15.0
#: the angle marks: dimple diameter, depth, pitch along the face, and the row's inset from the face (mm)
MARK_DIAMETER = 1.5
MARK_DEPTH = 0.6
MARK_PITCH = 3.0
MARK_INSET = 4.0
#: the least pitch of the marks, on a small hand's gauge: a dimple and half a millimetre of wall
MARK_MIN_PITCH = MARK_DIAMETER + 0.5
#: display colour
COLOR = (0.45, 0.65, 0.85)


class AngleGauge(PrintAid):
    """The angle gauge of a hand's parameters (see the module doc). Refuses (ParamError) a hand
    whose joint ranges reach 180 degrees less a step (the outline would not close convex), or
    whose faces are too short for their marks (or whose marks would come within a dimple's radius
    of an edge)."""

    kind = "gauge"
    name = NAME
    title = "the angle gauge"
    color = COLOR
    listed = ("faces",)

    def __init__(self, params: HandParams):
        super().__init__(params)
        top = self.angles_deg[-1]
        if top + STEP_DEG >= 180.0:
            raise ParamError("fingers.*.limits_rad", round(math.radians(self.largest_limit_deg), 6),
                             f"the angle gauge covers joint ranges up to {180.0 - 2 * STEP_DEG:g} degrees "
                             "(its faces turn by 15 degrees and must close a convex outline)", params.source)
        # the most marks in a row at the least pitch, and a dimple's width of face beyond each end
        need = (len(self.angles_deg) - 2) * MARK_MIN_PITCH + 3.0 * MARK_DIAMETER
        if self.face_length < need - 1e-9:
            raise ParamError("fingers.*.length_fraction", round(self.radius, 3),
                             f"the angle gauge's faces ({self.face_length:.1f} mm, from the longest finger) are "
                             f"shorter than their marks need ({need:.1f} mm)", params.source)
        wall = self.mark_clearance()
        if wall < MARK_DIAMETER / 2.0:
            raise ParamError("fingers.*.length_fraction", round(self.radius, 3),
                             f"the angle gauge's marks leave {wall:.2f} mm of wall to its outline, less than "
                             f"{MARK_DIAMETER / 2.0:g} mm", params.source)

    # -- dimensions (mm, degrees) ----------------------------------------------------
    @property
    def largest_limit_deg(self) -> float:
        """The largest joint limit of the parameter file (every chain's joints and the thumb's CMC)."""
        limits = [hi for c in self.params.chains for _, hi in c.limits]
        limits.append(self.params.thumb.cmc_limits[1])
        return math.degrees(max(limits))

    @cached_property
    def angles_deg(self) -> tuple[float, ...]:
        """The reference faces' angles from the datum: 0, 15, ... up to the largest joint limit
        rounded up to a step (at least 90)."""
        n = max(math.ceil(self.largest_limit_deg / STEP_DEG - 1e-9), round(90.0 / STEP_DEG))
        return tuple(STEP_DEG * k for k in range(n + 1))

    @property
    def radius(self) -> float:
        """The circle the outline's corners lie on: the longest finger's length beyond its MCP."""
        fingers = [self.params.digit(n) for n in FINGERS]
        return max(mm(f.proximal + f.middle + f.distal) for f in fingers)

    @property
    def face_length(self) -> float:
        """Each reference face: the chord of one step on the circle of :attr:`radius`."""
        return 2.0 * self.radius * math.sin(math.radians(STEP_DEG) / 2.0)

    @property
    def mark_pitch(self) -> float:
        """The marks' pitch along a face: MARK_PITCH, or less where the faces are too short for it
        (a small hand's gauge), so that the row of the most marks and a dimple's width beyond each
        end fill the face; never under MARK_MIN_PITCH (the constructor refuses that)."""
        rows = len(self.angles_deg) - 2
        return min(MARK_PITCH, (self.face_length - 3.0 * MARK_DIAMETER) / rows)

    @property
    def thickness(self) -> float:
        """The plate: two palm walls (stiff and flat in print; the marks leave a floor under them)."""
        return 2.0 * mm(self.params.palm.wall)

    @cached_property
    def corners(self) -> np.ndarray:
        """The outline's corners (n + 2, 2): the origin, the end of each reference face, then the
        circle's centre."""
        pts = [np.zeros(2)]
        for a in self.angles_deg:
            t = math.radians(a)
            pts.append(pts[-1] + self.face_length * np.array([math.cos(t), math.sin(t)]))
        # the centre: the datum's midpoint moved inward by the chord's distance from the centre
        centre = np.array([self.face_length / 2.0, self.radius * math.cos(math.radians(STEP_DEG) / 2.0)])
        return np.array([*pts, centre])

    def normal(self, angle_deg: float) -> np.ndarray:
        """The outward normal (x, y) of the reference face at ``angle_deg``: the datum's, (0, -1),
        turned by that angle."""
        t = math.radians(angle_deg)
        return np.array([math.sin(t), -math.cos(t)])

    def marks(self) -> list[tuple[float, float]]:
        """The centres (x, y) of the engraved dimples: k in a row along the k-th face's middle,
        MARK_INSET inside it."""
        out = []
        for k, a in enumerate(self.angles_deg):
            if k == 0:
                continue
            t = math.radians(a)
            along = np.array([math.cos(t), math.sin(t)])
            mid = (self.corners[k] + self.corners[k + 1]) / 2.0 - MARK_INSET * self.normal(a)
            for i in range(k):
                out.append(tuple(mid + (i - (k - 1) / 2.0) * self.mark_pitch * along))
        return out

    def mark_clearance(self) -> float:
        """The least distance (mm) from a dimple's centre to an edge of the outline (less its radius:
        how much wall it leaves)."""
        c = self.corners
        edges = list(zip(c, np.roll(c, -1, axis=0)))
        out = math.inf
        for p in self.marks():
            for a, b in edges:
                d = (b - a) / np.linalg.norm(b - a)
                e = np.asarray(p) - a
                out = min(out, abs(float(d[0] * e[1] - d[1] * e[0])))
        return out - MARK_DIAMETER / 2.0

    def area(self) -> float:
        """The outline's area (shoelace)."""
        x, y = self.corners[:, 0], self.corners[:, 1]
        return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))

    def volume(self) -> float:
        """Closed form: the plate less the dimples."""
        return self.area() * self.thickness - len(self.marks()) * math.pi * MARK_DIAMETER ** 2 / 4.0 * MARK_DEPTH

    # -- solid ---------------------------------------------------------------------------
    def build(self):
        """The gauge's solid (mm, print orientation)."""
        b = bd()
        wire = b.Wire.make_polygon([b.Vector(float(x), float(y), 0.0) for x, y in self.corners], close=True)
        shape = b.Solid.extrude(b.Face(wire), b.Vector(0.0, 0.0, self.thickness))
        h = self.thickness
        # the dimples do not touch one another: one boolean cuts them all
        tools = [cylinder((x, y, h + 1.0), (x, y, h - MARK_DEPTH), MARK_DIAMETER / 2.0) for x, y in self.marks()]
        return as_solid(shape.cut(*tools).clean())

    def face_angles(self, shape) -> list[float]:
        """The angles (degrees, from the datum's normal, counter-clockwise) of the solid's side
        faces (normals in the bed's plane) of at least one face's area."""
        from .measure import planar_faces

        out = []
        for f in planar_faces(shape, 0.5 * self.face_length * self.thickness):
            n = f["normal"]
            if abs(n[2]) < 1e-9:
                out.append(math.degrees(math.atan2(n[0], -n[1])) % 360.0)
        return sorted(out)

    def verify(self, shape) -> list[str]:
        """Each reference face measured on the solid: a side face at its angle from the datum."""
        found = self.face_angles(shape)
        out = []
        for a in self.angles_deg:
            if not any(abs(f - a) < 1e-6 for f in found):
                out.append(f"{NAME}: no side face at {a:g} degrees from the datum (found {found})")
        return out

    @staticmethod
    def inputs(params: HandParams) -> dict:
        """The fingers and the thumb (lengths, joint limits), the hand's length, the wall it is made
        of and the STL tolerance."""
        doc = params.document
        return {"hand": plain(doc["hand"]), "fingers": plain(doc["fingers"]), "thumb": plain(doc["thumb"]),
                "palm_wall_mm": doc["palm"]["wall_mm"], "stl_tolerance_m": params.print.stl_tolerance,
                "name": params.name}

    def subtitle(self) -> str:
        return f"reference faces at {', '.join(f'{a:g}' for a in self.angles_deg)} degrees; see {NAME}.md"

    def meta(self) -> dict:
        return {"faces": self.faces()}

    def faces(self) -> list[dict]:
        """The reference faces, for the manifest and the sheet."""
        return [{"angle_deg": a, "marks": k, "from_mm": [round(float(v), 6) for v in self.corners[k]],
                 "to_mm": [round(float(v), 6) for v in self.corners[k + 1]]}
                for k, a in enumerate(self.angles_deg)]

    def table(self) -> str:
        """gauge/angle_gauge.md: the maker's sheet (what the faces are and how to use them)."""
        rows = ["| face | angle from the datum (deg) | marks |", "|---|---|---|"]
        for k, a in enumerate(self.angles_deg):
            rows.append(f"| {'datum' if k == 0 else k} | {a:g} | {k} |")
        return "\n".join([
            f"# Angle gauge of {self.params.name}",
            "",
            f"Print `angle_gauge.stl` as exported (flat side down). It is a {self.thickness:.1f} mm plate whose "
            f"edges are reference faces {self.face_length:.1f} mm long, each {STEP_DEG:g} degrees from the one "
            f"before, from the datum (the straight edge with no marks) to {self.angles_deg[-1]:g} degrees "
            f"(the largest joint limit of the parameter file is {self.largest_limit_deg:.1f} degrees); each "
            "face carries one engraved dimple per step.",
            "",
            "Before diagnosing the hand (docs/calibration.md): hold the gauge where the finger moves, its top "
            "face in the finger's plane, and photograph it with the camera and the settings that measure the "
            "joints. Read each face's angle from the datum as the measurement reads a joint; the slope of "
            "measured against nominal angle, less 1, is the camera's scale. Correct it (or divide the "
            "measured joint angles by the slope), then diagnose the hand without `camera_scale`.",
            "",
            *rows,
            "",
        ])
