"""Fixtures of the part tests: the default hand's parts, built once per session.

* ``params``: the default hand (params/phantom.toml).
* ``built``: {name: Built} of every part (right hand).
* ``placed``: {name: solid} every part moved to its rest pose in the hand frame.
* ``variant(edit)``: parse the default document after ``edit(doc)`` (a plain dict).
* ``hand_parts(kind)``: (params, {name: shape}) of every part of one of the three reference hands
  (:data:`HANDS`), built once per session; ``hand_meshes(kind)``: their meshes at the export's
  STL tolerance.
"""

from __future__ import annotations

import copy
from pathlib import Path

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
def built(params):
    from phantom_cad.cad import assembly
    return {name: assembly.build_part(params, name) for name in assembly.part_names(params)}


@pytest.fixture(scope="session")
def placed(built):
    from phantom_cad.cad import measure
    return {name: measure.placed(b.shape, b.T_hand_link) for name, b in built.items()}


#: the three reference hands: the default, its left twin, and a hand of hand_length 170 mm (a file of its
#: own, params/examples/small.toml: the fingers narrower, the pitch shorter, its CMC placement solved
#: for it)
HANDS = ("default", "left", "hand_length_170")
SMALL = Path(__file__).resolve().parents[2] / "params" / "examples" / "small.toml"


def hand_document(kind: str, document: dict) -> dict:
    """The plain document of one of :data:`HANDS`."""
    if kind == "hand_length_170":
        return _plain(load_params(SMALL).document)
    doc = copy.deepcopy(document)
    if kind == "left":
        doc["hand"]["side"] = "left"
    return doc


@pytest.fixture(scope="session")
def hand_parts(document, built):
    """``hand_parts(kind)`` -> (params, {name: shape in its link frame}) of every part of one of
    :data:`HANDS`, built once per session (the default hand's are ``built``'s)."""
    from phantom_cad.cad import assembly

    cache = {}

    def get(kind: str):
        if kind not in cache:
            p = parse(hand_document(kind, document))
            if kind == "default":
                shapes = {n: b.shape for n, b in built.items()}
            else:
                shapes = {n: assembly.build_part(p, n).shape for n in assembly.part_names(p)}
            cache[kind] = (p, shapes)
        return cache[kind]
    return get


@pytest.fixture(scope="session")
def hand_meshes(hand_parts):
    """``hand_meshes(kind)`` -> {name: (vertices, faces)} of :func:`hand_parts`' shapes at the
    export's STL tolerance (link frames, mm), tessellated once per session."""
    from phantom_cad.export import step_stl

    cache = {}

    def get(kind: str):
        if kind not in cache:
            p, shapes = hand_parts(kind)
            tol = p.print.stl_tolerance * 1e3
            cache[kind] = {n: step_stl.tessellate(s, tol) for n, s in shapes.items()}
        return cache[kind]
    return get
