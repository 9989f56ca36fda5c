"""Verification of built parts, the one place: a part's validity (one valid solid of positive
volume, :func:`solid_problems`) and, for the parts of the registry, what their family measures
(``Part.verify``, with :mod:`phantom_cad.cad.measure`). :func:`verify_part` is what the export
pipeline runs once per part before writing it. build123d is imported lazily.
"""

from __future__ import annotations


from ..kinematics.hand_params import HandParams
from . import registry
from .measure import solid_report


class CheckError(RuntimeError):
    """A built part fails a check (solid, measurement, mesh, STEP round trip)."""

    def __init__(self, part: str, check: str, detail: str, problem: str | None = None):
        self.part, self.check, self.detail = part, check, detail
        #: the short text :func:`verify_part` lists (``"<part>: <problem>"``)
        self.problem = problem or detail
        super().__init__(f"part '{part}': check '{check}' failed: {detail}")


def solid_problems(name: str, shape) -> list[CheckError]:
    """What makes ``shape`` not one valid solid of positive volume (empty: it is one)."""
    rep = solid_report(shape)
    out = []
    if rep["n_solids"] != 1:
        out.append(CheckError(name, "one solid", f"the part has {rep['n_solids']} solids",
                              f"{rep['n_solids']} solids, expected 1"))
    if not rep["valid"]:
        out.append(CheckError(name, "valid solid", "BRepCheck_Analyzer reports an invalid shape",
                              "the solid is not valid"))
    if not rep["volume"] > 0:
        out.append(CheckError(name, "valid solid", f"volume {rep['volume']!r} mm^3 is not positive",
                              f"volume {rep['volume']:.3f} mm^3"))
    return out


def check_solid(name: str, shape) -> None:
    """Raise the first of :func:`solid_problems` (for parts without measurements)."""
    problems = solid_problems(name, shape)
    if problems:
        raise problems[0]


def verify_part(params: HandParams, name: str, shape) -> list[str]:
    """Problems found by measuring ``shape`` (part ``name`` in its link frame, mm) against the
    parameters: first one valid solid of positive volume (:func:`solid_problems`), then what
    the part's family measures (``Part.verify``: groove radius R, r_j or r6,
    the guide eyelets at d1 / d2, magnet pockets, socket angles). An empty list means the
    part is sound."""
    out = [f"{name}: {p.problem}" for p in solid_problems(name, shape)]
    if out:
        return out
    return registry.part(params, name).verify(shape)
