"""The worker processes of the build: one part (build, verify, STEP, STL, render into its
cache entry), the assembly STEP and the assembly render.

Workers receive plain tasks (the plain parameter document, which they re-parse, and the name
of the assembly module, :mod:`phantom_cad.export.interface`) and return plain dicts; a
failure is reported, never raised, so one broken part does not bring the pool down.
build123d/OCP are imported inside the workers.
"""

from __future__ import annotations

import json
import shutil
import time
import traceback
from pathlib import Path

import numpy as np

from .. import units
from ..atomic import write_atomic
from ..canon import jsonable, sha256
from ..params import parse
from ..workers import apply_environment, die_with_parent, keep_freed_memory
from ..kinematics.hand_params import HandParams
from . import interface, orient
from .cache import Cache, seal
from .manifest import mass_g
from .results import failure_from

#: STEP re-import must give the same volume to this relative tolerance
STEP_VOLUME_RTOL = 1e-3
#: STL volume vs solid volume (tessellation removes material on convex faces)
STL_VOLUME_RTOL = 1e-2


#: the module the build's fork server imports for its workers (``workers.mp_context``)
PRELOAD = ("phantom_cad.export.pool_preload",)


def init_worker(parent_pid: int | None, occt_threads: int | None, environ: dict[str, str] | None = None) -> None:
    """Pool initializer of the build's workers: the environment ``environ`` of the process that
    starts the pool where given (``workers.apply_environment``: a fork server's worker would have
    the server's), die with the parent (``workers.die_with_parent``),
    keep the memory they free for reuse (``workers.keep_freed_memory``), load build123d now,
    without scikit-learn (``cad.kernel.import_build123d``), and when ``occt_threads`` is given
    run OpenCascade on that many threads (``cad.kernel.use_threads``: the pipeline gives each
    worker its share of the CPUs when the workers fill them)."""
    from ..cad import kernel

    if environ is not None:
        apply_environment(environ)
    die_with_parent(parent_pid)
    keep_freed_memory()
    kernel.import_build123d()
    if occt_threads is not None:
        kernel.use_threads(occt_threads)


def _bbox(v: np.ndarray) -> dict:
    return {"min": [round(float(x), 6) for x in v.min(axis=0)],
            "max": [round(float(x), 6) for x in v.max(axis=0)]}


def _check(asm, params: HandParams, name: str, shape) -> str:
    """The part's one validity check and its measured verification: the assembly module's
    ``verify_part`` when it has one ("ok", or CheckError listing the problems), else only
    ``phantom_cad.cad.verify.check_solid`` ("skipped": nothing measured)."""
    from ..cad import verify

    if not hasattr(asm, "verify_part"):
        verify.check_solid(name, shape)
        return "skipped"
    problems = asm.verify_part(params, name, shape)
    if problems:
        raise verify.CheckError(name, "verify_part", "; ".join(problems))
    return "ok"


def _checked_stl(name: str, v, f, volume: float) -> tuple[bytes, dict]:
    """The binary STL of a mesh and the checks of what is written: the float32 mesh read back from
    the STL bytes (``step_stl.check_mesh``, against the solid's volume)."""
    from . import step_stl

    stl = step_stl.stl_bytes(v, f, name)
    sv, sf = step_stl.read_stl(stl)
    return stl, step_stl.check_mesh(name, sv, sf, volume, STL_VOLUME_RTOL)


