"""The fits of one `diagnose` call, run in worker processes.

The candidate fits of a selection round, the held-out checks of the candidates that pass the
information criterion, and the trials of the backward step are independent of each other. A
:class:`FitPool` runs them on the machine's cores. Its workers are forked after the data are
prepared, so they inherit the hand, the problem and its folds, the registered effects (a user's
``--plugin`` included) and the loss of the fits (``robust_loss``); a task is only the effect names
(and the restriction of their parameters, if any) and the starting point, and a result only
arrays. Each result is the one :func:`~.fitting.fit` computes in the parent (the same code on the
same data: the same bytes whichever worker ran it).

Where fork is missing (Windows, macOS's default) or with one CPU the tasks run in this process.
A task that raises in a worker is run again here, so that the error is the genuine one
(a plugin's exception, with its type and message). Workers die with the parent
(:func:`phantom_cad.workers.die_with_parent`).
"""

from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from ..workers import available_cpus, die_with_parent, fork_context
from .fitting import FitResult, Model, Problem, fit, heldout_fold

#: what the forked workers inherit: {"hand", "problems": {key: Problem}}
_STATE: dict = {}

#: a result that says "this task raised in the worker: run it again in the parent"
_FAILED = "failed"


def _run(state: dict, task) -> tuple:
    kind, names, only, key, x0, uncertainty = task
    hand, problems = state["hand"], state["problems"]
    problem = problems["all"]
    model = Model(hand, names, problem, dict(only))
    if kind == "fit":
        res = fit(model, problem, x0, uncertainty)
        return res.theta, res.std, res.residual, res.jtj
    # "heldout": fit on one fold, the sum of squares on the other (fitting.folds)
    return (heldout_fold(model, problems[f"fold{1 - key}"], problems[f"fold{key}"], x0),)


def _work(task) -> tuple:
    try:
        return _run(_STATE, task)
    except BaseException:   # noqa: BLE001 - reported by running the task again in the parent
        return (_FAILED,)


class FitPool:
    """Fits of models (lists of effect names) on one problem, in parallel where the machine allows.

    ``parts``: the two folds of the held-out check (row positions into ``problem``)."""

    def __init__(self, hand, problem: Problem, parts, jobs: int | None = None):
        self.hand, self.problem = hand, problem
        self.state = {"hand": hand, "problems": {"all": problem, "fold0": problem.subset(parts[0]),
                                                 "fold1": problem.subset(parts[1])}}
        self.jobs = available_cpus() if jobs is None else max(1, int(jobs))
        self.executor: ProcessPoolExecutor | None = None
        #: every fit made, by its effect names (the first of a model, whatever its start)
        self.fitted: dict[tuple, FitResult] = {}
        ctx = fork_context()
        if ctx is not None and self.jobs > 1:
            _STATE.clear()
            _STATE.update(self.state)      # inherited by the workers, forked at the first task
            self.executor = ProcessPoolExecutor(self.jobs, mp_context=ctx, initializer=die_with_parent,
                                                initargs=(os.getpid(),))

    def __enter__(self) -> "FitPool":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self.executor is not None:
            self.executor.shutdown(wait=True, cancel_futures=True)
            self.executor = None
        _STATE.clear()

    def _map(self, tasks: list) -> list[tuple]:
        if self.executor is None or len(tasks) < 2:
            return [_run(self.state, t) for t in tasks]
        out = list(self.executor.map(_work, tasks))
        return [_run(self.state, t) if isinstance(r[0], str) and r[0] == _FAILED else r for t, r in zip(tasks, out)]

    def fits(self, jobs: list[tuple[Model, np.ndarray | None]]) -> list[FitResult]:
        """fit(model, problem, x0) of each (model, x0), models on this pool's problem."""
        tasks = [("fit", model.names, model.only, None, x0, True) for model, x0 in jobs]
        out = [FitResult(model, theta, std, residual, self.problem, jtj=jtj)
               for (model, _), (theta, std, residual, jtj) in zip(jobs, self._map(tasks))]
        for res in out:
            if not res.model.only:          # a restricted model is not the model its names say
                self.fitted.setdefault(res.model.names, res)
        return out

    def fit(self, model: Model, x0=None) -> FitResult:
        return self.fits([(model, x0)])[0]

    def heldout(self, jobs: list[tuple[Model, np.ndarray | None]]) -> list[float]:
        """The held-out sum of squares of each (model, x0): fitted on each fold from x0, scored on
        the other (fitting.heldout_fold), the two folds summed."""
        tasks = [("heldout", model.names, model.only, k, x0, False) for model, x0 in jobs for k in (0, 1)]
        sse = [r[0] for r in self._map(tasks)]
        return [sse[2 * i] + sse[2 * i + 1] for i in range(len(jobs))]
