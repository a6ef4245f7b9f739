"""Sparse assembly and solution: the planned scatter and the track-order solver against scipy."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from catenary_env.fem.assembly import SparseScatter
from catenary_env.fem.track_order import MAX_BAND, TrackOrderSolver


@pytest.mark.parametrize("format", ["csr", "csc"])
def test_scatter_sums_duplicates_and_leaves_out_negative_coordinates_as_scipy_does(format):
    rng = np.random.default_rng(0)
    rows, cols = rng.integers(-1, 7, 200), rng.integers(-1, 5, 200)
    scatter = SparseScatter(rows, cols, (7, 5), format)
    keep = (rows >= 0) & (cols >= 0)
    for _ in range(2):  # the pattern is reused
        values = rng.normal(size=200)
        matrix = scatter(values[:120], values[120:])  # parts are joined in order
        expected = sp.coo_matrix((values[keep], (rows[keep], cols[keep])), shape=(7, 5)).toarray()
        assert matrix.format == format and matrix.has_canonical_format
        assert np.allclose(matrix.toarray(), expected, rtol=1e-14, atol=1e-14)
    assert scatter.pattern.nnz == scatter.nnz == np.count_nonzero(expected)


def _track_system(n: int, reach: int, seed: int) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray]:
    """A diagonally dominant matrix coupling unknowns at most ``reach`` apart along a track, its rows and
    columns shuffled; returns it with the track positions of its equations and unknowns."""
    rng = np.random.default_rng(seed)
    offsets = rng.integers(-reach, reach + 1, 6 * n)
    i = rng.integers(0, n, 6 * n)
    j = np.clip(i + offsets, 0, n - 1)
    banded = sp.coo_matrix((rng.normal(size=i.size), (i, j)), shape=(n, n)) + sp.diags(
        np.full(n, 10.0 * reach)
    )
    row_order, col_order = rng.permutation(n), rng.permutation(n)
    matrix = sp.csc_matrix(banded)[row_order][:, col_order]
    matrix.sort_indices()
    return matrix, row_order.astype(float), col_order.astype(float)


@pytest.mark.parametrize(("reach", "banded"), [(5, True), (MAX_BAND, False)])
def test_track_order_solver_matches_superlu(reach, banded):
    matrix, equations, unknowns = _track_system(400, reach, seed=reach)
    solver = TrackOrderSolver(matrix, equations, unknowns)
    assert solver.banded == banded
    rhs = np.random.default_rng(1).normal(size=400)
    for scale in (1.0, 2.0):  # new values, same pattern
        scaled = matrix.copy()
        scaled.data *= np.linspace(1.0, scale, scaled.nnz)
        assert np.allclose(solver.solve(scaled, rhs), spla.spsolve(scaled, rhs), rtol=1e-10, atol=1e-12)


def test_track_order_solver_refuses_a_singular_matrix_or_another_pattern():
    matrix, equations, unknowns = _track_system(50, 3, seed=2)
    solver = TrackOrderSolver(matrix, equations, unknowns)
    singular = matrix.copy()
    singular.data[singular.indptr[7] : singular.indptr[8]] = 0.0  # column 7 is zero
    with pytest.raises(np.linalg.LinAlgError):
        solver.solve(singular, np.ones(50))
    with pytest.raises(ValueError, match="pattern"):
        solver.solve(sp.csc_matrix(np.eye(50)), np.ones(50))
