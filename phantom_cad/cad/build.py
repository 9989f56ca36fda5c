"""``phantom-cad build``: every printable part of the hand from the parameter file.

    from phantom_cad.cad.build import build_hand
    result = build_hand("params/phantom.toml", "exports/phantom")

Writes ``exports/<hand>/`` (see docs/exports.md): ``step/<part>.step``,
``step/hand_assembly.step``, ``stl/<part>.stl`` (print orientation), ``bom.csv``,
``manifest.json``, ``renders/*.png`` and ``slicer/config.ini``.

Pipeline
--------
1. parse the parameter file (``--side`` overrides ``hand.side``) and hash every part's
   ``assembly.part_inputs`` into a cache key (:mod:`phantom_cad.cad.cache`);
2. build the parts missing from the cache in parallel worker processes (each worker gets
   the plain parameter document and re-parses it); a worker builds the part
   (``assembly.build_part``), checks it is one valid solid and measures it against the
   parameters (``phantom_cad.check.verify_part``), writes BREP/STEP, re-imports
   the STEP (same volume), tessellates it (``print.stl_tolerance``), checks the mesh
   (watertight, manifold, volume) and renders it;
3. the assembly STEP (parts placed with ``assembly.pose_transforms``), the assembly
   render and the interference check (manifold3d booleans of the placed meshes; only
   ``assembly.designed_contacts`` may overlap) are cached under a key of all part keys
   and poses;
4. every STL is sliced with PrusaSlicer (when installed) for print time and filament;
5. everything is written into a temporary directory beside the target, which replaces
   the previous export only when the whole build succeeded.

The module imports numpy only; build123d/OCP are imported inside the workers.
"""

from __future__ import annotations

import copy
import csv
import io
import json
import multiprocessing
import os
import shutil
import sys
import time
import traceback
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..atomic import replace_dir, write_atomic
from ..params import ParamError, load_document, parse
from ..params.io import DEFAULT_PARAMS
from ..params.schema import _plain
from . import cache as cache_mod
from .cache import Cache, canonical, jsonable, sha256
from ..export.manifest import mass_g

#: coarse tessellation used only for pictures (mm, rad)
VIEW_TOLERANCE_MM = 0.15
VIEW_ANGULAR_TOLERANCE_RAD = 0.35
#: STEP re-import must give the same volume to this relative tolerance
STEP_VOLUME_RTOL = 1e-3
#: STL volume vs solid volume (tessellation removes material on convex faces)
STL_VOLUME_RTOL = 1e-2
#: overlap volume (mm^3) above which two placed parts count as intersecting; it absorbs
#: the tessellation error (params.print.stl_tolerance) of parts that merely touch
INTERFERENCE_TOL_MM3 = 1.0


# ---------------------------------------------------------------------------
# results and errors

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


# ---------------------------------------------------------------------------
# helpers

#: the module providing the parts (cad_interface.md); tests may install a stand-in
ASSEMBLY_MODULE = "phantom_cad.cad.assembly"


def _assembly(module: str | None = None):
    """The parts module (imported lazily; it imports OCP only inside build_part)."""
    import importlib

    return importlib.import_module(module or ASSEMBLY_MODULE)


def _load(params_path, side):
    path = Path(params_path) if params_path is not None else DEFAULT_PARAMS
    document = load_document(path)
    file_side = (document.get("hand") or {}).get("side") if isinstance(document.get("hand"), dict) else None
    if side is not None:
        document = copy.deepcopy(document)
        if not isinstance(document.get("hand"), dict):
            raise ParamError("hand", document.get("hand"), "must be a table", str(path))
        document["hand"]["side"] = side
    params = parse(document, source=str(path))
    return path, document, params, file_side


def _default_out(params, side, file_side) -> Path:
    name = params.name
    if side is not None and side != file_side:
        name = f"{name}_{side}"
    return Path("exports") / name


