"""The CAD kernel's process set-up: importing build123d, and OpenCascade's threads.

Used by the build's worker processes (``export.pool.init_worker``), which build every part of a
cold build; measured in docs/performance.md ("Parts build").
"""

from __future__ import annotations

import sys
import types

#: the modules :func:`import_build123d` stands in for while build123d loads
_DEFERRED = ("sklearn", "sklearn.cluster")


def _dbscan(*args, **kwargs):
    """scikit-learn's DBSCAN, imported when first called (``build123d.brep_from_stl`` calls it in
    ``detect_primitives``, which no part uses)."""
    from sklearn.cluster import DBSCAN

    return DBSCAN(*args, **kwargs)


def import_build123d():
    """Import build123d (once per process) without loading scikit-learn, and return it.

    ``build123d/__init__`` imports ``build123d.brep_from_stl``, whose module body runs
    ``from sklearn.cluster import DBSCAN``: 0.8-0.9 s of scikit-learn and the SciPy it pulls in,
    in every worker of a cold build, for a function no part calls. While build123d loads, two
    placeholder modules stand in for ``sklearn`` and ``sklearn.cluster``, whose ``DBSCAN`` is
    :func:`_dbscan` (the real class, imported when first called); they are removed as soon as the
    import returns, so a later ``import sklearn`` loads the real package. Where scikit-learn or
    build123d is already loaded, or the import fails with the placeholders in place (a build123d
    that uses more of scikit-learn), build123d is imported as usual."""
    if "build123d" in sys.modules or any(m in sys.modules for m in _DEFERRED):
        import build123d
        return build123d
    parent, cluster = types.ModuleType("sklearn"), types.ModuleType("sklearn.cluster")
    cluster.DBSCAN = _dbscan
    parent.cluster = cluster
    sys.modules.update({"sklearn": parent, "sklearn.cluster": cluster})
    try:
        import build123d
    except (ImportError, AttributeError):       # it asked the placeholders for more than DBSCAN
        for name in [m for m in sys.modules if m == "build123d" or m.startswith("build123d.")]:
            del sys.modules[name]
        build123d = None
    finally:
        for name in _DEFERRED:
            del sys.modules[name]
    if build123d is None:
        import build123d
    return build123d


def use_threads(n: int) -> None:
    """Run OpenCascade's parallel algorithms on ``n`` threads in this process: its own default
    thread pool made with ``n`` threads (by default it has one per logical processor). build123d
    asks for parallel booleans (``SetRunParallel(True)``); where as many worker processes as cores
    build parts at once, the extra threads only contend: one thread per worker measured 17.4 s of
    CPU for the default hand's parts (build, STEP, mesh) against 21.0 s, the same bytes. Call
    before the first parallel algorithm runs (the pool's size is fixed when it is first made)."""
    if n < 1:
        raise ValueError(f"use_threads: n = {n}, at least 1")
    from OCP.OSD import OSD_Parallel, OSD_ThreadPool

    OSD_Parallel.SetUseOcctThreads_s(True)
    OSD_ThreadPool.DefaultPool_s(n)
