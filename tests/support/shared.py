"""What the test processes of one run share: a folder, and values made once.

``make test`` runs the tests in two processes (pytest-xdist). A session fixture runs once per
process, so a whole-hand build or a power grasp would be made once per process: :func:`once` makes
it in whichever process asks first and hands the others its pickle (a file lock orders them).
Without xdist the folder is the session's own base temp, so nothing outlives the session.
"""

from __future__ import annotations

import os
import pickle
from pathlib import Path
from typing import Any, Callable

from phantom_cad.atomic import write_atomic


def run_root(tmp_path_factory) -> Path:
    """The folder every process of this test run shares (the run's base temp: under xdist, the
    parent of each worker's)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


def once(root: Path, name: str, make: Callable[[], Any]) -> Any:
    """``make()``'s value, made once per test run under ``root`` (:func:`run_root`): the first
    process to ask makes it and leaves its pickle; the others wait for it and read it back."""
    from filelock import FileLock

    path = root / f"{name}.pickle"
    with FileLock(str(root / f"{name}.lock")):
        if path.exists():
            return pickle.loads(path.read_bytes())
        value = make()
        write_atomic(path, pickle.dumps(value))
        return value
