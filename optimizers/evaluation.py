"""Parallel evaluation of a batch of designs: in-process, local worker processes, or a Dask cluster.

A backend takes one picklable ``simulate`` function and a batch of argument tuples and yields
``(position, outcome)`` pairs as the simulations complete, so that the caller can store each result at
once. The batch is what the optimiser asked for (a GA generation, a nevergrad batch); which backend runs
it does not change the results, because each simulation is deterministic and the caller puts the
outcomes back in the batch's order before telling the optimiser.

- :class:`InProcessBackend`: one after the other in this process (``n_workers=1``).
- :class:`ProcessPoolBackend`: ``n_workers`` local processes (``concurrent.futures``, spawned, so that
  nothing of the parent's threads is inherited). The workers die with the run: stopped at once when it
  ends by an error, Ctrl-C or SIGTERM, and gone within a second or two after a SIGKILL of the run
  (:func:`die_with_parent`).
- :class:`DaskBackend`: a Dask distributed cluster at a scheduler address (``pip install
  catenary-env[parallel]``).

Examples
--------
>>> from optimizers.synthetic import get_synthetic_problem
>>> problem = get_synthetic_problem("synthetic-quadratic")
>>> with make_backend(n_workers=1) as backend:
...     results = dict(backend.run(problem.simulate, [((0.0, 0.0, 0.0), 300.0, "test")]))
>>> round(results[0].sigma, 2)
21.75
"""

from __future__ import annotations

import concurrent.futures
import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from types import TracebackType
from typing import Any, Protocol

from catenary_env.blas_threads import limit_process
from catenary_env.errors import CatenaryError, MissingDependency, UsageError

from .problem import Outcome, SimulateFunction

__all__ = [
    "DaskBackend",
    "EvaluationBackend",
    "InProcessBackend",
    "ProcessPoolBackend",
    "SimulationArguments",
    "die_with_parent",
    "start_worker",
    "make_backend",
]

SimulationArguments = tuple[tuple[float, ...], float, str]
"""``(x, speed_kmh, fidelity)``: the arguments of one call of a problem's ``simulate``."""


class SchedulerUnreachable(CatenaryError, ConnectionError):
    """The Dask scheduler the user named (``--scheduler``) did not answer; the message gives the address."""


class EvaluationBackend(Protocol):
    """Runs batches of simulations; a context manager that releases its workers on exit."""

    description: str

    def run(
        self, simulate: SimulateFunction, batch: Sequence[SimulationArguments]
    ) -> Iterator[tuple[int, Outcome]]:
        """Yield ``(position in batch, outcome)`` as each simulation completes."""
        ...

    def close(self) -> None: ...

    def __enter__(self) -> EvaluationBackend: ...

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None: ...


class _Closing:
    """Context-manager plumbing shared by the backends."""

    def close(self) -> None:
        """Release the workers."""

    def __enter__(self) -> Any:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()


class InProcessBackend(_Closing):
    """Simulate one design after the other in this process."""

    description = "in-process"

    def run(
        self, simulate: SimulateFunction, batch: Sequence[SimulationArguments]
    ) -> Iterator[tuple[int, Outcome]]:
        for position, arguments in enumerate(batch):
            yield position, simulate(*arguments)


_PR_SET_PDEATHSIG = 1
"""``prctl`` option of Linux (``<linux/prctl.h>``): the signal a process gets when its parent dies."""

SCHEDULER_TIMEOUT = 10.0
"""Seconds to wait for a Dask scheduler to answer before giving up."""

PARENT_POLL_INTERVAL = 1.0
"""Seconds between two checks of a worker that the run which started it is still alive."""


def die_with_parent(parent_pid: int) -> None:
    """Make this worker process exit when the process ``parent_pid`` that started it dies.

    The initializer of the local workers. A SIGKILLed run cannot stop its workers, and they would live on
    under init (each holding a model in memory) until their queue breaks. On Linux the kernel sends them
    SIGKILL when the run dies (``prctl(PR_SET_PDEATHSIG)``); everywhere, and in case the run died before
    that call, a daemon thread checks every :data:`PARENT_POLL_INTERVAL` that the parent is still the run.

    Parameters
    ----------
    parent_pid : int
        Process id of the run (``os.getpid()`` in the process that starts the pool).
    """
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # no libc symbol: the thread below still does the job
            pass
    threading.Thread(target=_exit_when_orphaned, args=(parent_pid,), daemon=True).start()


