"""Parallel evaluation: local processes and a Dask LocalCluster give the results of in-process evaluation,
also when a Dask worker dies in the middle of a run."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from conftest import requires

from optimizers import optimize
from optimizers.evaluation import DaskBackend, InProcessBackend, ProcessPoolBackend
from optimizers.store import RunStore
from optimizers.synthetic import get_synthetic_problem

PROBLEM = get_synthetic_problem("synthetic-quadratic")
BATCH = [((0.001 * i, -0.002 * i, 0.02 - 0.003 * i), 300.0, "test") for i in range(12)]


def _comparable(history):
    return [dataclasses.replace(record, wall_time=0.0) for record in history]


def _outcomes(backend):
    with backend:
        return {
            position: outcome._replace(wall_time=0.0)
            for position, outcome in backend.run(PROBLEM.simulate, BATCH)
        }


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None
    ) as local_cluster:
        yield local_cluster


def test_backends_evaluate_a_batch_identically(cluster):
    reference = _outcomes(InProcessBackend())
    assert sorted(reference) == list(range(len(BATCH)))
    assert _outcomes(ProcessPoolBackend(2)) == reference
    assert _outcomes(DaskBackend(cluster.scheduler_address)) == reference


@pytest.mark.parametrize("optimizer", ["ga", pytest.param("de", marks=requires("nevergrad"))])
def test_runs_are_identical_on_every_backend(cluster, optimizer):
    local = optimize(PROBLEM, optimizer, budget=120, seed=2, n_workers=1)
    processes = optimize(PROBLEM, optimizer, budget=120, seed=2, n_workers=2)
    dask = optimize(PROBLEM, optimizer, budget=120, seed=2, scheduler=cluster.scheduler_address)
    assert _comparable(processes.history) == _comparable(local.history)
    assert _comparable(dask.history) == _comparable(local.history)
    assert dask.best_x == local.best_x and dask.n_simulations == 120


def _children(pid: int) -> set[int]:
    """Process ids whose parent is ``pid`` (Linux /proc)."""
    children = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):  # the process ended while we looked
            continue
        if int(fields[1]) == pid:
            children.add(int(stat.parent.name))
    return children


def _alive(pids: set[int]) -> set[int]:
    alive = set()
    for pid in pids:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        if state != "Z":  # a zombie has exited (it waits for init to reap it)
            alive.add(pid)
    return alive


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the process table in /proc")
@pytest.mark.parametrize("kill", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_a_killed_run_leaves_no_worker_alive(tmp_path, kill):
    command = [
        sys.executable, "-m", "catenary_env.cli", "optimize", "synthetic-quadratic-slow",
        "--budget", "100000", "--workers", "2", "--fidelity", "test",
        "--store", str(tmp_path / "runs.sqlite"), "--quiet",
    ]  # fmt: skip
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60.0
    while len(_children(process.pid)) < 3 and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)  # the 2 workers and multiprocessing's resource tracker
    time.sleep(1.0)  # the workers are simulating
    workers = _children(process.pid)
    assert len(workers) >= 2, "the run did not start its workers"
    process.send_signal(kill)
    _, stderr = process.communicate(timeout=30.0)
    deadline = time.monotonic() + 10.0
    while _alive(workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _alive(workers)
    if kill == signal.SIGTERM:
        assert process.returncode == 128 + signal.SIGTERM
        assert "terminated (SIGTERM)" in stderr and "--resume" in stderr
        assert "Traceback" not in stderr


def _kill_a_busy_worker(scheduler: str, store: Path, after: int, killed: list[tuple[int, int]]) -> None:
    """Once ``after`` evaluations are in the store, SIGKILL a Dask worker process that is simulating;
    record (its pid, the evaluations stored by then) in ``killed``."""
    import sqlite3

    from distributed import Client

    with Client(scheduler, timeout=30) as client:
        pids = client.run(os.getpid)
        for _ in range(6000):  # up to a minute
            time.sleep(0.01)
            try:
                with contextlib.closing(sqlite3.connect(store, timeout=1.0)) as connection:
                    done = connection.execute("SELECT count(*) FROM evaluations").fetchone()[0]
            except sqlite3.Error:  # the run has not made its tables yet
                continue
            busy = [address for address, tasks in client.processing().items() if tasks]
            if done >= after and busy:
                os.kill(pids[busy[0]], signal.SIGKILL)
                killed.append((pids[busy[0]], done))
                return


def test_a_run_survives_a_dask_worker_killed_mid_run(tmp_path):
    """A worker killed while it simulates: its lost evaluations run again elsewhere, the run finishes,
    nothing is lost or charged twice, and the history is the undisturbed run's."""
    distributed = pytest.importorskip("distributed")
    problem = dataclasses.replace(get_synthetic_problem("synthetic-quadratic-slow"), delay=0.05)
    budget, store = 60, tmp_path / "runs.sqlite"
    undisturbed = optimize(dataclasses.replace(problem, delay=0.0), "ga", budget=budget, seed=3)
    with distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None
    ) as cluster:
        killed: list[tuple[int, int]] = []
        killer = threading.Thread(
            target=_kill_a_busy_worker, args=(cluster.scheduler_address, store, budget // 3, killed)
        )
        killer.start()
        try:
            result = optimize(
                problem, "ga", budget=budget, seed=3, scheduler=cluster.scheduler_address, store=store
            )
        finally:
            killer.join()
        computed = [
            entry.key
            for entry in cluster.scheduler.transition_log
            if str(entry.key).startswith("simulate_quadratic") and entry.finish == "memory"
        ]
    assert killed and killed[0][1] < budget, "no worker was killed while the run was simulating"
    # Only the evaluation the killed worker was simulating ran twice: the results already received are not
    # computed again (the cluster had forgotten them).
    assert budget <= len(computed) <= budget + 1
    assert _comparable(result.history) == _comparable(undisturbed.history)
    assert result.n_simulations == budget
    with RunStore(store) as run_store:
        (run,) = run_store.run_progress()
        assert run["evaluations"] == len(undisturbed.history) and run["simulations"] == budget
