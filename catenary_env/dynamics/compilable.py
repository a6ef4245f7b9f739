"""Functions written once for both time-loop backends (docs/performance.md, 'Benchmark').

A function marked :func:`compilable` is plain Python, loops over scalars and arrays only, that numba compiles
into the compiled loops which call it; without numba (an optional dependency) it stays plain Python. The
shared rules of a passage (:mod:`~catenary_env.dynamics.active_set`, :mod:`~catenary_env.dynamics.newmark`,
:mod:`~catenary_env.dynamics.contact_point`, :mod:`~catenary_env.dynamics.history`) are written this way, so
that both models' compiled loops run the same source.

numba's on-disk cache follows the file of each compiled loop only: after editing a compilable function, the
loops that call it keep their cached machine code until their own file changes. The numba = numpy tests
(``tests/test_kernels.py``, ``tests/test_span_modes.py``) then fail; ``find . -name '*.nbi' -delete`` clears
the cache.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

try:
    from numba.extending import register_jitable
except ImportError:  # numba is optional: the numpy loops call these functions as they are
    register_jitable = None


def compilable(**options: Any) -> Callable[[Callable], Callable]:
    """Mark a function for compilation into the numba loops that call it; ``options`` as numba's
    (``fastmath``)."""

    def mark(function: Callable) -> Callable:
        if register_jitable is None:
            return function
        return register_jitable(**options)(function) if options else register_jitable(function)

    return mark
