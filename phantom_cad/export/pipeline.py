"""``phantom-cad build``: every printable part of the hand from the parameter file.

    from phantom_cad.export.pipeline import build_hand
    result = build_hand("params/phantom.toml", "exports/phantom")

Writes ``exports/<hand>/`` (see docs/exports.md): ``step/<part>.step``,
``step/hand_assembly.step``, ``stl/<part>.stl`` (print orientation), ``coupon/`` and ``gauge/``
(the print aids, :mod:`phantom_cad.cad.print_aids`: the fit-test coupon ``fit_coupon.step``, ``.stl``,
``.md``, ``.png`` and the angle gauge ``angle_gauge.*``), ``bom.csv``,
``routing.json`` (every tendon's path, ``kinematics.routing``; docs/transmission.md),
``manifest.json``, ``renders/*.png`` and ``slicer/config.ini``.

Pipeline
--------
1. parse the parameter file (``--side`` overrides ``hand.side``) and hash every part's
   ``assembly.part_inputs`` into a cache key (:mod:`phantom_cad.export.cache`);
2. build the parts missing from the cache in parallel worker processes
   (:mod:`phantom_cad.export.pool`): a worker builds the part, verifies it once
   (``phantom_cad.cad.verify``: one valid solid, measured against the parameters), writes
   BREP/STEP, re-imports the STEP (same volume), tessellates it (``print.stl_tolerance``),
   checks the mesh (watertight, manifold, volume) and renders it;
3. the assembly STEP (parts placed with ``assembly.pose_transforms``), the assembly render
   and the interference check (:mod:`phantom_cad.export.interference`; only
   ``assembly.designed_contacts`` may overlap) are cached under a key of all part keys and poses
   (the STEP and the render in the workers, which go on while steps 4 and 5 slice and write the
   description, the BOM and the routing; the export waits for them before its manifest);
4. every STL is sliced with PrusaSlicer (when installed) for print time and filament;
5. every output is written by its exporter (:data:`phantom_cad.export.exporters.EXPORTERS`, in
   order) into a temporary directory beside the target, which replaces the previous export only
   when the whole build succeeded.

The parts come from the assembly interface (:mod:`phantom_cad.export.interface`). The module
imports numpy only; build123d/OCP are imported inside the workers.
"""

from __future__ import annotations

import copy
import json
import os
import shutil
import time
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..atomic import check_replaceable, replace_dir
from ..cad import preflight
from ..canon import canonical, plain, sha256
from ..params import ParamError, load_document, parse
from ..params.io import DEFAULT_PARAMS
from .. import workers
from ..kinematics.hand_params import HandParams
from . import cache as cache_mod
from . import interface, pool as pool_mod
from .cache import Cache
from .interference import INTERFERENCE_TOL_MM3, interference
from .results import BuildError, BuildResult, PartFailure, failure_from

__all__ = ["build_hand", "BuildError", "BuildResult", "PartFailure", "INTERFERENCE_TOL_MM3"]


def occt_threads(jobs: int, cpus: int | None = None) -> int | None:
    """OpenCascade threads for each of ``jobs`` workers on ``cpus`` CPUs (default: this process's,
    ``workers.available_cpus``): each worker's share, at least one, when the workers fill the CPUs;
    None (OpenCascade's default, every core) when one worker has them all."""
    cpus = workers.available_cpus() if cpus is None else cpus
    share = cpus // max(1, jobs)
    return None if share >= cpus else max(1, share)


def _is_export(folder: Path) -> bool:
    """Whether ``folder`` holds an earlier export (its manifest.json names our format)."""
    from .manifest import MANIFEST_FORMAT

    try:
        return json.loads((folder / "manifest.json").read_text(encoding="utf-8")).get("format") == MANIFEST_FORMAT
    except (OSError, ValueError, AttributeError):
        return False


def load_build_params(params_path, side, effects=None) -> tuple[Path, dict[str, Any], HandParams, Any]:
    """(path, document, params, the file's own side) of the parameter file a build or an export's
    reader is given (the default file for None), ``side`` overriding the file's; the pre-build
    rules checked (``cad.preflight``)."""
    path = Path(params_path) if params_path is not None else DEFAULT_PARAMS
    document = load_document(path)
    file_side = (document.get("hand") or {}).get("side") if isinstance(document.get("hand"), dict) else None
    if side is not None:
        document = copy.deepcopy(document)
        if not isinstance(document.get("hand"), dict):
            raise ParamError("hand", document.get("hand"), "must be a table", str(path))
        document["hand"]["side"] = side
    params = parse(document, source=str(path), effects=effects)
    preflight.check(params)
    return path, document, params, file_side


