"""What a build returns or raises: :class:`BuildResult`, :class:`BuildError` with the
:class:`PartFailure` of each part that failed."""

from __future__ import annotations

import json
import traceback
from dataclasses import dataclass, field
from pathlib import Path

from ..canon import jsonable
from ..cad.verify import CheckError
from ..params import ParamError


@dataclass
class PartFailure:
    part: str
    error: str                      # "ExceptionType: message"
    field: str | None = None        # the ParamError field, when the failure names one
    check: str | None = None        # the failed export check, when it was a check
    part_inputs: dict | None = None
    traceback: str | None = None

    def describe(self) -> str:
        lines = [f"part '{self.part}' failed: {self.error}"]
        if self.field:
            lines.append(f"  parameter: {self.field}")
        if self.check:
            lines.append(f"  check: {self.check}")
        if self.part_inputs is not None and not self.field:
            lines.append(f"  part_inputs: {json.dumps(self.part_inputs, sort_keys=True)}")
        return "\n".join(lines)


def failure_from(name: str, exc: BaseException, inputs) -> PartFailure:
    """The failure report of part ``name`` from the exception it raised."""
    fld = getattr(exc, "field", None) if isinstance(exc, ParamError) else None
    chk = exc.check if isinstance(exc, CheckError) else None
    return PartFailure(part=name, error=f"{type(exc).__name__}: {exc}", field=fld, check=chk,
                       part_inputs=jsonable(inputs) if inputs is not None else None,
                       traceback="".join(traceback.format_exception(exc)))


class BuildError(RuntimeError):
    """The build failed; nothing was written to the export directory."""

    def __init__(self, message: str, failures: list[PartFailure] | None = None):
        self.failures = failures or []
        text = message
        if self.failures:
            text += "\n" + "\n".join(f.describe() for f in self.failures)
        super().__init__(text)


@dataclass
class BuildResult:
    out_dir: Path
    hand: str
    side: str
    params_digest: str
    parts: list[str]
    built: list[str]                # parts built in this run
    cached: list[str]               # parts taken from the cache
    manifest: dict
    timings: dict[str, float] = field(default_factory=dict)
    sliced: bool = False
    #: seconds per step of each part built in this run (build_part, step, stl, render, total)
    part_timings: dict[str, dict[str, float]] = field(default_factory=dict)

    def summary(self) -> str:
        t = self.timings.get("total", float("nan"))
        extra = "" if self.sliced else " (not sliced)"
        return (f"{self.hand} ({self.side}): {len(self.parts)} parts, {len(self.built)} built, "
                f"{len(self.cached)} from cache, {t:.1f} s -> {self.out_dir}{extra}")
