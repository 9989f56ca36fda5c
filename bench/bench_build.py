"""Benchmark of ``phantom-cad build`` on the default hand (figures for docs/performance.md).

    .venv/bin/python bench/bench_build.py [--jobs N] [--slice] [--repeat K]

Each build runs in a fresh process (``python -m phantom_cad build``), as a user runs it,
with a private cache and export directory in a temporary folder:

1. cold build: empty cache (imports, every part built, checked, exported);
2. warm rebuild: same parameters (every part from the cache);
3. one finger changed: ``fingers.index.width_mm`` - 0.5 mm (only the index parts rebuild);
4. with ``--slice``: a cold slicing pass of every STL with PrusaSlicer, then a warm one.

Prints one line per case: wall time, CPU time of the build process and its workers (user +
sys; on a busy machine wall grows but CPU does not: the idle 2-core wall is about CPU / 2 plus
the serial start-up), parts built / taken from the cache.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _children_cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(args: list[str], env: dict) -> tuple[float, float, str]:
    """(wall s, CPU s of the build and its workers, output)"""
    cpu0 = _children_cpu()
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "phantom_cad", "build", *args], capture_output=True,
                          text=True, env=env, cwd=ROOT)
    wall = time.perf_counter() - t
    cpu = _children_cpu() - cpu0
    if proc.returncode != 0:
        sys.exit(f"build failed ({' '.join(args)}):\n{proc.stderr[-3000:]}")
    return wall, cpu, proc.stdout + proc.stderr


def counts(out: str) -> str:
    m = re.search(r"(\d+) parts, (\d+) built, (\d+) from cache", out)
    return f"{m.group(2)} built, {m.group(3)} cached" if m else "?"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--jobs", type=int, default=None, help="worker processes (default: os.cpu_count())")
    ap.add_argument("--slice", action="store_true", help="also time PrusaSlicer estimates (cold and cached)")
    ap.add_argument("--repeat", type=int, default=1, help="repeat the whole series K times (report each)")
    a = ap.parse_args()

    import tomli_w

    from phantom_cad.params import DEFAULT_PARAMS, load_document

    print(f"# phantom-cad build benchmark: {platform.node()}, {os.cpu_count()} cores, "
          f"python {platform.python_version()}, jobs={a.jobs or os.cpu_count()}")
    try:
        print(f"# load average before: {os.getloadavg()[0]:.2f}")
    except OSError:
        pass
    env = dict(os.environ)
    for rep in range(a.repeat):
        with tempfile.TemporaryDirectory(prefix="phantom-bench-") as tmp:
            tmp = Path(tmp)
            base = ["--out", str(tmp / "out" / "phantom"), "--cache-dir", str(tmp / "cache")]
            jobs = ["--jobs", str(a.jobs)] if a.jobs else []
            rows = []
            wall, cpu, out = run(base + jobs + ["--no-slice"], env)
            rows.append(("cold build (STEP+STL+renders+manifest)", wall, cpu, counts(out)))
            wall, cpu, out = run(base + jobs + ["--no-slice"], env)
            rows.append(("warm rebuild, same parameters", wall, cpu, counts(out)))
            doc = load_document(DEFAULT_PARAMS)
            doc["fingers"]["index"]["width_mm"] = doc["fingers"]["index"]["width_mm"] - 0.5
            changed = tmp / "changed.toml"
            changed.write_text(tomli_w.dumps(doc))
            wall, cpu, out = run(base + jobs + ["--no-slice", "--params", str(changed)], env)
            rows.append(("one finger changed (index width -0.5 mm)", wall, cpu, counts(out)))
            if a.slice:
                wall, cpu, out = run(base + jobs + ["--slice"], env)
                rows.append(("--slice, cold slicer cache (every part)", wall, cpu, counts(out)))
                wall, cpu, out = run(base + jobs + ["--slice"], env)
                rows.append(("--slice, warm (estimates cached)", wall, cpu, counts(out)))
            try:
                load = f", load average after {os.getloadavg()[0]:.2f}"
            except OSError:
                load = ""
            print(f"\n## run {rep + 1}{load}")
            print("| case | wall [s] | CPU [s] | parts |")
            print("|---|---:|---:|---|")
            for name, wall, cpu, c in rows:
                print(f"| {name} | {wall:.2f} | {cpu:.1f} | {c} |")


if __name__ == "__main__":
    main()
