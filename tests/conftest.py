from __future__ import annotations

import copy
from pathlib import Path

import pytest

from tests.support import hands, shared

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
def shared_root(tmp_path_factory) -> Path:
    """The folder the test processes of this run share (``tests.support.shared``)."""
    return shared.run_root(tmp_path_factory)


@pytest.fixture(scope="session")
def part_cache(shared_root):
    """The part cache of every whole-hand build of the run: a part is built once, by whichever
    build needs it first (the cache verifies every entry it serves; builds in several processes
    share it safely)."""
    path = shared_root / "part-cache"
    path.mkdir(exist_ok=True)
    return path


def _export(shared_root: Path, part_cache: Path, kind: str):
    """The BuildResult of one of the hands of ``tests.support.hands``, built once per test run with
    the run's part cache (jobs = 2): the default hand sliced when PrusaSlicer is installed (its
    description's masses then come from the slicer), the others not (``hands.SLICED``)."""
    from phantom_cad.export.pipeline import build_hand

    def make():
        path, side = hands.hand_source(kind)
        return build_hand(path, shared_root / "exports" / kind, side=side, cache_dir=part_cache, jobs=2,
                          slice=None if kind in hands.SLICED else False)
    return shared.once(shared_root, f"export-{kind}", make)


@pytest.fixture(scope="session")
def hand_build(shared_root, part_cache):
    """(BuildResult, part cache) of the default hand with the real parts, built once per run."""
    return _export(shared_root, part_cache, "default"), part_cache


@pytest.fixture(scope="session")
def hand_export(hand_build, shared_root, part_cache):
    """``hand_export(kind)`` -> the BuildResult of one of the reference hands
    (``tests.support.hands.HANDS``; the default hand's is ``hand_build``'s) or of ``"slender"``,
    each built once per run (:func:`_export`)."""
    def get(kind: str):
        return hand_build[0] if kind == "default" else _export(shared_root, part_cache, kind)
    return get


#: the sized hand of the tests: `phantom-cad size --hand-length 160 --hand-breadth 72`
SIZED_HAND = (160.0, 72.0, "sized_160")

#: a large sized left hand: `phantom-cad size --hand-length 205 --hand-breadth 95 --side left` (its
#: thumb CMC base's near relief sphere dips 0.03 mm through the palmar face)
SIZED_HAND_205 = (205.0, 95.0, "sized_205", "left")


#: a person measured digit by digit (mm, joint centre to joint centre): 190.2 x 85 mm, each segment
#: within 8 % of the reference's ratio
SIZED_DIGITS = (190.2, 85.0, "sized_digits", "right", """\
[thumb]
metacarpal = 45.3
proximal = 39.4
distal = 30.3

[index]
proximal = 45.1
middle = 26.9
distal = 17.1

[middle]
proximal = 47.6
middle = 33.2
distal = 21.0

[ring]
proximal = 47.3
middle = 30.8
distal = 22.0

[pinky]
proximal = 41.8
middle = 22.9
distal = 18.1
""")


def _sized(shared_root, length: float, breadth: float, name: str, side: str = "right", segments: str = ""):
    """(parameter file, the command's CompletedProcess) of ``phantom-cad size --hand-length
    LENGTH --hand-breadth BREADTH --side SIDE --name NAME [--segments FILE]`` (the CMC placement
    searched, the preflight rules checked; ``segments``: the file's text), run once per test run, its
    files in the run's folder."""
    import subprocess
    import sys

    path = shared_root / f"{name}.toml"

    def make():
        extra = []
        if segments:
            person = shared_root / f"{name}_segments.toml"
            person.write_text(segments, encoding="utf-8")
            extra = ["--segments", str(person)]
        return subprocess.run([sys.executable, "-m", "phantom_cad", "size", "--hand-length", str(length),
                               "--hand-breadth", str(breadth), "--side", side, "--name", name, "--out", str(path),
                               *extra], capture_output=True, text=True)
    return path, shared.once(shared_root, f"size-{name}", make)


@pytest.fixture(scope="session")
def sized_file(shared_root):
    """(parameter file, the command's CompletedProcess) of :data:`SIZED_HAND`, made once per run."""
    return _sized(shared_root, *SIZED_HAND)


@pytest.fixture(scope="session")
def sized_file_205(shared_root):
    """(parameter file, the command's CompletedProcess) of :data:`SIZED_HAND_205`, made once per run."""
    return _sized(shared_root, *SIZED_HAND_205)


def _sized_build(sized, name: str, shared_root, part_cache):
    """(document, BuildResult) of a sized file (``_sized``'s), built with the run's part cache,
    unsliced; made once per run."""
    import tomllib

    path, proc = sized
    assert proc.returncode == 0, proc.stderr

    def make():
        from phantom_cad.export.pipeline import build_hand

        return build_hand(path, shared_root / "exports" / name, cache_dir=part_cache, jobs=2, slice=False)
    return tomllib.loads(path.read_text(encoding="utf-8")), shared.once(shared_root, f"export-{name}", make)


