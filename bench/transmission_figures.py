"""Pictures of the routed tendons (docs/transmission.md): a finger and the thumb seen from the
side, at rest and at full servo travel, drawn from the routing model (kinematics.routing) and the
link frames (kinematics.frames). Run: .venv/bin/python bench/transmission_figures.py [OUT_DIR]

Each link is drawn as its outline in the digit's plane (its proximal joint to its distal one,
the digit's thickness), each pulley as its circle, every strand as its path. Strands are drawn
in the joints' plane: their x (across the digit) is left out.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from phantom_cad.kinematics import routing  # noqa: E402
from phantom_cad.kinematics import routing_paths
from phantom_cad.kinematics.frames import segment_length  # noqa: E402
from phantom_cad.kinematics.model import Hand  # noqa: E402
from phantom_cad.kinematics.topology import SERVOS, chain, digit_links, joint  # noqa: E402
from phantom_cad.params.io import DEFAULT_PARAMS, load_params  # noqa: E402

COLOURS = {"drive": "#d62728", "a": "#ff7f0e", "b": "#2ca02c", "return": "#1f77b4"}


def draw(ax, p, digit: str, frac: float, title: str) -> None:
    hand = Hand(p)
    u = np.zeros(len(SERVOS))
    s = chain(digit).servo
    lo, hi = p.digit(digit).chain.travel
    u[s] = lo + frac * (hi - lo)
    q = hand.forward(u, compensated=False)
    Ts = routing_paths.pose(p, q, u)
    first = digit_links(digit)[0].name
    inv = np.linalg.inv(Ts[first])
    to2d = lambda P: (inv @ np.c_[P, np.ones(len(P))].T)[1:3].T * 1e3  # noqa: E731
    T = p.digit(digit).thickness
    for ln in digit_links(digit):
        if ln.segment == "servo_pulley":
            continue
        L = segment_length(p, ln)
        y0 = -p.cad.finger_base_length if ln.segment == "base" else -T / 2
        y1 = L + T / 2 if L > 0 else 0.0
        box = np.array([[0, y0, -T / 2], [0, y1, -T / 2], [0, y1, T / 2], [0, y0, T / 2], [0, y0, -T / 2]])
        P = (Ts[ln.name] @ np.c_[box, np.ones(5)].T).T[:, :3]
        xy = to2d(P)
        ax.fill(xy[:, 0], xy[:, 1], color="0.88", ec="0.55", lw=0.8, zorder=1)
    for jn, R in zip(chain(digit).joint_names, p.digit(digit).chain.radii):
        c = to2d(Ts[joint(jn).child][None, :3, 3])[0]
        ax.add_patch(plt.Circle(c, R * 1e3, fill=False, ec="0.35", lw=0.8, zorder=2))
        ax.plot(*c, "k+", ms=4, zorder=2)
    for r in routing.routes(p):
        if r.tendon.digit != digit:
            continue
        for st in r.strands:
            _, pts = routing_paths.strand_path(p, st, Ts)
            xy = to2d(pts)
            key = r.tendon.kind if r.tendon.kind != "coupling" else st.name[-1]
            label = {"drive": "drive", "a": "coupling loops, strand a", "b": "coupling loops, strand b",
                     "return": "return cord (k_s)"}[key]
            ax.plot(xy[:, 0], xy[:, 1], color=COLOURS[key], lw=1.4, zorder=3, label=label)
    handles, labels = ax.get_legend_handles_labels()
    seen = dict(zip(labels, handles))
    ax.legend(seen.values(), seen.keys(), fontsize=7, loc="lower right")
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel(f"y along the {digit}'s first link (mm)", fontsize=8)
    ax.set_ylabel("z dorsal (mm)", fontsize=8)
    ax.tick_params(labelsize=7)


def main(out: Path) -> None:
    p = load_params(DEFAULT_PARAMS)
    out.mkdir(parents=True, exist_ok=True)
    for digit in ("index", "thumb"):
        fig, axes = plt.subplots(1, 2, figsize=(11, 5.2))
        draw(axes[0], p, digit, 0.0, f"{digit}: rest (u = 0)")
        draw(axes[1], p, digit, 1.0, f"{digit}: full servo travel (hand.forward, uncompensated)")
        for ax in axes:
            ax.set_xlim(-35, 105)
            ax.set_ylim(-100, 25)
        fig.tight_layout()
        fig.savefig(out / f"transmission_{digit}.png", dpi=130)
        plt.close(fig)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "img")
