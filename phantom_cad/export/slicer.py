"""Slice STL files headless with PrusaSlicer and read its print estimates.

PrusaSlicer's command line (``prusa-slicer --export-gcode``) runs without a display.
The configuration is PrusaSlicer's built-in defaults (its default printer: 0.4 mm
nozzle, 200 x 200 mm bed, 1.75 mm filament) overridden only by what the parameter file
says about printing: the layer height (``print.layer_height_mm``, also the first layer's;
PrusaSlicer's own default is 0.3 mm), infill density (``print.infill``) and filament
density (``print.density_g_per_cm3``, so that PrusaSlicer reports grams). The .ini we
load is written next to the exports (``slicer/config.ini``) so the estimate can be
reproduced by hand::

    prusa-slicer --load slicer/config.ini --export-gcode --output part.gcode stl/part.stl
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import shutil
import subprocess
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

from .. import units
from ..kinematics.hand_params import Print

EXECUTABLE = "prusa-slicer"


@dataclass(frozen=True)
class PrintEstimate:
    time_s: float            # estimated printing time, normal mode
    time_text: str           # as PrusaSlicer prints it ("1h 2m 3s")
    filament_mm: float
    filament_cm3: float
    filament_g: float

    def as_dict(self) -> dict:
        return asdict(self)


class SlicerError(RuntimeError):
    pass


def find_slicer() -> str | None:
    """Path of the prusa-slicer executable, or None."""
    return shutil.which(EXECUTABLE)


def slicer_version(exe: str | None = None) -> str | None:
    exe = exe or find_slicer()
    if exe is None:
        return None
    out = subprocess.run([exe, "--help"], capture_output=True, text=True, timeout=60,
                         env=_env()).stdout
    m = re.search(r"PrusaSlicer-([^\s]+)", out)
    return m.group(1) if m else "unknown"


def config_ini(print_params: Print) -> str:
    """The PrusaSlicer config derived from ``params.print`` (a phantom_cad Print)."""
    density_g_cm3 = print_params.density / units.G_PER_CM3   # kg/m^3 -> g/cm^3
    return (
        "# PrusaSlicer config written by phantom_cad from params [print]; everything else\n"
        "# is PrusaSlicer's built-in default.\n"
        f"fill_density = {print_params.infill * 100:g}%\n"
        f"layer_height = {units.mm(print_params.layer_height):g}\n"
        f"first_layer_height = {units.mm(print_params.layer_height):g}\n"
        f"filament_density = {density_g_cm3:g}\n"
    )


def _env() -> dict:
    env = dict(os.environ)
    env.pop("DISPLAY", None)     # headless: never try to open the GUI
    env.pop("WAYLAND_DISPLAY", None)
    return env


_TIME = re.compile(r"^; estimated printing time \(normal mode\) = (.+)$", re.M)
_FIELDS = {
    "filament_mm": re.compile(r"^; filament used \[mm\] = ([0-9.eE+-]+)", re.M),
    "filament_cm3": re.compile(r"^; filament used \[cm3\] = ([0-9.eE+-]+)", re.M),
    "filament_g": re.compile(r"^; (?:total )?filament used \[g\] = ([0-9.eE+-]+)", re.M),
}


def parse_duration(text: str) -> float:
    """'1d 2h 3m 4s' -> seconds."""
    units = {"d": 86400, "h": 3600, "m": 60, "s": 1}
    parts = re.findall(r"(\d+)\s*([dhms])", text)
    if not parts:
        raise SlicerError(f"cannot read the printing time {text!r}")
    return float(sum(int(n) * units[u] for n, u in parts))


def parse_gcode(text: str) -> PrintEstimate:
    """Read PrusaSlicer's summary comments at the end of a G-code file."""
    m = _TIME.search(text)
    if not m:
        raise SlicerError("no '; estimated printing time (normal mode)' line in the G-code")
    values = {}
    for key, rx in _FIELDS.items():
        found = rx.search(text)
        if not found:
            raise SlicerError(f"no '{rx.pattern}' line in the G-code")
        values[key] = float(found.group(1))
    return PrintEstimate(time_s=parse_duration(m.group(1)), time_text=m.group(1).strip(), **values)


def _gcode(stl_path: Path, ini_text: str, exe: str | None, timeout: float, options: tuple = (),
           gcode_path: str | os.PathLike | None = None) -> str:
    """Slice one STL (or 3MF) with the given config and extra command-line ``options``; the G-code text
    (also kept at ``gcode_path`` when given)."""
    exe = exe or find_slicer()
    if exe is None:
        raise SlicerError(f"{EXECUTABLE} is not installed (Debian: apt-get install prusa-slicer; "
                          "see .ci/sysdeps)")
    with tempfile.TemporaryDirectory(prefix="phantom-slice-") as tmp:
        ini = Path(tmp) / "config.ini"
        ini.write_text(ini_text)
        out = Path(gcode_path).resolve() if gcode_path else Path(tmp) / "part.gcode"
        cmd = [exe, "--load", str(ini), *options, "--export-gcode", "--output", str(out), str(stl_path)]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=_env(), cwd=tmp)
        if proc.returncode != 0 or not out.exists():
            tail = "\n".join((proc.stderr + proc.stdout).strip().splitlines()[-5:])
            raise SlicerError(f"prusa-slicer failed on {stl_path} (exit {proc.returncode}): {tail}")
        return out.read_text(encoding="utf-8", errors="replace")


