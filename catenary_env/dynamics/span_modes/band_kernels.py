"""Compiled triangular solves with a banded Cholesky factor and many right-hand sides, with numba.

The span types' eigensolutions (:func:`~catenary_env.dynamics.span_modes.reduction.generalised_eigh`)
solve with the mass matrix's banded Cholesky factor U (M = Uᵀ U, half-band w = 7 in the presets' spans) for
as many right-hand sides as the span has DOFs. LAPACK's ``dtbtrs`` solves them a column at a time, each a
chain of short dependent updates: 1 ms for 356 columns. Here the substitution runs by rows, each row's update
an axpy over all the right-hand sides at once, which vectorises: 0.13 ms (docs/performance.md, 'The span
types' eigensolutions through the mass matrix's band').

numba is optional: :mod:`~catenary_env.dynamics.span_modes.reduction` imports this module only where numba
is installed, and solves with ``dtbtrs`` otherwise.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, fastmath={"contract"})
def solve_upper_in_place(factor, rows, transposed):  # pragma: no cover - compiled
    """rows ← U⁻ᵀ rows (``transposed``: forward substitution, Uᵀ is lower triangular) or U⁻¹ rows (back
    substitution); rows (n, m) in C order, ``factor`` U in LAPACK's upper band storage (w + 1, n),
    U[i, j] = factor[w + i - j, j]."""
    w = factor.shape[0] - 1
    n, m = rows.shape
    for step in range(n):
        i = step if transposed else n - 1 - step
        first, stop = (max(0, i - w), i) if transposed else (i + 1, min(n, i + w + 1))
        for j in range(first, stop):
            u = factor[w + j - i, i] if transposed else factor[w + i - j, j]  # U[j, i] or U[i, j]
            for k in range(m):
                rows[i, k] -= u * rows[j, k]
        d = factor[w, i]
        for k in range(m):
            rows[i, k] /= d
