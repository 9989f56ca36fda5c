from __future__ import annotations

import copy
from pathlib import Path

import pytest

from tests.support import hands

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_PARAMS = ROOT / "params" / "phantom.toml"
#: the power grasp's cylinder across the palm (mm): the paper's 35 mm
POWER_GRASP_MM = 35.0


@pytest.fixture(scope="session")
def default_document():
    import tomllib

    return tomllib.loads(DEFAULT_PARAMS.read_text(encoding="utf-8"))


@pytest.fixture
def document(default_document):
    """A fresh, mutable copy of the default parameter document."""
    return copy.deepcopy(default_document)


@pytest.fixture(scope="session")
def hand():
    from phantom_cad import load_hand

    return load_hand()


@pytest.fixture(scope="session")
def part_cache(tmp_path_factory):
    """The part cache of every whole-hand build of the session: a part is built once, by whichever
    build needs it first (the cache verifies every entry it serves)."""
    return tmp_path_factory.mktemp("part-cache")


@pytest.fixture(scope="session")
def hand_build(tmp_path_factory, part_cache):
    """(BuildResult, part cache) of the default hand with the real parts, built once per session
    (jobs = 2) with the session's part cache."""
    from phantom_cad.export.pipeline import build_hand

    root = tmp_path_factory.mktemp("hand")
    result = build_hand(None, root / "exports" / "phantom", cache_dir=part_cache, jobs=2, slice=None)
    return result, part_cache


@pytest.fixture(scope="session")
def hand_export(hand_build, tmp_path_factory):
    """``hand_export(kind)`` -> the BuildResult of one of the reference hands
    (``tests.support.hands.HANDS``; the default hand's is ``hand_build``'s), each built once per
    session with the session's part cache, and sliced when PrusaSlicer is installed (the
    description's masses then come from the slicer); or of ``"slender"``, not sliced."""
    from phantom_cad.export.pipeline import build_hand

    result, cache = hand_build
    done = {"default": result}

    def get(kind: str):
        if kind not in done:
            path, side = hands.hand_source(kind)
            done[kind] = build_hand(path, tmp_path_factory.mktemp(kind) / "export", side=side, cache_dir=cache,
                                    jobs=2, slice=None if kind in hands.HANDS else False)
        return done[kind]
    return get


@pytest.fixture(scope="session")
def hand_parts(hand_export, part_cache):
    """``hand_parts(kind)`` -> (params, {name: solid in its link frame, mm}) of every part of a
    hand ``hand_export`` exports: the solids of its export, each read back from the BREP of the
    part cache entry the export's manifest names."""
    from phantom_cad.params import parse

    done = {}

    def get(kind: str):
        if kind not in done:
            p = parse(hands.hand_document(kind))
            result = hand_export(kind)
            assert (p.side, p.digest) == (result.side, result.params_digest)
            done[kind] = (p, hands.export_solids(result, part_cache))
        return done[kind]
    return get


@pytest.fixture(scope="session")
def hand_meshes(hand_export, part_cache):
    """``hand_meshes(kind)`` -> {name: (vertices, faces)} of ``hand_parts(kind)``'s solids at the
    export's STL tolerance (link frames, mm): the meshes of the export (each part's mesh.npz)."""
    done = {}

    def get(kind: str):
        if kind not in done:
            done[kind] = hands.export_meshes(hand_export(kind), part_cache)
        return done[kind]
    return get


@pytest.fixture(scope="session")
def power_grasps(hand_parts):
    """``power_grasps(kind)`` -> (hand, grasp, every position tried) of ``cad.grasp.power_grasp``:
    the 35 mm cylinder across the palm of one of the reference hands, on its export's solids."""
    from phantom_cad import make_hand
    from phantom_cad.cad import grasp

    done = {}

    def get(kind: str):
        if kind not in done:
            p, shapes = hand_parts(kind)
            h = make_hand(p)
            done[kind] = (h, *grasp.power_grasp(h, shapes, POWER_GRASP_MM))
        return done[kind]
    return get


#: session fixtures that build a whole hand or every part of one: a test that uses any of them
#: (directly or through another fixture) is in the slow tier (`make test`, not `make test-fast`)
SLOW_FIXTURES = frozenset({
    "built", "placed", "hand_parts", "hand_meshes",      # tests/cad/conftest.py, here
    "hand_build", "hand_export", "power_grasps",         # here
    "pkg",                                               # tests/export/conftest.py
    "standin_build",                                     # the stand-in hand, through worker processes
    "part_cache",                                        # a build that shares the session's cache
})


@pytest.hookimpl(tryfirst=True)     # before -m deselects by marker
def pytest_collection_modifyitems(config, items):
    for item in items:
        if SLOW_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)
