"""Pictures of the thumb's opposition (docs/opposition.md): the hand's digits as their link axes
(link_frames.link_transforms), the fingertip capsules of kinematics.opposition and the palm envelope,
at rest and at the commands where the thumb's pad meets each opposed fingertip's most squarely,
for the file's CMC placement (solved within the palm's thenar, docs/opposition.md).
Run: .venv/bin/python bench/opposition_figures.py [OUT_DIR]
"""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from phantom_cad.kinematics import frames as F, opposition as O, thumb_placement as TP  # noqa: E402
from phantom_cad.kinematics import link_frames as LF
from phantom_cad.kinematics.model import Hand  # noqa: E402
from phantom_cad.kinematics.topology import CHAINS, FINGERS, N_SERVOS, chain, digit_links  # noqa: E402
from phantom_cad.params.io import DEFAULT_PARAMS, load_params  # noqa: E402


def _with_thumb(p, offset, axis):
    return replace(p, palm=replace(p.palm, thumb_cmc_offset=tuple(offset), thumb_cmc_axis=tuple(axis)))


def draw(ax, hand, p, u, title, highlight, view):
    q = hand.forward(u, compensated=True)
    Ts = LF.link_transforms(p, q)
    lo, hi = TP.palm_envelope(p)
    # the palm envelope's edges
    c = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) * 1e3
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(np.abs(c[i] - c[j]) > 1e-9) == 1:
                ax.plot(*zip(c[i], c[j]), color="0.7", lw=0.8)
    for ch in CHAINS:
        links = [ln for ln in digit_links(ch.digit) if ln.segment not in ("base",)]
        pts = [Ts[ln.name][:3, 3] for ln in links]
        L, r, _ = F.fingertip(p, ch.digit)
        tip = Ts[links[-1].name] @ np.array([0.0, L - r, 0.0, 1.0])
        pts = np.array([*pts, tip[:3]]) * 1e3
        colour = "#d62728" if ch.digit == "thumb" else ("#1f77b4" if ch.digit == highlight else "0.35")
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], "-o", color=colour, lw=2.5, ms=3)
        pad = (Ts[links[-1].name] @ F.T_distal_pad(p, ch.digit))[:3, 3] * 1e3
        ax.scatter(*pad, color=colour, s=25, marker="s")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x ulnar (mm)", fontsize=7)
    ax.set_ylabel("y distal (mm)", fontsize=7)
    ax.set_zlabel("z dorsal (mm)", fontsize=7)
    ax.tick_params(labelsize=6)
    ax.set_xlim(-75, 75)
    ax.set_ylim(-80, 70)
    ax.set_zlim(-90, 30)
    ax.set_box_aspect((150, 150, 120))
    ax.view_init(*view)


def main(out: Path) -> None:
    p = load_params(DEFAULT_PARAMS)
    hand = Hand(p)
    reach = O.reach(hand)
    out.mkdir(parents=True, exist_ok=True)
    fig = plt.figure(figsize=(15, 8.4))
    views = ((-90, -90), (0, 180))          # from the palmar side; from the radial side
    for row, view in enumerate(views):
        draw(fig.add_subplot(2, 4, 4 * row + 1, projection="3d"), hand, p, np.zeros(N_SERVOS),
             "the file's thumb at rest", None, view)
        for k, f in enumerate(O.OPPOSED):
            r = reach[f]
            u = np.zeros(N_SERVOS)
            u[chain("thumb").servo], u[5], u[chain(f).servo] = r.u_contact
            draw(fig.add_subplot(2, 4, 4 * row + k + 2, projection="3d"), hand, p, u,
                 f"the file's thumb pad meets the {f}\n(margin {math.degrees(r.margin):+.1f} deg)", f, view)
    fig.suptitle("thumb (red) and fingers as link axes, pads as squares, the palm envelope in grey; "
                 "top: seen from the palm side, bottom: from the radial side", fontsize=10)
    fig.tight_layout()
    fig.savefig(out / "opposition.png", dpi=120)
    plt.close(fig)
    print(f"wrote {out / 'opposition.png'} ({', '.join(FINGERS)})")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "img")
