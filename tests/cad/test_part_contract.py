"""The part protocol as a contract: every family implements what the assembly and the export
pipeline call on a part, and a part's cache key (``inputs()``) covers every parameter it reads."""

from __future__ import annotations

import inspect
import sys
from pathlib import Path

import numpy as np
import pytest

from phantom_cad import canon
from phantom_cad.canon import plain
from phantom_cad.cad import assembly, registry
from phantom_cad.cad.parts import pulley, tendons
from phantom_cad.cad.parts.base import Part
from phantom_cad.kinematics import routing, routing_paths, topology
from phantom_cad.params import parse

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "support"))
import param_reads  # noqa: E402

#: what the assembly (``cad.assembly``, ``cad.verify``) and the export pipeline call on a part
CALLED = ("for_link", "build", "inputs", "verify", "collision_solids", "support_blockers", "print_rotation",
          "color", "digit", "name")


def test_the_part_base_is_abstract_in_what_every_family_must_make():
    assert inspect.isabstract(Part)
    assert Part.__abstractmethods__ == {"for_link", "build", "inputs"}
    with pytest.raises(TypeError):
        Part()


@pytest.mark.parametrize("family", registry.FAMILIES, ids=lambda f: f.__name__)
def test_every_family_implements_the_protocol(family):
    assert issubclass(family, Part)
    assert not inspect.isabstract(family), f"{family.__name__} lacks {sorted(family.__abstractmethods__)}"
    for method in ("for_link", "build", "inputs"):
        assert getattr(family, method) is not getattr(Part, method), f"{family.__name__}.{method}"


def test_every_part_of_the_default_hand_is_made_through_the_registry(params):
    for name in registry.PART_NAMES:
        part = registry.part(params, name)
        assert type(part) is registry.FAMILY[name]
        for what in CALLED:
            assert hasattr(part, what), f"{name} has no {what}"
        assert isinstance(part.inputs(), dict)


def test_the_fingertip_pads_the_assembly_asks_for_are_implemented(params):
    """``assembly.tip_frames`` asks each digit's last link for its pad: its family has one of its
    own (the base's refuses), and it is a rigid transform."""
    for digit in topology.DIGITS:
        distal = topology.digit_links(digit)[-1]
        part = registry.part(params, distal.name)
        assert type(part).pad is not Part.pad, f"{type(part).__name__} makes the fingertip {distal.name} without pad()"
        T = np.asarray(part.pad(), float)
        assert T.shape == (4, 4)
        assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3)) and np.allclose(T[3], [0, 0, 0, 1])
    assert set(assembly.tip_frames(params)) == {f"{d}_tip" for d in topology.DIGITS}


def test_a_part_without_a_fingertip_refuses_a_pad(params):
    tips = {topology.digit_links(d)[-1].name for d in topology.DIGITS}
    for name in registry.PART_NAMES:
        if name not in tips:
            with pytest.raises(ValueError, match=f"{name} is not a fingertip"):
                registry.part(params, name).pad()


# ---------------------------------------------------------------------------
# the cache key covers what a part reads
# ---------------------------------------------------------------------------

@pytest.fixture(autouse=True)
def _memos_kept(monkeypatch):
    """Every memo of the package keeps its entries while a test of this module runs: a store
    cleared past its cap in the middle of a recording (it may be near its cap from earlier tests)
    drops what ``_routing_ahead`` made unrecorded, and the part is charged with the whole hand."""
    from phantom_cad.kinematics.memo import memoised

    def kept(store, key, make, cap=None):
        return memoised(store, key, make, cap=sys.maxsize)

    users = [m for name, m in sys.modules.items() if name.startswith("phantom_cad.")
             and name != "phantom_cad.kinematics.memo" and getattr(m, "memoised", None) is memoised]
    assert users, "no module memoises through kinematics.memo"
    for module in users:
        monkeypatch.setattr(module, "memoised", kept)


def _routing_ahead(params) -> None:
    """The whole-hand routing computations a part takes its link's share of (every tendon routed,
    its runs, the travel poses), made for the memo. Each reads every digit, so recorded they would
    charge every part with the whole hand; what a part takes of them is checked on its own
    (``test_what_a_part_takes_of_the_routing_moves_only_with_its_key``)."""
    routing.routes(params, right_handed=True)
    routing_paths.runs(params, right_handed=True)
    for n in (11, 21):      # the fractions of routing_paths.arc_range and run_sweep
        routing_paths.travel_poses(params, np.linspace(0.0, 1.0, n))


def _reads(params, name: str, build: bool) -> param_reads.Reads:
    """What part ``name`` reads while it is made, its properties are evaluated, its pad found (a
    fingertip) and, with ``build``, while it is built, verified and asked for its collision solids
    and support blockers."""
    rp, reads = param_reads.recording(params)
    _routing_ahead(param_reads.ahead(params, reads))
    part = registry.part(rp, name)
    for attr, value in inspect.getmembers(type(part)):
        if isinstance(value, property):
            getattr(part, attr)
    if type(part).pad is not Part.pad and part.link.name == topology.digit_links(part.digit)[-1].name:
        part.pad()
    if build:
        shape = part.build()
        part.verify(shape)
        part.collision_solids()
        part.support_blockers()
    return reads


