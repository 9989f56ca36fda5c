"""Fixtures of the export tests.

* ``standin``: the assembly interface (phantom_cad.export.interface.ASSEMBLY_MODULE, normally
  phantom_cad.cad.assembly) replaced by tests/export/standin_assembly.py
  (three parts of known geometry; faults can be injected) for the pipeline tests.
* ``standin_build``: the stand-in hand built once per session into a tmp dir.
* ``pkg``: the robot description package (``description/``) of the default hand
  (``hand_build``, tests/conftest.py).
"""

from __future__ import annotations

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


@pytest.fixture(scope="session")
def pkg(hand_build):
    """The description package of the default hand (``hand_build``)."""
    result, _ = hand_build
    return result.out_dir / "description"
