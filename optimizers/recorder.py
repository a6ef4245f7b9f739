"""The bookkeeping of one run: its history, the simulations charged, its rows in the store, and replay.

Shared by the ask / tell driver (:mod:`optimizers.runner`) and the RL trainer (:mod:`optimizers.rl`):
both ask the recorder whether the next evaluation is already stored (a resumed run replays it), write
each new evaluation to the store as it completes, and append the evaluations to the history in order.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import json
from typing import Any

from .base import EvaluationRecord, OptimizationResult, best_record
from .problem import GridSpace
from .progress import ProgressDisplay
from .store import RunConfig, RunStore, StoredEvaluation, StoreError

__all__ = ["RunRecorder", "open_run", "options_json", "package_version"]


def package_version() -> str:
    """The installed catenary-env version ("unknown" when not installed)."""
    try:
        return importlib.metadata.version("catenary-env")
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover - running from a bare checkout
        return "unknown"


def options_json(options: Any) -> str:
    """Canonical JSON of a frozen dataclass of hyper-parameters (part of a run's identity)."""
    return json.dumps(dataclasses.asdict(options), sort_keys=True)


def open_run(store: RunStore, config: RunConfig, resume: bool) -> int:
    """The run to write into: with ``resume`` the latest stored run of this configuration if any, else new."""
    if resume:
        run_id = store.find_run(config)
        if run_id is not None:
            return run_id
    return store.start_run(config)


class RunRecorder:
    """History, budget and store rows of one run.

    Parameters
    ----------
    store : RunStore
        Where the run's evaluations go.
    run_id : int
        The run (new, or resumed: its stored evaluations are replayed by index).
    config : RunConfig
        The run's configuration.
    space : GridSpace
        The problem's grid (names for the result).
    source : str
        ``"simulation"`` (our evaluations: served as cache) or ``"env"`` (an env's: not served).
    progress : ProgressDisplay
        Refreshed as evaluations are appended.
    """

    def __init__(
        self,
        store: RunStore,
        run_id: int,
        config: RunConfig,
        space: GridSpace,
        source: str,
        progress: ProgressDisplay,
    ) -> None:
        self.store = store
        self.run_id = run_id
        self.config = config
        self.space = space
        self.source = source
        self.progress = progress
        self.history: list[EvaluationRecord] = []
        self.n_charged = 0
        self._stored = store.evaluations(run_id)
        self._best_sigma: float | None = None

    @property
    def next_index(self) -> int:
        """Index of the next evaluation to append."""
        return len(self.history)

    def stored(self, index: int, design_key: tuple[int, ...]) -> StoredEvaluation | None:
        """The stored evaluation ``index`` of a resumed run, checked against the design now asked.

        Raises
        ------
        StoreError
            The run asks another design than it did before: it is not deterministic, or the store's run
            was made with other settings.
        """
        stored = self._stored.get(index)
        if stored is not None and stored.design_key != design_key:
            raise StoreError(
                f"{self.store.path}: run {self.run_id} does not replay: evaluation {index} was design "
                f"{stored.design_key}, now {design_key} (same seed and settings should ask the same designs)"
            )
        return stored

    def persist(
        self, record: EvaluationRecord, design_key: tuple[int, ...], reward: float | None = None
    ) -> None:
        """Commit a new evaluation to the store (never a replayed one)."""
        problem, fidelity = self.config.problem, self.config.fidelity
        self.store.add_evaluation(self.run_id, problem, fidelity, design_key, record, self.source, reward)

    def append(self, record: EvaluationRecord) -> None:
        """Add the next evaluation of the history."""
        if record.index != self.next_index:
            raise RuntimeError(f"evaluation {record.index} appended as number {self.next_index}")
        self.history.append(record)
        self.n_charged += int(record.charged)
        if record.loss != float("inf") and (self._best_sigma is None or record.loss < self._best_sigma):
            self._best_sigma = record.loss
        self.progress.update(self.n_charged, len(self.history), self._best_sigma)

    def result(self, stop_reason: str) -> OptimizationResult:
        """Mark the run finished in the store and return its result."""
        self.store.finish_run(self.run_id, stop_reason)
        best = best_record(self.history)
        self.progress.update(self.n_charged, len(self.history), self._best_sigma, force=True)
        self.progress.finish(f"stopped ({stop_reason})")
        config = self.config
        return OptimizationResult(
            optimizer=config.optimizer,
            problem=config.problem,
            variable_names=self.space.variable_names,
            budget=config.budget,
            seed=config.seed,
            speed_kmh=config.speed_kmh,
            fidelity=config.fidelity,
            best_x=None if best is None else best.x,
            best_sigma=None if best is None else best.sigma,
            feasible=best is not None,
            history=tuple(self.history),
            stop_reason=stop_reason,
            n_simulations=self.n_charged,
            run_id=self.run_id,
        )