def part_worker(task: dict) -> dict:
    """Build, check and export one part into its cache entry. Runs in a worker process."""
    name = task["name"]
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    inputs = None
    try:
        params = parse(task["document"], source=task["source"])
        asm = interface.assembly(task.get("assembly_module"))
        inputs = asm.part_inputs(params, name)
        from . import description, project3mf, render, step_stl

        built = asm.build_part(params, name)
        timings["build_part"] = time.perf_counter() - t0
        if built.name != name:
            raise step_stl.CheckError(name, "name", f"build_part returned a part named {built.name!r}")
        shape = built.shape
        verified = _check(asm, params, name, shape)
        from ..cad.measure import mass_properties
        mass_props = mass_properties(shape)     # link frame: the description's inertials
        volume = mass_props["volume_mm3"]       # OpenCascade's volume properties, computed once
        area = float(shape.area)

        cache = Cache(task["cache_root"])
        final = cache.part_dir(task["key"])
        tmp = cache.staging(final)
        t = time.perf_counter()
        (tmp / "part.brep").write_bytes(step_stl.brep_bytes(shape))
        step = step_stl.step_bytes(shape, label=name, color=built.color)
        (tmp / "part.step").write_bytes(step)
        reimported = step_stl.step_volume(tmp / "part.step")
        if abs(reimported - volume) > STEP_VOLUME_RTOL * volume:
            raise step_stl.CheckError(name, "STEP round trip",
                                      f"re-imported volume {reimported:.4f} mm^3 vs {volume:.4f} mm^3")
        timings["step"] = time.perf_counter() - t

        t = time.perf_counter()
        tol_mm = units.mm(params.print.stl_tolerance)
        # one mesh for the STL, the descriptions, the checks and the pictures
        v, f = step_stl.tessellate(shape, tol_mm)
        R = np.asarray(built.print_rotation, dtype=float)
        if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
            raise step_stl.CheckError(name, "print_rotation", f"not a proper rotation: {R.tolist()}")
        # the declared orientation or an axis-aligned one with less overhang (export/orient.py)
        R, overhang_mm2 = orient.print_rotation(v, f, R)
        vp, T_print = step_stl.to_print_pose(v, R)
        stl, mesh_checks = _checked_stl(name, vp, f, volume)
        (tmp / "part.stl").write_bytes(stl)
        # the PrusaSlicer project: the part as in the STL, and the support blockers that hold in
        # this orientation (a groove's only with its axis flat), moved alike
        blockers = [(b.label, b.vertices @ T_print[:3, :3].T + T_print[:3, 3], b.faces)
                    for b in getattr(built, "blockers", ()) if b.holds(R[2])]
        (tmp / "part.3mf").write_bytes(project3mf.project_bytes(name, vp, f, blockers))
        np.savez(tmp / "mesh.npz", vertices=v, faces=f.astype(np.int32))
        # the robot description's; a part's convex collision solids (if it names them) each give
        # one collision piece
        pieces = [step_stl.tessellate(c, tol_mm)[0] for c in getattr(built, "collision", ())]
        meshes = description.part_meshes(v, f, name, pieces)
        for kind, data in meshes.items():
            (tmp / description.MESH_FILES[kind]).write_bytes(data)
        n_collision = len(description.collision_pieces(meshes["collision"]))
        timings["stl"] = time.perf_counter() - t

        meta = {
            "name": name,
            "digit": built.digit,
            "color": [float(c) for c in built.color],
            "collision_pieces": n_collision,
            "print_rotation": R.tolist(),
            "overhang_mm2": round(overhang_mm2, 3),
            "print_transform": T_print.tolist(),
            "T_hand_link": np.asarray(built.T_hand_link, dtype=float).tolist(),
            "volume_mm3": volume,
            "mass_properties": mass_props,
            "area_mm2": area,
            "bbox_mm": _bbox(v),
            "print_bbox_mm": _bbox(vp),
            "support_blockers": len(blockers),
            "stl": {"sha256": sha256(stl), "bytes": len(stl), **mesh_checks},
            "step": {"sha256": sha256(step), "bytes": len(step), "reimport_volume_mm3": reimported},
            "part_inputs": jsonable(inputs),
            "verify_part": verified,
        }
        if task.get("render", True):
            t = time.perf_counter()
            mass = mass_g(volume, params.print)
            render.render_png(
                [render.MeshItem(name, vp, f, tuple(built.color), closed=True)], tmp / "render.png",
                title=f"{name}  (print orientation)",
                subtitle=(f"{units.cm3(volume):.2f} cm³, ~{mass:.1f} g at {params.print.infill:.0%} infill, "
                          f"bbox {np.ptp(vp[:, 0]):.1f} x {np.ptp(vp[:, 1]):.1f} x {np.ptp(vp[:, 2]):.1f} mm"),
                size_px=700, bed=True)
            timings["render"] = time.perf_counter() - t
        # what the cache serves is checked against these hashes (Cache.part_problem)
        meta["files"] = {f.name: sha256(f.read_bytes()) for f in sorted(tmp.iterdir())}
        (tmp / "meta.json").write_text(json.dumps(meta, indent=1, sort_keys=True))
        Cache.commit(tmp, final)
        timings["total"] = time.perf_counter() - t0
        return {"name": name, "ok": True, "timings": timings}
    except BaseException as exc:  # report, never crash the pool
        failure = failure_from(name, exc, inputs)
        c = Cache(task["cache_root"])
        shutil.rmtree(c.staging_path(c.part_dir(task["key"])), ignore_errors=True)
        return {"name": name, "ok": False, "failure": failure.__dict__}


