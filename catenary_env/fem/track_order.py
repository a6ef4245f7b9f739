"""Direct solution of a section's sparse linear systems with equations and unknowns in track order.

Nodes are numbered along the track (:mod:`catenary_env.fem.layout`), so once the equations and the
unknowns are each sorted by their position along the track, every entry of a matrix lies near its
diagonal, and a narrow band holds them all. LAPACK's banded LU (``gbsv``, partial pivoting within the
band) then needs no ordering analysis and no fill outside the band: on the 20-span benchmark's
shape-finding Jacobian (14,000 unknowns, band 25 + 23) it takes 4.3 ms, SuperLU 8 to 12 ms in the same
order and 21 ms in its own (COLAMD; one BLAS thread, 2026-12-05).

A few couplings that reach far along the track widen the band without filling it: a stitch wire's
bars span several metres, and the stitched section's band is some 280 wide. Banded LU's work grows as
the square of the band (44 ms there), while SuperLU in the same order keeps its fill within the
profile (10 ms); they meet near a band of 60, hence :data:`MAX_BAND`.

A Newton loop solves with one sparsity pattern many times, so the solver is planned for a pattern
once: where each stored entry goes in the band (or in the permuted matrix).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.linalg import lapack
from scipy.sparse.csgraph import reverse_cuthill_mckee

from .assembly import RecentPlans

MAX_BAND = 64
"""Widest band (sub- plus super-diagonals) solved by banded LU; wider ones go to SuperLU."""


def _ranks(position: np.ndarray) -> np.ndarray:
    """Rank of each entry of ``position`` in increasing (stable) order."""
    order = np.argsort(position, kind="stable")
    rank = np.empty(order.size, dtype=np.int64)
    rank[order] = np.arange(order.size)
    return rank


class TrackOrderSolver:
    """Solves A x = b for square CSC matrices A of one sparsity pattern, in track order.

    Parameters
    ----------
    pattern : scipy.sparse.csc_matrix (n, n)
        The sparsity pattern (values unused) of every matrix to be solved.
    equation_position, unknown_position : ndarray (n,)
        Position along the track of each equation (row) and unknown (column), in any increasing
        measure: the index of a node's coordinates will do, nodes being numbered along the track.
    """

    def __init__(
        self, pattern: sp.csc_matrix, equation_position: np.ndarray, unknown_position: np.ndarray
    ) -> None:
        pattern = sp.csc_matrix(pattern)
        self._indptr, self._indices = pattern.indptr.copy(), pattern.indices.copy()
        self.n = n = pattern.shape[0]
        self._row_rank = _ranks(np.asarray(equation_position))
        self._col_rank = _ranks(np.asarray(unknown_position))
        # Row and column of each stored entry (CSC order) in the track-ordered matrix.
        i = self._row_rank[pattern.indices]
        j = self._col_rank[np.repeat(np.arange(n), np.diff(pattern.indptr))]
        self.lower = int(max(np.max(i - j, initial=0), 0))
        self.upper = int(max(np.max(j - i, initial=0), 0))
        self.banded = self.lower + self.upper <= MAX_BAND
        if self.banded:
            # gbsv's storage: entry (i, j) at row `lower + upper + i - j` of column j, with `lower`
            # spare rows on top for the fill that row interchanges bring; Fortran order, as LAPACK
            # reads it, so that it is not copied.
            self._band_shape = (2 * self.lower + self.upper + 1, n)
            self._band_index = np.ravel_multi_index(
                (self.lower + self.upper + i - j, j), self._band_shape, order="F"
            )
        else:
            self._order = np.lexsort((i, j))  # CSC order of the permuted matrix
            self._permuted_indices = i[self._order].astype(np.int32)
            self._permuted_indptr = np.r_[0, np.cumsum(np.bincount(j, minlength=n))].astype(np.int32)

    def solve(self, matrix: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray:
        """x with ``matrix @ x = rhs``, by :meth:`factorize` (and its errors)."""
        return self.factorize(matrix)(rhs)

    def factorize(self, matrix: sp.csc_matrix) -> Callable[[np.ndarray], np.ndarray]:
        """The factors of ``matrix``, as a function that solves ``matrix @ x = rhs`` for any ``rhs`` (the
        same numbers as :meth:`solve`, which factorises and solves at once).

        Raises
        ------
        ValueError
            When the matrix does not have the planned pattern.
        numpy.linalg.LinAlgError
            When the matrix is singular.
        """
        if not (
            matrix.format == "csc"
            and np.array_equal(matrix.indptr, self._indptr)
            and np.array_equal(matrix.indices, self._indices)
        ):
            raise ValueError("TrackOrderSolver.solve: the matrix does not have the planned sparsity pattern")
        if self.banded:
            flat = np.zeros(self._band_shape[0] * self.n)
            flat[self._band_index] = matrix.data
            band = flat.reshape(self._band_shape, order="F")
            # gbsv is gbtrf then gbtrs: the factors kept, the same numbers.
            lu, pivots, info = lapack.dgbtrf(band, self.lower, self.upper, overwrite_ab=True)
            if info > 0:
                raise np.linalg.LinAlgError(f"singular matrix: zero pivot in column {info}")

            def solve_permuted(b: np.ndarray) -> np.ndarray:
                y, _ = lapack.dgbtrs(lu, self.lower, self.upper, b, pivots, overwrite_b=True)
                return y

        else:
            permuted = sp.csc_matrix(
                (matrix.data[self._order], self._permuted_indices, self._permuted_indptr), shape=matrix.shape
            )
            try:
                # Panels of 2 columns: the stitched section's factorisation 8.5-9 ms instead of 11-13 (the
                # default of 10 suits wider supernodes than a narrow profile's; docs/performance.md, 'Speed').
                solve_permuted = spla.splu(permuted, permc_spec="NATURAL", panel_size=2).solve
            except RuntimeError as error:  # SuperLU: "Factor is exactly singular"
                raise np.linalg.LinAlgError(f"singular matrix: {error}") from None

        def solve(rhs: np.ndarray) -> np.ndarray:
            b = np.empty(self.n)
            b[self._row_rank] = rhs
            return solve_permuted(b)[self._col_rank]

        return solve


MAX_CHOLESKY_BAND = 32
"""Widest band (sub-diagonals) of a symmetric matrix that :func:`compliances` factorises by banded Cholesky,
in track order or renumbered; beyond it, banded Cholesky's work (growing as the square of the band) exceeds a
sparse solver's."""


