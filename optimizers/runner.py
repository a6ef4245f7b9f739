"""The driver of an ask / tell optimisation run: budget, cache, store, replay and parallel evaluation.

:func:`optimize` asks the optimiser for a batch, evaluates it and tells the losses, until the optimiser
stops by its own rule or the budget is spent. Each design of a batch is, in this order:

1. *replayed* when the run is resumed and its evaluation with that index is stored (checked to be the
   same design): nothing is simulated, the stored record is reused as it was;
2. a *free cache hit* when the run has evaluated the design before (``cached``, not ``charged``);
3. *charged*, then served from the store's cache when another run of the store simulated it
   (``cached``), or simulated (in parallel with the rest of the batch). A design that would take the
   charged count past the budget is not evaluated: the batch is cut there and the run stops.

Every new evaluation is committed to the store as it completes; the optimiser is told the whole batch
in its order, so the results do not depend on the backend or on the order of completion.

Examples
--------
>>> from optimizers.synthetic import get_synthetic_problem
>>> result = optimize(get_synthetic_problem("synthetic-quadratic"), "random", budget=20, seed=3)
>>> result.n_simulations, result.stop_reason
(20, 'budget')
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from contextlib import ExitStack
from typing import Any

import numpy as np
from numpy.typing import NDArray

from catenary_env.cli.progress import LOG_INTERVAL, ProgressDisplay

from . import ga, nevergrad_adapters, optuna_adapters  # noqa: F401  (register the built-in optimisers)
from .base import EvaluationRecord, OptimizationResult, Optimizer
from .evaluation import EvaluationBackend, make_backend
from .plugins import get_optimizer
from .problem import GridProblem, GridSpace, Outcome
from .problem_registry import resolve_problem
from .recorder import RunRecorder, open_run, options_json, package_version
from .store import RunConfig, RunStore

__all__ = ["optimize", "run_config"]


def optimize(
    problem: GridProblem | str,
    optimizer: str,
    budget: int,
    seed: int = 0,
    *,
    speed_kmh: float = 300.0,
    fidelity: str = "study",
    options: Any = None,
    store: RunStore | str | os.PathLike[str] | None = None,
    resume: bool = False,
    start_if_none: bool = True,
    n_workers: int = 1,
    scheduler: str | None = None,
    max_evaluations: int | None = None,
    quiet: bool = True,
    progress_interval: float = LOG_INTERVAL,
    archive: str | os.PathLike[str] | None = None,
) -> OptimizationResult:
    """Run a registered optimiser on a problem and return its result.

    Parameters
    ----------
    problem : GridProblem or str
        The problem, or its name (a catenary problem of docs/problems.md or a synthetic one).
    optimizer : str
        A name in :data:`optimizers.base.OPTIMIZERS`.
    budget : int
        Simulations the run may charge (see :mod:`optimizers.base` for what is charged).
    seed : int
        Random seed; the same seed gives the same history.
    speed_kmh : float
        Design speed, km/h.
    fidelity : str
        ``"study"`` or ``"test"`` (passed to the problem's ``simulate``).
    options : dataclass, optional
        The optimiser's hyper-parameters (its ``options_class``); default: its defaults.
    store : RunStore or path, optional
        The run store; default: a store in memory (nothing kept after the call).
    resume : bool
        Continue the latest stored run of the same configuration instead of starting a new one.
    start_if_none : bool
        With ``resume``, start a new run when the store holds none of this configuration (else
        :class:`~optimizers.store.StoreError` lists the runs it holds).
    n_workers : int
        Local worker processes for the simulations (1: in this process).
    scheduler : str, optional
        Dask scheduler address; the simulations go to that cluster instead.
    max_evaluations : int, optional
        Cap on evaluations, free cache hits included; default 10 × budget.
    quiet : bool
        No progress display.
    progress_interval : float
        Seconds between two progress lines when stderr is not a terminal.
    archive : path, optional
        A run archive (:mod:`optimizers.archive`): the run goes into it when it finishes, and a snapshot of
        it while it runs (:class:`~optimizers.recorder.RunRecorder`).
    """
    grid_problem = resolve_problem(problem)
    space = GridSpace.from_problem(grid_problem)
    spec = get_optimizer(optimizer)
    settings = spec.options_class() if options is None else options
    if not isinstance(settings, spec.options_class):
        raise TypeError(
            f"{optimizer}: options must be a {spec.options_class.__name__}, got {type(settings).__name__}"
        )
    config = run_config(optimizer, space, budget, seed, speed_kmh, fidelity, settings)
    cap = 10 * int(budget) if max_evaluations is None else int(max_evaluations)
    with ExitStack() as stack:
        run_store = (
            store if isinstance(store, RunStore) else stack.enter_context(RunStore(store or ":memory:"))
        )
        run_id, resumed = stack.enter_context(open_run(run_store, config, resume, start_if_none))
        progress = ProgressDisplay(
            f"{optimizer} on {space.name}",
            int(budget),
            "simulations",
            quiet=quiet,
            interval=progress_interval,
        )
        recorder = RunRecorder(run_store, run_id, config, space, "simulation", progress, resumed, archive)
        stack.callback(recorder.keep_unfinished)  # interrupted: the archive keeps what it made
        backend = stack.enter_context(make_backend(n_workers, scheduler))
        engine = spec.optimizer_class(space, int(budget), int(seed), settings)  # type: ignore[call-arg]
        loop = _BatchEvaluator(grid_problem, space, recorder, backend, cap)
        stop_reason = _run(engine, loop, recorder, int(budget), cap)
        return recorder.result(stop_reason)


def run_config(
    optimizer: str, space: GridSpace, budget: int, seed: int, speed_kmh: float, fidelity: str, settings: Any
) -> RunConfig:
    """The identity in the store of the run :func:`optimize` makes with these arguments (``settings``: the
    optimiser's options), so that a reader finds the run without making it."""
    return RunConfig(
        optimizer, space.store_key, int(budget), int(seed), float(speed_kmh), fidelity,
        options_json(settings), package_version(),
    )  # fmt: skip


def _run(engine: Optimizer, loop: _BatchEvaluator, recorder: RunRecorder, budget: int, cap: int) -> str:
    """Ask, evaluate, tell until a stop rule; return the stop reason."""
    while True:
        if engine.stop_reason is not None:
            return engine.stop_reason
        if recorder.n_charged >= budget:
            return "budget"
        if len(recorder.history) >= cap:
            return "max_evaluations"
        points = engine.ask()
        records = loop.evaluate(points)
        for record in records:
            recorder.append(record)
        if len(records) < len(points):  # cut short by the budget or the cap: the batch cannot be told
            return "budget" if recorder.n_charged >= budget else "max_evaluations"
        engine.tell(points, [record.loss for record in records], [record.constraints for record in records])


class _BatchEvaluator:
    """Evaluates batches for one run: replay, run-local cache, store cache, parallel simulation."""

    def __init__(
        self,
        problem: GridProblem,
        space: GridSpace,
        recorder: RunRecorder,
        backend: EvaluationBackend,
        cap: int,
    ) -> None:
        self.simulate = problem.simulate
        self.space = space
        self.recorder = recorder
        self.backend = backend
        self.cap = cap
        self.speed_kmh = float(recorder.config.speed_kmh or 0.0)
        self.fidelity = recorder.config.fidelity
        self.seen: dict[tuple[int, ...], Outcome] = {}  # designs this run has evaluated

    def evaluate(self, points: NDArray[np.int64]) -> list[EvaluationRecord]:
        """The records of the batch, in its order; fewer than asked when the budget or the cap cut it."""
        records: dict[int, EvaluationRecord] = {}
        waiting: dict[tuple[int, ...], list[int]] = {}  # design -> positions, first one to be simulated
        designs: list[NDArray[np.float64]] = []
        charged = self.recorder.n_charged
        base = self.recorder.next_index
        limit = min(len(points), self.cap - base)
        for position in range(limit):
            x = self.space.to_design(points[position])
            key = self.space.design_key(x)
            designs.append(x)
            record, counted = self._plan(base + position, x, key, waiting, charged)
            if counted and charged + 1 > self.recorder.config.budget:
                limit = position
                break
            charged += counted
            if record is not None:
                records[position] = record
            elif key in waiting:
                waiting[key].append(position)
            else:
                waiting[key] = [position]
        self._simulate(waiting, designs, records, base)
        return [records[position] for position in range(limit)]

    def _plan(
        self,
        index: int,
        x: NDArray[np.float64],
        key: tuple[int, ...],
        waiting: dict[tuple[int, ...], list[int]],
        charged: int,
    ) -> tuple[EvaluationRecord | None, int]:
        """The record of one design if known without simulating, and whether it is charged (0 or 1)."""
        stored = self.recorder.stored(index, key)
        if stored is not None:
            record = stored.record
            self.seen.setdefault(
                key,
                Outcome(record.feasible, record.sigma, record.reason, record.wall_time, record.constraints,
                        record.statistics),
            )  # fmt: skip
            return record, int(record.charged)
        if key in self.seen:
            return self._record(index, x, self.seen[key], cached=True, charged=False, key=key), 0
        if key in waiting:
            return None, 0  # a duplicate within the batch: filled when the first one is simulated
        if charged + 1 > self.recorder.config.budget:
            return None, 1  # over budget: the caller cuts the batch here
        outcome = self.recorder.store.lookup(self.space.store_key, key, self.speed_kmh, self.fidelity)
        if outcome is None:
            return None, 1
        self.seen[key] = outcome
        return self._record(index, x, outcome, cached=True, charged=True, key=key), 1

    def _simulate(
        self,
        waiting: dict[tuple[int, ...], list[int]],
        designs: Sequence[NDArray[np.float64]],
        records: dict[int, EvaluationRecord],
        base: int,
    ) -> None:
        """Simulate the first position of each waiting design; store each result as it completes."""
        keys = list(waiting)
        arguments = [
            (tuple(designs[waiting[key][0]].tolist()), self.speed_kmh, self.fidelity) for key in keys
        ]
        for number, outcome in self.backend.run(self.simulate, arguments):
            key = keys[number]
            self.seen[key] = outcome
            first, *duplicates = waiting[key]
            x = designs[first]
            records[first] = self._record(base + first, x, outcome, cached=False, charged=True, key=key)
            for position in duplicates:
                records[position] = self._record(
                    base + position, x, outcome, cached=True, charged=False, key=key
                )

    def _record(
        self,
        index: int,
        x: NDArray[np.float64],
        outcome: Outcome,
        cached: bool,
        charged: bool,
        key: tuple[int, ...],
    ) -> EvaluationRecord:
        """Build a new evaluation record and commit it to the store."""
        record = EvaluationRecord(
            index=index,
            x=tuple(float(v) for v in x),
            feasible=bool(outcome.feasible),
            sigma=None if outcome.sigma is None else float(outcome.sigma),
            reason=str(outcome.reason),
            wall_time=0.0 if cached else float(outcome.wall_time),
            cached=cached,
            charged=charged,
            speed_kmh=self.speed_kmh,
            constraints=tuple(float(v) for v in outcome.constraints),
            statistics=tuple(float(v) for v in outcome.statistics),
        )
        self.recorder.persist(record, key)
        return record