def _failure_from(name: str, exc: BaseException, inputs) -> PartFailure:
    from ..export.step_stl import CheckError

    fld = getattr(exc, "field", None) if isinstance(exc, ParamError) else None
    chk = exc.check if isinstance(exc, CheckError) else None
    return PartFailure(part=name, error=f"{type(exc).__name__}: {exc}", field=fld, check=chk,
                       part_inputs=jsonable(inputs) if inputs is not None else None,
                       traceback="".join(traceback.format_exception(exc)))


def _mp_context():
    """fork when this process has not loaded OCP yet (fast: the CLI's case); spawn once OCP
    is loaded (its thread pools make a forked child deadlock) or where fork is missing."""
    methods = multiprocessing.get_all_start_methods()
    ocp_loaded = any(m == "OCP" or m.startswith("OCP.") for m in sys.modules)
    return multiprocessing.get_context("fork" if "fork" in methods and not ocp_loaded else "spawn")


def _bbox(v: np.ndarray) -> dict:
    return {"min": [round(float(x), 6) for x in v.min(axis=0)],
            "max": [round(float(x), 6) for x in v.max(axis=0)]}


# ---------------------------------------------------------------------------
# worker: one part

def _verify(params, name: str, shape, module: str | None) -> str:
    """Helper A's measured part-vs-parameters verification (phantom_cad.check.verify_part:
    groove radii, guide eyelets, magnet pockets, ...). Runs for the real parts module only.
    Returns "ok" or "skipped"; raises CheckError listing the problems."""
    if (module or ASSEMBLY_MODULE) != "phantom_cad.cad.assembly":
        return "skipped"
    try:
        from ..check import verify_part
    except ImportError:
        return "skipped"
    problems = verify_part(params, name, shape)
    if problems:
        from ..export.step_stl import CheckError

        raise CheckError(name, "verify_part", "; ".join(problems))
    return "ok"


def _part_worker(task: dict) -> dict:
    """Build, check and export one part into its cache entry. Runs in a worker process."""
    name = task["name"]
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    inputs = None
    try:
        params = parse(task["document"], source=task["source"])
        asm = _assembly(task.get("assembly_module"))
        inputs = asm.part_inputs(params, name)
        from ..export import render, step_stl

        built = asm.build_part(params, name)
        timings["build_part"] = time.perf_counter() - t0
        if built.name != name:
            raise step_stl.CheckError(name, "name", f"build_part returned a part named {built.name!r}")
        shape = built.shape
        step_stl.check_solid(name, shape)
        verified = _verify(params, name, shape, task.get("assembly_module"))
        volume = float(shape.volume)
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
        tol_mm = params.print.stl_tolerance * 1000.0
        vv, fv = step_stl.tessellate(shape, VIEW_TOLERANCE_MM, VIEW_ANGULAR_TOLERANCE_RAD)
        v, f = step_stl.tessellate(shape, tol_mm)
        R = np.asarray(built.print_rotation, dtype=float)
        if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
            raise step_stl.CheckError(name, "print_rotation", f"not a proper rotation: {R.tolist()}")
        vp, T_print = step_stl.to_print_pose(v, R)
        stl = step_stl.stl_bytes(vp, f, name)
        # check what is written: the float32 mesh read back from the STL bytes
        sv, sf = step_stl.read_stl(stl)
        mesh_checks = step_stl.check_mesh(name, sv, sf, volume, STL_VOLUME_RTOL)
        (tmp / "part.stl").write_bytes(stl)
        np.savez(tmp / "mesh.npz", vertices=v, faces=f.astype(np.int32))
        np.savez(tmp / "view.npz", vertices=vv, faces=fv.astype(np.int32))
        timings["stl"] = time.perf_counter() - t

        meta = {
            "name": name,
            "digit": built.digit,
            "color": [float(c) for c in built.color],
            "print_rotation": R.tolist(),
            "print_transform": T_print.tolist(),
            "T_hand_link": np.asarray(built.T_hand_link, dtype=float).tolist(),
            "volume_mm3": volume,
            "area_mm2": area,
            "bbox_mm": _bbox(v),
            "print_bbox_mm": _bbox(vp),
            "stl": {"sha256": sha256(stl), "bytes": len(stl), **mesh_checks},
            "step": {"sha256": sha256(step), "bytes": len(step), "reimport_volume_mm3": reimported},
            "part_inputs": jsonable(inputs),
            "verify_part": verified,
        }
        if task.get("render", True):
            t = time.perf_counter()
            vpv = (vv @ R.T) + T_print[:3, 3]
            mass = mass_g(volume, params.print)
            render.render_png(
                [render.MeshItem(name, vpv, fv, tuple(built.color))], tmp / "render.png",
                title=f"{name}  (print orientation)",
                subtitle=(f"{volume / 1000:.2f} cm³, ~{mass:.1f} g at {params.print.infill:.0%} infill, "
                          f"bbox {np.ptp(vp[:, 0]):.1f} x {np.ptp(vp[:, 1]):.1f} x {np.ptp(vp[:, 2]):.1f} mm"),
                size_px=700, bed=True)
            timings["render"] = time.perf_counter() - t
        (tmp / "meta.json").write_text(json.dumps(meta, indent=1, sort_keys=True))
        Cache.commit(tmp, final)
        timings["total"] = time.perf_counter() - t0
        return {"name": name, "ok": True, "timings": timings}
    except BaseException as exc:  # report, never crash the pool
        failure = _failure_from(name, exc, inputs)
        c = Cache(task["cache_root"])
        shutil.rmtree(c.staging_path(c.part_dir(task["key"])), ignore_errors=True)
        return {"name": name, "ok": False, "failure": failure.__dict__}


