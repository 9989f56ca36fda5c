from __future__ import annotations

import copy
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_PARAMS = ROOT / "params" / "phantom.toml"


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


#: session fixtures that build a whole hand or every part of one: a test that uses any of them
#: (directly or through another fixture) is in the slow tier (`make test`, not `make test-fast`)
SLOW_FIXTURES = frozenset({
    "built", "placed", "hand_parts", "hand_meshes",      # tests/cad/conftest.py
    "hand_build", "pkg", "hand_export",                  # tests/export/conftest.py
    "standin_build",                                     # the stand-in hand, through worker processes
    "part_cache",                                        # a build that shares the session's cache
})


@pytest.hookimpl(tryfirst=True)     # before -m deselects by marker
def pytest_collection_modifyitems(config, items):
    for item in items:
        if SLOW_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)
