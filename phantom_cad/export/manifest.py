"""manifest.json of an export directory: what was built from what, with checksums.

The manifest has no timestamps and no absolute paths, so the same parameters (and
the same tool versions) give the same manifest. Fields (see docs/exports.md):

``format``, ``hand`` {name, side, parts}, ``params`` {file, file_sha256, digest},
``versions`` {phantom_cad, python, build123d, cadquery-ocp, ..., prusa-slicer},
``settings`` {stl_tolerance_mm, angular_tolerance_rad, density_g_per_cm3, infill,
step_timestamp, mass_model}, ``parts`` [per part: name, digit, color, cache_key,
volume_mm3, area_mm2, mass_g, bbox_mm (link frame), print_bbox_mm, print_rotation,
overhang_mm2, print_transform,
T_hand_link (rest pose, from assembly.pose_transforms), stl_triangles, checks, print
(PrusaSlicer estimate or null)], ``assembly`` {bbox_mm, volume_mm3, mass_g,
interference}, ``totals`` {mass_g, print_time_s, filament_g, filament_mm}, ``slicer``,
``bom`` (rows), ``files`` {relative path: {sha256, bytes, kind, part?, volume_mm3?,
bbox_mm?, mass_g?}}.
"""

from __future__ import annotations

import hashlib
import platform
from pathlib import Path

import numpy as np

from .. import units
from ..canon import jsonable
from ..kinematics.hand_params import HandParams, Print
from .cache import cad_versions, code_digest, package_version
from .step_stl import ANGULAR_TOLERANCE_RAD, step_timestamp

MANIFEST_FORMAT = "phantom_cad.exports/1"


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def mass_g(volume_mm3: float, printing: Print) -> float:
    """Mass estimate (g) of a part printed with ``params.print`` (density, infill):
    cm^3 times g/cm^3 times infill."""
    return units.cm3(volume_mm3) * (printing.density / units.G_PER_CM3) * printing.infill


def _r(x: float, nd: int = 6) -> float:
    return round(float(x), nd)