def aid_worker(task: dict) -> dict:
    """Build, verify and export a print aid (``cad.print_aids``, ``task["kind"]``) into its cache
    entry: STEP, STL (as built: it prints flat side down), the maker's sheet and a picture."""
    from ..cad import verify
    from ..cad.print_aids import BY_KIND

    aid = BY_KIND[task["kind"]]
    try:
        params = parse(task["document"], source=task["source"])
        from . import render, step_stl

        a = aid(params)
        shape = a.build()
        verify.check_solid(aid.name, shape)
        problems = a.verify(shape)
        volume = float(shape.volume)
        if abs(volume - a.volume()) > 1e-6 * a.volume():
            problems.append(f"{aid.name}: volume {volume:.4f} mm^3, closed form {a.volume():.4f}")
        if problems:
            raise verify.CheckError(aid.name, "verify", "; ".join(problems))
        cache = Cache(task["cache_root"])
        final = cache.aid_dir(aid, task["key"])
        tmp = cache.staging(final)
        step = step_stl.step_bytes(shape, label=aid.name, color=a.color)
        (tmp / f"{aid.name}.step").write_bytes(step)
        v, f = step_stl.tessellate(shape, units.mm(params.print.stl_tolerance))
        stl, mesh_checks = _checked_stl(aid.name, v, f, volume)
        (tmp / f"{aid.name}.stl").write_bytes(stl)
        (tmp / f"{aid.name}.md").write_text(a.table(), encoding="utf-8")
        if task.get("render", True):
            render.render_png([render.MeshItem(aid.name, v, f, tuple(a.color), closed=True)], tmp / "render.png",
                              title=f"{aid.name}  (print orientation)", subtitle=a.subtitle(), size_px=700, bed=True)
        meta = {"name": aid.name, "volume_mm3": volume, "bbox_mm": _bbox(v),
                "mass_g": mass_g(volume, params.print),
                "stl": {"sha256": sha256(stl), "bytes": len(stl), **mesh_checks}, **a.meta()}
        (tmp / "meta.json").write_text(json.dumps(jsonable(meta), indent=1, sort_keys=True))
        seal(tmp)
        Cache.commit(tmp, final)
        return {"ok": True}
    except BaseException as exc:  # report, never crash the pool
        c = Cache(task["cache_root"])
        shutil.rmtree(c.staging_path(c.aid_dir(aid, task["key"])), ignore_errors=True)
        return {"ok": False, "failure": failure_from(aid.name, exc, None).__dict__}


def assembly_step_worker(task: dict) -> dict:
    """hand_assembly.step from the cached BREPs placed at the rest pose."""
    try:
        from build123d import Color, Compound

        from . import step_stl

        children = []
        for name, part_dir, T, color in task["parts"]:
            shape = step_stl.read_brep(Path(part_dir) / "part.brep")
            placed = step_stl.transform_shape(shape, np.asarray(T))
            placed.label = name
            placed.color = Color(*color)
            children.append(placed)
        hand = Compound(children=children, label=task["label"])
        data = step_stl.step_bytes(hand)
        out = Path(task["out"])
        write_atomic(out, data)
        return {"ok": True, "sha256": sha256(data)}
    except BaseException as exc:
        return {"ok": False, "error": f"{type(exc).__name__}: {exc}",
                "traceback": "".join(traceback.format_exception(exc))}


def assembly_render_worker(task: dict) -> dict:
    try:
        from . import render

        items = []
        for name, part_dir, T, color, digit in task["parts"]:
            d = np.load(Path(part_dir) / "mesh.npz")
            T = np.asarray(T)
            v = d["vertices"] @ T[:3, :3].T + T[:3, 3]
            # each digit's name on all its parts (drawn once, over what shows of them), the palm's
            label = digit or ("palm" if name == "palm" else None)
            items.append(render.MeshItem(name, v, d["faces"], tuple(color), label, closed=True))
        render.render_png(items, task["out"], title=task["title"], subtitle=task["subtitle"],
                          elev=28.0, azim=-62.0, size_px=1000)
        return {"ok": True}
    except BaseException as exc:
        return {"ok": False, "error": f"{type(exc).__name__}: {exc}",
                "traceback": "".join(traceback.format_exception(exc))}