@pytest.fixture(scope="session")
def sized_hand(sized_file, shared_root, part_cache):
    """(document, BuildResult) of :data:`SIZED_HAND`: the file ``phantom-cad size`` wrote
    (``sized_file``), built with the run's part cache, unsliced; made once per run."""
    return _sized_build(sized_file, SIZED_HAND[2], shared_root, part_cache)


@pytest.fixture(scope="session")
def sized_hand_205(sized_file_205, shared_root, part_cache):
    """(document, BuildResult) of :data:`SIZED_HAND_205` (``sized_file_205``), as ``sized_hand``."""
    return _sized_build(sized_file_205, SIZED_HAND_205[2], shared_root, part_cache)


@pytest.fixture(scope="session")
def sized_hand_digits(shared_root, part_cache):
    """(document, BuildResult) of :data:`SIZED_DIGITS`, sized once and built as ``sized_hand``."""
    return _sized_build(_sized(shared_root, *SIZED_DIGITS), SIZED_DIGITS[2], shared_root, part_cache)


@pytest.fixture(scope="session")
def hand_entries(hand_export, part_cache):
    """``hand_entries(kind)`` -> {name: part cache entry} of every part of a hand ``hand_export``
    exports, as its manifest names them, each checked once against its hashes."""
    done = {}

    def get(kind: str):
        if kind not in done:
            done[kind] = hands.export_entries(hand_export(kind), part_cache)
        return done[kind]
    return get


@pytest.fixture(scope="session")
def hand_parts(hand_export, hand_entries):
    """``hand_parts(kind)`` -> (params, {name: solid in its link frame, mm}) of every part of a
    hand ``hand_export`` exports: the solids of its export, each read back from the BREP of its
    part cache entry."""
    from phantom_cad.params import parse

    done = {}

    def get(kind: str):
        if kind not in done:
            p = parse(hands.hand_document(kind))
            result = hand_export(kind)
            assert (p.side, p.digest) == (result.side, result.params_digest)
            done[kind] = (p, hands.entry_solids(hand_entries(kind)))
        return done[kind]
    return get


@pytest.fixture(scope="session")
def hand_meshes(hand_entries):
    """``hand_meshes(kind)`` -> {name: (vertices, faces)} of ``hand_parts(kind)``'s solids at the
    export's STL tolerance (link frames, mm): the meshes of the export (each part's mesh.npz)."""
    done = {}

    def get(kind: str):
        if kind not in done:
            done[kind] = hands.entry_meshes(hand_entries(kind))
        return done[kind]
    return get


@pytest.fixture(scope="session")
def power_grasps(hand_parts, shared_root):
    """``power_grasps(kind)`` -> (hand, grasp, every position tried) of ``cad.grasp.power_grasp``:
    the power grasp's cylinder (35 mm at 189 mm, scaled with the hand) across the palm of one of the
    reference hands, on its export's solids; made once per run."""
    from phantom_cad import make_hand
    from phantom_cad.cad import grasp
    from phantom_cad.kinematics.power_grasp import power_grasp_diameter_mm

    done = {}

    def get(kind: str):
        if kind not in done:
            p, shapes = hand_parts(kind)
            # the grasp's commands and the hold in tests/export/test_mjcf.py are set on the paper's
            # compensation: with the routed statics (measured with the cylinder free while the
            # fingers closed) the default hand squeezed the cylinder 5.6 mm and the left hand dropped it
            h = make_hand(p, compensation="paper")
            found = shared.once(shared_root, f"power-grasp-{kind}",
                                lambda: grasp.power_grasp(h, shapes, power_grasp_diameter_mm(p)))
            done[kind] = (h, *found)
        return done[kind]
    return get


#: session fixtures that build a whole hand or every part of one: a test that uses any of them
#: (directly or through another fixture) is in the slow tier (`make test`, not `make test-fast`)
SLOW_FIXTURES = frozenset({
    "hand_build", "hand_export", "hand_entries", "hand_parts", "hand_meshes", "power_grasps",  # here
    "sized_hand", "sized_hand_205", "sized_hand_digits",  # here
    "built", "placed",                                   # tests/cad/conftest.py
    "pkg", "standin_build",                              # tests/export/conftest.py (the stand-in through workers)
    "part_cache",                                        # a build that shares the run's cache
})


@pytest.hookimpl(tryfirst=True)     # before -m deselects by marker
def pytest_collection_modifyitems(config, items):
    for item in items:
        if SLOW_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)