def slice_stl(stl_path: str | os.PathLike, ini_text: str, exe: str | None = None,
              gcode_path: str | os.PathLike | None = None, timeout: float = 600) -> PrintEstimate:
    """Slice one STL with the given config; return PrusaSlicer's estimates."""
    # PrusaSlicer runs in a scratch folder: relative paths (the default cache is .cache/) must
    # be made absolute first
    return parse_gcode(_gcode(Path(stl_path).resolve(), ini_text, exe, timeout, gcode_path=gcode_path))


#: the spacing (mm) of :func:`support_points`' samples
SUPPORT_SPACING = 0.25
#: PrusaSlicer's extrusion roles that are support
SUPPORT_ROLES = ("Support material", "Support material interface")
#: where the support slice centres the object (``--center``), bed mm
BED_CENTRE = (100.0, 100.0)


def support_points(text: str, spacing: float = SUPPORT_SPACING):
    """(n, 3) points (bed frame, mm) every ``spacing`` mm along the extrusions of a G-code file
    whose role (``;TYPE:``) is support (:data:`SUPPORT_ROLES`); z the layer's top (``;Z:``). A move
    extrudes when E grows (absolute E, ``M82``, with ``G92`` resets) or is positive (``M83``)."""
    import numpy as np

    pts: list = []
    role, z, x, y = None, 0.0, None, None
    relative, e = False, 0.0            # M82 (absolute E, PrusaSlicer's default) / M83; G92 E resets
    for line in text.splitlines():
        if line.startswith(";TYPE:"):
            role = line[6:].strip()
        elif line.startswith(";Z:"):
            z = float(line[3:])
        elif line.startswith(("M82", "M83")):
            relative = line.startswith("M83")
        elif line.startswith("G92"):
            words = dict((w[0], w[1:]) for w in line.split(";")[0].split()[1:] if w[0] == "E")
            e = float(words.get("E", e))
        elif line.startswith("G1 "):
            words = dict((w[0], w[1:]) for w in line.split(";")[0].split()[1:] if w[0] in "XYE")
            nx = float(words["X"]) if "X" in words else x
            ny = float(words["Y"]) if "Y" in words else y
            extrudes = False
            if "E" in words:
                de = float(words["E"]) if relative else float(words["E"]) - e
                e = e + de
                extrudes = de > 0.0
            if role in SUPPORT_ROLES and x is not None and nx is not None and extrudes and (nx, ny) != (x, y):
                n = max(int(math.hypot(nx - x, ny - y) / spacing), 1)
                t = np.linspace(0.0, 1.0, n + 1)
                pts.append(np.c_[x + t * (nx - x), y + t * (ny - y), np.full(n + 1, z)])
            x, y = nx, ny
    return np.vstack(pts) if pts else np.zeros((0, 3))


def slice_supports(stl_path: str | os.PathLike, ini_text: str, exe: str | None = None, timeout: float = 600,
                   project: str | os.PathLike | None = None):
    """Where PrusaSlicer puts support under an STL as it lies (its automatic supports, the
    config's other settings): :func:`support_points` moved into the STL's own frame (the object
    is centred on :data:`BED_CENTRE` by its bounding box and stands on the bed at z = 0).
    ``project``: slice that part's PrusaSlicer project instead (``export.project3mf``: the STL's
    mesh centred on its ``BED_CENTRE``, with its support blockers), where it lies."""
    from . import project3mf
    from .step_stl import read_stl

    stl_path = Path(stl_path).resolve()
    v, _ = read_stl(stl_path.read_bytes())
    centre = (v.min(axis=0) + v.max(axis=0)) / 2.0
    if project is None:
        bed = BED_CENTRE
        pts = support_points(_gcode(stl_path, ini_text, exe, timeout, options=(
            "--support-material", "--support-material-auto", "--center", f"{bed[0]:g},{bed[1]:g}")))
    else:
        bed = project3mf.BED_CENTRE
        pts = support_points(_gcode(Path(project).resolve(), ini_text, exe, timeout, options=(
            "--support-material", "--support-material-auto", "--dont-arrange")))
    pts[:, 0] += centre[0] - bed[0]
    pts[:, 1] += centre[1] - bed[1]
    pts[:, 2] += v[:, 2].min()
    return pts


def estimate_key(stl_bytes: bytes, ini_text: str, version: str | None) -> str:
    h = hashlib.sha256()
    for chunk in (stl_bytes, ini_text.encode(), (version or "").encode()):
        h.update(hashlib.sha256(chunk).digest())
    return h.hexdigest()
