"""Metrics, pictures (matplotlib, Agg) and markdown reports of compare and diagnose (the text they
carry is composed by diagnosis_text.py).

Reports are written into a temporary folder next to the target and moved into place when
complete. Pictures:
  residual_<label>.png  residual (measured - model) against the joint's servo angle, coloured by
                        direction (the paper's residual figure), one panel per measured joint;
  mae.png               per-joint MAE, before and after (the paper's MAE figure);
  hysteresis.png        measured and modelled deviation from the analytic model against the servo
                        angle, flexing and extending: hysteresis loops show as two branches.

The pictures do not mislead: the MAE bars carry the noise floor estimated from the data (overall
and per joint) and flag the joints the model made worse; a few outliers do not set the residual
plot's y range (they are clipped to its edge and marked); a panel whose data move in one direction
says that no hysteresis can be seen there. Each plot function returns its (closed) figure, whose
artists carry ``gid`` tags the tests read.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np


from ..kinematics.topology import JOINT_NAMES, Q_COLUMNS, U_COLUMNS
from ..units import DEG_PER_RAD
from .data import Measurements
from .framework import JOINT_SERVO

FLEX, EXTEND = "tab:red", "tab:blue"


def metrics(m: Measurements, q_model: np.ndarray) -> dict:
    """MAE / RMS / max |residual| (degrees) per measured joint and overall."""
    r = (m.q - q_model) * DEG_PER_RAD
    out = {"per_joint": {}, "overall": _summary(r[np.isfinite(r)])}
    for j, c in enumerate(Q_COLUMNS):
        x = r[:, j][np.isfinite(r[:, j])]
        if x.size:
            out["per_joint"][c] = _summary(x)
    return out


def _summary(x: np.ndarray) -> dict:
    return {"mae": float(np.mean(np.abs(x))), "rms": float(np.sqrt(np.mean(x * x))),
            "max": float(np.max(np.abs(x))), "n": int(x.size)}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _grid(n):
    cols = min(5, max(n, 1))
    rows = (n + cols - 1) // cols
    return rows, cols


def _panels(m: Measurements, sharey: bool):
    """One panel per measured joint: (plt, fig, axes, [(ax, joint, servo), ...])."""
    plt = _plt()
    joints = [j for j in range(len(Q_COLUMNS)) if m.measured[j]]
    rows, cols = _grid(len(joints))
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.6 * rows), squeeze=False, sharey=sharey)
    panels = []
    for ax, j in zip(axes.flat, joints):
        s = JOINT_SERVO[j]
        ax.set_title(f"{Q_COLUMNS[j]} {JOINT_NAMES[j]}", fontsize=9)
        ax.set_xlabel(f"{U_COLUMNS[s]} (deg)", fontsize=8)
        ax.tick_params(labelsize=7)
        panels.append((ax, j, s))
    for ax in list(axes.flat)[len(joints):]:
        ax.axis("off")
    return plt, fig, axes, panels


def _save(plt, fig, axes, path, ylabel: str, title: str, legend_size: int) -> None:
    axes[0, 0].set_ylabel(ylabel, fontsize=8)
    axes[0, 0].legend(fontsize=legend_size)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


#: the residual plot's y range: Tukey fences at FENCE interquartile ranges beyond the quartiles of
#: every plotted residual; points outside are clipped to the range's edge and marked
FENCE = 3.0
#: the MAE axis is logarithmic when the largest bar is beyond this multiple of the noise floor
LOG_RATIO = 20.0

#: margin of the y range beyond the data inside the fences, fraction of their span
Y_PAD = 0.08


def robust_limits(values: np.ndarray) -> tuple[float, float]:
    """A y range set by the bulk of ``values`` (degrees), not by a few outliers: the extremes of the
    values inside the Tukey fences (quartiles -/+ FENCE interquartile ranges), padded by Y_PAD, and
    always including 0."""
    v = values[np.isfinite(values)]
    if v.size == 0:
        return -1.0, 1.0
    q1, q3 = np.percentile(v, [25, 75])
    iqr = q3 - q1
    inside = v[(v >= q1 - FENCE * iqr) & (v <= q3 + FENCE * iqr)]
    lo, hi = min(float(inside.min()), 0.0), max(float(inside.max()), 0.0)
    pad = Y_PAD * (hi - lo) if hi > lo else 0.1
    return lo - pad, hi + pad


def plot_residuals(path, m: Measurements, q_model: np.ndarray, title: str):
    """One panel per joint, residual against the servo angle, coloured by direction. The y range
    (shared) spans the :func:`robust_limits` of each joint's residual: a joint's structure (a
    sinusoid of 2 deg where the other joints show 0.1 deg of noise) is inside it, a glitch
    beyond its own joint's fences is not. Points beyond it are drawn on its edge as black
    triangles (gid ``clipped``) and each panel with some says how many and the largest.
    Returns the (closed) figure."""
    plt, fig, axes, panels = _panels(m, sharey=True)
    d = m.direction
    r = (m.q - q_model) * DEG_PER_RAD
    limits = [robust_limits(r[:, j][np.isfinite(r[:, j])]) for _, j, _ in panels]
    lo, hi = (min(a for a, _ in limits), max(b for _, b in limits)) if limits else robust_limits(np.zeros(0))
    for ax, j, s in panels:
        ok = np.isfinite(r[:, j])
        inside = ok & (r[:, j] >= lo) & (r[:, j] <= hi)
        for sign, colour, label in ((1, FLEX, "flexing"), (-1, EXTEND, "extending"), (0, "0.5", "at rest")):
            sel = inside & (d[:, s] == sign)
            if sel.any():
                ax.plot(m.u[sel, s] * DEG_PER_RAD, r[sel, j], "o", ms=2.5, color=colour, label=label)
        out = ok & ~inside
        if out.any():
            above = out & (r[:, j] > hi)
            for sel, edge, marker in ((above, hi, "^"), (out & ~above, lo, "v")):
                if sel.any():
                    ax.plot(m.u[sel, s] * DEG_PER_RAD, np.full(int(sel.sum()), edge), marker, ms=5, color="k",
                            clip_on=False, zorder=5, gid="clipped",
                            label=f"beyond the range ({int(out.sum())})")
            worst = r[out, j][np.argmax(np.abs(r[out, j]))]
            ax.text(0.02, 0.04, f"{int(out.sum())} outside the range (largest {worst:+.2f} deg)", fontsize=6,
                    transform=ax.transAxes, gid="clipped_note")
        ax.axhline(0, color="k", lw=0.6)
    axes[0, 0].set_ylim(lo, hi)
    _save(plt, fig, axes, path, "residual (deg)", title, legend_size=7)
    return fig


def plot_mae(path, before: dict, after: dict | None, labels=("before", "after"), title="",
             floor: dict | None = None, noise_floor: float | None = None, worse=()):
    """Per-joint MAE bars, before and after. ``floor``: each joint's noise floor (a short black
    tick over its bars, gid ``noise_floor_joint``); ``noise_floor``: the overall floor, a dashed
    line across (gid ``noise_floor``); ``worse``: joints made worse (see :func:`made_worse`), their
    tick label in red with a "!" and a note over their bars (gid ``worse``). The axis is
    logarithmic when the largest bar is beyond LOG_RATIO x the floor. Returns the figure."""
    plt = _plt()
    cols = list(before)
    x = np.arange(len(cols))
    fig, ax = plt.subplots(figsize=(max(5.0, 0.55 * len(cols) + 2) + 2.6, 3.2))
    w = 0.38 if after else 0.7
    ax.bar(x - (w / 2 if after else 0), [before[c] for c in cols], w, color="tab:red", label=labels[0])
    if after:
        ax.bar(x + w / 2, [after[c] for c in cols], w, color="tab:green", label=labels[1])
    if noise_floor is not None and np.isfinite(noise_floor):
        ax.axhline(noise_floor, color="k", ls="--", lw=0.9, gid="noise_floor",
                   label=f"noise floor {noise_floor:.3f} (from the data)")
    if floor:
        first = True
        for k, c in enumerate(cols):
            if c in floor and np.isfinite(floor[c]):
                ax.hlines(floor[c], k - 0.45, k + 0.45, color="k", lw=1.6, gid="noise_floor_joint",
                          label="noise floor per joint" if first else None)
                first = False
    ax.set_xticks(x)
    ax.set_xticklabels([f"{c}!" if c in worse else c for c in cols], fontsize=8)
    top = max([before[c] for c in cols] + ([after[c] for c in cols] if after else []) + [0.0])
    for k, c in enumerate(cols):
        if c in worse:
            ax.get_xticklabels()[k].set_color("red")
            ax.text(k, top * 1.08, "worse", color="red", fontsize=7, ha="center", va="bottom", gid="worse")
    floors = [v for v in (floor or {}).values() if np.isfinite(v)] + (
        [noise_floor] if noise_floor is not None and np.isfinite(noise_floor) else [])
    low = min([v for v in [before[c] for c in cols] + ([after[c] for c in cols] if after else []) if v > 0] + floors,
              default=0.0)
    if floors and low > 0 and top > LOG_RATIO * min(floors):
        # bars far above the floor: a log axis keeps the floor and the "after" bars readable
        ax.set_yscale("log")
        ax.set_ylim(0.5 * low, top * (2.5 if worse else 1.6))
    elif worse:
        ax.set_ylim(0, top * 1.18)
        title = f"{title}; worse after: {', '.join(worse)}" if title else f"worse after: {', '.join(worse)}"
    ax.set_ylabel("MAE (deg)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return fig


ONE_DIRECTION = "one direction only: no hysteresis can be seen; record the return sweep"


def plot_hysteresis(path, m: Measurements, q_model: np.ndarray, q_analytic: np.ndarray, title: str):
    """Deviation from the analytic model (measured and modelled) against the servo angle, per
    direction: a direction-dependent effect opens a loop between the two branches. A panel whose
    servo moves in one direction only says so (text, gid ``one_direction``), and so does the title
    when every panel does. Returns the figure."""
    plt, fig, axes, panels = _panels(m, sharey=False)
    d = m.direction
    one = 0
    for ax, j, s in panels:
        ok = np.isfinite(m.q[:, j])
        seen = 0
        for sign, colour, label in ((1, FLEX, "flexing"), (-1, EXTEND, "extending")):
            sel = ok & (d[:, s] == sign)
            if not sel.any():
                continue
            seen += 1
            order = np.argsort(m.u[sel, s], kind="stable")
            ax.plot(m.u[sel, s] * DEG_PER_RAD, (m.q[sel, j] - q_analytic[sel, j]) * DEG_PER_RAD, "o", ms=2,
                    color=colour, alpha=0.6, label=f"measured, {label}")
            ax.plot(m.u[sel, s][order] * DEG_PER_RAD, (q_model[sel, j] - q_analytic[sel, j])[order] * DEG_PER_RAD, "-",
                    lw=1, color=colour, label=f"model, {label}")
        if seen < 2:
            one += 1
            ax.text(0.98, 0.97, "one direction only: no hysteresis can be seen", transform=ax.transAxes,
                    ha="right", va="top", fontsize=6, color="0.25", gid="one_direction",
                    bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="0.6", alpha=0.85))
    if panels and one == len(panels):
        title = f"{title}\n{ONE_DIRECTION}"
    _save(plt, fig, axes, path, "q - q_analytic (deg)", title, legend_size=6)
    return fig


def _is_report(folder: Path) -> bool:
    """Whether ``folder`` holds an earlier report (its report.md starts with ``# phantom-cad``)."""
    try:
        with open(folder / "report.md", encoding="utf-8") as fh:
            return fh.readline().startswith("# phantom-cad ")
    except (OSError, ValueError):
        return False


class ReportDir:
    """Build a report folder in a temporary sibling, move it into place on success."""

    def __init__(self, target):
        self.target = Path(target)

    def __enter__(self) -> Path:
        from ..atomic import check_replaceable

        check_replaceable(self.target, _is_report, "a phantom-cad report (report.md)")
        self.target.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = Path(tempfile.mkdtemp(prefix=f".{self.target.name}.", dir=self.target.parent))
        return self.tmp

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            return False
        from ..atomic import replace_dir

        replace_dir(self.tmp, self.target)
        return False


def mae_table(before: dict, after: dict | None, labels=("before", "after")) -> list[str]:
    head = f"| joint | {labels[0]} MAE (deg) |" + (f" {labels[1]} MAE (deg) |" if after else "")
    sep = "|---|---:|" + ("---:|" if after else "")
    lines = [head, sep]
    for c in before:
        j = Q_COLUMNS.index(c)
        row = f"| {c} {JOINT_NAMES[j]} | {before[c]:.3f} |"
        if after:
            row += f" {after[c]:.3f} |"
        lines.append(row)
    return lines


def compare_markdown(m: Measurements, digest: str, lines: list[str], before: dict, after: dict | None,
                     label: str | None) -> str:
    """report.md of ``compare``: the printed ``lines``, the MAE table (``before``/``after`` per joint,
    deg) and the pictures (residual_after.png only with a model ``after``)."""
    md = ["# phantom-cad compare", "", f"data: `{m.source}`, {len(m)} rows, params digest "
          f"{digest[:12]}", "", "```", *lines, "```", "",
          *mae_table(before, after, ("analytic", label or "")), "",
          "![residual before](residual_before.png)", ""]
    if after is not None:
        md += ["![residual after](residual_after.png)", ""]
    md += ["![MAE](mae.png)", "", "![hysteresis](hysteresis.png)", ""]
    return "\n".join(md)


def diagnose_markdown(m: Measurements, digest: str, text: list[str], before: dict, after: dict, label: str) -> str:
    """report.md of ``diagnose``: the printed ``text``, the MAE table and the pictures."""
    md = ["# phantom-cad diagnose", "", f"data: `{m.source}`, {len(m)} rows, params digest "
          f"{digest[:12]}", "", "```", *text, "```", "",
          *mae_table(before, after, ("analytic", f"with {label}")), "",
          "![residual before](residual_before.png)", "", "![residual after](residual_after.png)", "",
          "![MAE](mae.png)", "", "![hysteresis](hysteresis.png)", ""]
    return "\n".join(md)