_RENUMBERINGS = RecentPlans()
"""The reverse Cuthill-McKee order of the last few sparsity patterns (every design of a problem has one)."""


def _cuthill_mckee_rank(matrix: sp.csr_matrix) -> np.ndarray:
    """Position of each index in the reverse Cuthill-McKee order of a symmetric pattern."""
    order = reverse_cuthill_mckee(matrix, symmetric_mode=True)
    rank = np.empty(order.size, dtype=np.int64)
    rank[order] = np.arange(order.size)
    return rank


def compliances(matrix: sp.spmatrix, dofs: np.ndarray, loads: np.ndarray) -> np.ndarray:
    """hₚᵀ A⁻¹ hₚ for load vectors hₚ, A symmetric and banded in track order.

    hₚ holds ``loads[p]`` at the indices ``dofs[p]`` (repeated indices add up). A positive definite A of
    a narrow band (at most :data:`MAX_CHOLESKY_BAND`, in track order or renumbered) is factorised by banded
    Cholesky (LAPACK ``pbtrf``), A = L Lᵀ, and hᵀ A⁻¹ h = |L⁻¹ h|², one forward solve from the first loaded
    index on (L⁻¹ h is zero before it): on the presets' sections a quarter of the time of SuperLU's
    factorisation and a solve with every load (docs/performance.md, 'Speed'), which any other A takes. The
    same numbers either way, to rounding.

    Parameters
    ----------
    matrix : scipy.sparse matrix (n, n)
        A; its lower triangle is read.
    dofs : ndarray of int (P, k)
    loads : ndarray (P, k)

    Returns
    -------
    ndarray (P,)
    """
    csr = sp.csr_matrix(matrix)
    coo = csr.tocoo()
    n = coo.shape[0]
    points = np.broadcast_to(np.arange(dofs.shape[0])[:, None], dofs.shape)
    row, col, at = coo.row, coo.col, dofs
    if np.max(np.abs(row - col), initial=0) > MAX_CHOLESKY_BAND:
        # Stitch wires reach far along the track: renumber by reverse Cuthill-McKee (once per pattern), which
        # keeps the section's order along the track but narrows the band (some 70 to 20).
        rank = _RENUMBERINGS.get((csr.indptr, csr.indices), lambda: _cuthill_mckee_rank(csr))
        row, col, at = rank[row], rank[col], rank[dofs]
    lower = row >= col
    row, col = row[lower], col[lower]
    band = int(np.max(row - col, initial=0))
    if band <= MAX_CHOLESKY_BAND:
        # LAPACK's lower band storage of A: entry (i, j), i >= j, at row i - j of column j.
        ab = np.zeros((band + 1, n), order="F")
        ab[row - col, col] = coo.data[lower]
        factor, info = lapack.dpbtrf(ab, lower=1, overwrite_ab=1)
        if info == 0:
            first = int(np.min(at))
            rhs = np.zeros((n - first, dofs.shape[0]))
            np.add.at(rhs, (at - first, points), loads)
            z, _ = lapack.dtbtrs(factor[:, first:], rhs, uplo="L")
            return np.einsum("ip,ip->p", z, z)
    rhs = np.zeros((n, dofs.shape[0]))
    np.add.at(rhs, (dofs, points), loads)
    response = spla.splu(csr.tocsc()).solve(rhs)
    return np.einsum("ip,ip->p", rhs, response)
