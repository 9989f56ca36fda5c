"""Worker processes: the start method, and a worker that dies with the process that started it.

Used by the parts build (export/pipeline.py) and by `diagnose`'s candidate fits
(calibration/parallel.py). Pure standard library: every layer may import it.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import time


def mp_context():
    """fork when this process has not loaded OCP yet (fast: the CLI's case); spawn once OCP
    is loaded (its thread pools make a forked child deadlock) or where fork is missing."""
    methods = multiprocessing.get_all_start_methods()
    ocp_loaded = any(m == "OCP" or m.startswith("OCP.") for m in sys.modules)
    return multiprocessing.get_context("fork" if "fork" in methods and not ocp_loaded else "spawn")


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


def die_with_parent(parent_pid: int, interval_s: float = 0.5) -> None:
    """Pool initializer: the worker exits as soon as the process that started it is gone (killed,
    crashed), instead of living on as an orphan holding hundreds of MB. A daemon thread polls the
    parent's pid (a reparented worker sees another one); no signal tied to the starting thread."""
    import threading

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