def build_manifest(*, stage: Path, params: HandParams, params_path: Path, names, keys, metas, poses, estimates,
                   slicer_info, interference, contacts, bom) -> dict:
    printing = params.print
    parts = []
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    total_volume = 0.0
    for n in names:
        m = metas[n]
        T = np.asarray(poses[n], dtype=float)
        box = np.array([m["bbox_mm"]["min"], m["bbox_mm"]["max"]])
        corners = np.array([[box[i, 0], box[j, 1], box[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
        w = corners @ T[:3, :3].T + T[:3, 3]
        lo, hi = np.minimum(lo, w.min(axis=0)), np.maximum(hi, w.max(axis=0))
        total_volume += m["volume_mm3"]
        parts.append({
            "name": n,
            "digit": m["digit"],
            "color": m["color"],
            "cache_key": keys[n],
            "volume_mm3": _r(m["volume_mm3"], 4),
            "area_mm2": _r(m["area_mm2"], 4),
            "mass_g": _r(mass_g(m["volume_mm3"], printing), 6),
            "bbox_mm": m["bbox_mm"],
            "print_bbox_mm": m["print_bbox_mm"],
            "print_rotation": [[_r(x, 9) for x in row] for row in m["print_rotation"]],
            # area (mm^2) facing down more steeply than 45 deg off the bed (export/orient.py)
            "overhang_mm2": m.get("overhang_mm2"),
            # STL vertex = print_transform @ link-frame vertex (rotation, then resting on z = 0)
            "print_transform": [[_r(x, 9) for x in row] for row in m["print_transform"]],
            "T_hand_link": [[_r(x, 9) for x in row] for row in T.tolist()],
            "stl_triangles": m["stl"]["triangles"],
            # print/<name>.3mf: the STL's mesh (centred on project3mf.BED_CENTRE) and this many
            # support blockers over its tendon features (cad/parts/tendons.feature_blockers)
            "support_blockers": m.get("support_blockers", 0),
            "checks": {
                "one_valid_solid": True,
                "verify_part": m.get("verify_part", "skipped"),
                "step_reimport_volume_mm3": _r(m["step"]["reimport_volume_mm3"], 4),
                "stl_watertight": m["stl"]["watertight"],
                "stl_is_volume": m["stl"]["is_volume"],
                "stl_manifold3d": m["stl"]["manifold"],
                "stl_volume_mm3": _r(m["stl"]["mesh_volume_mm3"], 4),
            },
            "print": estimates.get(n),
        })

    files = {}
    by_file = {}
    for p in parts:
        by_file[f"step/{p['name']}.step"] = ("step", p, p["bbox_mm"], p["volume_mm3"])
        by_file[f"stl/{p['name']}.stl"] = ("stl", p, p["print_bbox_mm"], p["checks"]["stl_volume_mm3"])
        by_file[f"print/{p['name']}.3mf"] = ("print_project", p, None, None)
        by_file[f"renders/{p['name']}.png"] = ("render", p, None, None)
    asm_box = {"min": [_r(x) for x in lo], "max": [_r(x) for x in hi]}
    by_file["step/hand_assembly.step"] = ("assembly_step", None, asm_box, _r(total_volume, 4))
    by_file["renders/hand_assembly.png"] = ("render", None, None, None)
    for path in sorted(p for p in stage.rglob("*") if p.is_file()):
        rel = path.relative_to(stage).as_posix()
        if rel == "manifest.json":
            continue
        entry = {"sha256": file_sha256(path), "bytes": path.stat().st_size}
        kind, part, box, vol = by_file.get(rel, (rel.split("/")[0] if "/" in rel else rel.split(".")[-1],
                                                 None, None, None))
        entry["kind"] = kind
        if part is not None:
            entry["part"] = part["name"]
        if vol is not None:
            entry["volume_mm3"] = vol
            entry["mass_g"] = _r(mass_g(vol, printing), 6)
        if box is not None:
            entry["bbox_mm"] = box
        files[rel] = entry

    est = [e for e in estimates.values() if e]
    totals = {"parts": len(names), "volume_mm3": _r(total_volume, 4),
              "mass_g": _r(mass_g(total_volume, printing), 6)}
    if est and len(est) == len(names):
        totals.update({
            "print_time_s": sum(e["time_s"] for e in est),
            "filament_g": _r(sum(e["filament_g"] for e in est), 3),
            "filament_mm": _r(sum(e["filament_mm"] for e in est), 3),
        })
    versions = {"phantom_cad": package_version("phantom_cad"), "python": platform.python_version(), **cad_versions(),
                "prusa-slicer": slicer_info.get("version")}
    return {
        "format": MANIFEST_FORMAT,
        "hand": {"name": params.name, "side": params.side, "parts": list(names)},
        "params": {"file": Path(params_path).name, "file_sha256": file_sha256(Path(params_path)),
                   "digest": params.digest},
        "versions": versions,
        "code_digest": code_digest(),
        "settings": {
            "units": "mm",
            "stl_tolerance_mm": _r(units.mm(printing.stl_tolerance), 9),
            "angular_tolerance_rad": ANGULAR_TOLERANCE_RAD,
            "stl_format": "binary, fixed header, print orientation resting on z = 0",
            "density_g_per_cm3": _r(printing.density / units.G_PER_CM3, 9),
            "infill": printing.infill,
            "mass_model": "mass_g = volume x density x infill",
            "step_timestamp": step_timestamp(),
        },
        "totals": totals,
        "assembly": {"file": "step/hand_assembly.step", "pose": "rest (q = 0)", "bbox_mm": asm_box,
                     "designed_contacts": [list(c) for c in contacts],
                     "interference": interference},
        "slicer": slicer_info,
        "bom": jsonable(bom),
        "parts": parts,
        "files": files,
    }
