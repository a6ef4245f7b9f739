"""One BLAS thread per evaluating process (docs/performance.md, 'Threads').

numpy's and scipy's OpenBLAS start one thread per core in every process. An evaluation gains nothing from
them (its matrices are small and banded, and its time loop is compiled code without BLAS), but two
processes evaluating at once then run four BLAS threads on two cores, and each evaluation takes about
twice as long. One evaluation alone is faster on one thread too (measured: 0.43 s against 0.63 s for B1's
level design). So the pipeline's public steps run under :func:`one_blas_thread`, and the optimisers'
worker processes call :func:`limit_process` once when they start. It also makes the results independent
of the caller's thread setting: a BLAS reduction split over two threads adds in another order, and the
span modes' round-off differences reach 1e-6 N in the contact force of a passage with contact loss.

`threadpoolctl <https://github.com/joblib/threadpoolctl>`_ does the work where it is installed (the
``fast`` extra, and every extra that runs evaluations in parallel); without it both functions do nothing,
and ``OPENBLAS_NUM_THREADS=1`` in the environment has the same effect.

Examples
--------
>>> import numpy as np
>>> with one_blas_thread():
...     float(np.ones((2, 2)) @ np.ones(2) @ np.ones(2))
4.0
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

__all__ = ["limit_process", "one_blas_thread", "single_threaded"]

F = TypeVar("F", bound=Callable[..., Any])


@functools.cache
def _controller() -> Any | None:
    """threadpoolctl's view of the BLAS libraries loaded in this process (found once: 3 ms), or None."""
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:
        return None
    import numpy  # noqa: F401  (BLAS must be loaded before the controller looks for it)
    import scipy.linalg  # noqa: F401

    return ThreadpoolController()


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the block with one BLAS thread, and give the caller's setting back after it (15 µs)."""
    controller = _controller()
    if controller is None:
        yield
        return
    with controller.limit(limits=1, user_api="blas"):
        yield


def single_threaded(function: F) -> F:
    """Decorate ``function`` to run under :func:`one_blas_thread`."""

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with one_blas_thread():
            return function(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def limit_process() -> None:
    """Keep this whole process to one BLAS thread (a worker process whose only work is evaluations)."""
    controller = _controller()
    if controller is not None:
        controller.limit(limits=1, user_api="blas")
