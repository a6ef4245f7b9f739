"""Assembly of element vectors and matrices into global ones (scipy sparse), for a :class:`Layout`.

The section's internal forces, tangent stiffness, length derivatives, gravity and mass are
assembled here from the cable (ANCF) and bar kernels; shape-finding, static analysis and the
linearised dynamics all build on these few functions.

Forces are summed into a global vector at once. Matrices are returned as element blocks, in the
order of :func:`matrix_coordinates` (cables, then bars); a :class:`SparseScatter` sums them into
a sparse matrix. Their pattern is fixed by the layout, so a Newton loop plans that summation once,
restricted to its own unknowns, and each iteration is then one weighted bincount.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple, TypeVar

import numpy as np
import scipy.sparse as sp

from ..model.design import GRAVITY
from .ancf import cable_state, gravity_load, mass_matrix
from .bar import bar_mass_matrix, bar_state
from .layout import DROPPER, Layout


class SparseScatter:
    """A fixed sparsity pattern: sums values given at COO coordinates into a CSR or CSC matrix.

    Sorting the coordinates and merging duplicates is done once, here; each call is one weighted
    bincount, several times faster than scipy's COO conversion of the same entries.

    Parameters
    ----------
    rows, cols : ndarray of int, shape (m,)
        Coordinates of the values each call will receive; an entry with a negative row or column is
        left out (a coordinate that is not an unknown of the system).
    shape : tuple of int
    format : "csr" or "csc"
    """

    def __init__(
        self, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int], format: str = "csr"
    ) -> None:
        rows = np.asarray(rows, dtype=np.int64).ravel()
        cols = np.asarray(cols, dtype=np.int64).ravel()
        major, minor = (rows, cols) if format == "csr" else (cols, rows)
        n_major, n_minor = shape if format == "csr" else shape[::-1]
        kept = np.flatnonzero((rows >= 0) & (cols >= 0))
        key = major[kept] * n_minor + minor[kept]
        # Timsort (stable) is the faster here: the coordinates come in sorted runs, element by element.
        order = np.argsort(key, kind="stable")
        sorted_key = key[order]
        first = np.r_[True, sorted_key[1:] != sorted_key[:-1]]
        unique = sorted_key[first]
        # Where each value goes in the matrix's data; left-out values go to one more slot, dropped
        # after summing.
        slot = np.full(rows.size, unique.size, dtype=np.int64)
        slot[kept[order]] = np.cumsum(first) - 1
        self.shape = shape
        self.format = format
        self.nnz = unique.size
        self._slot = slot
        self._indices = (unique % n_minor).astype(np.int32)
        self._indptr = np.r_[0, np.cumsum(np.bincount(unique // n_minor, minlength=n_major))].astype(np.int32)

    @property
    def pattern(self) -> sp.csr_matrix | sp.csc_matrix:
        """A matrix of this pattern, with zeros as values."""
        return self(np.zeros(self._slot.size))

    def __call__(self, *values: np.ndarray) -> sp.csr_matrix | sp.csc_matrix:
        """The matrix of ``values`` summed at the coordinates (arrays raveled and joined: m values)."""
        weights = np.concatenate([np.ravel(v) for v in values])
        data = np.bincount(self._slot, weights=weights, minlength=self.nnz + 1)[: self.nnz]
        kind = sp.csr_matrix if self.format == "csr" else sp.csc_matrix
        # Copies of the pattern: a caller may change a matrix's structure (eliminate_zeros) in place.
        matrix = kind((data, self._indices.copy(), self._indptr.copy()), shape=self.shape)
        matrix.has_sorted_indices = True
        return matrix


Plan = TypeVar("Plan")


class RecentPlans:
    """The last few plans made (a :class:`SparseScatter`, a solver's ordering), each under the arrays it was
    made from: a layout of the same topology, every design of a problem, takes its plan again instead of
    sorting the same coordinates anew (some 30 ms an evaluation), equal bit for bit. The arrays are
    compared entry by entry, so a plan is never taken for another topology."""

    def __init__(self, kept: int = 4) -> None:
        self.kept = kept
        self._plans: list[tuple[tuple[np.ndarray, ...], object]] = []

    def get(self, key: tuple[np.ndarray, ...], make: Callable[[], Plan]) -> Plan:
        """The plan made for arrays equal to ``key``, or ``make()``'s, kept under copies of them."""
        for made_for, plan in self._plans:
            if len(made_for) == len(key) and all(
                a.shape == b.shape and np.array_equal(a, b) for a, b in zip(made_for, key, strict=True)
            ):
                return plan  # type: ignore[return-value]
        plan = make()
        self._plans = [*self._plans[-(self.kept - 1) :], (tuple(np.array(a, copy=True) for a in key), plan)]
        return plan


_FREE_SCATTERS = RecentPlans()


def _block_coordinates(dofs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of element blocks (E, k, k) placed at global indices ``dofs`` (E, k), raveled."""
    k = dofs.shape[1]
    return np.repeat(dofs, k, axis=1).ravel(), np.tile(dofs, (1, k)).ravel()


def matrix_coordinates(layout: Layout) -> tuple[np.ndarray, np.ndarray]:
    """Global rows and columns of the entries of the cable blocks, then the bar blocks; each (m,)."""
    cable_rows, cable_cols = _block_coordinates(layout.cable_dofs())
    bar_rows, bar_cols = _block_coordinates(layout.bar_dofs())
    return np.r_[cable_rows, bar_rows], np.r_[cable_cols, bar_cols]


def free_matrix_scatter(layout: Layout, free: np.ndarray, format: str = "csr") -> SparseScatter:
    """The :class:`SparseScatter` of element blocks plus a diagonal onto the coordinates ``free``.

    Call it with the cable blocks, the bar blocks and a diagonal (n_dofs,) (springs, point masses);
    row and column k of the result are coordinate ``free[k]``. Planned once per topology
    (:class:`RecentPlans`).
    """

    def plan() -> SparseScatter:
        index = np.full(layout.n_dofs, -1)
        index[free] = np.arange(free.size)
        rows, cols = matrix_coordinates(layout)
        diagonal = np.arange(layout.n_dofs)
        rows, cols = index[np.r_[rows, diagonal]], index[np.r_[cols, diagonal]]
        return SparseScatter(rows, cols, (free.size, free.size), format)

    return _FREE_SCATTERS.get((*layout.topology(), np.asarray(free), np.array([format == "csr"])), plan)


def dlength_coordinates(layout: Layout) -> tuple[np.ndarray, np.ndarray]:
    """Global rows and length indices (cables, then bars) of the entries of the length derivatives."""
    cdofs, bdofs = layout.cable_dofs(), layout.bar_dofs()
    n_c = cdofs.shape[0]
    rows = np.r_[cdofs.ravel(), bdofs.ravel()]
    cols = np.r_[np.repeat(np.arange(n_c), 8), n_c + np.repeat(np.arange(bdofs.shape[0]), 4)]
    return rows, cols


def scatter_vector(dofs: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """Sum element vectors (E, k) at global indices ``dofs`` (E, k) into a vector of length n."""
    return np.bincount(dofs.ravel(), weights=values.ravel(), minlength=n)


class Assembled(NamedTuple):
    """Global internal force state, with the matrices as element blocks.

    Attributes
    ----------
    force : ndarray (n_dofs,)
        Internal nodal forces minus the external loads (gravity), N: the equilibrium residual
        before boundary terms.
    cable_stiffness, bar_stiffness : ndarray (Ec, 8, 8) and (Eb, 4, 4), or None
        Tangent d(force)/dX of each element, N/m, at :func:`matrix_coordinates`.
    cable_dlength, bar_dlength : ndarray (Ec, 8) and (Eb, 4), or None
        d(force)/d(reference length) of each element, gravity included, N/m, at
        :func:`dlength_coordinates`.
    bar_force : ndarray (Eb,)
        Axial forces of the bars, N.
    """

    force: np.ndarray
    cable_stiffness: np.ndarray | None
    bar_stiffness: np.ndarray | None
    cable_dlength: np.ndarray | None
    bar_dlength: np.ndarray | None
    bar_force: np.ndarray


def assemble(
    layout: Layout,
    X: np.ndarray,
    lengths: np.ndarray,
    tangent: bool = True,
    dlength: bool = False,
    tension_only: bool = False,
    axial_material: bool = True,
) -> Assembled:
    """Internal forces minus gravity, with optional tangent and length derivative.

    Parameters
    ----------
    X : ndarray (n_dofs,)
        Nodal coordinates, m.
    lengths : ndarray (Ec + Eb,)
        Reference lengths, m: cable elements first, then bars.
    tension_only : bool
        Droppers in compression carry nothing (slack), as in the real catenary; shape-finding uses
        False so that a compressed dropper shows as a negative force (an infeasible design).
    axial_material : bool
        False leaves the wires' axial material stiffness out of their tangent (see
        :func:`~catenary_env.fem.ancf.cable_state`).
    """
    n = layout.n_dofs
    n_c = layout.cable_nodes.shape[0]
    cdofs = layout.cable_dofs()
    bdofs = layout.bar_dofs()
    Lc, Lb = lengths[:n_c], lengths[n_c:]
    cs = cable_state(
        X[cdofs],
        Lc,
        layout.cable_axial_stiffness,
        layout.cable_bending_stiffness,
        tangent,
        dlength,
        axial_material,
    )
    bs = bar_state(X[bdofs], Lb, layout.bar_stiffness, layout.bar_axial_stiffness)
    g_c, dg_c = gravity_load(Lc, layout.cable_linear_mass * GRAVITY)
    bar_force, b_force, b_stiff, b_dlen = bs.axial_force, bs.force, bs.stiffness, bs.force_dlength
    if tension_only:
        slack = (layout.bar_kind == DROPPER) & (bar_force < 0.0)
        if np.any(slack):
            bar_force = np.where(slack, 0.0, bar_force)
            b_force = np.where(slack[:, None], 0.0, b_force)
            b_stiff = np.where(slack[:, None, None], 0.0, b_stiff)
            b_dlen = np.where(slack[:, None], 0.0, b_dlen)
    w_b = 0.5 * layout.bar_linear_mass * GRAVITY  # half a bar's weight at each end
    g_b = np.zeros((Lb.size, 4))
    g_b[:, 1] = g_b[:, 3] = -w_b * Lb
    force = scatter_vector(cdofs, cs.force - g_c, n) + scatter_vector(bdofs, b_force - g_b, n)
    z_mass = layout.node_dof[layout.mass_nodes] + 1
    force += np.bincount(z_mass, weights=layout.mass_values * GRAVITY, minlength=n)

    cable_dlength = bar_dlength = None
    if dlength:
        assert cs.force_dlength is not None
        dg_b = np.zeros((Lb.size, 4))
        dg_b[:, 1] = dg_b[:, 3] = -w_b
        cable_dlength, bar_dlength = cs.force_dlength - dg_c, b_dlen - dg_b
    return Assembled(force, cs.stiffness, b_stiff if tangent else None, cable_dlength, bar_dlength, bar_force)


def assemble_mass(layout: Layout, lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Consistent mass of wires and bars as element blocks, and the point masses, kg.

    Returns
    -------
    cable, bar : ndarray (Ec, 8, 8) and (Eb, 4, 4)
        Element mass matrices, at :func:`matrix_coordinates`.
    point : ndarray (n_dofs,)
        Point masses on the diagonal (on x and z of their node).
    """
    n_c = layout.cable_nodes.shape[0]
    cable = mass_matrix(lengths[:n_c], layout.cable_linear_mass)
    bar = bar_mass_matrix(lengths[n_c:], layout.bar_linear_mass)
    start = layout.node_dof[layout.mass_nodes]
    point = np.bincount(start, weights=layout.mass_values, minlength=layout.n_dofs)
    point += np.bincount(start + 1, weights=layout.mass_values, minlength=layout.n_dofs)
    return cable, bar, point