# ---------------------------------------------------------------------------
# worker: assembly STEP and render

def _assembly_step_worker(task: dict) -> dict:
    """hand_assembly.step from the cached BREPs placed at the rest pose."""
    try:
        from build123d import Color, Compound

        from ..export import step_stl

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


def _assembly_render_worker(task: dict) -> dict:
    try:
        from ..export import render

        items = []
        labelled = set()
        for name, part_dir, T, color, digit in task["parts"]:
            d = np.load(Path(part_dir) / "view.npz")
            T = np.asarray(T)
            v = d["vertices"] @ T[:3, :3].T + T[:3, 3]
            label = None
            key = digit or name
            if key not in labelled and (digit is not None or name == "palm"):
                labelled.add(key)
                label = key
            items.append(render.MeshItem(name, v, d["faces"], tuple(color), label))
        render.render_png(items, task["out"], title=task["title"], subtitle=task["subtitle"],
                          elev=28.0, azim=-62.0, size_px=1000, max_faces=150000)
        return {"ok": True}
    except BaseException as exc:
        return {"ok": False, "error": f"{type(exc).__name__}: {exc}",
                "traceback": "".join(traceback.format_exception(exc))}


# ---------------------------------------------------------------------------
# interference

def interference(meshes: dict[str, tuple[np.ndarray, np.ndarray]], poses: dict[str, np.ndarray],
                 allowed: set[frozenset], tol_mm3: float = INTERFERENCE_TOL_MM3) -> dict:
    """Pairwise intersection volumes of the placed meshes (manifold3d booleans).

    ``meshes`` are in link frames (mm), ``poses`` the 4x4 placements. Pairs whose boxes
    do not overlap are skipped. Returns {"checked_pairs", "collisions": [...],
    "designed_contacts": [...]} where a collision is a non-designed pair overlapping by more
    than ``tol_mm3``."""
    import manifold3d

    names = sorted(meshes)
    placed, boxes = {}, {}
    for n in names:
        v, f = meshes[n]
        T = np.asarray(poses[n], dtype=float)
        w = v @ T[:3, :3].T + T[:3, 3]
        boxes[n] = (w.min(axis=0), w.max(axis=0))
        placed[n] = (w, f)
    solids: dict[str, Any] = {}

    def solid(n):
        if n not in solids:
            w, f = placed[n]
            solids[n] = manifold3d.Manifold(manifold3d.Mesh(
                vert_properties=w.astype(np.float32), tri_verts=f.astype(np.uint32)))
        return solids[n]

    checked, collisions, contacts, largest = 0, [], [], None
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            (alo, ahi), (blo, bhi) = boxes[a], boxes[b]
            if np.any(alo > bhi) or np.any(blo > ahi):
                continue
            checked += 1
            vol = float((solid(a) ^ solid(b)).volume())
            designed = frozenset((a, b)) in allowed
            entry = {"parts": [a, b], "volume_mm3": round(max(vol, 0.0), 4) + 0.0}
            if designed:
                contacts.append(entry)
            else:
                if largest is None or vol > largest["volume_mm3"]:
                    largest = entry
                if vol > tol_mm3:
                    collisions.append(entry)
    return {"checked_pairs": checked, "tolerance_mm3": tol_mm3,
            "collisions": collisions, "designed_contacts": contacts,
            "largest_other_overlap": largest}


