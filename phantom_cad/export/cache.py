"""The part cache of ``phantom-cad build``.

Layout (default root ``.cache`` in the working directory, or ``$PHANTOM_CAD_CACHE``)::

    .cache/parts/<key>/       one built part: part.brep, part.step, part.stl,
                              mesh.npz (link frame; the pictures' too),
                              visual.stl, collision.npz (the robot description's, metres),
                              render.png, meta.json
    .cache/coupon/<key>/      the fit-test coupon: fit_coupon.step, .stl, .md, render.png, meta.json
    .cache/gauge/<key>/       the angle gauge: angle_gauge.step, .stl, .md, render.png, meta.json
    .cache/assembly/<key>/    hand_assembly.step, render.png, interference.json, meta.json
    .cache/slice/<key>.json   PrusaSlicer estimates of one STL with one config, and their SHA-256
    .cache/mjcf/<key>.json    a compiled MJCF (export/mjcf.py) of one robot model and its meshes,
                              and its SHA-256 (MuJoCo compiled it before it was kept)

Every entry records the SHA-256 of what it holds when it is made, and is served only when its
files still match (anything else is rebuilt, and the build log says why).

A part's key is the SHA-256 of its name, ``assembly.part_inputs(params, name)`` (the
plain values the part depends on, declared by its part family), the hand side, the STL
tolerance, the versions of build123d/OCP and a digest of the phantom_cad source that makes
geometry and exported bytes (:func:`code_digest`). So changing
one finger rebuilds only that finger's parts, and editing the modelling code rebuilds
everything. Entries are written to a temporary directory and renamed into place, so a
crashed build never leaves a half entry; any entry can be deleted at any time.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import Any, Mapping

from ..atomic import write_json_atomic
from ..canon import canonical, plain, sha256
from ..kinematics.hand_params import HandParams

#: bump when the cached files' format or the export pipeline changes their bytes
PIPELINE_VERSION = 1

_PKG = Path(__file__).resolve().parents[1]      # .../phantom_cad
#: sources whose code decides the geometry and the exported bytes: the packages that make
#: and export the parts (the part families, their verification, frames, the parameters) and
#: the foundation modules they compute with
_CODE_DIRS = ("cad", "export", "kinematics", "params")
_CODE_FILES = ("units.py", "canon.py")


def default_root() -> Path:
    return Path(os.environ.get("PHANTOM_CAD_CACHE", ".cache"))


@lru_cache(maxsize=1)
def code_digest() -> str:
    """SHA-256 over the phantom_cad sources that make geometry and exported bytes
    (:data:`_CODE_DIRS`, :data:`_CODE_FILES`; the CLI, calibration and interop are not)."""
    h = hashlib.sha256()
    for sub in _CODE_DIRS:
        for path in sorted((_PKG / sub).rglob("*.py")):
            h.update(str(path.relative_to(_PKG)).encode())
            h.update(hashlib.sha256(path.read_bytes()).digest())
    for extra in _CODE_FILES:
        path = _PKG / extra
        if path.is_file():
            h.update(extra.encode())
            h.update(hashlib.sha256(path.read_bytes()).digest())
    return h.hexdigest()


def package_version(dist: str) -> str | None:
    """The installed version of a distribution (package metadata), or None."""
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


@lru_cache(maxsize=1)
def cad_versions() -> dict[str, str | None]:
    """Versions of the CAD stack, read from package metadata (no OCP import)."""
    return {
        "build123d": package_version("build123d"),
        "cadquery-ocp": package_version("cadquery-ocp") or package_version("cadquery_ocp"),
        "cadquery": package_version("cadquery"),
        "trimesh": package_version("trimesh"),
        "manifold3d": package_version("manifold3d"),
        "matplotlib": package_version("matplotlib"),      # the pictures' font file
        "pillow": package_version("pillow"),              # the pictures' text and PNG writer
        "mujoco": package_version("mujoco"),
    }


def coupon_key(params: HandParams) -> str:
    """The fit-test coupon's key: the print settings, the hardware and the wall it is made of."""
    doc = params.document
    return sha256(canonical({
        "pipeline": PIPELINE_VERSION,
        "coupon": {"print": plain(doc["print"]), "hardware": plain(doc["hardware"]),
                   "palm_wall_mm": doc["palm"]["wall_mm"], "name": params.name},
        "code": code_digest(),
        "versions": cad_versions(),
    }))


