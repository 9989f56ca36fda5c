"""A population study: size, build and check a hand for many people (docs/sizing.md, "A population").

    .venv/bin/python bench/population.py --out DIR [--limit N] [--only NAME ...] [--workers N]
                                         [--scheduler ADDRESS] [--cache-dir DIR]

The people (:func:`population`): hand lengths from the 1st-percentile woman to the 99th-percentile
man in :data:`LENGTH_STEPS` steps, each with the hand breadths of the 5th, 50th and 95th percentile
of women and of men; then :data:`DIGIT_PEOPLE` people of the 50th-percentile length and breadth
(women and men in turn) whose every segment is the reference ratio times the hand length times a
factor drawn uniformly within +-8 % (seeded). Each person runs end to end in :func:`run_person`:
``sizing.size`` (``phantom-cad size``'s solver, the preflight rules), the file built into its own
folder with the shared part cache and checked with every row (``export.check.check_export``,
``phantom-cad check``'s); or the refusal's one-line error and its binding rule.

A script, not a ``phantom-cad`` subcommand: ``size`` builds no geometry and imports no CAD library,
and a Dask cluster (``dask.distributed``, a dev dependency) is a lab's tool, not a user's.

Runs on a local process pool (``--workers``, default the CPUs) or, given ``--scheduler ADDRESS``,
on a Dask cluster: its workers need phantom_cad installed, the part cache's folder shared, and
``distributed.worker.daemon: false`` (each build starts worker processes of its own). Writes
``population.csv``, ``population.json`` and ``population.md`` into ``--out``, atomically; every
column but the timings is the same on every run.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import os
import re
import resource
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

#: hand length, wrist crease to the middle fingertip (mm): mean and SD. Ibeachu, Abu & Didia 2011
#: (docs/sizing.md), 150 men and 150 women, right hands: means 190.2 / 176.2 mm; its +- (0.8 / 0.7
#: mm) are standard errors of the mean, SD = SE x sqrt(150)
LENGTH = {"woman": (176.2, 0.7 * math.sqrt(150.0)), "man": (190.2, 0.8 * math.sqrt(150.0))}
#: hand breadth at the metacarpal heads (mm): mean (the 50th percentile) and SD, British adults
#: aged 19-65 (docs/sizing.md's City University of Hong Kong tables)
BREADTH = {"woman": (75.0, 4.0), "man": (85.0, 5.0)}
#: the length range's ends (percentiles), its steps, the breadths' percentiles
LENGTH_ENDS, LENGTH_STEPS, BREADTH_PERCENTILES = (1.0, 99.0), 8, (5.0, 50.0, 95.0)
#: people with per-digit lengths: how many, the spread around the reference ratios, the seed
DIGIT_PEOPLE, DIGIT_SPREAD, SEED = 10, 0.08, 0


@dataclass(frozen=True)
class Person:
    name: str
    hand_length: float                     # mm
    hand_breadth: float                    # mm
    segments: dict = field(default_factory=dict)    # {digit: {segment: mm}}, as ``size --segments``


@dataclass
class Record:
    """What became of one person: ``outcome`` passed (every row of check ok), failed (the failing
    rows), refused (``size``'s line and its binding rule) or error (a build's or check's line)."""
    name: str
    hand_length: float
    hand_breadth: float
    segments: str
    outcome: str
    binding: str          # refused: the rule that binds; else ""
    failing: list         # failed: "check: worst item (measured, tolerance)" per failing row
    error: str            # refused or error: the one line, as the command prints it
    rows: int             # rows of check run
    seconds: float        # wall time, size to check
    cpu_seconds: float    # this process's and its children's CPU time (a threaded worker's shares its process)


def percentile(sex: str, what: str, pct: float) -> float:
    """The ``pct`` percentile (mm) of ``what`` ("length" or "breadth") for ``sex``, normal."""
    from scipy.stats import norm

    mean, sd = (LENGTH if what == "length" else BREADTH)[sex]
    return mean + float(norm.ppf(pct / 100.0)) * sd


def hand_lengths() -> list[float]:
    """From the 1st-percentile woman's to the 99th-percentile man's, :data:`LENGTH_STEPS` equal
    steps, to 0.1 mm."""
    lo, hi = percentile("woman", "length", LENGTH_ENDS[0]), percentile("man", "length", LENGTH_ENDS[1])
    return [round(lo + (hi - lo) * i / LENGTH_STEPS, 1) for i in range(LENGTH_STEPS + 1)]


def breadths() -> list[tuple[str, float, float]]:
    """(sex, percentile, breadth to 0.1 mm) of :data:`BREADTH_PERCENTILES`, women then men."""
    return [(s, p, round(percentile(s, "breadth", p), 1)) for s in ("woman", "man") for p in BREADTH_PERCENTILES]


def digit_people(n: int = DIGIT_PEOPLE, seed: int = SEED, spread: float = DIGIT_SPREAD) -> list[Person]:
    """``n`` people at the 50th-percentile length and breadth (women and men in turn), each
    measured segment the reference's ratio of the hand length (params/phantom.toml, Buchholz et al.
    1992) times a factor uniform in [1 - spread, 1 + spread], to 0.1 mm."""
    import numpy as np

    from phantom_cad.kinematics.dimensions import digit_entry
    from phantom_cad.sizing import template
    from phantom_cad.sizing.inputs import SEGMENT_KEYS

    doc = template()
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        sex = ("woman", "man")[i % 2]
        hl, hb = round(LENGTH[sex][0], 1), round(BREADTH[sex][0], 1)
        segments = {}
        for d, keys in SEGMENT_KEYS.items():
            ratios = digit_entry(doc, d)["length_fraction"]
            segments[d] = {k: round(ratios[k] * hl * float(rng.uniform(1.0 - spread, 1.0 + spread)), 1)
                           for k in keys if k != "width"}
        out.append(Person(f"digits-{i:02d}-{sex}", hl, hb, segments))
    return out


def population(seed: int = SEED) -> list[Person]:
    """The study's people in order: the length x breadth grid (:func:`hand_lengths`,
    :func:`breadths`), then :func:`digit_people`."""
    grid = [Person(f"L{hl:g}-{sex[0]}{pct:02.0f}-B{hb:g}".replace(".", "_"), hl, hb)
            for hl in hand_lengths() for sex, pct, hb in breadths()]
    return grid + digit_people(seed=seed)


def _segments_text(segments: dict) -> str:
    return " ".join(f"{d}.{k}={v:g}" for d, t in segments.items() for k, v in t.items())


def _cpu() -> float:
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def binding_rule(line: str) -> str:
    """The rule a refusal names: its line without the input it repeats and the nearest input."""
    rule = re.split(r"; nearest that works|; no nearer input", line, maxsplit=1)[0]
    return re.sub(r"^(--[a-z-]+ \S+ ?)+: ", "", rule)


def run_person(person: Person, out_root: str | os.PathLike, cache_dir: str | os.PathLike | None = None,
               search: bool = True) -> Record:
    """Size ``person`` (``sizing.size`` with the preflight rules, the CMC placement searched), write
    the file to ``out_root/NAME.toml``, build it into ``out_root/NAME/`` with the part cache
    ``cache_dir`` and check it with every row; or the refusal. Never raises for a person: any
    ``UserError`` or build failure becomes the record's one line."""
    from phantom_cad.cad import preflight
    from phantom_cad.calibration.effects import PARAMS_EFFECTS
    from phantom_cad.cli.size import MARKER
    from phantom_cad.errors import UserError, one_line
    from phantom_cad.export.check import check_export
    from phantom_cad.export.pipeline import BuildError, ensure_export
    from phantom_cad.params import ParamError
    from phantom_cad.params.io import dump_params
    from phantom_cad.sizing import Person as SizingPerson
    from phantom_cad.sizing import size

    out_root = Path(out_root)
    t0, c0 = time.perf_counter(), _cpu()
    rec = dict(name=person.name, hand_length=person.hand_length, hand_breadth=person.hand_breadth,
               segments=_segments_text(person.segments), binding="", failing=[], error="", rows=0)

    def done(outcome: str) -> Record:
        return Record(outcome=outcome, seconds=round(time.perf_counter() - t0, 1),
                      cpu_seconds=round(_cpu() - c0, 1), **rec)

    try:
        sized = size(SizingPerson(person.hand_length, person.hand_breadth, "right", person.name, person.segments),
                     check=preflight.check, search=search, floor=preflight.cmc_base_floor)
    except (UserError, ParamError) as exc:
        rec["error"] = f"error: {one_line(exc)}"
        rec["binding"] = binding_rule(one_line(exc))
        return done("refused")
    path = out_root / f"{person.name}.toml"
    header = (f"{MARKER} hand length {person.hand_length:g} mm, hand breadth {person.hand_breadth:g} mm, right "
              f"hand{', measured: ' + rec['segments'] if person.segments else ''} (bench/population.py)\n\n")
    dump_params(sized.document, path, header)
    try:
        # what `phantom-cad check --params FILE` does: built (sliced when PrusaSlicer is installed)
        folder, params = ensure_export(path, out_root / person.name, effects=PARAMS_EFFECTS, cache_dir=cache_dir,
                                       slice=None)
        rows = check_export(folder, params, functional=True)
    except (BuildError, UserError) as exc:
        rec["error"] = f"error: {one_line(exc)}"
        return done("error")
    rec["rows"] = len(rows)
    rec["failing"] = [f"{r.check}: {r.item} ({r.measured}, tolerance {r.tolerance})" for r in rows if r.ok is False]
    return done("failed" if rec["failing"] else "passed")


def run_study(people: list[Person], out_root: str | os.PathLike, cache_dir: str | os.PathLike | None = None,
              workers: int | None = None, scheduler: str | None = None, search: bool = True) -> list[Record]:
    """Every person's record, in the order of ``people``: on a local process pool of ``workers``
    processes (each dies with this one, ``phantom_cad.workers``), or on the Dask cluster whose
    scheduler is at ``scheduler`` (an address, or a ``distributed`` cluster object)."""
    out_root = Path(out_root)
    out_root.mkdir(parents=True, exist_ok=True)
    args = (str(out_root), None if cache_dir is None else str(cache_dir), search)
    if scheduler is not None:
        from distributed import Client

        with Client(scheduler) as client:
            futures = [client.submit(run_person, p, *args, pure=False, key=f"population-{p.name}") for p in people]
            return client.gather(futures)
    from concurrent.futures import ProcessPoolExecutor

    from phantom_cad import workers as W

    from phantom_cad.export.pool import PRELOAD

    # the workers load OCP (the check): forked only while this process has not (W.mp_context); a
    # fork server's worker imports this module by name, from its folder
    if str(Path(__file__).resolve().parent) not in sys.path:
        sys.path.append(str(Path(__file__).resolve().parent))
    ctx = W.mp_context(preload=PRELOAD)
    n = max(1, min(len(people), workers or W.available_cpus()))
    with ProcessPoolExecutor(n, mp_context=ctx, initializer=W.die_with_parent,
                             initargs=(W.watched_parent(ctx),)) as pool:
        return list(pool.map(run_person, people, *([a] * len(people) for a in args)))


COLUMNS = ("name", "hand_length", "hand_breadth", "segments", "outcome", "binding", "failing", "error", "rows",
           "seconds", "cpu_seconds")


def csv_text(records: list[Record]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in records:
        d = asdict(r)
        d["failing"] = " | ".join(d["failing"])
        w.writerow([d[c] for c in COLUMNS])
    return buf.getvalue()


#: the failing rows the table names briefly (``brief``): (a pattern on the row's line, its brief form)
BRIEF = (
    (re.compile(r"held palm down.*?\((?:let go, moved ([\d.]+) mm >= [\d.]+; )?moved ([\d.]+) mm"),
     lambda m: f"hold (moved {m[2]} mm{f', let go {m[1]} mm' if m[1] else ''})"),
    (re.compile(r"held palm down.*?\(let go, moved ([\d.]+) mm"), lambda m: f"hold (let go {m[1]} mm)"),
    (re.compile(r"^walls >= .*?: (\w+) \(([\d.]+) mm"), lambda m: f"walls ({m[1]} {m[2]} mm)"),
    (re.compile(r"^thumb pad to .*?: (\w+): ([^(]+?) \("), lambda m: f"opposition ({m[1]}: {m[2]})"),
)


def brief(line: str) -> str:
    """A failing row's line (``Record.failing``) as the table names it: the hold, the walls and the
    opposition briefly, any other row whole."""
    for pattern, form in BRIEF:
        m = pattern.search(line)
        if m:
            return form(m)
    return line


def markdown_table(records: list[Record]) -> str:
    """The table docs/sizing.md carries: one row a person (the failing rows brief, ``brief``; the
    CSV and JSON keep them whole)."""
    out = ["| person | length x breadth (mm) | outcome | failing rows, or the binding rule | s (wall) | CPU s |",
           "|---|---|---|---|---:|---:|"]
    for r in records:
        why = (r.binding if r.outcome == "refused" else "; ".join(map(brief, r.failing)) if r.failing
               else " / ".join(r.error.replace("\\n", "\n").splitlines()[:2]))     # a build's error: its first two lines
        out.append(f"| {r.name} | {r.hand_length:g} x {r.hand_breadth:g} | {r.outcome} | {why.replace('|', '/')} | "
                   f"{r.seconds:.0f} | {r.cpu_seconds:.0f} |")
    return "\n".join(out) + "\n"


def write_results(records: list[Record], out_root: str | os.PathLike) -> None:
    """population.csv, .json and .md in ``out_root``, each written atomically."""
    from phantom_cad.atomic import write_atomic, write_json_atomic

    out_root = Path(out_root)
    write_atomic(out_root / "population.csv", csv_text(records))
    write_json_atomic(out_root / "population.json", [asdict(r) for r in records], sort_keys=True)
    write_atomic(out_root / "population.md", markdown_table(records))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, required=True, help="folder of the files, exports and tables")
    ap.add_argument("--limit", type=int, default=None, help="only the first N people")
    ap.add_argument("--only", nargs="+", default=None, help="only the people of these names")
    ap.add_argument("--workers", type=int, default=None, help="local processes (default: the CPUs)")
    ap.add_argument("--scheduler", default=None, help="a Dask scheduler's address (tcp://HOST:8786)")
    ap.add_argument("--cache-dir", type=Path, default=None,
                    help="the shared part cache (default $PHANTOM_CAD_CACHE or .cache)")
    ap.add_argument("--list", action="store_true", help="print the people and run nothing")
    a = ap.parse_args(argv)
    people = population()
    if a.only:
        unknown = sorted(set(a.only) - {p.name for p in people})
        if unknown:
            print(f"error: --only {' '.join(unknown)}: no such person (--list names them)", file=sys.stderr)
            return 2
        people = [p for p in people if p.name in a.only]
    people = people[:a.limit] if a.limit is not None else people
    if a.list:
        for p in people:
            print(f"{p.name}\t{p.hand_length:g}\t{p.hand_breadth:g}\t{_segments_text(p.segments)}")
        return 0
    records = run_study(people, a.out, a.cache_dir, a.workers, a.scheduler)
    write_results(records, a.out)
    sys.stdout.write(markdown_table(records))
    return 0


if __name__ == "__main__":
    sys.exit(main())
