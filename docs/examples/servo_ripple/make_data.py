"""Stand-in for a measured recording, for the walk-through of docs/effects.md ("From an unexplained
residual to your own effect").

Every servo sweeps its travel and back (60 steps each way, the others at rest) while a camera
measures the joints of its digit with 0.1 deg of noise. The index and ring servos (u2, u4) carry a
periodic transmission error: their output turns by u + A (sin(2 pi u / 40 deg + phi) - sin(phi)),
zero at rest, where the servo was zeroed. Written independently of phantom_cad's effect library:
the paper's cosine law in closed form, eq. (2) for the distal joints, q15 = u6.

Run: python docs/examples/servo_ripple/make_data.py ripple.csv
"""

import math
import sys

import numpy as np

from phantom_cad import load_hand
from phantom_cad.calibration.data import write_measurements

PERIOD_DEG = 40.0
#: servo index (0-based): (amplitude deg, phase rad)
RIPPLE = {1: (1.5, 0.6), 3: (1.2, -1.1)}
NOISE_DEG = 0.1
STEPS = 60


def true_angles(params, u):
    """q (N, 15): the cosine law per chain at the servo's true output, eq. (2), q15 = u6."""
    q = np.zeros((len(u), 15))
    for chain in params.chains:
        s, g, r = chain.spec.servo, chain.guide, chain.servo_radius
        out = u[:, s].copy()
        if s in RIPPLE:
            a, phi = math.radians(RIPPLE[s][0]), RIPPLE[s][1]
            w = 2 * math.pi / math.radians(PERIOD_DEG)
            out += a * (np.sin(w * u[:, s] + phi) - math.sin(phi))
        L0 = math.sqrt(g.d1 ** 2 + g.d2 ** 2 - 2 * g.d1 * g.d2 * math.cos(g.alpha))
        L = L0 - r * out
        q_ref = g.alpha - np.arccos((g.d1 ** 2 + g.d2 ** 2 - L ** 2) / (2 * g.d1 * g.d2))
        for k, j in enumerate(chain.spec.q_index):
            q[:, j] = q_ref * chain.radii[0] / chain.radii[k]
    q[:, 14] = u[:, 5]
    return q


def main(path):
    hand = load_hand()
    rng = np.random.default_rng(7)
    us, qs, sweeps = [], [], []
    digit_joints = {c.spec.servo: c.spec.q_index for c in hand.params.chains} | {5: (14,)}
    for s in range(6):
        travel = np.linspace(hand.u_min[s], hand.u_max[s], STEPS)
        u = np.zeros((2 * STEPS, 6))
        u[:, s] = np.concatenate([travel, travel[::-1]])
        q_true = true_angles(hand.params, u)
        q = np.full_like(q_true, np.nan)
        for j in digit_joints[s]:
            q[:, j] = q_true[:, j] + np.radians(rng.normal(0.0, NOISE_DEG, len(u)))
        us.append(u)
        qs.append(q)
        sweeps += [f"u{s + 1}"] * len(u)
    write_measurements(path, np.vstack(us), np.vstack(qs), sweep=sweeps,
                       comments=["servo ripple hidden on u2 and u4 (docs/examples/servo_ripple/make_data.py)"])


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "ripple.csv")