# ---------------------------------------------------------------------------
# the build

def build_hand(params_path: str | os.PathLike | None = None, out_dir: str | os.PathLike | None = None,
               side: str | None = None, jobs: int | None = None, *, slice: bool | None = False,
               render: bool = True, cache_dir: str | os.PathLike | None = None,
               check_interference: bool = True,
               log: Callable[[str], None] | None = None) -> BuildResult:
    """Build every part of the hand described by ``params_path`` into ``out_dir``.

    ``side`` overrides ``hand.side``; ``jobs`` worker processes (default os.cpu_count());
    ``slice`` False = skip (default: slicing every part costs ~1-4 s each, cached after),
    True = slice with PrusaSlicer (error if missing), None = slice when it is installed;
    ``cache_dir`` default ``$PHANTOM_CAD_CACHE`` or ``.cache``.
    Raises :class:`BuildError` (nothing written) or :class:`ParamError`.
    """
    from ..export import manifest as manifest_mod
    from ..export import slicer

    log = log or (lambda msg: None)
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    path, document, params, file_side = _load(params_path, side)
    out = Path(out_dir) if out_dir is not None else _default_out(params, side, file_side)
    jobs = max(1, int(jobs or os.cpu_count() or 1))
    cache = Cache(cache_dir)
    asm = _assembly()

    names = list(asm.part_names(params))
    if len(set(names)) != len(names):
        raise BuildError(f"assembly.part_names gives duplicate names: {names}")
    inputs, keys = {}, {}
    for n in names:
        try:
            inputs[n] = asm.part_inputs(params, n)
        except Exception as exc:
            raise BuildError("cannot compute the part inputs", [_failure_from(n, exc, None)]) from exc
        keys[n] = cache_mod.part_key(params, n, inputs[n])
    missing = [n for n in names if not cache.has_part(keys[n])]
    timings["prepare"] = time.perf_counter() - t_start

    pool: ProcessPoolExecutor | None = None
    astage: Path | None = None

    def get_pool() -> ProcessPoolExecutor:
        nonlocal pool
        if pool is None:
            pool = ProcessPoolExecutor(max_workers=jobs, mp_context=_mp_context())
        return pool

    try:
        # 1. parts -----------------------------------------------------------------
        t = time.perf_counter()
        part_timings: dict[str, dict] = {}
        if missing:
            log(f"building {len(missing)} of {len(names)} parts with {jobs} worker(s)")
            plain = _plain(document)
            tasks = [{"name": n, "key": keys[n], "document": plain, "source": str(path),
                      "assembly_module": asm.__name__,
                      "cache_root": str(cache.root), "render": render} for n in missing]
            if jobs == 1 or len(missing) == 1:
                results = [_part_worker(task) for task in tasks]
            else:
                try:
                    results = list(get_pool().map(_part_worker, tasks))
                except BrokenProcessPool as exc:
                    raise BuildError(f"a worker process died while building {missing} "
                                     f"(crash in OCP?): {exc}; {out} was left untouched") from exc
            failures = []
            for r in results:
                if r["ok"]:
                    part_timings[r["name"]] = r["timings"]
                else:
                    failures.append(PartFailure(**r["failure"]))
            if failures:
                raise BuildError(f"{len(failures)} part(s) failed; {out} was left untouched", failures)
        timings["parts"] = time.perf_counter() - t
        metas = {n: cache.part_meta(keys[n]) for n in names}

        # 2. assembly: poses, STEP, render, interference ----------------------------
        t = time.perf_counter()
        poses = {n: np.asarray(T, dtype=float) for n, T in asm.pose_transforms(params).items()}
        absent = [n for n in names if n not in poses]
        if absent:
            raise BuildError(f"assembly.pose_transforms has no placement for {absent}")
        contacts = [tuple(c) for c in asm.designed_contacts(params)]
        allowed = {frozenset(c[:2]) for c in contacts}
        akey = sha256(canonical({
            "keys": [keys[n] for n in names],
            "poses": {n: np.round(poses[n], 9) for n in names},
            "contacts": sorted(sorted(c[:2]) for c in contacts),
            "label": params.name, "render": render, "tol": INTERFERENCE_TOL_MM3,
            "code": cache_mod.code_digest(),
        }))
        adir = cache.assembly_dir(akey)
        futures: dict[str, Future] = {}
        if not (adir / "interference.json").is_file():
            astage = cache.staging(adir)
            parts_arg = [(n, str(cache.part_dir(keys[n])), poses[n].tolist(), metas[n]["color"]) for n in names]
            futures["step"] = get_pool().submit(_assembly_step_worker, {
                "parts": parts_arg, "label": f"{params.name}_{params.side}",
                "out": str(astage / "hand_assembly.step")})
            if render:
                futures["render"] = get_pool().submit(_assembly_render_worker, {
                    "parts": [p + (metas[p[0]]["digit"],) for p in parts_arg],
                    "out": str(astage / "render.png"),
                    "title": f"{params.name} hand ({params.side}), rest pose, {len(names)} parts",
                    "subtitle": f"parameters {params.digest[:12]}"})
            if check_interference:
                meshes = {}
                for n in names:
                    d = np.load(cache.part_dir(keys[n]) / "mesh.npz")
                    meshes[n] = (d["vertices"], d["faces"])
                inter = interference(meshes, poses, allowed)
            else:
                inter = {"skipped": True}
            for what, fut in futures.items():
                r = fut.result()
                if not r["ok"]:
                    raise BuildError(f"assembly {what} failed: {r['error']}\n{r['traceback']}")
            if inter.get("collisions"):
                shutil.rmtree(astage, ignore_errors=True)
                lines = [f"  {c['parts'][0]} x {c['parts'][1]}: {c['volume_mm3']:.3f} mm^3"
                         for c in inter["collisions"]]
                raise BuildError(
                    f"parts intersect at the rest pose (overlap > {INTERFERENCE_TOL_MM3} mm^3, not in "
                    f"assembly.designed_contacts); {out} was left untouched:\n" + "\n".join(lines))
            cache.write_json(astage / "interference.json", inter)
            Cache.commit(astage, adir)
            astage = None
        inter = json.loads((adir / "interference.json").read_text())
        timings["assembly"] = time.perf_counter() - t

        # 3. slicing -----------------------------------------------------------------
        t = time.perf_counter()
        exe = slicer.find_slicer() if slice is not False else None
        if slice is True and exe is None:
            raise BuildError("--slice: prusa-slicer is not installed (bash .ci/sysdeps, or apt-get install "
                             "prusa-slicer)")
        estimates: dict[str, dict | None] = {n: None for n in names}
        ini = slicer.config_ini(params.print)
        slicer_info: dict[str, Any] = {"used": False}
        if exe is not None:
            version = slicer.slicer_version(exe)
            slicer_info = {"used": True, "program": "PrusaSlicer", "version": version,
                           "config": "slicer/config.ini"}

            def one(n):
                stl_path = cache.part_dir(keys[n]) / "part.stl"
                skey = slicer.estimate_key(stl_path.read_bytes(), ini, version)
                sfile = cache.slice_file(skey)
                if sfile.is_file():
                    return n, json.loads(sfile.read_text())
                try:
                    est = slicer.slice_stl(stl_path, ini, exe).as_dict()
                except Exception as exc:
                    return n, {"error": f"{type(exc).__name__}: {exc}"}
                cache.write_json(sfile, est)
                return n, dict(sorted(est.items()))     # the same key order as a cache hit

            with ThreadPoolExecutor(max_workers=jobs) as tp:
                for n, est in tp.map(one, names):
                    estimates[n] = est
            bad = [PartFailure(part=n, error=e["error"], check="slice")
                   for n, e in estimates.items() if e and "error" in e]
            if bad:
                raise BuildError(f"slicing failed; {out} was left untouched", bad)
        else:
            slicer_info["reason"] = ("not requested (phantom-cad build --slice)" if slice is False else
                                     "prusa-slicer is not installed (bash .ci/sysdeps)")
        timings["slice"] = time.perf_counter() - t

        # 4. write the export into a staging directory --------------------------------------
        t = time.perf_counter()
        out.parent.mkdir(parents=True, exist_ok=True)
        stage = out.parent / f".{out.name}.{os.getpid()}.tmp"
        if stage.exists():
            shutil.rmtree(stage)
        try:
            for sub in ("step", "stl", "renders", "slicer"):
                (stage / sub).mkdir(parents=True)
            for n in names:
                pdir = cache.part_dir(keys[n])
                shutil.copyfile(pdir / "part.step", stage / "step" / f"{n}.step")
                shutil.copyfile(pdir / "part.stl", stage / "stl" / f"{n}.stl")
                if render and (pdir / "render.png").is_file():
                    shutil.copyfile(pdir / "render.png", stage / "renders" / f"{n}.png")
            shutil.copyfile(adir / "hand_assembly.step", stage / "step" / "hand_assembly.step")
            if render and (adir / "render.png").is_file():
                shutil.copyfile(adir / "render.png", stage / "renders" / "hand_assembly.png")
            (stage / "slicer" / "config.ini").write_text(ini)
            bom = list(asm.bill_of_materials(params))
            (stage / "bom.csv").write_text(bom_csv(bom), encoding="utf-8")
            man = manifest_mod.build_manifest(
                stage=stage, params=params, params_path=path, names=names, keys=keys, metas=metas,
                poses=poses, estimates=estimates, slicer_info=slicer_info, interference=inter,
                contacts=contacts, bom=bom)
            (stage / "manifest.json").write_text(json.dumps(man, indent=1, sort_keys=False) + "\n")
            replace_dir(stage, out)
        except BaseException:
            shutil.rmtree(stage, ignore_errors=True)
            raise
        timings["write"] = time.perf_counter() - t
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
        if astage is not None:
            shutil.rmtree(astage, ignore_errors=True)
    timings["total"] = time.perf_counter() - t_start
    return BuildResult(out_dir=out, hand=params.name, side=params.side, params_digest=params.digest,
                       parts=names, built=missing, cached=[n for n in names if n not in missing],
                       manifest=man, timings=timings, sliced=slicer_info["used"], part_timings=part_timings)


def bom_csv(rows: list[dict]) -> str:
    buf = io.StringIO()
    cols = ["item", "spec", "quantity", "used_in"]
    extra = sorted({k for r in rows for k in r} - set(cols))
    w = csv.DictWriter(buf, fieldnames=cols + extra, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (";".join(map(str, v)) if isinstance(v, (list, tuple)) else v) for k, v in r.items()})
    return buf.getvalue()
