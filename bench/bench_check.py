"""Benchmark of ``phantom-cad check --params`` on the default hand from a warm cache (figures for
docs/performance.md; target: under 3 minutes).

    .venv/bin/python bench/bench_check.py [--cache-dir DIR]

In a temporary folder: ``phantom-cad build`` (rendered, sliced when PrusaSlicer is installed, as
``check`` builds) warms a private part cache (a copy of ``--cache-dir``, default $PHANTOM_CAD_CACHE or
.cache, when it exists; not timed), then ``phantom-cad check --params
params/phantom.toml --out <new folder>`` runs as a user runs it: the export built on the spot from
the cache, then every row. Prints its wall time, its CPU time (user + sys, with the build's
workers), the rows' counts and each step's share of the wall time (from the check's log).
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ROOT / "params" / "phantom.toml"
TARGET_S = 180.0


def _children_cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache-dir", type=Path, default=Path(os.environ.get("PHANTOM_CAD_CACHE", ROOT / ".cache")),
                    help="a part cache to start from (copied, never written)")
    a = ap.parse_args()
    print(f"# phantom-cad check benchmark: {platform.node()}, {os.cpu_count()} cores, "
          f"python {platform.python_version()}")
    with tempfile.TemporaryDirectory(prefix="phantom-bench-check-") as tmp:
        tmp = Path(tmp)
        cache = tmp / "cache"
        if a.cache_dir.is_dir():
            shutil.copytree(a.cache_dir, cache)
        # the build check makes: rendered, sliced when PrusaSlicer is installed
        sliced = ["--slice"] if shutil.which("prusa-slicer") else []
        warm = subprocess.run([sys.executable, "-m", "phantom_cad", "build", "--params", str(PARAMS), "--out",
                               str(tmp / "warm"), "--cache-dir", str(cache), *sliced],
                              capture_output=True, text=True, cwd=ROOT)
        if warm.returncode != 0:
            sys.exit(f"the warming build failed:\n{warm.stderr[-3000:]}")
        cpu0 = _children_cpu()
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "phantom_cad", "check", "--params", str(PARAMS), "--out",
                                 str(tmp / "export"), "--cache-dir", str(cache)], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, cwd=ROOT)
        steps = []                      # (seconds since the start, the check's log line)
        for line in proc.stderr:
            steps.append((time.perf_counter() - t0, line.rstrip()))
        out = proc.stdout.read()
        rc = proc.wait()
        wall = time.perf_counter() - t0
        cpu = _children_cpu() - cpu0
    if rc not in (0, 1):
        sys.exit(f"check failed (exit {rc}):\n" + "\n".join(s for _, s in steps[-20:]))
    counts = re.search(r"\d+ ok, \d+ failed, \d+ not run", out)
    print("| case | wall [s] | CPU [s] | rows | target |")
    print("|---|---:|---:|---|---|")
    print(f"| check --params, warm cache (default hand) | {wall:.1f} | {cpu:.1f} | "
          f"{counts.group(0) if counts else '?'} (exit {rc}) | < {TARGET_S:.0f} s "
          f"{'met' if wall < TARGET_S else 'MISSED'} |")
    marks = [(s, line) for s, line in steps if line.startswith("check: ") and "pinch contact" not in line]
    for (s, line), (s1, _) in zip(marks, marks[1:] + [(wall, "")]):
        print(f"#   {s:6.1f} s  +{s1 - s:5.1f} s  {line}")
    for line in out.splitlines():
        if "FAIL" in line:
            print(f"# failing row: {line}")


if __name__ == "__main__":
    main()
