"""Fixtures of the part tests: the default hand's parts, built once per session.

* ``params``: the default hand (params/phantom.toml).
* ``built``: {name: Built} of every part (right hand).
* ``placed``: {name: solid} every part moved to its rest pose in the hand frame.
* ``variant(edit)``: parse the default document after ``edit(doc)`` (a plain dict).

The three reference hands' solids and meshes (``hand_parts``, ``hand_meshes``) are the session's
exports' (tests/conftest.py).
"""

from __future__ import annotations

import copy

import pytest

from phantom_cad import load_params
from phantom_cad.params import parse
from phantom_cad.canon import plain as _plain


@pytest.fixture(scope="session")
def params():
    return load_params()


@pytest.fixture(scope="session")
def document(params):
    return _plain(params.document)


@pytest.fixture(scope="session")
def variant(document):
    def make(edit):
        doc = copy.deepcopy(document)
        edit(doc)
        return parse(doc)
    return make


@pytest.fixture(scope="session")
def built(params, hand_parts):
    """{name: Built} of every part of the default hand: the solids of the session's export
    (``hand_parts``: each part's BREP from its cache entry), the rest made around them."""
    from phantom_cad.cad import assembly

    p, shapes = hand_parts("default")
    assert p.digest == params.digest
    return {name: assembly.build_part(params, name, shape=shapes[name]) for name in assembly.part_names(params)}


@pytest.fixture(scope="session")
def placed(built):
    from phantom_cad.cad import measure
    return {name: measure.placed(b.shape, b.T_hand_link) for name, b in built.items()}
