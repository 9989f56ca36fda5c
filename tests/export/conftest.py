"""Fixtures of the export tests.

* ``standin``: the assembly interface (phantom_cad.export.interface.ASSEMBLY_MODULE, normally
  phantom_cad.cad.assembly) replaced by tests/export/standin_assembly.py
  (three parts of known geometry; faults can be injected) for the pipeline tests.
* ``standin_build``: the stand-in hand built once per session into a tmp dir.
* ``hand_build``: the real default hand (phantom_cad.cad's parts) built once per session.
* ``pkg``: its robot description package (``description/``).
* ``hand_export``: ``hand_export(kind)`` -> the export of one of the three reference hands
  (tests/cad/conftest.py ``HANDS``), built once per session with ``hand_build``'s part cache.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import standin_assembly  # noqa: E402


@pytest.fixture
def standin(monkeypatch):
    """The stand-in assembly module, installed for one test."""
    from phantom_cad.export import interface

    monkeypatch.setattr(interface, "ASSEMBLY_MODULE", "standin_assembly")
    standin_assembly.FAULT.clear()
    standin_assembly.OVERLAP.clear()
    yield standin_assembly
    standin_assembly.FAULT.clear()
    standin_assembly.OVERLAP.clear()


@pytest.fixture(scope="session")
def standin_build(tmp_path_factory):
    """(BuildResult, cache dir) of the stand-in hand, built once."""
    from phantom_cad.export.pipeline import build_hand

    mp = pytest.MonkeyPatch()
    from phantom_cad.export import interface

    mp.setattr(interface, "ASSEMBLY_MODULE", "standin_assembly")
    try:
        root = tmp_path_factory.mktemp("standin")
        result = build_hand(None, root / "exports" / "phantom", cache_dir=root / "cache", jobs=2,
                            slice=None)
    finally:
        mp.undo()
    return result, root / "cache"


def real_assembly_available() -> bool:
    try:
        importlib.import_module("phantom_cad.cad.assembly")
    except ImportError:
        return False
    return True


@pytest.fixture(scope="session")
def hand_build(tmp_path_factory, part_cache):
    """The default hand with the real parts, built once per session (jobs = 2)."""
    if not real_assembly_available():
        pytest.skip("phantom_cad.cad.assembly (the real parts) is not there yet")
    from phantom_cad.export.pipeline import build_hand

    root = tmp_path_factory.mktemp("hand")
    result = build_hand(None, root / "exports" / "phantom", cache_dir=part_cache, jobs=2, slice=None)
    return result, part_cache


@pytest.fixture(scope="session")
def pkg(hand_build):
    """The description package of the default hand (``hand_build``)."""
    result, _ = hand_build
    return result.out_dir / "description"


#: the three reference hands (tests/cad/conftest.py HANDS): (name, parameter file, side)
EXPORT_HANDS = [("default", None, None), ("left", None, "left"),
                ("hand_length_170", HERE.parents[1] / "params" / "examples" / "small.toml", None)]


@pytest.fixture(scope="session")
def hand_export(hand_build, tmp_path_factory):
    """``hand_export(kind)`` -> the BuildResult of one of :data:`EXPORT_HANDS` (the default hand's
    is ``hand_build``'s), each built once per session with the session's part cache, and sliced
    when PrusaSlicer is installed (the description's masses then come from the slicer)."""
    from phantom_cad.export.pipeline import build_hand

    result, cache = hand_build
    done = {"default": result}

    def get(kind: str):
        if kind not in done:
            _, path, side = next(h for h in EXPORT_HANDS if h[0] == kind)
            done[kind] = build_hand(path, tmp_path_factory.mktemp(kind) / "export", side=side, cache_dir=cache,
                                    jobs=2, slice=None)
        return done[kind]
    return get
