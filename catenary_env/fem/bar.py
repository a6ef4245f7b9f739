"""Planar bar elements (axial force only, linear interpolation), vectorised over elements.

Used for droppers, stitch wires and steady arms (docs/model.md, 'Elements'). A bar joins node a to node b; its
axial force is N = k (l - L), with l the current length, L the reference (unstretched) length and
k the spring rate: either a constant (EN 50318:2002 gives droppers as a stiffness) or EA / L.
Element vectors are ordered (x_a, z_a, x_b, z_b).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class BarState(NamedTuple):
    """Axial forces of bar elements and the derivatives of their nodal forces.

    Attributes
    ----------
    axial_force : ndarray, shape (E,)
        N, positive in tension.
    length : ndarray, shape (E,)
        Current length l, m.
    direction : ndarray, shape (E, 2)
        Unit vector from node a to node b.
    force : ndarray, shape (E, 4)
        Internal nodal forces dU/dq, N.
    stiffness : ndarray, shape (E, 4, 4)
        Tangent, material k n nᵀ plus geometric N / l (I - n nᵀ), N/m.
    force_dlength : ndarray, shape (E, 4)
        d(force)/dL, N/m.
    """

    axial_force: np.ndarray
    length: np.ndarray
    direction: np.ndarray
    force: np.ndarray
    stiffness: np.ndarray
    force_dlength: np.ndarray


def spring_rate(
    reference_length: np.ndarray, stiffness: np.ndarray, axial_stiffness: np.ndarray
) -> np.ndarray:
    """Spring rate k, N/m: ``stiffness`` where it is finite, else EA / L."""
    return np.where(np.isfinite(stiffness), stiffness, axial_stiffness / reference_length)


def bar_state(
    q: np.ndarray, reference_length: np.ndarray, stiffness: np.ndarray, axial_stiffness: np.ndarray
) -> BarState:
    """Forces and tangents of bars.

    Parameters
    ----------
    q : ndarray, shape (E, 4)
        Nodal positions, m.
    reference_length : ndarray, shape (E,)
        L, m.
    stiffness : ndarray, shape (E,)
        Constant spring rate, N/m, or NaN where the rate is EA / L.
    axial_stiffness : ndarray, shape (E,)
        EA, N (used where ``stiffness`` is NaN).
    """
    d = q[:, 2:] - q[:, :2]
    length = np.linalg.norm(d, axis=1)
    n = d / length[:, None]
    k = spring_rate(reference_length, stiffness, axial_stiffness)
    N = k * (length - reference_length)
    force = np.hstack([-N[:, None] * n, N[:, None] * n])
    nn = n[:, :, None] * n[:, None, :]
    block = k[:, None, None] * nn + (N / length)[:, None, None] * (np.eye(2)[None] - nn)
    stiff = np.block([[block, -block], [-block, block]])
    dN = np.where(np.isfinite(stiffness), -k, -axial_stiffness * length / reference_length**2)
    force_dlength = np.hstack([-dN[:, None] * n, dN[:, None] * n])
    return BarState(N, length, n, force, stiff, force_dlength)


def geometric_tangent(state: BarState) -> np.ndarray:
    """The geometric part (N / l)(I - n nᵀ) of the bars' tangent, N/m; shape (E, 4, 4).

    It acts across the bar; the rest of :attr:`BarState.stiffness` is the material part k n nᵀ.
    """
    n = state.direction
    block = (state.axial_force / state.length)[:, None, None] * (
        np.eye(2)[None] - n[:, :, None] * n[:, None, :]
    )
    return np.block([[block, -block], [-block, block]])


def bar_mass_matrix(reference_length: np.ndarray, linear_mass: np.ndarray) -> np.ndarray:
    """Consistent mass matrices of linear bars, ρ L / 6 [[2, 1], [1, 2]] ⊗ I₂, kg; shape (E, 4, 4)."""
    m = linear_mass * reference_length / 6.0
    base = np.kron(np.array([[2.0, 1.0], [1.0, 2.0]]), np.eye(2))
    return m[:, None, None] * base[None]
