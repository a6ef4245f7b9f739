"""The bookkeeping of one run: its history, the simulations charged, its rows in the store, and replay.

Shared by the ask / tell driver (:mod:`optimizers.runner`) and the RL trainer (:mod:`optimizers.rl`):
both ask the recorder whether the next evaluation is already stored (a resumed run replays it), write
each new evaluation to the store as it completes, and append the evaluations to the history in order.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib.metadata
import json
import os
import time
from collections.abc import Iterator
from typing import Any

from catenary_env.cli.progress import ProgressDisplay

from .archive import archive_run, snapshot_run
from .base import EvaluationRecord, OptimizationResult, best_record
from .problem import GridSpace
from .store import RunConfig, RunStore, StoredEvaluation, StoreError

__all__ = [
    "SNAPSHOT_EVERY_S",
    "RunRecorder",
    "finished_result",
    "open_run",
    "options_json",
    "package_version",
]

SNAPSHOT_EVERY_S = 600.0
"""Seconds between two snapshots of a run going on into its archive: a run interrupted with its store
lost is resumed from at most this long before."""


def package_version() -> str:
    """The installed catenary-env version ("unknown" when not installed)."""
    try:
        return importlib.metadata.version("catenary-env")
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover - running from a bare checkout
        return "unknown"


def options_json(options: Any) -> str:
    """Canonical JSON of a frozen dataclass of hyper-parameters (part of a run's identity)."""
    return json.dumps(dataclasses.asdict(options), sort_keys=True)


@contextlib.contextmanager
def open_run(
    store: RunStore, config: RunConfig, resume: bool, start_if_none: bool = True
) -> Iterator[tuple[int, bool]]:
    """The run to write into and whether it is resumed, held by this process while the block runs
    (:meth:`RunStore.claim <optimizers.store.RunStore.claim>`).

    With ``resume``: the latest stored run of this configuration; when there is none, a new run if
    ``start_if_none``, else :class:`StoreError` listing the runs the store holds; :class:`StoreError` too when
    another process is making that run now (two processes writing one run would interleave their
    evaluations). Without: a new run.
    """
    with store.claim(config) as held:
        if resume and not held:
            raise StoreError(
                f"{store.path}: {_asked(config)} is being made by another process now; wait for it to end "
                "(then resume it), or give another seed or store"
            )
        if resume:
            run_id = store.find_run(config)
            if run_id is not None:
                yield run_id, True
                return
            if not start_if_none:
                raise StoreError(f"{store.path}: {_no_run_to_resume(store, config)}")
        yield store.start_run(config), False


def _asked(config: RunConfig) -> str:
    """The run a configuration names, in words."""
    speed = "a speed range" if config.speed_kmh is None else f"speed {config.speed_kmh:g} km/h"
    return (
        f"{config.optimizer} on {config.problem}, budget {config.budget}, seed {config.seed}, {speed}, "
        f"fidelity {config.fidelity}"
    )


def _no_run_to_resume(store: RunStore, config: RunConfig) -> str:
    """Why nothing matches --resume: the configuration asked and the runs the store holds."""
    asked = _asked(config)
    runs = store.runs()
    found = "; ".join(
        f"run {r['run_id']}: {r['optimizer']} on {r['problem']}, budget {r['budget']}, seed {r['seed']}, "
        f"fidelity {r['fidelity']}"
        for r in runs[-5:]
    )
    held = f"it holds {len(runs)} run(s), the latest: {found}" if runs else "it holds no run"
    return (
        f"no run to resume with {asked} (and these optimiser settings); {held}. Give that run's options, "
        "or start anew: drop --resume (or use --resume-or-start)"
    )


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
    resumed : bool
        The run is resumed: say so, with the number of evaluations that will be replayed.
    archive : path, optional
        A run archive (:mod:`optimizers.archive`): the run is written into it when it finishes, and a
        snapshot of it every :data:`SNAPSHOT_EVERY_S` seconds while it goes on (a long run survives the
        loss of its store: a fresh checkout restores the snapshot and resumes from there), and when it
        stops unfinished (:meth:`keep_unfinished`, which its maker calls on the way out).
    """

    def __init__(
        self,
        store: RunStore,
        run_id: int,
        config: RunConfig,
        space: GridSpace,
        source: str,
        progress: ProgressDisplay,
        resumed: bool = False,
        archive: str | os.PathLike[str] | None = None,
    ) -> None:
        self.store = store
        self.archive = archive
        self._snapshot_at = time.monotonic()
        self.run_id = run_id
        self.config = config
        self.space = space
        self.source = source
        self.progress = progress
        self.history: list[EvaluationRecord] = []
        self.n_charged = 0
        self._stored = store.evaluations(run_id)
        self._best_sigma: float | None = None
        self._done_in_batch = 0  # persisted, not yet appended
        self._charged_in_batch = 0
        if resumed:
            progress.note(
                f"resuming run {run_id} of {store.path}: its {len(self._stored)} stored evaluations are "
                "replayed, not simulated"
            )

    @property
    def next_index(self) -> int:
        """Index of the next evaluation to append."""
        return len(self.history)

    def stored(self, index: int, design_key: tuple[int, ...]) -> StoredEvaluation | None:
        """The stored evaluation ``index`` of a resumed run, if it is of the design now asked.

        Where the run asks another design than it did, it branches off its stored history there: the
        evaluations stored from ``index`` on are dropped and the run goes on with new ones. Its optimiser
        proposed every design from the run's own history, so it is still a run of that optimiser and seed,
        though not the one an uninterrupted run would have made. This happens when a run made on one
        processor is resumed on another, whose rounding (BLAS kernels, torch's) turns a model-based
        sampler's or a policy's choice between near-equal designs the other way; on one machine a resumed
        run replays exactly (docs/problems.md, 'Optimisers', Determinism).
        """
        stored = self._stored.get(index)
        if stored is None or stored.design_key == design_key:
            return stored
        dropped = self.store.drop_evaluations(self.run_id, index)
        self._stored = {i: s for i, s in self._stored.items() if i < index}
        self.progress.note(
            f"run {self.run_id} branches off its stored history at evaluation {index}: it asks design "
            f"{design_key}, where it asked {stored.design_key} (another processor's rounding, or an "
            f"optimiser that is not deterministic); its {dropped} later stored evaluations are dropped"
        )
        return None

    def persist(
        self,
        record: EvaluationRecord,
        design_key: tuple[int, ...],
        reward: float | None = None,
        problem: str | None = None,
    ) -> None:
        """Commit a new evaluation to the store (never a replayed one); ``problem``: its problem's store key
        where it is not the run's (a policy conditioned on the contact-wire tension: the tension's)."""
        problem, fidelity = problem or self.config.problem, self.config.fidelity
        self.store.add_evaluation(self.run_id, problem, fidelity, design_key, record, self.source, reward)
        # The batch is appended to the history when it is complete; show each evaluation as it is done.
        self._done_in_batch += 1
        self._charged_in_batch += int(record.charged)
        if record.loss != float("inf") and (self._best_sigma is None or record.loss < self._best_sigma):
            self._best_sigma = record.loss
        self._show(self.n_charged + self._charged_in_batch, len(self.history) + self._done_in_batch)
        if self.archive is not None and time.monotonic() - self._snapshot_at >= SNAPSHOT_EVERY_S:
            snapshot_run(self.store, self.run_id, self.archive)
            self._snapshot_at = time.monotonic()

    def append(self, record: EvaluationRecord) -> None:
        """Add the next evaluation of the history."""
        if record.index != self.next_index:
            raise RuntimeError(f"evaluation {record.index} appended as number {self.next_index}")
        self.history.append(record)
        self.n_charged += int(record.charged)
        # (a replayed record was not persisted: the counts of the batch only reach 0 sooner, never below)
        self._done_in_batch = max(0, self._done_in_batch - 1)
        self._charged_in_batch = max(0, self._charged_in_batch - int(record.charged))
        if record.loss != float("inf") and (self._best_sigma is None or record.loss < self._best_sigma):
            self._best_sigma = record.loss
        self._show(self.n_charged, len(self.history))

    def _show(self, n_charged: int, n_evaluations: int, force: bool = False) -> None:
        """Show the simulations spent, the evaluations and the best σ so far on the progress display."""
        best = "none feasible yet" if self._best_sigma is None else f"best sigma {self._best_sigma:.3f} N"
        self.progress.update(n_charged, f"{n_evaluations} evaluations, {best}", force)

    def keep_unfinished(self) -> None:
        """Where the run stops before it finishes (an error, Ctrl-C, SIGTERM) with an archive: write a last
        snapshot of it there, so that the archive holds what the store does (the run resumes from there on
        another checkout). Nothing for a finished run, or one with no evaluation yet."""
        if (
            self.archive is not None
            and self.store.stop_reason(self.run_id) is None
            and self.store.count_evaluations(self.run_id)
        ):
            snapshot_run(self.store, self.run_id, self.archive)

    def result(self, stop_reason: str) -> OptimizationResult:
        """Mark the run finished in the store and return its result."""
        self.store.finish_run(self.run_id, stop_reason)
        if self.archive is not None:
            archive_run(self.store, self.run_id, self.archive)
        self._show(self.n_charged, len(self.history), force=True)
        self.progress.finish(f"stopped ({stop_reason})")
        return _result(self.config, self.space, self.run_id, self.history, stop_reason)


def finished_result(store: RunStore, run_id: int, config: RunConfig, space: GridSpace) -> OptimizationResult:
    """The result of a run that finished in the store (its stop reason recorded), read back without replaying
    its optimiser: the same result its resumption would return, every stored evaluation in order.

    Raises
    ------
    StoreError
        The run has not finished, or its evaluations have gaps (a damaged store).
    """
    stop_reason = store.stop_reason(run_id)
    stored = store.evaluations(run_id)
    if stop_reason is None or list(stored) != list(range(len(stored))):
        why = "has not finished" if stop_reason is None else "has gaps in its evaluations"
        raise StoreError(f"{store.path}: run {run_id} {why}: it cannot be read back as a finished run")
    return _result(config, space, run_id, [s.record for s in stored.values()], str(stop_reason))


def _result(
    config: RunConfig, space: GridSpace, run_id: int, history: list[EvaluationRecord], stop_reason: str
) -> OptimizationResult:
    best = best_record(history)
    return OptimizationResult(
        optimizer=config.optimizer,
        problem=config.problem,
        variable_names=space.variable_names,
        budget=config.budget,
        seed=config.seed,
        speed_kmh=config.speed_kmh,
        fidelity=config.fidelity,
        best_x=None if best is None else best.x,
        best_sigma=None if best is None else best.sigma,
        feasible=best is not None,
        history=tuple(history),
        stop_reason=stop_reason,
        n_simulations=sum(int(record.charged) for record in history),
        run_id=run_id,
        best_speed_kmh=None if best is None else best.speed_kmh,
    )
