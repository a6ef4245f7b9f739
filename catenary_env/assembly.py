"""Assembly of element vectors and matrices into global ones (scipy sparse), for a :class:`Layout`.

The section's internal forces, tangent stiffness, length derivatives, gravity and mass are
assembled here from the cable (ANCF) and bar kernels; shape-finding, static analysis and the
linearised dynamics all build on these few functions.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from .ancf import cable_state, gravity_load, mass_matrix
from .bar import bar_mass_matrix, bar_state
from .design import GRAVITY
from .layout import DROPPER, Layout


class Assembled(NamedTuple):
    """Global internal force state.

    Attributes
    ----------
    force : ndarray (n_dofs,)
        Internal nodal forces minus the external loads (gravity), N: the equilibrium residual
        before boundary terms.
    stiffness : scipy.sparse.csr_matrix (n_dofs, n_dofs) or None
        Tangent d(force)/dX, N/m.
    dlength : scipy.sparse.csr_matrix (n_dofs, Ec + Eb) or None
        d(force)/d(reference lengths), cables first then bars, N/m.
    bar_force : ndarray (Eb,)
        Axial forces of the bars, N.
    """

    force: np.ndarray
    stiffness: sp.csr_matrix | None
    dlength: sp.csr_matrix | None
    bar_force: np.ndarray


def scatter_matrix(dofs: np.ndarray, blocks: np.ndarray, n: int) -> sp.csr_matrix:
    """Sum element blocks (E, k, k) at global indices ``dofs`` (E, k) into an n-by-n sparse matrix."""
    k = dofs.shape[1]
    rows = np.repeat(dofs, k, axis=1).ravel()
    cols = np.tile(dofs, (1, k)).ravel()
    return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(n, n))


def scatter_vector(dofs: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    return np.bincount(dofs.ravel(), weights=values.ravel(), minlength=n)


def assemble(
    layout: Layout,
    X: np.ndarray,
    lengths: np.ndarray,
    tangent: bool = True,
    dlength: bool = False,
    tension_only: bool = False,
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
    """
    n = layout.n_dofs
    n_c = layout.cable_nodes.shape[0]
    cdofs = layout.cable_dofs()
    bdofs = layout.bar_dofs()
    Lc, Lb = lengths[:n_c], lengths[n_c:]
    cs = cable_state(
        X[cdofs], Lc, layout.cable_axial_stiffness, layout.cable_bending_stiffness, tangent, dlength
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

    stiffness = None
    if tangent:
        assert cs.stiffness is not None
        stiffness = scatter_matrix(cdofs, cs.stiffness, n) + scatter_matrix(bdofs, b_stiff, n)
    dlen = None
    if dlength:
        assert cs.force_dlength is not None
        dg_b = np.zeros((Lb.size, 4))
        dg_b[:, 1] = dg_b[:, 3] = -w_b
        rows = np.r_[cdofs.ravel(), bdofs.ravel()]
        cols = np.r_[np.repeat(np.arange(n_c), 8), n_c + np.repeat(np.arange(Lb.size), 4)]
        vals = np.r_[(cs.force_dlength - dg_c).ravel(), (b_dlen - dg_b).ravel()]
        dlen = sp.csr_matrix((vals, (rows, cols)), shape=(n, n_c + Lb.size))
    return Assembled(force, stiffness, dlen, bar_force)


def assemble_mass(layout: Layout, lengths: np.ndarray) -> sp.csr_matrix:
    """Consistent mass of wires and bars plus the point masses (on x and z), kg."""
    n = layout.n_dofs
    n_c = layout.cable_nodes.shape[0]
    M = scatter_matrix(layout.cable_dofs(), mass_matrix(lengths[:n_c], layout.cable_linear_mass), n)
    M = M + scatter_matrix(layout.bar_dofs(), bar_mass_matrix(lengths[n_c:], layout.bar_linear_mass), n)
    start = layout.node_dof[layout.mass_nodes]
    point = np.bincount(start, weights=layout.mass_values, minlength=n)
    point += np.bincount(start + 1, weights=layout.mass_values, minlength=n)
    return (M + sp.diags(point)).tocsr()
