"""Random perturbations of a parameter document, for the property test (tests/test_validation_builds.py)
and its large-sample benchmark (bench/bench_validation.py).

A perturbation changes a few numeric fields of the default file: ``changes`` is a list of
(leaf index, x) with x in [-1, 1]; a non-zero value v becomes v * 4**x (a factor between 1/4 and
4), a zero becomes x * 10 (in the key's unit). Every numeric field of the file is a leaf, array
elements and inline tables included (``schema_version`` excepted).
"""

from __future__ import annotations

import copy
from typing import Any, Iterator

#: the range of the multiplicative change: v * FACTOR**x, x in [-1, 1]
FACTOR = 4.0
#: a zero moves by x * ZERO_STEP
ZERO_STEP = 10.0


def leaves(doc: Any, path: tuple = ()) -> Iterator[tuple[tuple, float]]:
    """(path, value) of every numeric leaf, in document order."""
    if isinstance(doc, dict):
        for k, v in doc.items():
            if path == () and k == "schema_version":
                continue
            yield from leaves(v, path + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from leaves(v, path + (i,))
    elif isinstance(doc, (int, float)) and not isinstance(doc, bool):
        yield path, float(doc)


def field_name(path: tuple) -> str:
    """``fingers.index.servo_travel_deg[1]``."""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def moved(value: float, x: float) -> float:
    return value * FACTOR ** x if value != 0.0 else x * ZERO_STEP


def perturb(doc: dict, changes: list[tuple[int, float]]) -> tuple[dict, list[tuple[str, float, float]]]:
    """A deep copy of ``doc`` with ``changes`` applied; also [(field, old, new)]."""
    out = copy.deepcopy(doc)
    table = list(leaves(out))
    done = []
    for index, x in changes:
        path, value = table[index % len(table)]
        new = round(moved(value, x), 6)
        node = out
        for p in path[:-1]:
            node = node[p]
        node[path[-1]] = new
        done.append((field_name(path), value, new))
    return out, done
