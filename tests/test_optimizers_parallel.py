"""Parallel evaluation: local processes and a Dask LocalCluster give the results of in-process evaluation."""

from __future__ import annotations

import dataclasses

import pytest
from conftest import requires

from optimizers import optimize
from optimizers.evaluation import DaskBackend, InProcessBackend, ProcessPoolBackend
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