def gauge_key(params: HandParams) -> str:
    """The angle gauge's key: the fingers and the thumb (lengths, joint limits), the hand's length,
    the wall it is made of and the STL tolerance."""
    doc = params.document
    return sha256(canonical({
        "pipeline": PIPELINE_VERSION,
        "gauge": {"hand": plain(doc["hand"]), "fingers": plain(doc["fingers"]), "thumb": plain(doc["thumb"]),
                  "palm_wall_mm": doc["palm"]["wall_mm"], "stl_tolerance_m": params.print.stl_tolerance,
                  "name": params.name},
        "code": code_digest(),
        "versions": cad_versions(),
    }))


def part_key(params: HandParams, name: str, part_inputs: Mapping[str, Any]) -> str:
    return sha256(canonical({
        "pipeline": PIPELINE_VERSION,
        "part": name,
        "inputs": part_inputs,
        "side": params.side,
        "stl_tolerance_m": params.print.stl_tolerance,
        "code": code_digest(),
        "versions": cad_versions(),
    }))


#: the files of every part entry (render.png too unless the build was --no-render)
PART_FILES = ("part.brep", "part.step", "part.stl", "part.3mf", "mesh.npz", "visual.stl", "collision.npz")
#: the files of the fit-test coupon's entry (render.png too unless the build was --no-render)
COUPON_FILES = ("fit_coupon.step", "fit_coupon.stl", "fit_coupon.md")
#: the files of the angle gauge's entry (render.png too unless the build was --no-render)
GAUGE_FILES = ("angle_gauge.step", "angle_gauge.stl", "angle_gauge.md")
#: the files of every assembly entry (render.png too unless the build was --no-render)
ASSEMBLY_FILES = ("hand_assembly.step", "interference.json")


def seal(entry: Path) -> None:
    """Record the SHA-256 of every file of a staged entry in its meta.json (merged into what
    meta.json already holds), for :func:`entry_problem` to check before the entry is served."""
    meta_path = entry / "meta.json"
    meta = json.loads(meta_path.read_text(encoding="utf-8")) if meta_path.is_file() else {}
    meta["files"] = {f.name: sha256(f.read_bytes()) for f in sorted(entry.iterdir()) if f.name != "meta.json"}
    write_json_atomic(meta_path, meta, indent=1, sort_keys=True)


def entry_problem(entry: Path, need: tuple[str, ...]) -> str | None:
    """Why the cache entry folder ``entry`` cannot be served (None: it can): missing, an
    unreadable meta.json, a file of ``need`` not recorded, or a recorded file missing or not
    matching the SHA-256 recorded when the entry was made."""
    try:
        meta = json.loads((entry / "meta.json").read_text(encoding="utf-8"))
    except FileNotFoundError:
        return "meta.json is missing" if entry.exists() else "missing"
    except (OSError, ValueError) as exc:
        return f"meta.json is unreadable ({exc.__class__.__name__})"
    files = meta.get("files") if isinstance(meta, dict) else None
    if not isinstance(files, dict):
        return "meta.json records no file hashes"
    for name in need:
        if name not in files:
            return f"{name} is missing"
    for name, digest in files.items():
        try:
            if sha256((entry / name).read_bytes()) != digest:
                return f"{name} does not match its SHA-256"
        except OSError:
            return f"{name} is missing"
    return None


def _digest(value: dict | str) -> str:
    """The SHA-256 recorded with a cached value: of its text, or of a dict's canonical JSON."""
    return sha256(value.encode("utf-8") if isinstance(value, str) else canonical(value))


def _sealed(field: str, value: dict | str) -> dict:
    """A small cache file's document: the value under ``field`` and its SHA-256."""
    return {field: value, "sha256": _digest(value)}


