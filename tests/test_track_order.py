"""Compliances by banded Cholesky (catenary_env.fem.track_order.compliances) against SuperLU."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from catenary_env.fem.track_order import MAX_CHOLESKY_BAND, compliances


def _spd_track_matrix(n: int, reach: int, seed: int, far: int = 0) -> sp.csr_matrix:
    """A symmetric, diagonally dominant matrix coupling indices at most ``reach`` apart, plus ``far``
    couplings across a band too wide for Cholesky (a stitch wire's)."""
    rng = np.random.default_rng(seed)
    i = rng.integers(0, n, 4 * n)
    j = np.clip(i + rng.integers(1, reach + 1, i.size), 0, n - 1)
    if far:
        k = rng.integers(0, n - 2 * MAX_CHOLESKY_BAND, far)
        i, j = np.r_[i, k], np.r_[j, k + 2 * MAX_CHOLESKY_BAND]
    upper = sp.coo_matrix((rng.normal(size=i.size), (i, j)), shape=(n, n))
    return sp.csr_matrix(upper + upper.T + sp.diags(np.full(n, 20.0 * reach)))


def _by_superlu(matrix: sp.csr_matrix, dofs: np.ndarray, loads: np.ndarray) -> np.ndarray:
    points = np.broadcast_to(np.arange(dofs.shape[0])[:, None], dofs.shape)
    rhs = np.zeros((matrix.shape[0], dofs.shape[0]))
    np.add.at(rhs, (dofs, points), loads)
    response = spla.splu(matrix.tocsc()).solve(rhs)
    return np.einsum("ip,ip->p", rhs, response)


@pytest.mark.parametrize(
    ("reach", "far", "first"),
    [
        (5, 0, 200),  # in track order, loads in the middle
        (5, 0, 0),  # loads at the start
        (5, 0, 2),  # loads within a band of the start
        (5, 0, 389),  # loads within a band of the end
        (5, 0, 392),  # loads at the end
        (3, 6, 180),  # far couplings: renumbered
    ],
)
def test_compliances_match_superlu(reach, far, first):
    matrix = _spd_track_matrix(400, reach, seed=reach + first, far=far)
    rng = np.random.default_rng(first)
    dofs = first + rng.integers(0, 8, (24, 4))
    dofs[3, 1] = dofs[3, 0]  # a repeated index adds up
    loads = rng.normal(size=(24, 4))
    found = compliances(matrix, dofs, loads)
    assert np.allclose(found, _by_superlu(matrix, dofs, loads), rtol=1e-12, atol=0.0)


def test_compliances_of_a_matrix_banded_cholesky_cannot_take_are_superlu_s():
    """An indefinite matrix, and one whose band stays too wide renumbered, go to SuperLU."""
    indefinite = _spd_track_matrix(100, 3, seed=1)
    indefinite = sp.csr_matrix(indefinite - sp.diags(np.r_[np.zeros(99), 1e3]))
    wide = _spd_track_matrix(200, MAX_CHOLESKY_BAND + 8, seed=2)
    dofs = np.array([[10, 11, 12, 13], [98, 99, 98, 97]])
    loads = np.random.default_rng(3).normal(size=dofs.shape)
    for matrix in (indefinite, wide):
        h = np.zeros((matrix.shape[0], dofs.shape[0]))
        np.add.at(h, (dofs, np.arange(dofs.shape[0])[:, None]), loads)
        dense = np.einsum("ip,ip->p", h, np.linalg.solve(matrix.toarray(), h))
        assert np.allclose(compliances(matrix, dofs, loads), dense, rtol=1e-10, atol=0.0)