def start_worker(parent_pid: int) -> None:
    """The initializer of the local workers: one BLAS thread (docs/performance.md, 'Threads': two workers
    on two cores with numpy's default of a thread per core take twice as long a design) and
    :func:`die_with_parent`."""
    limit_process()
    die_with_parent(parent_pid)


def _exit_when_orphaned(parent_pid: int) -> None:
    while os.getppid() == parent_pid:
        time.sleep(PARENT_POLL_INTERVAL)
    os._exit(1)  # no clean-up: the run that would read this worker's results is gone


class ProcessPoolBackend(_Closing):
    """Simulate on ``n_workers`` local worker processes.

    Parameters
    ----------
    n_workers : int
        Worker processes, >= 1. They are started once and kept for the whole run, so that each one's
        per-process caches (presets, the pantograph's uplift calibration) are filled only once.
    """

    def __init__(self, n_workers: int) -> None:
        if n_workers < 1:
            raise UsageError(f"n_workers = {n_workers}: must be at least 1")
        self.description = f"{n_workers} local processes"
        context = multiprocessing.get_context("spawn")
        self._pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=n_workers, mp_context=context, initializer=start_worker, initargs=(os.getpid(),)
        )

    def run(
        self, simulate: SimulateFunction, batch: Sequence[SimulationArguments]
    ) -> Iterator[tuple[int, Outcome]]:
        futures = {
            self._pool.submit(simulate, *arguments): position for position, arguments in enumerate(batch)
        }
        try:
            for future in concurrent.futures.as_completed(futures):
                yield futures[future], future.result()
        finally:
            for future in futures:
                future.cancel()

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        if kind is None:
            self.close()
            return
        # On an error, Ctrl-C or SIGTERM, stop the simulations in flight: their results are lost anyway,
        # and a worker left running would keep the interpreter's exit waiting for it. (``_processes`` is
        # private; Python 3.14's ``terminate_workers`` does the same.)
        workers = list((self._pool._processes or {}).values())
        self._pool.shutdown(wait=False, cancel_futures=True)
        for worker in workers:
            worker.terminate()
        for worker in workers:
            worker.join(timeout=5.0)


class DaskBackend(_Closing):
    """Simulate on a Dask distributed cluster.

    Parameters
    ----------
    scheduler : str
        The scheduler's address, e.g. ``"tcp://10.0.0.5:8786"``. The workers must be able to import
        ``optimizers`` and ``catenary_env`` (install the package on them).
    """

    def __init__(self, scheduler: str) -> None:
        try:
            from distributed import Client
        except ImportError as error:
            raise MissingDependency(
                "--scheduler needs Dask distributed: pip install catenary-env[parallel]"
            ) from error
        self.description = f"Dask cluster at {scheduler}"
        try:
            self._client = Client(scheduler, timeout=SCHEDULER_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as error:
            raise SchedulerUnreachable(
                f"--scheduler {scheduler}: no Dask scheduler answered within {SCHEDULER_TIMEOUT:g} s "
                f"({type(error).__name__}: {error}); check the address, or start one with: dask scheduler"
            ) from error

    def run(
        self, simulate: SimulateFunction, batch: Sequence[SimulationArguments]
    ) -> Iterator[tuple[int, Outcome]]:
        from distributed import as_completed

        # pure=False: never let Dask merge calls by their arguments; the run store is the cache.
        futures = [self._client.submit(simulate, *arguments, pure=False) for arguments in batch]
        positions = {future.key: position for position, future in enumerate(futures)}
        try:
            for future in as_completed(futures):
                outcome = Outcome(*future.result())
                # The result is here: the cluster may forget it. A worker that dies later (its evaluations
                # in flight run again on another) then leaves no finished evaluation to compute again.
                futures.remove(future)
                future.release()
                yield positions[future.key], outcome
        finally:
            self._client.cancel(futures)

    def close(self) -> None:
        self._client.close()


def make_backend(n_workers: int = 1, scheduler: str | None = None) -> EvaluationBackend:
    """The backend for the options: a Dask cluster if ``scheduler`` is given, else local processes.

    Parameters
    ----------
    n_workers : int
        Local worker processes; 1 simulates in this process. Ignored with ``scheduler``.
    scheduler : str, optional
        Dask scheduler address, ``tcp://HOST:PORT``.
    """
    if scheduler:
        return DaskBackend(scheduler)
    if n_workers == 1:
        return InProcessBackend()
    return ProcessPoolBackend(n_workers)