def _read_sealed(path: Path, field: str, kind: type) -> tuple[Any, str | None]:
    """(the value a _sealed document at ``path`` holds, None) or (None, why it cannot be served:
    missing, unreadable, or not matching the SHA-256 recorded with it)."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None, "missing"
    except (OSError, ValueError) as exc:
        return None, f"unreadable ({exc.__class__.__name__})"
    value = doc.get(field) if isinstance(doc, dict) else None
    if not isinstance(value, kind) or doc.get("sha256") != _digest(value):
        return None, "does not match its SHA-256"
    return value, None


class Cache:
    def __init__(self, root: str | os.PathLike | None = None):
        self.root = Path(root) if root is not None else default_root()

    # parts ----------------------------------------------------------------
    def part_dir(self, key: str) -> Path:
        return self.root / "parts" / key

    def part_problem(self, key: str, render: bool = True) -> str | None:
        """Why the entry ``key`` cannot be served (None: it can): see :func:`entry_problem`; a
        render is wanted unless the build is --no-render (a --no-render build must not change
        what a later build writes)."""
        return entry_problem(self.part_dir(key), PART_FILES + (("render.png",) if render else ()))

    def discard(self, final: Path) -> None:
        """Remove a bad entry (renamed aside first, so no reader sees half of it)."""
        if final.exists():
            aside = self.staging_path(final)
            shutil.rmtree(aside, ignore_errors=True)
            os.rename(final, aside)
            shutil.rmtree(aside, ignore_errors=True)

    def part_meta(self, key: str) -> dict:
        return json.loads((self.part_dir(key) / "meta.json").read_text())

    # fit-test coupon ----------------------------------------------------------
    def coupon_dir(self, key: str) -> Path:
        return self.root / "coupon" / key

    def coupon_problem(self, key: str, render: bool = True) -> str | None:
        """Why the coupon entry ``key`` cannot be served (None: it can): see :func:`entry_problem`."""
        return entry_problem(self.coupon_dir(key), COUPON_FILES + (("render.png",) if render else ()))

    # angle gauge ---------------------------------------------------------------
    def gauge_dir(self, key: str) -> Path:
        return self.root / "gauge" / key

    def gauge_problem(self, key: str, render: bool = True) -> str | None:
        """Why the gauge entry ``key`` cannot be served (None: it can): see :func:`entry_problem`."""
        return entry_problem(self.gauge_dir(key), GAUGE_FILES + (("render.png",) if render else ()))

    # assembly ---------------------------------------------------------------
    def assembly_dir(self, key: str) -> Path:
        return self.root / "assembly" / key

    def assembly_problem(self, key: str, render: bool = True) -> str | None:
        """Why the assembly entry ``key`` cannot be served (None: it can): see :func:`entry_problem`."""
        return entry_problem(self.assembly_dir(key), ASSEMBLY_FILES + (("render.png",) if render else ()))

    # slicing ------------------------------------------------------------------
    def slice_file(self, key: str) -> Path:
        return self.root / "slice" / f"{key}.json"

    def read_slice(self, key: str) -> tuple[dict | None, str | None]:
        """(the PrusaSlicer estimate cached under ``key``, None) or (None, why it cannot be
        served: missing, unreadable, or not matching the SHA-256 recorded with it)."""
        return _read_sealed(self.slice_file(key), "estimate", dict)

    def write_slice(self, key: str, estimate: dict) -> None:
        self.write_json(self.slice_file(key), _sealed("estimate", estimate))

    # compiled MJCF -------------------------------------------------------------
    def mjcf_file(self, key: str) -> Path:
        return self.root / "mjcf" / f"{key}.json"

    def read_mjcf(self, key: str) -> tuple[str | None, str | None]:
        """(the MJCF text cached under ``key``, None) or (None, why it cannot be served)."""
        return _read_sealed(self.mjcf_file(key), "xml", str)

    def write_mjcf(self, key: str, xml: str) -> None:
        self.write_json(self.mjcf_file(key), _sealed("xml", xml))

    # helpers -------------------------------------------------------------------
    @staticmethod
    def staging_path(final: Path) -> Path:
        return final.parent / f".{final.name}.{os.getpid()}.tmp"

    def staging(self, final: Path) -> Path:
        """A fresh temporary directory beside ``final`` (same file system)."""
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.staging_path(final)
        if tmp.exists():
            shutil.rmtree(tmp)
        tmp.mkdir()
        return tmp

    @staticmethod
    def commit(tmp: Path, final: Path) -> None:
        """Rename a finished staging directory into place (first writer wins)."""
        try:
            os.rename(tmp, final)
        except OSError:
            if (final / "meta.json").exists() or final.exists():
                shutil.rmtree(tmp, ignore_errors=True)
            else:
                raise

    def write_json(self, path: Path, obj: Any) -> None:
        write_json_atomic(path, obj, indent=1, sort_keys=True)
