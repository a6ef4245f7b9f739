"""The numpy side of the compiled exact passage: its arrays, built before the loop (docs/performance.md,
'Benchmark').

:mod:`catenary_env.dynamics._kernels` holds only compiled code; what it reads is prepared here with numpy
and scipy: the factor of K̂ in the rows and columns the sweeps read, the mass matrix's upper rows, and
the rows where each dropper's unit response is not negligible.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

WIDTH_STEP = 8  # band widths are padded to a multiple of this: fewer compiled versions
TRUNCATION = 1e-30  # relative size of a unit response's entries left out (unit_responses)


def padded_width(bandwidth: int) -> int:
    """The band width the kernels are compiled for: ``bandwidth`` rounded up to a multiple of WIDTH_STEP."""
    return -(-bandwidth // WIDTH_STEP) * WIDTH_STEP


class UnitFactor(NamedTuple):
    """K̂ = Uᵀ U = Ûᵀ D² Û with Û unit upper triangular, for the sweeps of :func:`solve`. Band width w.

    Attributes
    ----------
    upper : ndarray (n + w, w)
        Û by rows, ``upper[i, m - 1] = Û[i, i + m]`` for m = 1..w, zero outside the matrix.
    lower : ndarray (n + w, w)
        Û by columns in reverse order, ``lower[n - 1 - j, m - 1] = Û[j - m, j]``, zero outside.
    scale : ndarray (n + w,)
        D⁻² = 1 / U[i, i]², zero in the padding.
    """

    upper: np.ndarray
    lower: np.ndarray
    scale: np.ndarray


def unit_factor(ab: np.ndarray, width: int) -> UnitFactor:
    """:class:`UnitFactor` of scipy's upper band storage of U (``ab[b + i - j, j] = U[i, j]``, b <= width)."""
    b, n = ab.shape[0] - 1, ab.shape[1]
    w = width
    diagonal = ab[b]
    upper = np.zeros((n + w, w))
    lower = np.zeros((n + w, w))
    for m in range(1, b + 1):
        entries = ab[b - m, m:] / diagonal[: n - m]  # Û[i, i + m], i = 0..n-m-1
        upper[: n - m, m - 1] = entries
        lower[: n - m, m - 1] = entries[::-1]  # column j = i + m at row n - 1 - j
    scale = np.zeros(n + w)
    scale[:n] = 1.0 / diagonal**2
    return UnitFactor(upper, lower, scale)


def response_windows(responses: np.ndarray) -> np.ndarray:
    """First and last row of each column of ``responses`` above TRUNCATION times its largest entry, (k, 2)."""
    big = np.abs(responses) > TRUNCATION * np.abs(responses).max(axis=0)
    first = np.argmax(big, axis=0)
    last = responses.shape[0] - 1 - np.argmax(big[::-1], axis=0)
    return np.stack([first, last], axis=1).astype(np.int64)


def upper_rows(matrix: sp.spmatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Upper triangle of a symmetric matrix by rows, diagonal first, for :func:`symmetric_product`.

    Returns ``ptr`` (n + 1,), ``offset`` (nnz,) = column - row (uint8, or uint16 for a wide band)
    and ``values`` (nnz,): the product reads each stored entry once for both triangles.
    """
    upper = sp.triu(matrix).tocsr()
    upper.sum_duplicates()
    upper.sort_indices()
    n = upper.shape[0]
    rows = np.repeat(np.arange(n), np.diff(upper.indptr))
    offset = upper.indices - rows
    if np.any(offset[upper.indptr[:-1]] != 0) or np.any(np.diff(upper.indptr) == 0):
        raise ValueError("upper_rows: a row without its diagonal entry")
    return (
        upper.indptr.astype(np.int64),
        offset.astype(np.uint8 if offset.max() < 256 else np.uint16),
        upper.data.astype(float),
    )
