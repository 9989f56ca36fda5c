"""bom.csv: the bill of materials rows (``assembly.bill_of_materials``) as CSV."""

from __future__ import annotations

import csv
import io


def bom_csv(rows: list[dict]) -> str:
    buf = io.StringIO()
    cols = ["item", "spec", "quantity", "used_in"]
    extra = sorted({k for r in rows for k in r} - set(cols))
    w = csv.DictWriter(buf, fieldnames=cols + extra, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (";".join(map(str, v)) if isinstance(v, (list, tuple)) else v) for k, v in r.items()})
    return buf.getvalue()
