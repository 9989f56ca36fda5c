"""The twin-vs-model table of docs/transmission.md: the MJCF twin of an export (gravity and
contacts off) settled under each servo alone at 1/4, 1/2, 3/4 and all of its travel and under
all servos together at 0.3, 0.6 and 1, against ``hand.forward(u, compensated=True)`` at the servo
angles the twin reached, with the routed compensation and with the paper's eq. (11)-(14): the
largest |twin - model| (degrees) per joint kind.

    python bench/twin_vs_model.py default=exports/phantom left=exports/phantom_left \\
        hand_length_170=exports/<170 mm hand>

Each name is one of tests.support.hands.HANDS (its parameters) or a parameter file (``*.toml``,
e.g. one ``phantom-cad size`` wrote), each folder its export.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

KINDS = {"MCP": ("mcp",), "PIP": ("pip",), "DIP": ("dip",), "thumb MP": ("mp",), "thumb IP": ("ip",),
         "thumb CMC": ("cmc",)}


def errors(kind: str, folder: Path) -> dict[str, np.ndarray]:
    import mujoco

    from phantom_cad.export import twin
    from phantom_cad.kinematics.model import Hand
    from phantom_cad.kinematics.topology import JOINTS
    from phantom_cad.params import parse
    from tests.support.hands import hand_document

    if kind.endswith(".toml"):
        from phantom_cad.params.io import load_params

        params = load_params(kind)
    else:
        params = parse(hand_document(kind))
    hands = {c: Hand(params, compensation=c) for c in ("routed", "paper")}
    m = mujoco.MjModel.from_xml_path(str(folder / "description" / "mjcf" / "scene.xml"))
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_GRAVITY
    d = mujoco.MjData(m)
    q_adr, u_adr = twin.addresses(mujoco, m)
    commands = twin.sweep(m.actuator_ctrlrange[:, 0], m.actuator_ctrlrange[:, 1], (0.25, 0.5, 0.75, 1.0),
                          (0.3, 0.6, 1.0))
    err = {c: np.zeros(len(JOINTS)) for c in hands}
    for u in commands:
        mujoco.mj_resetDataKeyframe(m, d, 0)
        d.ctrl[:] = u
        twin.settle(mujoco, m, d, 1e-6, 10.0)
        for c, hand in hands.items():
            model = hand.forward(d.qpos[u_adr], compensated=True)
            err[c] = np.maximum(err[c], np.abs(d.qpos[q_adr] - model))
    out = {}
    for c, e in err.items():
        out[c] = {name: math.degrees(max(e[j.index] for j in JOINTS
                                         if j.key in keys and (j.digit == "thumb") == name.startswith("thumb")))
                  for name, keys in KINDS.items()}
    return out


def main(argv: list[str]) -> None:
    rows = {}
    for arg in argv:
        kind, folder = arg.split("=", 1)
        rows[kind] = errors(kind, Path(folder))
    names = list(KINDS)
    print("| hand | compensation | " + " | ".join(names) + " |")
    print("|---|---|" + "---|" * len(names))
    for kind, by in rows.items():
        for c, e in by.items():
            print(f"| {kind} | {c} | " + " | ".join(f"{e[n]:.3f}" for n in names) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
