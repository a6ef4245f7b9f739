"""One BLAS thread per evaluation and per worker process (docs/performance.md, 'Threads')."""

from __future__ import annotations

import pytest

threadpoolctl = pytest.importorskip("threadpoolctl")

from catenary_env import pipeline  # noqa: E402
from catenary_env.blas_threads import one_blas_thread  # noqa: E402
from catenary_env.problems import PROBLEMS  # noqa: E402
from catenary_env.statics.shape_finding import ShapeFindingError  # noqa: E402
from optimizers.evaluation import ProcessPoolBackend  # noqa: E402


def blas_threads() -> set[int]:
    """The thread counts of the BLAS libraries loaded in this process."""
    return {lib["num_threads"] for lib in threadpoolctl.threadpool_info() if lib["user_api"] == "blas"}


def test_the_block_runs_on_one_thread_and_the_callers_setting_comes_back() -> None:
    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        with one_blas_thread():
            assert blas_threads() == {1}
        assert blas_threads() == {2}


def test_an_evaluation_runs_on_one_blas_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: list[set[int]] = []

    def shape_finding(*args: object) -> None:
        seen.append(blas_threads())
        raise ShapeFindingError("stopped here by the test")

    monkeypatch.setattr(pipeline, "_find_static", shape_finding)
    problem = PROBLEMS["B1"]
    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        outcome = problem.evaluate(problem.reference_x(), fidelity="test", uplift_force=150.0)
        assert blas_threads() == {2}
    assert not outcome.feasible and "stopped here by the test" in outcome.reason
    assert seen == [{1}]


def test_the_optimisers_worker_processes_keep_to_one_blas_thread() -> None:
    with ProcessPoolBackend(2) as backend:
        infos = [info for _, info in backend.run(threadpoolctl.threadpool_info, [(), ()])]
    for info in infos:
        assert {lib["num_threads"] for lib in info if lib["user_api"] == "blas"} == {1}
