"""diagnose's fits in worker processes (calibration/parallel.py): the same answer as in one process,
a plugin's error surfaces as itself, and the workers die with the process that started them."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from phantom_cad.calibration.diagnose import diagnose
from phantom_cad.calibration.effects import Effect, Param, register_effect, unregister_effect
from phantom_cad.calibration.fitting import Problem, folds
from phantom_cad.calibration.parallel import FitPool
from phantom_cad.calibration.simulate import simulate

fork = pytest.mark.skipif(not hasattr(os, "fork"), reason="the worker processes are forked")


@fork
def test_a_pool_of_two_forks_workers(hand):
    sim = simulate(hand, [], noise_deg=0.1, seed=0, points=20)
    problem = Problem(hand, sim.measurements)
    with FitPool(hand, problem, folds(problem), jobs=2) as pool:
        assert pool.executor is not None
    with FitPool(hand, problem, folds(problem), jobs=1) as pool:
        assert pool.executor is None


@fork
@pytest.mark.slow
def test_workers_and_one_process_give_the_same_bytes(hand):
    sim = simulate(hand, ["tendon_elasticity", "joint_offset"], noise_deg=0.1, seed=4, points=40)
    one = diagnose(hand, sim.measurements, jobs=1)
    two = diagnose(hand, sim.measurements, jobs=2)
    assert one.selected == two.selected and len(one.selected) >= 2
    assert one.after.theta.tobytes() == two.after.theta.tobytes()
    assert one.after.residual.tobytes() == two.after.residual.tobytes()
    assert len(one.rounds) == len(two.rounds)
    for r1, r2 in zip(one.rounds, two.rounds):
        assert [(c.effect, c.delta_ic, c.passes) for c in r1] == [(c.effect, c.delta_ic, c.passes) for c in r2]
        assert np.array_equal([c.heldout_ratio for c in r1], [c.heldout_ratio for c in r2], equal_nan=True)


@pytest.fixture
def exploding_effect():
    @register_effect
    class Exploding(Effect):
        name = "exploding_test_effect"
        stage = "joint"
        explanation = "raises while the fit evaluates it"
        formula = "-"
        signature = "-"
        reference = "tests/calibration/test_parallel.py"

        def parameters(self, hand):
            return [Param("gain", -0.3, 0.3, (0.02, 0.05), True, (14,), True, "a gain")]

        def apply(self, ctx, x):
            raise KeyError("the plugin's own error: q15 is not here")

    yield "exploding_test_effect"
    unregister_effect("exploding_test_effect")


@fork
def test_an_error_in_a_worker_is_raised_as_itself(hand, exploding_effect):
    sim = simulate(hand, [], noise_deg=0.1, seed=0, points=20)
    with pytest.raises(KeyError, match="the plugin's own error"):
        diagnose(hand, sim.measurements, candidates=["joint_offset", exploding_effect], jobs=2)


@fork
@pytest.mark.slow
def test_the_workers_die_with_their_parent(tmp_path):
    script = textwrap.dedent("""
        import os, sys, time
        from phantom_cad import load_hand
        from phantom_cad.calibration.fitting import Problem, folds
        from phantom_cad.calibration.parallel import FitPool
        from phantom_cad.calibration.simulate import simulate
        hand = load_hand()
        sim = simulate(hand, [], noise_deg=0.1, seed=0, points=10)
        problem = Problem(hand, sim.measurements)
        pool = FitPool(hand, problem, folds(problem), jobs=2)
        futures = [pool.executor.submit(time.sleep, 60) for _ in range(2)]
        while len(pool.executor._processes) < 2:
            time.sleep(0.05)
        print(" ".join(str(p) for p in pool.executor._processes), flush=True)
        time.sleep(60)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        workers = [int(p) for p in proc.stdout.readline().split()]
        assert len(workers) == 2
        for pid in workers:
            os.kill(pid, 0)                    # alive while the parent is
        proc.send_signal(signal.SIGKILL)       # no clean-up: the parent is simply gone
        proc.wait()
        deadline = time.monotonic() + 20.0
        alive = workers
        while alive and time.monotonic() < deadline:
            time.sleep(0.2)
            alive = [p for p in workers if _alive(p)]
        assert not alive, f"workers {alive} outlived their parent"
    finally:
        proc.kill()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie waiting for init to reap it is gone as well
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(") ")[1][0] != "Z"
    except OSError:
        return False
