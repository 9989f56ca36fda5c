"""bom.csv and bom.md: the orderable bill of materials (``cad.purchase.order_lines``), one line per
purchasable item; bom.md groups them by category with the per-category and hand totals, and ends
with the assembly list they are made of."""

from __future__ import annotations

import csv
import io

from ..cad import purchase


def _cell(v) -> str:
    return "" if v is None else f"{v:g}" if isinstance(v, float) else str(v)


def bom_csv(lines: list[dict]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(purchase.COLUMNS)
    for ln in lines:
        w.writerow([_cell(ln[c]) for c in purchase.COLUMNS])
    return buf.getvalue()


def _money(v: float | None, currency: str) -> str:
    return "not priced" if v is None else f"{v:.2f} {currency}"


def bom_md(lines: list[dict], rows: list[dict], hand: str, sliced: bool, level: int = 1) -> str:
    """The lines by category, each category's subtotal, and the totals; then the assembly list
    the lines are made of (``rows``: ``assembly.bill_of_materials``, with each cut's working
    lengths and anchoring, which docs/assembly.md follows). ``level``: the title's heading level
    (docs/bom.md has it under its own title)."""
    cat = purchase.catalogue()
    cur = cat["currency"]
    per, total = purchase.totals(lines)
    h = "#" * level
    out = [f"{h} Bill of materials: {hand}", "",
           f"One line per item to buy. Prices in {cur}: {cat['price_note']}. The packs "
           "cover the quantity; a line costs its packs times the pack's price. The cord lines list the cut "
           "lengths.", ""]
    if not sliced:
        out += ["Not sliced: the filament is the printed parts' estimated mass (volume x density x infill); "
                "`phantom-cad build --slice` gives the slicer's.", ""]
    for category, cost in per.items():
        out += [f"{h}# {category[0].upper()}{category[1:]}", "",
                "| item | specification | quantity | pack | packs | line cost | used in |",
                "|---|---|---|---|---|---|---|"]
        for ln in lines:
            if ln["category"] == category:
                used = ln["used_in"].replace("|", "/")
                out.append(f"| {ln['item']} | {ln['specification']} | {_cell(ln['quantity'])} {ln['unit']} | "
                           f"{_cell(ln['pack_size'])} {ln['unit']} | {ln['packs']} | "
                           f"{_money(ln['line_cost'], cur)} | {used} |")
        out += ["", f"{category[0].upper()}{category[1:]}: {cost:.2f} {cur}", ""]
    out += [f"{h}# Totals", "", "| category | cost |", "|---|---|"]
    out += [f"| {c} | {v:.2f} {cur} |" for c, v in per.items()]
    out += [f"| **hand** | **{total:.2f} {cur}** |", ""]
    if any(ln["line_cost"] is None for ln in lines):
        out += ["Lines marked *not priced* are not in the catalogue and not in the totals.", ""]
    out += [f"{h}# Assembly list", "",
            "What the parts use, each cut with its length, anchoring and tensioning (docs/assembly.md).", "",
            "| item | specification | quantity | used in |", "|---|---|---|---|"]
    out += [f"| {r['item']} | {r['spec']} | {r['quantity']} | {str(r['used_in']).replace('|', '/')} |" for r in rows]
    out.append("")
    return "\n".join(out)
