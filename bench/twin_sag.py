"""The twin's sag under gravity, in the table of docs/transmission.md: the MJCF twin of an export
(contacts off), gravity 9.81 m/s^2 along each of the palm frame's six axis directions in turn,
settled under each servo alone at 1/2 and all of its travel and all servos together at 1/2 and
all of it; the largest |twin - model| (degrees) per joint kind, the model
``hand.forward(u, compensated=True)`` (routed) at the servo angles the twin reached: what gravity
adds on top of the model (the model has no gravity).

    python bench/twin_sag.py exports/phantom          # the default hand's export
    python bench/twin_sag.py exports/phantom --png docs/img/twin_sag.png   # and the figure
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

KINDS = {"MCP": "mcp", "PIP": "pip", "DIP": "dip", "thumb MP": "mp", "thumb IP": "ip", "thumb CMC": "cmc"}


def figure(rows: dict[str, list[float]], path: Path) -> None:
    """The table as grouped bars (log scale: the sag spans two decades), the twin-vs-model
    tolerance without gravity (0.1 degree) drawn for scale."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.0, 4.0), dpi=100)
    width = 0.8 / len(KINDS)
    for k, kind in enumerate(KINDS):
        x = np.arange(len(rows)) + (k - (len(KINDS) - 1) / 2.0) * width
        ax.bar(x, [max(v[k], 1e-3) for v in rows.values()], width, label=kind)
    ax.axhline(0.1, color="0.3", lw=0.8, ls="--", label="twin = model without gravity: within 0.1 deg")
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(rows)), [f"gravity {g}" for g in rows])
    ax.set_ylabel("largest |twin - model| (deg)")
    ax.set_title("The twin's sag under gravity (default hand, contacts off, servos holding)", fontsize=10)
    ax.legend(ncol=4, fontsize=8, loc="upper left")
    ax.set_ylim(0.01, 1000.0)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, metadata={"Software": None})
    plt.close(fig)


def main(folder: Path, png: Path | None = None) -> None:
    import mujoco

    from phantom_cad import load_hand
    from phantom_cad.export import twin
    from phantom_cad.kinematics.topology import JOINTS

    hand = load_hand()
    m = mujoco.MjModel.from_xml_path(str(folder / "description" / "mjcf" / "scene.xml"))
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    d = mujoco.MjData(m)
    q_adr, u_adr = twin.addresses(mujoco, m)
    commands = twin.sweep(m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1], (0.5, 1.0), (0.5, 1.0))
    print("| gravity along (palm frame) | " + " | ".join(KINDS) + " |")
    print("|---|" + "---|" * len(KINDS))
    rows = {}
    for axis in range(3):
        for sign in (1.0, -1.0):
            m.opt.gravity[:] = 0.0
            m.opt.gravity[axis] = sign * 9.81
            err = np.zeros(len(JOINTS))
            for u in commands:
                mujoco.mj_resetDataKeyframe(m, d, 0)
                d.ctrl[:] = u
                twin.settle(mujoco, m, d, 1e-5, 10.0)
                err = np.maximum(err, np.abs(d.qpos[q_adr] - hand.forward(d.qpos[u_adr], compensated=True)))
            cells = [math.degrees(max(err[j.index] for j in JOINTS if j.key == key)) for key in KINDS.values()]
            rows[f"{'+-'[sign < 0]}{'xyz'[axis]}"] = cells
            print(f"| {'+-'[sign < 0]}{'xyz'[axis]} | " + " | ".join(f"{c:.2f}" for c in cells) + " |")
    if png is not None:
        figure(rows, png)


if __name__ == "__main__":
    args = sys.argv[1:]
    png = Path(args[args.index("--png") + 1]) if "--png" in args else None
    main(Path(args[0]), png)
