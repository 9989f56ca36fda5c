"""The command line of this source tree, in a subprocess (not whichever copy the venv's
``phantom-cad`` script points at): ``run_cli("fit", data, "--out", path)``."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def run_cli(*args) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-c", "from phantom_cad.cli import main; main()", *map(str, args)],
                          capture_output=True, text=True, cwd=ROOT, env=env)