def _cover(params, name: str) -> param_reads.Reads:
    """The document keys part ``name``'s ``inputs()`` reads (its cache key)."""
    rp, cover = param_reads.recording(params)
    registry.part(rp, name).inputs()
    return cover


@pytest.fixture(scope="module")
def sources():
    cache = {}

    def get(params):
        if params.digest not in cache:
            cache[params.digest] = param_reads.field_sources(plain(params.document))
        return cache[params.digest]
    return get


def test_the_field_map_comes_from_the_parser(params, sources):
    """Known answers of the schema: a segment length is its fraction of the hand length, a chain's
    radii are its pulley table, a guide's d1 its ``d1_mm``; the topology's chain spec comes from
    no key; every key the parser asks for can be nudged alone."""
    src, stuck = sources(params)
    assert src[("fingers", "index", "proximal")] == {("fingers", "index", "length_fraction", "proximal"),
                                                     ("hand", "hand_length_mm")}
    assert src[("thumb", "chain", "radii")] == {("thumb", "pulley_radius_mm", "ip"), ("thumb", "pulley_radius_mm", "mp")}
    assert src[("thumb", "chain", "guide", "d1")] == {("thumb", "guide", "d1_mm")}
    assert src[("side",)] == {("hand", "side")}
    assert src[("thumb", "chain", "spec", "keys")] == set()
    assert stuck == [("schema_version",), ("plugins",)]


def test_the_recording_sees_what_a_part_reads_and_its_key_leaves_out(params, sources):
    """A family that reads a parameter its ``inputs()`` leaves out is caught, through a field and
    through the document."""
    from phantom_cad.cad.parts.phalanx import Phalanx

    class Leaky(Phalanx):
        @property
        def leak(self):
            return self.params.mechanics.tendon_EA + self.params.document["servo"]["speed_deg_s"]

    src, _ = sources(params)
    rp, reads = param_reads.recording(params)
    part = Leaky.for_link(rp, topology.link("index_proximal"))
    assert part.leak > 0
    assert ("fingers", "index", "proximal") in reads.fields
    assert param_reads.uncovered(reads, _cover(params, "index_proximal"), src, plain(params.document)) == [
        "mechanics.tendon_EA_N (read as mechanics.tendon_EA)", "servo.speed_deg_s"]


@pytest.mark.parametrize("side", ("right", "left"))
def test_a_part_reads_nothing_its_cache_key_leaves_out(params, variant, sources, side):
    """What each part reads while it is made and measured (no solid built) is in its ``inputs()``."""
    p = params if side == "right" else variant(lambda d: d["hand"].__setitem__("side", "left"))
    src, _ = sources(p)
    doc = plain(p.document)
    problems = {name: param_reads.uncovered(_reads(p, name, build=False), _cover(p, name), src, doc)
                for name in registry.PART_NAMES}
    assert {n: u for n, u in problems.items() if u} == {}


@pytest.mark.slow
def test_a_built_part_reads_nothing_its_cache_key_leaves_out(params, sources):
    """What each part reads while it is made, built, verified, and asked for its collision solids
    and support blockers is in its ``inputs()``."""
    src, _ = sources(params)
    doc = plain(params.document)
    problems = {name: param_reads.uncovered(_reads(params, name, build=True), _cover(params, name), src, doc)
                for name in registry.PART_NAMES}
    assert {n: u for n, u in problems.items() if u} == {}


def _rounded(obj, digits: int = 9):
    if isinstance(obj, float):
        return round(obj, digits) + 0.0
    if isinstance(obj, dict):
        return {k: _rounded(v, digits) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_rounded(v, digits) for v in obj]
    return obj


def _routing_share(params, name: str):
    """What part ``name`` takes of the whole-hand routing: its link's grooves, anchors, channels and
    sweeps (``tendons.LinkTendons``) and its clamps' angles (a pulley's), to 1e-9 mm or rad (a
    channel's ends come back from the palm frame through another finger's transforms, which moves
    their last bits)."""
    lt = tendons.LinkTendons(params, name)
    return _rounded(canon.jsonable({**{k: v for k, v in vars(lt).items() if k != "params"},
                                    "clamps": pulley._anchor_angles(params, name)}))


@pytest.mark.slow
def test_what_a_part_takes_of_the_routing_moves_only_with_its_key(params):
    """Nudge each document key alone: the routing share of every part whose ``inputs()`` leaves
    that key out stays the same."""
    doc = plain(params.document)
    covers = {name: _cover(params, name) for name in registry.PART_NAMES}
    base = {name: _routing_share(params, name) for name in registry.PART_NAMES}
    moved, _ = param_reads.nudges(doc)
    problems = []
    for key, nudged in moved:
        outside = [n for n in registry.PART_NAMES if not param_reads.covered(key, covers[n], doc)]
        if outside:
            q = parse(nudged)
            problems += [f"{n}: {'.'.join(map(str, key))}" for n in outside if _routing_share(q, n) != base[n]]
    assert problems == []
