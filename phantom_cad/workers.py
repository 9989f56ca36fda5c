"""Worker processes: the start method, and a worker that dies with the process that started it.

Used by the parts build (export/pipeline.py) and by `diagnose`'s candidate fits
(calibration/parallel.py). Pure standard library: every layer may import it.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import time
from collections.abc import Sequence


def mp_context(preload: Sequence[str] = ()):
    """fork when this process has not loaded OCP yet (fast: the CLI's case). Once OCP is loaded a
    forked child can deadlock on its thread pools, so the workers then start from a fork server: a
    process started once per process, which imports ``preload`` (module names) and runs nothing
    else, and from which each worker forks with those modules loaded instead of importing them
    again as a spawned one would (2-3 s for build123d). A fork server's worker is the server's
    child (:func:`watched_parent`; ``preload`` makes the server exit with this process) and starts
    with the environment the server started with (:func:`apply_environment`). spawn where neither
    start method exists."""
    methods = multiprocessing.get_all_start_methods()
    ocp_loaded = any(m == "OCP" or m.startswith("OCP.") for m in sys.modules)
    if "fork" in methods and not ocp_loaded:
        return multiprocessing.get_context("fork")
    if "forkserver" in methods:
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(list(preload))   # effective until the server starts: the first caller's
        return ctx
    return multiprocessing.get_context("spawn")


def watched_parent(ctx) -> int | None:
    """The pid a worker started by ``ctx`` watches (:func:`die_with_parent`): this process's, or
    None (the worker's parent when it starts) for a fork server's worker, whose parent is the
    server, gone when this process is."""
    return None if ctx.get_start_method() == "forkserver" else os.getpid()


def apply_environment(environ: dict[str, str]) -> None:
    """Make this process's environment ``environ``: a fork server's worker starts with the
    server's, taken when it started, not the environment of the process that asks for the worker
    now (what a spawned or forked worker gets)."""
    os.environ.clear()
    os.environ.update(environ)


def fork_context():
    """The fork context, or None where fork is missing (workers that inherit their parent's state
    and never call OCP may fork even after OCP is loaded: they take none of its locks)."""
    if "fork" not in multiprocessing.get_all_start_methods():
        return None
    return multiprocessing.get_context("fork")


def available_cpus() -> int:
    """The CPUs this process may run on (its affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:      # not Linux
        return max(1, os.cpu_count() or 1)


def die_with_parent(parent_pid: int | None, interval_s: float = 0.5) -> None:
    """Pool initializer: the worker exits as soon as the process that started it is gone (killed,
    crashed), instead of living on as an orphan holding hundreds of MB. A daemon thread polls the
    parent's pid (a reparented worker sees another one); no signal tied to the starting thread.
    ``parent_pid`` None: the parent the worker has now (:func:`watched_parent`)."""
    import threading

    if parent_pid is None:
        parent_pid = os.getppid()

    def watch():
        while True:
            if os.getppid() != parent_pid:
                os._exit(1)
            time.sleep(interval_s)

    if os.getppid() != parent_pid:
        os._exit(1)
    threading.Thread(target=watch, name="die-with-parent", daemon=True).start()


#: glibc's mallopt parameters (malloc.h)
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
#: blocks up to this size come from the heap (glibc's largest mmap threshold on 64-bit systems)
MMAP_THRESHOLD = 32 * 1024 * 1024
#: freed heap memory up to this much is kept for reuse rather than returned to the system
TRIM_THRESHOLD = 1024 * 1024 * 1024


def keep_freed_memory() -> bool:
    """Make this process's glibc malloc keep the memory it frees for the next allocation, instead
    of handing it back to the system and faulting fresh pages in again: arrays up to
    :data:`MMAP_THRESHOLD` come from the heap (not their own mmap), and up to
    :data:`TRIM_THRESHOLD` of freed heap stays mapped. For short-lived workers that allocate and
    free large arrays over and over (the parts build's meshes and pictures), it saves the system
    time of those page faults (docs/performance.md); the process keeps its peak memory until it
    exits. Returns False, changing nothing, where the C library has no ``mallopt`` (not glibc)."""
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (AttributeError, OSError):
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))
