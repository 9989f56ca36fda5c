"""Property: every parameter file that validates builds (validation is complete).

Files are the default file with one to three numeric fields moved by a factor between 1/4 and 4
(tests/support/param_space.py; zeros move by up to +-10 in their unit). Each one that
``params validate`` accepts (``parse`` and the palm layout's ``cad.preflight.check``) is built for real (every part, its checks, the assembly and its interference
check, STEP and STL with their read-back checks; renders and slicing off) and must build.

``make test`` runs a small derandomized sample (PHANTOM_PROPERTY_EXAMPLES, default 10); ``make
property`` runs a large one (docs/reliability.md gives its figures). A file that validates and
does not build fails the test with the fields that were moved.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, Phase, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "support"))
from param_space import leaves, perturb  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = int(os.environ.get("PHANTOM_PROPERTY_EXAMPLES", "10"))
REPORT = os.environ.get("PHANTOM_PROPERTY_REPORT")

pytestmark = pytest.mark.slow     # the property test: EXAMPLES builds

import tomllib  # noqa: E402

DEFAULT = tomllib.loads((ROOT / "params" / "phantom.toml").read_text(encoding="utf-8"))
N_LEAVES = len(list(leaves(DEFAULT)))

changes = st.lists(st.tuples(st.integers(0, N_LEAVES - 1), st.floats(-1.0, 1.0)), min_size=1, max_size=3)


@pytest.fixture(scope="module")
def cache(hand_build):
    """The session's part cache (the default hand's parts are in it: a perturbed file rebuilds
    only the parts whose inputs moved, and every served entry is verified)."""
    return hand_build[1]


@pytest.fixture(scope="module")
def sample(cache):
    """The derandomized sample, each file that validates built: its counts and the first failure
    (None when every file that validated was built)."""
    import tomli_w

    from phantom_cad.cad import preflight
    from phantom_cad.export.pipeline import build_hand
    from phantom_cad.params import ParamError, parse

    stats = {"generated": 0, "validated": 0, "built": 0, "refused": {}, "build_seconds": [], "failure": None}

    @settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
              phases=(Phase.explicit, Phase.generate),
              suppress_health_check=list(HealthCheck))
    @given(changes)
    def every_file_that_validates_builds(changes):
        doc, moved = perturb(DEFAULT, changes)
        stats["generated"] += 1
        try:
            preflight.check(parse(doc, "perturbed.toml"))    # what `params validate` checks
        except ParamError as exc:
            stats["refused"][exc.field] = stats["refused"].get(exc.field, 0) + 1
            return
        stats["validated"] += 1
        work = Path(tempfile.mkdtemp(prefix="phantom-property-"))
        try:
            path = work / "hand.toml"
            path.write_text(tomli_w.dumps(doc), encoding="utf-8")
            t = time.perf_counter()
            try:
                build_hand(path, work / "out", jobs=2, slice=False, render=False, cache_dir=cache)
            except Exception as exc:   # any failure is the finding
                first = str(exc).splitlines()[0] if str(exc) else ""
                detail = "\n".join(str(exc).splitlines()[1:3])
                if stats["failure"] is None:
                    stats["failure"] = (f"validates but does not build: {moved}\n"
                                        f"{type(exc).__name__}: {first}\n{detail}")
                return
            stats["build_seconds"].append(time.perf_counter() - t)
            stats["built"] += 1
        finally:
            shutil.rmtree(work, ignore_errors=True)

    every_file_that_validates_builds()
    return stats


def test_every_file_that_validates_builds(sample):
    if sample["failure"] is not None:
        pytest.fail(sample["failure"])


def test_the_sample_built_files(sample):
    """The sample above is not all refusals: some perturbed files validated and were built."""
    assert sample["generated"] == EXAMPLES
    assert sample["built"] >= 1 and sample["built"] == sample["validated"]
    if REPORT:
        s = {k: v for k, v in sample.items() if k != "failure"}
        secs = sorted(s.pop("build_seconds"))
        s["median_build_s"] = round(secs[len(secs) // 2], 1) if secs else None
        s["refused"] = dict(sorted(s["refused"].items(), key=lambda kv: -kv[1]))
        Path(REPORT).write_text(json.dumps(s, indent=1) + "\n")
