"""Benchmark: `diagnose` on a full bidirectional sweep of all six servos (about 2,000 samples) with every library effect as a candidate, the verdict and the signature report included (`to_json`).

Data sets: nothing hidden (one round, every candidate scored and rejected), one effect hidden,
all five hidden (six rounds, the worst case), recording the swept finger's joints (simulate's
default) or every joint on every row (six times the residuals). Prints the wall time of each (best of 3).
Run: .venv/bin/python bench/bench_diagnose.py
"""

from __future__ import annotations

import time

from phantom_cad import load_hand
from phantom_cad.calibration.diagnose import diagnose, mae
from phantom_cad.calibration.simulate import simulate

POINTS = 167  # per direction per servo: 6 * 2 * 167 = 2004 rows
ALL = ["tendon_slack", "pulley_radius_error", "tendon_elasticity", "friction_hysteresis", "joint_offset"]
#: label: (hidden effects, which joints are recorded on each row)
CASES = {
    "nothing hidden": ([], "chain"),
    "friction_hysteresis hidden": (["friction_hysteresis"], "chain"),
    "all five hidden": (ALL, "chain"),
    "all five hidden, every joint on every row": (ALL, "all"),
}


def main() -> None:
    hand = load_hand()
    for label, (effects, measure) in CASES.items():
        sim = simulate(hand, effects, noise_deg=0.1, seed=0, points=POINTS, measure=measure)
        best = float("inf")
        for _ in range(3):
            t0 = time.perf_counter()
            d = diagnose(hand, sim.measurements)
            d.to_json()                      # the verdict, the signatures and their match: part of every report
            best = min(best, time.perf_counter() - t0)
        print(f"diagnose, {len(sim.measurements)} samples ({d.before.m} measured angles), {label}: "
              f"{best:.2f} s; selected {d.selected or 'nothing'}; MAE {mae(d.before):.3f} -> {mae(d.after):.3f} deg "
              f"(noise floor {sim.noise_mae_deg:.3f})")


if __name__ == "__main__":
    main()
