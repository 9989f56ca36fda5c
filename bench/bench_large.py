"""Benchmark: the commands on a 1,000,000-row measurement file, run as a user runs them (targets:
`model forward` < 5 s, `diagnose` < 30 s and < 1 GB).

The file: every servo swept both ways, 83,334 points per direction and servo (1,000,008 rows), the
swept finger's joints recorded, hidden friction hysteresis and joint offsets, 0.1 deg noise.
Prints the wall time and peak memory (max RSS) of each command, each in a fresh process.
Run: .venv/bin/python bench/bench_large.py
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time


def run(args: list[str]) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of `python -m phantom_cad *args` in a fresh process."""
    code = ("import resource, subprocess, sys, time; t = time.perf_counter(); "
            "r = subprocess.run([sys.executable, '-m', 'phantom_cad', *sys.argv[1:]], capture_output=True, text=True); "
            "dt = time.perf_counter() - t; assert r.returncode == 0, r.stderr; "
            "print(dt, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)")
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, check=True)
    dt, mb = map(float, out.stdout.split())
    return dt, mb


def main() -> None:
    with tempfile.TemporaryDirectory() as d:
        data = os.path.join(d, "big.csv")
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "phantom_cad", "simulate", "--points", "83334", "--effects",
                        "friction_hysteresis,joint_offset", "--seed", "3", "--out", data], check=True,
                       capture_output=True)
        print(f"simulate, 1,000,008 rows ({os.path.getsize(data) / 1e6:.0f} MB): {time.perf_counter() - t0:.1f} s")
        for label, args in [
            ("model forward", ["model", "forward", "--in", data, "--out", os.path.join(d, "q.csv")]),
            ("diagnose", ["diagnose", data]),
        ]:
            dt, mb = run(args)
            print(f"{label}, 1,000,008 rows: {dt:.1f} s, peak {mb:.0f} MB")


if __name__ == "__main__":
    main()
