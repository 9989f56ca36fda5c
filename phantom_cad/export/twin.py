"""The MJCF twin brought to rest: the one settling loop and the one servo sweep that
``phantom-cad check``, the twin-vs-model tests and the twin benchmarks share. ``mujoco`` is passed
in: the caller imports it (only commands that simulate do)."""

from __future__ import annotations

import numpy as np

from ..kinematics.topology import JOINTS, SERVOS

#: the twin is at rest when no joint moves faster than its threshold at this many checks in a row,
#: CHECK_S apart: one sample can fall on a swing's turning point
STILL_CHECKS, CHECK_S = 4, 0.05


def settle(mujoco, m, d, rest: float, seconds: float) -> bool:
    """Step ``d`` until every joint is slower than ``rest`` (rad/s) at :data:`STILL_CHECKS` checks
    :data:`CHECK_S` apart, or for ``seconds`` of simulated time; whether it came to rest."""
    check = max(1, int(CHECK_S / m.opt.timestep))
    still = 0
    for i in range(1, int(seconds / m.opt.timestep)):
        mujoco.mj_step(m, d)
        if i % check == 0:
            still = still + 1 if np.abs(d.qvel).max() < rest else 0
            if still == STILL_CHECKS:
                return True
    return False


def sweep(lo, hi, fractions, together) -> list[np.ndarray]:
    """Servo commands between the ranges' ends ``lo`` and ``hi``: each servo alone at each of
    ``fractions`` of its range (the others at ``lo``), then all of them together at ``together``."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    out = []
    for k in range(len(lo)):
        for f in fractions:
            u = lo.copy()
            u[k] += f * (hi[k] - lo[k])
            out.append(u)
    return out + [lo + f * (hi - lo) for f in together]


def addresses(mujoco, m) -> tuple[list[int], list[int]]:
    """qpos addresses of the 15 joints (topology order) and of the six servo hinges (servo order)."""
    def adr(name: str) -> int:
        return int(m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)])
    return [adr(j.name) for j in JOINTS], [adr(s.name) for s in SERVOS]
