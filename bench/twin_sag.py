"""The twin's sag under gravity, in the table of docs/transmission.md: the MJCF twin of an export
(contacts off), gravity 9.81 m/s^2 along each of the palm frame's six axis directions in turn,
settled under each servo alone at 1/2 and all of its travel and all servos together at 1/2 and
all of it; the largest |twin - model| (degrees) per joint kind, the model
``hand.forward(u, compensated=True)`` (routed) at the servo angles the twin reached: what gravity
adds on top of the model (the model has no gravity).

    python bench/twin_sag.py exports/phantom          # the default hand's export
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

KINDS = {"MCP": "mcp", "PIP": "pip", "DIP": "dip", "thumb MP": "mp", "thumb IP": "ip", "thumb CMC": "cmc"}


def main(folder: Path) -> None:
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
            print(f"| {'+-'[sign < 0]}{'xyz'[axis]} | " + " | ".join(f"{c:.2f}" for c in cells) + " |")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
