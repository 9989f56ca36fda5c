"""The walk-through of docs/effects.md ("From an unexplained residual to your own effect"), runnable.

``run(workdir)`` executes the commands of the walk-through, exactly as the page prints them, in
``workdir`` (with a copy of this folder at docs/examples/servo_ripple) and returns their outputs.
``control_law_errors(calibrated)`` measures what the calibrated file's control law is for: the pose
the hand with the hidden ripple reaches when commanded by the nominal and by the calibrated model.
tests/calibration/test_walkthrough.py runs both; bench/walkthrough_figures.py draws the pictures.
"""

from __future__ import annotations

import importlib.util
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]

#: the commands of the walk-through, in order (docs/effects.md prints them with a leading "$ ")
COMMANDS = [
    "python docs/examples/servo_ripple/make_data.py ripple.csv",
    "phantom-cad diagnose ripple.csv --report report_analytic",
    "phantom-cad diagnose ripple.csv --plugin docs/examples/servo_ripple/servo_ripple.py --report report_plugin",
    "phantom-cad fit ripple.csv --effects servo_ripple --plugin docs/examples/servo_ripple/servo_ripple.py "
    "--out cal/calibrated.toml",
    "phantom-cad compare ripple.csv -p cal/calibrated.toml",
]


def run(workdir) -> dict[str, str]:
    """{command: its standard output}; a command that fails raises RuntimeError with its stderr."""
    workdir = Path(workdir)
    shutil.copytree(HERE, workdir / "docs" / "examples" / "servo_ripple", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("__pycache__"))
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = {}
    for command in COMMANDS:
        argv = shlex.split(command)
        argv = ([sys.executable, "-m", "phantom_cad"] if argv[0] == "phantom-cad" else [sys.executable]) + argv[1:]
        r = subprocess.run(argv, cwd=workdir, env=env, capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"{command}: exit {r.returncode}: {r.stderr.strip()}")
        out[command] = r.stdout
    return out


def make_data():
    """The data generator module (its ``true_angles`` is the hidden physics)."""
    spec = importlib.util.spec_from_file_location("servo_ripple_make_data", HERE / "make_data.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def control_law_errors(calibrated, servo: int = 1, steps: int = 181):
    """Command the index finger (servo u2) to ``steps`` target poses along its travel with the
    nominal model's control law and with the calibrated file's, and let the hand with the hidden
    ripple (make_data.true_angles) move: (u2 of the targets (rad), error of the nominal command
    (deg, steps x 15), error of the calibrated command (deg, steps x 15))."""
    import numpy as np

    from phantom_cad import load_hand
    from phantom_cad.calibration.effects import unload_plugin
    from phantom_cad.params.schema import plugin_paths

    nominal = load_hand()
    cal = load_hand(calibrated)
    try:
        u = np.zeros((steps, 6))
        u[:, servo] = np.linspace(nominal.u_min[servo], nominal.u_max[servo], steps)
        target = nominal.forward(u, compensated=False)          # poses the finger can take
        true = make_data().true_angles
        err_nominal = np.degrees(true(nominal.params, nominal.inverse(target, compensated=False)) - target)
        err_cal = np.degrees(true(nominal.params, cal.inverse(target, compensated=True)) - target)
        return u[:, servo], err_nominal, err_cal
    finally:
        for f in plugin_paths(cal.params.plugins, cal.params.source):
            unload_plugin(f)
