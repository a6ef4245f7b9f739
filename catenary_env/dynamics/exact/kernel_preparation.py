"""The numpy side of the exact model's compiled loop: its arrays, built once per prepared design
(docs/performance.md, 'Benchmark').

:mod:`~catenary_env.dynamics.exact.kernels` holds only compiled code; what it reads is prepared here with
numpy and scipy: the factor of K̂ in the rows and columns the sweeps read, the mass matrix's upper rows, and
the rows where each dropper's unit response is not negligible, all in the factor's DOF order.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from ..active_set import Droppers
from ..linear_system import LinearSystem
from ..newmark import StepCoefficients

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


class ExactArrays(NamedTuple):
    """What the compiled loop reads of the design, in the factor's DOF order. n DOFs, band width w, D
    droppers.

    Attributes
    ----------
    upper, lower, scale :
        K̂ = Ûᵀ D² Û by rows and by columns, and D⁻² (:func:`unit_factor`).
    m_ptr, m_offset, m_values :
        Upper triangle of M by rows (:func:`upper_rows`).
    b_ptr, b_index, b_values :
        CSR of the dropper elongation matrix B (D, n).
    dropper_response_t : ndarray (D, n)
        Wᵀ, C-contiguous.
    dropper_window : ndarray (D, 2)
        First and last DOF where each W_d is above TRUNCATION of its largest entry; the rest is left out of
        u₁.
    dropper_flexibility : ndarray (D, D)
        G = B W.
    droppers : Droppers
    z_dofs : ndarray (E, 4)
        Contact-wire z DOFs of each element.
    support_z : ndarray (S,)
    coefficients : StepCoefficients
    """

    upper: np.ndarray
    lower: np.ndarray
    scale: np.ndarray
    m_ptr: np.ndarray
    m_offset: np.ndarray
    m_values: np.ndarray
    b_ptr: np.ndarray
    b_index: np.ndarray
    b_values: np.ndarray
    dropper_response_t: np.ndarray
    dropper_window: np.ndarray
    dropper_flexibility: np.ndarray
    droppers: Droppers
    z_dofs: np.ndarray
    support_z: np.ndarray
    coefficients: StepCoefficients


class CompiledArrays(NamedTuple):
    """:class:`ExactArrays`, the band-width tuple the kernels are compiled for (its length is w), and the
    factor's DOF order (position -> DOF)."""

    arrays: ExactArrays
    width: tuple[int, ...]
    order: np.ndarray


def compiled_arrays(
    system: LinearSystem,
    coefficients: StepCoefficients,
    droppers: Droppers,
    band_factor: np.ndarray,
    permutation: np.ndarray | None,
    dropper_response: np.ndarray,
    dropper_flexibility: np.ndarray,
) -> CompiledArrays:
    """The compiled loop's arrays in the factor's DOF order: K̂'s upper band factor in scipy's storage, in the
    order ``permutation`` (None: the DOFs' own), W = K̂⁻¹ Bᵀ (n, D) and G = B W (D, D).

    The loop works in the factor's order throughout: it reads the state only at the contact wire, the
    supports and the droppers, whose indices are mapped once here.
    """
    M, W = system.mass, dropper_response
    B = sp.csr_matrix(system.dropper_elongation)
    order = np.arange(system.n_dofs)
    if permutation is not None:
        order = permutation
        M, B, W = M[order][:, order], B[:, order], W[order]
    index = np.empty_like(order)  # DOF -> position in the factor's order
    index[order] = np.arange(order.size)
    width = padded_width(band_factor.shape[0] - 1)
    unit = unit_factor(band_factor, width)
    m_ptr, m_offset, m_values = upper_rows(M)
    B.sort_indices()
    arrays = ExactArrays(
        upper=unit.upper,
        lower=unit.lower,
        scale=unit.scale,
        m_ptr=m_ptr,
        m_offset=m_offset,
        m_values=m_values,
        b_ptr=B.indptr.astype(np.int64),
        b_index=B.indices.astype(np.int64),
        b_values=B.data.astype(float),
        dropper_response_t=np.ascontiguousarray(W.T),
        dropper_window=response_windows(W),
        dropper_flexibility=np.ascontiguousarray(dropper_flexibility, dtype=float),
        droppers=droppers,
        z_dofs=index[system.contact_wire.z_dofs].astype(np.int64),
        support_z=index[system.support_z].astype(np.int64),
        coefficients=coefficients,
    )
    return CompiledArrays(arrays, (0,) * width, order)
