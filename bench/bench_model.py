"""Benchmark of the kinematic model (not a test: figures go to docs/performance.md).

For the routed compensation (the default) and the paper's (eq. 11-14), in the same run:
- single-call latency of hand.inverse(q_d, compensated=True) for one pose;
- throughput of hand.forward(u, compensated=True) on 1,000,000 poses;
and the paper's forward's ratio to the numpy floor of the same work: 5 arccos (of the same
poses' cosine-law arguments) and one (6 x 15) product per pose, nothing else.
Targets: < 20 us per single call; > 10 million poses per second batched; the paper's forward
within 1.5x of the floor.
"""

from __future__ import annotations

import time

import numpy as np

from phantom_cad import load_hand
from phantom_cad.kinematics import closed_form as cf


def best_of(fn, repeat, number):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return min(times), float(np.median(times))


def control_law(hand, label: str, U: np.ndarray) -> tuple[float, float]:
    """(single-pose inverse best, batched forward best), seconds, printed."""
    rng = np.random.default_rng(0)
    u1 = rng.uniform(hand.u_min, hand.u_max)
    q1 = hand.forward(u1, compensated=True)
    best, median = best_of(lambda: hand.inverse(q1, compensated=True), repeat=7, number=20000)
    print(f"{label}: inverse(q_d, compensated=True), one pose: best {best * 1e6:.2f} us, median "
          f"{median * 1e6:.2f} us per call (target < 20 us)")
    hand.forward(U[:1000], compensated=True)
    fbest, fmedian = best_of(lambda: hand.forward(U, compensated=True), repeat=7, number=1)
    print(f"{label}: forward(u, compensated=True), 1,000,000 poses: best {fbest * 1e3:.1f} ms "
          f"({1e6 / fbest:.3g} poses/s), median {fmedian * 1e3:.1f} ms ({1e6 / fmedian:.3g} poses/s) "
          f"(target > 1e7 poses/s)")
    return best, fbest


def main() -> dict:
    t0 = time.perf_counter()
    hand = load_hand()
    print(f"routed: load_hand() {1e3 * (time.perf_counter() - t0):.1f} ms (the routing's strand lengths "
          f"read once per parameter digest)")
    U = np.random.default_rng(1).uniform(hand.u_min, hand.u_max, size=(1_000_000, 6))
    best, fbest = control_law(hand, "routed", U)
    paper = load_hand(compensation="paper")
    pbest, pfbest = control_law(paper, "paper", U)
    # the floor: the same poses' arccos arguments, precomputed; time only arccos + the product
    a, b, c = cf.cosine_coefficients(hand._d1, hand._d2, hand._alpha, hand.servo_radius)
    X = a + U[:, :5] * (b + c * U[:, :5])
    S = np.zeros((U.shape[0], 6))
    P = paper.coupling_compensated

    def floor():
        np.arccos(X, out=S[:, :5])
        return S @ P

    lbest, lmedian = best_of(floor, repeat=7, number=1)
    print(f"numpy floor (5 arccos + one 6 x 15 product per pose), 1,000,000 poses: best {lbest * 1e3:.1f} ms, "
          f"median {lmedian * 1e3:.1f} ms; paper's forward / floor = {pfbest / lbest:.2f}x best "
          f"(target < 1.5x); routed forward / floor = {fbest / lbest:.2f}x best")
    return {"inverse_single_us": best * 1e6, "forward_batch_poses_per_s": 1e6 / fbest,
            "paper_inverse_single_us": pbest * 1e6, "paper_forward_batch_poses_per_s": 1e6 / pfbest,
            "forward_over_floor": pfbest / lbest}


if __name__ == "__main__":
    main()
