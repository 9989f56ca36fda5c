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
