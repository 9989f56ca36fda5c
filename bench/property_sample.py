"""A large random sample of the property test's space: does every file that validates build?

    .venv/bin/python bench/property_sample.py SEED N [LOG.jsonl]

Draws N perturbed files (tests/support/param_space.py: one to three numeric fields of the
default file moved by a factor in [1/4, 4]), validates each as ``params validate`` does
(``parse`` and ``cad.preflight.check``) and builds every one that validates (jobs = 2, renders
and slicing off, a shared part cache in .cache/property). Writes one JSON line per file and
prints the totals; docs/reliability.md quotes them. The same space at a small derandomized
sample runs in ``make test`` (tests/export/test_validation_builds.py).
"""

from __future__ import annotations

import json
import random
import shutil
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "support"))

from param_space import leaves, perturb  # noqa: E402


def main() -> int:
    import tomli_w

    from phantom_cad.cad import preflight
    from phantom_cad.export.pipeline import build_hand
    from phantom_cad.params import ParamError, parse

    seed, n = int(sys.argv[1]), int(sys.argv[2])
    log_path = Path(sys.argv[3]) if len(sys.argv) > 3 else Path(f"property_{seed}_{n}.jsonl")
    base = tomllib.loads((ROOT / "params" / "phantom.toml").read_text(encoding="utf-8"))
    n_leaves = len(list(leaves(base)))
    rng = random.Random(seed)
    totals = {"generated": 0, "validated": 0, "built": 0, "failed": 0}
    seconds = []
    with log_path.open("w", encoding="utf-8") as log:
        for i in range(n):
            k = rng.choice([1, 1, 2, 3])
            changes = [(rng.randrange(n_leaves), rng.uniform(-1.0, 1.0)) for _ in range(k)]
            doc, moved = perturb(base, changes)
            rec = {"i": i, "changes": moved}
            totals["generated"] += 1
            try:
                preflight.check(parse(doc, "perturbed.toml"))
            except ParamError as exc:
                rec["refused"] = exc.field
                log.write(json.dumps(rec) + "\n")
                continue
            totals["validated"] += 1
            work = Path(tempfile.mkdtemp(prefix="phantom-property-"))
            try:
                (work / "hand.toml").write_text(tomli_w.dumps(doc), encoding="utf-8")
                t = time.perf_counter()
                try:
                    build_hand(work / "hand.toml", work / "out", jobs=2, slice=False, render=False,
                               cache_dir=ROOT / ".cache" / "property")
                    rec["build"] = "ok"
                    totals["built"] += 1
                    seconds.append(time.perf_counter() - t)
                except Exception as exc:   # the finding
                    rec["build"] = f"{type(exc).__name__}: {str(exc)[:600]}"
                    totals["failed"] += 1
            finally:
                shutil.rmtree(work, ignore_errors=True)
            log.write(json.dumps(rec) + "\n")
            log.flush()
    seconds.sort()
    median = seconds[len(seconds) // 2] if seconds else float("nan")
    print(f"property sample seed {seed}: {totals['generated']} files, {totals['validated']} validated, "
          f"{totals['built']} built, {totals['failed']} failed to build (median build {median:.1f} s); log {log_path}")
    return 1 if totals["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
