"""The CAD kernel's process set-up (phantom_cad/cad/kernel.py): build123d imported without
scikit-learn, OpenCascade on a fixed number of threads, and the build's workers set up with both
(export.pool.init_worker, export.pipeline.occt_threads). Each check runs in a fresh interpreter:
what a process has imported is the thing measured."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _run(code: str) -> dict:
    """Run ``code`` in a fresh interpreter (the project on its path); it prints one JSON line."""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_build123d_without_scikit_learn():
    """After import_build123d, no sklearn module is loaded; build123d's DBSCAN is the real one
    when called (two clusters in a known point set: scikit-learn's own answer, imported then), and
    a later ``import sklearn`` gives the real package."""
    got = _run("""
import json, sys
import numpy as np
from phantom_cad.cad.kernel import import_build123d
bd = import_build123d()
loaded = sorted(m for m in sys.modules if m == "sklearn" or m.startswith("sklearn."))
from build123d import brep_from_stl
pts = np.array([[0.0, 0.0], [0.1, 0.0], [0.0, 0.1], [5.0, 5.0], [5.1, 5.0]])
labels = brep_from_stl.DBSCAN(eps=0.5, min_samples=2).fit(pts).labels_.tolist()
import sklearn, sklearn.cluster
print(json.dumps({"box": bd.Solid.make_box(1, 2, 3).volume, "loaded": loaded, "labels": labels,
                  "real": hasattr(sklearn, "__version__") and isinstance(sklearn.cluster.DBSCAN, type)}))
""")
    assert got["loaded"] == []
    assert got["box"] == pytest.approx(6.0)
    assert got["labels"] == [0, 0, 0, 1, 1]       # by hand: three points within 0.5 mm, two apart
    assert got["real"] is True


@pytest.mark.slow
def test_build123d_as_usual_when_scikit_learn_is_loaded():
    """With scikit-learn already imported, build123d is imported as usual (its own DBSCAN)."""
    got = _run("""
import json, sklearn.cluster
from phantom_cad.cad.kernel import import_build123d
import_build123d()
from build123d import brep_from_stl
print(json.dumps({"same": brep_from_stl.DBSCAN is sklearn.cluster.DBSCAN}))
""")
    assert got["same"] is True


@pytest.mark.slow
def test_build123d_asking_for_more_of_scikit_learn(tmp_path):
    """A build123d whose import asks scikit-learn for more than DBSCAN (a stand-in package first on
    the path) is imported again as usual: the real scikit-learn then, the stand-in's body run."""
    pkg = tmp_path / "build123d"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from sklearn.cluster import KMeans\nKIND = KMeans.__module__\n")
    code = f"""
import json, sys
sys.path.insert(0, {str(tmp_path)!r})
from phantom_cad.cad.kernel import import_build123d
bd = import_build123d()
print(json.dumps({{"file": bd.__file__, "kind": bd.KIND, "sklearn": hasattr(sys.modules["sklearn"], "__version__")}}))
"""
    got = _run(code)
    assert got["file"] == str(pkg / "__init__.py")
    assert got["kind"].startswith("sklearn.cluster") and got["sklearn"] is True


_PARTS = ("palm", "index_proximal", "thumb_cmc_base")
_BUILD = """
import hashlib, json
from phantom_cad import load_params
from phantom_cad.cad import assembly
from phantom_cad.export import step_stl
from OCP.OSD import OSD_ThreadPool
p = load_params()
out = {{n: hashlib.sha256(step_stl.brep_bytes(assembly.build_part(p, n).shape)).hexdigest() for n in {parts!r}}}
print(json.dumps({{"breps": out, "threads": OSD_ThreadPool.DefaultPool_s().NbThreads()}}))
"""


def test_a_workers_share_of_the_threads_builds_the_same_solids(hand_entries):
    """The parts of the session's default export, built by two workers with their share of the
    CPUs (kernel.use_threads(occt_threads(2)): one thread each on two cores), are the same BREP
    bytes as with OpenCascade's default pool (a thread per logical processor) in a fresh
    interpreter."""
    import hashlib

    from phantom_cad.export.pipeline import occt_threads

    entries = hand_entries("default")
    default = _run(_BUILD.format(parts=_PARTS))
    assert default["threads"] == os.cpu_count()
    assert occt_threads(2) is not None and occt_threads(2) < default["threads"]
    assert {n: hashlib.sha256((entries[n] / "part.brep").read_bytes()).hexdigest() for n in _PARTS} == default["breps"]


def test_use_threads_refuses_zero():
    from phantom_cad.cad.kernel import use_threads

    with pytest.raises(ValueError, match="at least 1"):
        use_threads(0)


@pytest.mark.parametrize("jobs, cpus, threads", [(1, 2, None), (1, 8, None), (2, 2, 1), (2, 8, 4), (3, 8, 2),
                                                 (16, 2, 1)])
def test_occt_threads_share(jobs, cpus, threads):
    """Each worker's share of the CPUs (by hand: cpus // jobs, at least 1), None for one worker."""
    from phantom_cad.export.pipeline import occt_threads

    assert occt_threads(jobs, cpus) == threads


def _worker_state() -> dict:
    import sys

    from OCP.OSD import OSD_Parallel, OSD_ThreadPool

    return {"sklearn": any(m == "sklearn" or m.startswith("sklearn.") for m in sys.modules),
            "build123d": "build123d" in sys.modules, "occt": OSD_Parallel.ToUseOcctThreads_s(),
            "threads": OSD_ThreadPool.DefaultPool_s().NbThreads(), "faults": _refaults() < 100}


#: allocate and free 24 MB arrays, as a part's mesh and picture do, twice; count the page faults of
#: the second round (the first one's memory reused, or faulted in again)
_CYCLE = """
import numpy as np, resource
def cycle():
    for _ in range(10):
        a = np.ones(3_000_000)
        b = np.ones(3_000_000)
        c = a + b
        del a, b, c
def refaults():
    cycle()
    f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    cycle()
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0
"""


def _refaults() -> int:
    scope: dict = {}
    exec(_CYCLE, scope)
    return scope["refaults"]()


def test_freed_memory_is_reused_without_page_faults():
    """With glibc's defaults, arrays of 24 MB allocated and freed in turn fault their pages in
    again each time (thousands of minor faults a round); after ``workers.keep_freed_memory``
    the second round reuses the first's memory: (almost) no page faults. Each in a fresh
    interpreter (the C library's state is what is measured)."""
    default = _run(_CYCLE + "\nimport json\nprint(json.dumps({'faults': refaults()}))")["faults"]
    kept = _run("import json\nfrom phantom_cad import workers\nok = workers.keep_freed_memory()\n"
                + _CYCLE + "\nprint(json.dumps({'ok': ok, 'faults': refaults()}))")
    if not kept["ok"]:
        pytest.skip("this C library has no mallopt (not glibc)")
    assert default > 1000, default
    assert kept["faults"] < 100, kept


@pytest.mark.slow
def test_init_worker_sets_up_the_build_workers():
    """A pool started as the pipeline starts its own: build123d loaded, no scikit-learn, one
    OpenCascade thread, freed memory reused (no page faults in the second round of _CYCLE)."""
    from phantom_cad import workers
    from phantom_cad.export import pool

    ctx = workers.mp_context(preload=pool.PRELOAD)
    with ProcessPoolExecutor(1, mp_context=ctx, initializer=pool.init_worker,
                             initargs=(workers.watched_parent(ctx), 1)) as ex:
        state = ex.submit(_worker_state).result(timeout=300)
    assert state == {"sklearn": False, "build123d": True, "occt": True, "threads": 1, "faults": True}
