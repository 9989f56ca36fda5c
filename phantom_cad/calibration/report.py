"""Metrics, pictures (matplotlib, Agg) and markdown reports of compare and diagnose.

Reports are written into a temporary folder next to the target and moved into place when
complete. Pictures:
  residual_<label>.png  residual (measured - model) against the joint's servo angle, coloured by
                        direction (the paper's residual figure), one panel per measured joint;
  mae.png               per-joint MAE, before and after (the paper's MAE figure);
  hysteresis.png        measured and modelled deviation from the analytic model against the servo
                        angle, flexing and extending: hysteresis loops show as two branches.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np


from ..kinematics.topology import JOINT_NAMES, Q_COLUMNS, U_COLUMNS
from ..units import DEG_PER_RAD
from .data import Measurements
from .effects import JOINT_SERVO

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


def plot_residuals(path, m: Measurements, q_model: np.ndarray, title: str) -> None:
    plt, fig, axes, panels = _panels(m, sharey=True)
    d = m.direction
    r = (m.q - q_model) * DEG_PER_RAD
    for ax, j, s in panels:
        ok = np.isfinite(r[:, j])
        for sign, colour, label in ((1, FLEX, "flexing"), (-1, EXTEND, "extending"), (0, "0.5", "at rest")):
            sel = ok & (d[:, s] == sign)
            if sel.any():
                ax.plot(m.u[sel, s] * DEG_PER_RAD, r[sel, j], "o", ms=2.5, color=colour, label=label)
        ax.axhline(0, color="k", lw=0.6)
    _save(plt, fig, axes, path, "residual (deg)", title, legend_size=7)


def plot_mae(path, before: dict, after: dict | None, labels=("before", "after"), title="") -> None:
    plt = _plt()
    cols = list(before)
    x = np.arange(len(cols))
    fig, ax = plt.subplots(figsize=(max(5.0, 0.55 * len(cols) + 2), 3.2))
    w = 0.38 if after else 0.7
    ax.bar(x - (w / 2 if after else 0), [before[c] for c in cols], w, color="tab:red", label=labels[0])
    if after:
        ax.bar(x + w / 2, [after[c] for c in cols], w, color="tab:green", label=labels[1])
    ax.set_xticks(x)
    ax.set_xticklabels(cols, fontsize=8)
    ax.set_ylabel("MAE (deg)")
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def plot_hysteresis(path, m: Measurements, q_model: np.ndarray, q_analytic: np.ndarray, title: str) -> None:
    """Deviation from the analytic model (measured and modelled) against the servo angle, per
    direction: a direction-dependent effect opens a loop between the two branches."""
    plt, fig, axes, panels = _panels(m, sharey=False)
    d = m.direction
    for ax, j, s in panels:
        ok = np.isfinite(m.q[:, j])
        for sign, colour, label in ((1, FLEX, "flexing"), (-1, EXTEND, "extending")):
            sel = ok & (d[:, s] == sign)
            if not sel.any():
                continue
            order = np.argsort(m.u[sel, s], kind="stable")
            ax.plot(m.u[sel, s] * DEG_PER_RAD, (m.q[sel, j] - q_analytic[sel, j]) * DEG_PER_RAD, "o", ms=2,
                    color=colour, alpha=0.6, label=f"measured, {label}")
            ax.plot(m.u[sel, s][order] * DEG_PER_RAD, (q_model[sel, j] - q_analytic[sel, j])[order] * DEG_PER_RAD, "-",
                    lw=1, color=colour, label=f"model, {label}")
    _save(plt, fig, axes, path, "q - q_analytic (deg)", title, legend_size=6)


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