def _default_out(params: HandParams, side, file_side) -> Path:
    name = params.name
    if side is not None and side != file_side:
        name = f"{name}_{side}"
    return Path("exports") / name


class _Build:
    """One run of :func:`build_hand`: its inputs, the lazily started process pool, the stages."""

    def __init__(self, path, document, params: HandParams, out: Path, jobs: int, cache: Cache, render: bool, log):
        self.path, self.document, self.params, self.out = path, document, params, out
        self.jobs, self.cache, self.render, self.log = jobs, cache, render, log
        self.asm = interface.assembly()
        self.pool: ProcessPoolExecutor | None = None
        self.astage: Path | None = None
        names = list(self.asm.part_names(params))
        if len(set(names)) != len(names):
            raise BuildError(f"assembly.part_names gives duplicate names: {names}")
        self.names = names
        self.keys = {}
        for n in names:
            try:
                inputs = self.asm.part_inputs(params, n)
            except Exception as exc:
                raise BuildError("cannot compute the part inputs", [failure_from(n, exc, None)]) from exc
            self.keys[n] = cache_mod.part_key(params, n, inputs)
        self.missing = []
        for n in names:
            problem = cache.part_problem(self.keys[n], render)
            if problem is None:
                continue
            if problem != "missing":   # never serve a bad entry: say so and rebuild it
                self.log(f"cache: {n} entry {self.keys[n][:12]} not served ({problem}); rebuilding it")
                cache.discard(cache.part_dir(self.keys[n]))
            self.missing.append(n)
        # the print aids (cad.print_aids: the fit-test coupon, the angle gauge), cached like parts
        from ..cad.print_aids import AIDS

        self.aids = AIDS
        self.aid_keys = {a.kind: cache_mod.aid_key(params, a) for a in AIDS}
        self.aid_missing = []
        for a in AIDS:
            problem = cache.aid_problem(a, self.aid_keys[a.kind], render)
            if problem not in (None, "missing"):
                self.log(f"cache: {a.title} entry {self.aid_keys[a.kind][:12]} not served ({problem}); rebuilding it")
                cache.discard(cache.aid_dir(a, self.aid_keys[a.kind]))
            if problem is not None:
                self.aid_missing.append(a)
        #: PrusaSlicer's estimate of each print aid (None unless sliced)
        self.aid_estimates: dict[str, dict | None] = {a.kind: None for a in AIDS}

    def get_pool(self) -> ProcessPoolExecutor:
        if self.pool is None:
            ctx = workers.mp_context(preload=pool_mod.PRELOAD)
            self.pool = ProcessPoolExecutor(max_workers=self.jobs, mp_context=ctx, initializer=pool_mod.init_worker,
                                            initargs=(workers.watched_parent(ctx), occt_threads(self.jobs),
                                                      dict(os.environ)))
        return self.pool

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)
        if self.astage is not None:
            shutil.rmtree(self.astage, ignore_errors=True)

    # 1. parts ------------------------------------------------------------------------
    def parts(self) -> dict[str, dict]:
        """Build the missing parts, and the print aids (the fit-test coupon, the angle gauge) when
        they are missing, into the cache; return {name: timings} of the parts built."""
        part_timings: dict[str, dict] = {}
        missing = self.missing
        doc = plain(self.document)
        jobs = [(pool_mod.part_worker, {"name": n, "key": self.keys[n], "document": doc, "source": str(self.path),
                                        "assembly_module": self.asm.__name__,
                                        "cache_root": str(self.cache.root), "render": self.render})
                for n in missing]
        for a in self.aid_missing:      # after the parts: the smallest jobs last
            jobs.append((pool_mod.aid_worker, {"kind": a.kind, "key": self.aid_keys[a.kind], "document": doc,
                                               "source": str(self.path), "cache_root": str(self.cache.root),
                                               "render": self.render}))
        if not jobs:
            return part_timings
        if missing:
            self.log(f"building {len(missing)} of {len(self.names)} parts with {self.jobs} worker(s)")
        if self.jobs == 1 or len(jobs) == 1:
            results = [worker(task) for worker, task in jobs]
        else:
            try:
                futures = [self.get_pool().submit(worker, task) for worker, task in jobs]
                results = [f.result() for f in futures]
            except BrokenProcessPool as exc:
                raise BuildError(f"a worker process died while building {missing} "
                                 f"(crash in OCP?): {exc}; {self.out} was left untouched") from exc
        aids = results[len(missing):]
        results = results[:len(missing)]
        failures = []
        for r in results:
            if r["ok"]:
                part_timings[r["name"]] = r["timings"]
            else:
                failures.append(PartFailure(**r["failure"]))
        if failures:
            raise BuildError(f"{len(failures)} part(s) failed; {self.out} was left untouched", failures)
        for a, r in zip(self.aid_missing, aids):
            if not r["ok"]:
                raise BuildError(f"{a.title} failed; {self.out} was left untouched", [PartFailure(**r["failure"])])
        return part_timings

    # 2. assembly: poses, STEP, render, interference -------------------------------------
    def assembly(self, metas, check_interference: bool):
        """(poses, contacts, interference report, ``finish``): the assembly STEP and picture are
        started in the workers, the interference measured here meanwhile; ``finish()`` waits for
        them, commits the assembly's cache entry and returns its folder (called as late as the
        export needs them: the robot description, the BOM and the routing are written first,
        while the workers draw and write)."""
        params, names, keys, cache = self.params, self.names, self.keys, self.cache
        poses = {n: np.asarray(T, dtype=float) for n, T in self.asm.pose_transforms(params).items()}
        absent = [n for n in names if n not in poses]
        if absent:
            raise BuildError(f"assembly.pose_transforms has no placement for {absent}")
        contacts = [tuple(c) for c in self.asm.designed_contacts(params)]
        allowed = {frozenset(c[:2]) for c in contacts}
        akey = sha256(canonical({
            "keys": [keys[n] for n in names],
            "poses": {n: np.round(poses[n], 9) for n in names},
            "contacts": sorted(sorted(c[:2]) for c in contacts),
            "label": params.name, "render": self.render, "tol": INTERFERENCE_TOL_MM3,
            "code": cache_mod.code_digest(),
        }))
        adir = cache.assembly_dir(akey)
        futures: dict[str, Future] = {}
        problem = cache.assembly_problem(akey, self.render)
        if problem not in (None, "missing"):
            self.log(f"cache: assembly entry {akey[:12]} not served ({problem}); rebuilding it")
            cache.discard(adir)
        if problem is None:
            inter = json.loads((adir / "interference.json").read_text())
            return poses, contacts, inter, lambda: adir
        self.astage = astage = cache.staging(adir)
        parts_arg = [(n, str(cache.part_dir(keys[n])), poses[n].tolist(), metas[n]["color"]) for n in names]
        futures["step"] = self.get_pool().submit(pool_mod.assembly_step_worker, {
            "parts": parts_arg, "label": f"{params.name}_{params.side}",
            "out": str(astage / "hand_assembly.step")})
        if self.render:
            futures["render"] = self.get_pool().submit(pool_mod.assembly_render_worker, {
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
        inter = json.loads(json.dumps(inter, sort_keys=True))   # as a warm build reads it from the cache
        if inter.get("collisions"):
            lines = [f"  {c['parts'][0]} x {c['parts'][1]}: {c['volume_mm3']:.3f} mm^3"
                     for c in inter["collisions"]]
            raise BuildError(
                f"parts intersect at the rest pose (overlap > {INTERFERENCE_TOL_MM3} mm^3, not in "
                f"assembly.designed_contacts); {self.out} was left untouched:\n" + "\n".join(lines))

        def finish() -> Path:
            for what, fut in futures.items():
                r = fut.result()
                if not r["ok"]:
                    raise BuildError(f"assembly {what} failed: {r['error']}\n{r['traceback']}")
            cache.write_json(astage / "interference.json", inter)
            cache_mod.seal(astage)
            Cache.commit(astage, adir)
            self.astage = None
            return adir
        return poses, contacts, inter, finish

    # 3. slicing -------------------------------------------------------------------------
    def slice(self, slice, ini: str):
        """({name: estimate or None}, slicer info for the manifest)."""
        from . import slicer

        names, keys, cache = self.names, self.keys, self.cache
        exe = slicer.find_slicer() if slice is not False else None
        if slice is True and exe is None:
            raise BuildError("--slice: prusa-slicer is not installed (bash .ci/sysdeps, or apt-get install "
                             "prusa-slicer)")
        estimates: dict[str, dict | None] = {n: None for n in names}
        if exe is None:
            reason = ("not requested (phantom-cad build --slice)" if slice is False else
                      "prusa-slicer is not installed (bash .ci/sysdeps)")
            return estimates, {"used": False, "reason": reason}
        version = slicer.slicer_version(exe)
        info: dict[str, Any] = {"used": True, "program": "PrusaSlicer", "version": version,
                                "config": "slicer/config.ini"}

        aids = {a.name: a for a in self.aids}

        def one(n):
            stl_path = (cache.aid_dir(aids[n], self.aid_keys[aids[n].kind]) / f"{n}.stl" if n in aids
                        else cache.part_dir(keys[n]) / "part.stl")
            skey = slicer.estimate_key(stl_path.read_bytes(), ini, version)
            est, problem = cache.read_slice(skey)
            if est is not None:
                return n, est
            if problem != "missing":
                self.log(f"cache: slicer estimate of {n} ({skey[:12]}) not served ({problem}); slicing again")
            try:
                est = slicer.slice_stl(stl_path, ini, exe).as_dict()
            except Exception as exc:
                return n, {"error": f"{type(exc).__name__}: {exc}"}
            cache.write_slice(skey, est)
            return n, dict(sorted(est.items()))     # the same key order as a cache hit

        with ThreadPoolExecutor(max_workers=self.jobs) as tp:
            for n, est in tp.map(one, [*names, *aids]):
                if n in aids:
                    self.aid_estimates[aids[n].kind] = est
                else:
                    estimates[n] = est
        bad = [PartFailure(part=n, error=e["error"], check="slice")
               for n, e in [*estimates.items(), *((a.name, self.aid_estimates[a.kind]) for a in self.aids)]
               if e and "error" in e]
        if bad:
            raise BuildError(f"slicing failed; {self.out} was left untouched", bad)
        return estimates, info

    # 4. write the export into a staging directory, then replace the target ---------------
    def write(self, metas, poses, contacts, inter, finish_assembly, estimates, slicer_info, ini: str) -> dict:
        """The export, staged (every exporter of :data:`exporters.EXPORTERS`, in order) and swapped
        in; ``finish_assembly()`` (from :meth:`assembly`) gives the assembly's cache folder once its
        workers are done: the exporters before the first that needs it (the description, the BOM,
        the routing) are written meanwhile."""
        from .exporters import EXPORTERS, ExportContext

        out = self.out
        ctx = ExportContext(
            params=self.params, params_path=self.path, asm=self.asm, names=self.names, keys=self.keys,
            cache=self.cache, render=self.render, metas=metas, poses=poses, contacts=contacts, interference=inter,
            estimates=estimates, slicer_info=slicer_info, ini=ini, aid_keys=self.aid_keys,
            aid_estimates=self.aid_estimates, finish_assembly=finish_assembly)
        out.parent.mkdir(parents=True, exist_ok=True)
        stage = out.parent / f".{out.name}.{os.getpid()}.tmp"
        if stage.exists():
            shutil.rmtree(stage)
        try:
            stage.mkdir()
            for exporter in EXPORTERS:
                exporter.write(ctx, stage)
            declared = {rel for exporter in EXPORTERS for rel in exporter.writes(ctx)}
            written = {p.relative_to(stage).as_posix() for p in stage.rglob("*") if p.is_file()}
            if declared != written:     # the exporters' writes() is what docs and tests rely on
                raise BuildError(f"the exporters wrote {sorted(written - declared)} they do not declare, and not "
                                 f"{sorted(declared - written)} they declare; {out} was left untouched")
            replace_dir(stage, out)
        except BaseException:
            shutil.rmtree(stage, ignore_errors=True)
            raise
        return ctx.manifest


def build_hand(params_path: str | os.PathLike | None = None, out_dir: str | os.PathLike | None = None,
               side: str | None = None, jobs: int | None = None, *, slice: bool | None = False,
               render: bool = True, cache_dir: str | os.PathLike | None = None,
               check_interference: bool = True,
               log: Callable[[str], None] | None = None, effects=None) -> BuildResult:
    """Build every part of the hand described by ``params_path`` into ``out_dir``.

    ``side`` overrides ``hand.side``; ``jobs`` worker processes (default os.cpu_count());
    ``slice`` False = skip (default: slicing every part costs ~1-4 s each, cached after),
    True = slice with PrusaSlicer (error if missing), None = slice when it is installed;
    ``cache_dir`` default ``$PHANTOM_CAD_CACHE`` or ``.cache``. ``effects``: the effect library
    that checks the file's ``plugins`` and ``[effects.*]`` (``params.parse``); the parts never read
    them.
    Raises :class:`BuildError` (nothing written), :class:`ParamError`, or UserError when ``out_dir``
    exists and is neither empty nor an earlier export (nothing is ever replaced but our own output).
    """
    from .slicer import config_ini

    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    path, document, params, file_side = load_build_params(params_path, side, effects)
    out = Path(out_dir) if out_dir is not None else _default_out(params, side, file_side)
    check_replaceable(out, _is_export, "a phantom-cad export (manifest.json)")
    jobs = max(1, int(jobs or os.cpu_count() or 1))
    run = _Build(path, document, params, out, jobs, Cache(cache_dir), render, log or (lambda msg: None))
    timings["prepare"] = time.perf_counter() - t_start
    try:
        t = time.perf_counter()
        part_timings = run.parts()
        timings["parts"] = time.perf_counter() - t
        metas = {n: run.cache.part_meta(run.keys[n]) for n in run.names}

        t = time.perf_counter()
        poses, contacts, inter, finish_assembly = run.assembly(metas, check_interference)
        timings["assembly"] = time.perf_counter() - t     # its STEP and picture go on in the workers

        t = time.perf_counter()
        ini = config_ini(params.print)
        estimates, slicer_info = run.slice(slice, ini)
        timings["slice"] = time.perf_counter() - t

        t = time.perf_counter()
        man = run.write(metas, poses, contacts, inter, finish_assembly, estimates, slicer_info, ini)
        timings["write"] = time.perf_counter() - t
    finally:
        run.close()
    timings["total"] = time.perf_counter() - t_start
    return BuildResult(out_dir=out, hand=params.name, side=params.side, params_digest=params.digest,
                       parts=run.names, built=run.missing, cached=[n for n in run.names if n not in run.missing],
                       manifest=man, timings=timings, sliced=slicer_info["used"], part_timings=part_timings)


def export_problem(out: Path, digest: str, side: str) -> str | None:
    """Why ``out`` is not an export of the parameters of ``digest`` for ``side`` with its robot
    description (None: it is)."""
    try:
        man = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
        built, built_side = man["params"]["digest"], man["hand"]["side"]
        local = out / man["description"]["local_urdf"]
    except FileNotFoundError:
        return f"no export in {out}"
    except (OSError, ValueError, KeyError, TypeError):
        return f"{out / 'manifest.json'} is unreadable or records no parameter digest and description"
    if (built, built_side) != (digest, side):
        return (f"the export {out} was built from parameter digest {str(built)[:12]} ({built_side}), "
                f"the file has {digest[:12]} ({side})")
    if not local.is_file():
        return f"the export {out} has no robot description ({local.relative_to(out)})"
    return None


def other_code(out: Path) -> str | None:
    """Why the export in ``out`` was not written by this phantom_cad's code (the manifest's
    ``code_digest``, ``cache.code_digest``), or None."""
    from .cache import code_digest

    try:
        built = json.loads((out / "manifest.json").read_text(encoding="utf-8")).get("code_digest")
    except (OSError, ValueError, AttributeError):
        return f"{out / 'manifest.json'} is unreadable"
    if built != code_digest():
        return (f"the export {out} was built by other phantom_cad code (code digest {str(built)[:12]}, this "
                f"one's {code_digest()[:12]})")
    return None


def ensure_export(params_path: str | os.PathLike | None = None, out_dir: str | os.PathLike | None = None,
                  side: str | None = None, log: Callable[[str], None] | None = None, effects=None,
                  **build_kwargs) -> tuple[Path, HandParams]:
    """(export folder, params) of an export of ``params_path`` (``side`` overriding the file's),
    built first (:func:`build_hand`, cached) when ``out_dir`` holds none, one built from other
    parameters, one without its robot description (:func:`export_problem`) or one built by other
    code (:func:`other_code`: after an update, what it measures would be the old code's). For the
    commands that read an export (check, view)."""
    path, _document, params, file_side = load_build_params(params_path, side, effects)
    out = Path(out_dir) if out_dir is not None else _default_out(params, side, file_side)
    reason = export_problem(out, params.digest, params.side) or other_code(out)
    if reason is not None:
        (log or (lambda msg: None))(f"{reason}; building it first from {path} (cached parts are reused)")
        build_hand(path, out, side=side, log=log, effects=effects, **build_kwargs)
        reason = export_problem(out, params.digest, params.side)
        if reason is not None:  # the build wrote what this reads: a defect, not a user error
            raise RuntimeError(f"after building: {reason}")
    return out, params
