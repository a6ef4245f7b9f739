"""Planar ANCF cable element (absolute nodal coordinates, cubic Hermite), vectorised over elements.

Each node carries its position r = (x, z) and position gradient r' = dr/ds, s the arc length of
the unstretched (reference) configuration. An element of reference length L interpolates

    r(ξ) = H1 r_i + L H2 r'_i + H3 r_j + L H4 r'_j,     ξ = s / L in [0, 1],

with the cubic Hermite functions H (Gerstmayr & Shabana 2006, Nonlinear Dyn. 45; Tur et al. 2014,
Eng. Struct. 71, who use this element to find the initial configuration of a catenary).
Strain energy U = ∫ ½ EA ε² + ½ EI κ² ds with the axial strain ε = |r_s| - 1 and the curvature
κ = r_s × r_ss; the latter drops the 1/|r_s|³ factor of the exact curvature, an error of order
ε ≈ T/EA ≈ 1e-3 on a bending term that is itself small in a tensioned wire (Berzeri & Shabana 2000,
J. Sound Vib. 235).

Element vectors are ordered q = (x_i, z_i, x'_i, z'_i, x_j, z_j, x'_j, z'_j).
"""

from __future__ import annotations

from types import ModuleType
from typing import NamedTuple

import numpy as np

# Gauss–Legendre points on [0, 1]; five points integrate the polynomial parts exactly.
_GP, _GW = np.polynomial.legendre.leggauss(5)
GAUSS_XI = 0.5 * (_GP + 1.0)
GAUSS_W = 0.5 * _GW

# Derivatives of the four nodal vectors' shape functions at the Gauss points, for the element written
# in the scaled coordinates q̃ = (r_i / L, r'_i, r_j / L, r'_j): then r_s = Σ_k A0[g, k] q̃_k and
# L r_ss = Σ_k B0[g, k] q̃_k, tables that no longer depend on the element (see cable_state).
_XI = GAUSS_XI[:, None]
_A0 = np.hstack(
    [-6 * _XI + 6 * _XI**2, 1 - 4 * _XI + 3 * _XI**2, 6 * _XI - 6 * _XI**2, -2 * _XI + 3 * _XI**2]
)
_B0 = np.hstack([-6 + 12 * _XI, -4 + 6 * _XI, 6 - 12 * _XI, -2 + 6 * _XI])
_POSITION = np.array([1.0, 0.0, 1.0, 0.0])  # 1 on the positions r_i, r_j; 0 on the gradients
_S0 = np.stack([_A0, _B0], axis=1)  # (G, 2, 4): row i = 0 gives r_s, i = 1 gives L r_ss
# Gauss-weighted tables that turn the sums over Gauss points and shape functions into one matrix
# product over all elements: _FORCE_TABLE[(g, i), k] = w_g S0[g, i, k] and
# _TANGENT_TABLE[(g, i, j), (k, m)] = w_g S0[g, i, k] S0[g, j, m].
_FORCE_TABLE = (GAUSS_W[:, None, None] * _S0).reshape(-1, 4)
_TANGENT_TABLE = (
    GAUSS_W[:, None, None, None, None] * _S0[:, :, None, :, None] * _S0[:, None, :, None, :]
).reshape(-1, 16)


class CableState(NamedTuple):
    """Internal forces of cable elements and their derivatives.

    Attributes
    ----------
    force : ndarray, shape (E, 8)
        dU/dq, the internal nodal forces (N; N·m for gradient coordinates).
    stiffness : ndarray, shape (E, 8, 8) or None
        Tangent d²U/dq², including the geometric stiffness of the tension.
    force_dlength : ndarray, shape (E, 8) or None
        d(force)/dL, the derivative with respect to the reference length.
    """

    force: np.ndarray
    stiffness: np.ndarray | None
    force_dlength: np.ndarray | None


def hermite(xi: np.ndarray, length: np.ndarray) -> np.ndarray:
    """Position shape functions (H1, L H2, H3, L H4) at ``xi``; shape (..., 4)."""
    xi = np.asarray(xi, dtype=float)
    length = np.asarray(length, dtype=float)
    return np.stack(
        [
            1 - 3 * xi**2 + 2 * xi**3,
            length * (xi - 2 * xi**2 + xi**3),
            3 * xi**2 - 2 * xi**3,
            length * (-(xi**2) + xi**3),
        ],
        axis=-1,
    )


def hermite_dxi(xi: np.ndarray, length: np.ndarray) -> np.ndarray:
    """d/dξ of :func:`hermite`; shape (..., 4)."""
    xi = np.asarray(xi, dtype=float)
    length = np.asarray(length, dtype=float)
    return np.stack(
        [
            -6 * xi + 6 * xi**2,
            length * (1 - 4 * xi + 3 * xi**2),
            6 * xi - 6 * xi**2,
            length * (-2 * xi + 3 * xi**2),
        ],
        axis=-1,
    )


def _outer(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u vᵀ at every Gauss point and element, for (G, 2, E) arrays; shape (G, 2, 2, E)."""
    return u[:, :, None] * v[:, None, :]


def _gauss_sum(table: np.ndarray, per_point: np.ndarray) -> np.ndarray:
    """Σ_a table[a, b] per_point[a, c]; shape (b, c).

    a runs over the leading axes of ``per_point`` (Gauss points and strain blocks, table.shape[0]
    entries in all), c over the rest (components and elements): one matrix product over all
    elements (BLAS) rather than a small sum per element.
    """
    return table.T @ per_point.reshape(table.shape[0], -1)


def cable_state(
    q: np.ndarray,
    length: np.ndarray,
    axial_stiffness: np.ndarray,
    bending_stiffness: np.ndarray,
    tangent: bool = True,
    dlength: bool = False,
    axial_material: bool = True,
    backend: str = "auto",
) -> CableState:
    """Internal forces, tangent stiffness and length derivative of cable elements.

    At a Gauss point the energy density W = ½ EA ε² + ½ EI κ² depends on q only through the
    generalised strains e = (r_s, r_ss) = G q, linear in q; so the force is Σ_g w_g L Gᵀ ∇W and the
    tangent Σ_g w_g L Gᵀ ∇²W G. In the scaled coordinates q̃ (see ``_A0``) G is a fixed table, and
    both sums are one matrix product over all elements. The length derivative follows from scaling
    the element by λ (positions and L by λ, gradients fixed): the axial energy grows as λ and the
    bending energy as 1/λ, so Euler's theorem for homogeneous functions gives
    L df/dL = (1 - P) f - 2 f_bending - K P q, with P = 1 on positions and 0 on gradients; it holds
    for the quadrature too, whose points do not move.

    Parameters
    ----------
    q : ndarray, shape (E, 8)
        Element nodal coordinates, m (gradients dimensionless).
    length : ndarray, shape (E,)
        Reference (unstretched) lengths, m.
    axial_stiffness, bending_stiffness : ndarray, shape (E,)
        EA (N) and EI (N·m²).
    tangent, dlength : bool
        Whether to return the stiffness and the length derivative.
    axial_material : bool
        False leaves the axial material stiffness EA t tᵀ out of the tangent, keeping the geometric
        stiffness of the axial force N (I - t tᵀ) / |r_s| and the bending terms: the tangent of a wire
        whose axial force does not change (the transverse-only linearisation, docs/model.md, 'Modelling
        choices').
    backend : str
        One of :data:`BACKENDS`: ``"numba"``, the compiled loop (:mod:`~catenary_env.fem.ancf_kernels`,
        several times faster), ``"numpy"``, the numpy code below, or ``"auto"``, numba where it is
        installed. The two agree to rounding.
    """
    if backend not in ("auto", *BACKENDS):
        raise ValueError(f"backend = {backend!r}: one of auto, {', '.join(BACKENDS)}")
    kernels = _compiled_kernels() if backend != "numpy" else None
    if kernels is None:
        if backend == "numba":
            raise ImportError("backend='numba' needs numba: pip install numba")
        return _numpy_state(q, length, axial_stiffness, bending_stiffness, tangent, dlength, axial_material)
    n_el = q.shape[0]
    force = np.empty((n_el, 8))
    stiffness = np.empty((n_el if tangent else 0, 8, 8))
    force_dlength = np.empty((n_el if dlength else 0, 8))
    kernels.cable_state_in_place(
        np.ascontiguousarray(q, dtype=float),
        np.ascontiguousarray(length, dtype=float),
        np.ascontiguousarray(_scale(length)[0]),
        np.ascontiguousarray(axial_stiffness, dtype=float),
        np.ascontiguousarray(bending_stiffness, dtype=float),
        _S0,
        _FORCE_TABLE,
        axial_material,
        force,
        stiffness,
        force_dlength,
    )
    return CableState(force, stiffness if tangent else None, force_dlength if dlength else None)


BACKENDS = ("numba", "numpy")
"""The backends of :func:`cable_state`; ``"auto"`` takes numba where it is installed."""


def _scale(length: np.ndarray) -> np.ndarray:
    """The factors of the scaled coordinates, q̃_k = scale_k q_k: 1 / L on positions, 1 on gradients, 1/m;
    shape (4, E). Both backends take them from here: numpy's power L⁻¹ differs from 1 / L in the last bit
    for some L, in a way that depends on the array's shape (its vectorised loops), and the compiled loop's
    force is the numpy code's to the bit (:mod:`~catenary_env.fem.ancf_kernels`)."""
    return length ** -_POSITION[:, None]


def _compiled_kernels() -> ModuleType | None:
    """:mod:`catenary_env.fem.ancf_kernels`, or None where numba is not installed."""
    try:
        from . import ancf_kernels
    except ImportError:
        return None
    return ancf_kernels


def _numpy_state(
    q: np.ndarray,
    length: np.ndarray,
    axial_stiffness: np.ndarray,
    bending_stiffness: np.ndarray,
    tangent: bool,
    dlength: bool,
    axial_material: bool,
) -> CableState:
    """:func:`cable_state` in numpy, vectorised over the elements (the reference of the compiled loop)."""
    # Arrays keep the element axis last, so that every elementwise operation runs over all
    # elements at once; per Gauss point vectors have shape (G, 2, E).
    n_el = q.shape[0]
    L = length
    scale = _scale(L)
    qs = q.T.reshape(4, 2, n_el) * scale[:, None, :]
    strain = (_S0.reshape(-1, 4) @ qs.reshape(4, -1)).reshape(-1, 2, 2, n_el)  # (G, r_s | L r_ss, 2, E)
    rs = strain[:, 0]
    rss = strain[:, 1] / L
    nrm = np.sqrt(rs[:, 0] ** 2 + rs[:, 1] ** 2)  # (G, E)
    eps = nrm - 1.0
    t = rs / nrm[:, None]
    kappa = rs[:, 0] * rss[:, 1] - rs[:, 1] * rss[:, 0]
    p = np.stack([rss[:, 1], -rss[:, 0]], axis=1)  # dκ/dr_s = J r_ss, J = [[0, 1], [-1, 0]]
    s = np.stack([-rs[:, 1], rs[:, 0]], axis=1)  # dκ/dr_ss = Jᵀ r_s
    ea, ei = axial_stiffness, bending_stiffness
    moment = (ei * kappa)[:, None]  # EI κ, N·m

    def nodal(d_rs: np.ndarray, d_rss: np.ndarray) -> np.ndarray:
        """Σ_g w_g L Gᵀ (d_rs, d_rss) for (G, 2, E) arrays, in the original coordinates; shape (E, 8)."""
        per_point = np.stack([d_rs * L, d_rss], axis=1)  # the L of ds = L dξ cancels the 1/L of r_ss
        f = _gauss_sum(_FORCE_TABLE, per_point).reshape(4, 2, n_el) * scale[:, None, :]
        return f.reshape(8, n_el).T.copy()

    force = nodal((ea * eps)[:, None] * t + moment * p, moment * s)

    stiffness = None
    if tangent or dlength:
        # ∇²W in blocks (r_s, L r_ss) x (r_s, L r_ss), times the L of ds: hessian[g, i, j, a, b, e].
        hessian = np.empty((GAUSS_W.size, 2, 2, 2, 2, n_el))
        axial = ea * eps / nrm  # ∂²(½ EA ε²)/∂r_s² = EA t tᵀ + EA ε / |r_s| (I - t tᵀ)
        material = ea if axial_material else 0.0
        h = _outer(t * (material - axial)[:, None], t) + _outer(p * ei, p)
        h[:, 0, 0] += axial
        h[:, 1, 1] += axial
        hessian[:, 0, 0] = h * L
        h = _outer(p * ei, s)  # plus EI κ ∂²κ/∂r_s∂r_ss = EI κ J
        h[:, 0, 1] += moment[:, 0]
        h[:, 1, 0] -= moment[:, 0]
        hessian[:, 0, 1] = h
        hessian[:, 1, 0] = h.swapaxes(1, 2)
        hessian[:, 1, 1] = _outer(s * (ei / L), s)
        k = _gauss_sum(_TANGENT_TABLE, hessian).reshape(4, 4, 2, 2, n_el)
        k *= scale[:, None, None, None, :] * scale[None, :, None, None, :]
        stiffness = np.ascontiguousarray(k.transpose(4, 0, 2, 1, 3)).reshape(n_el, 8, 8)

    force_dlength = None
    if dlength:
        assert stiffness is not None
        position = np.repeat(_POSITION, 2)
        k_pq = np.matmul(stiffness, (position * q)[..., None])[..., 0]
        force_bending = nodal(moment * p, moment * s)
        force_dlength = ((1.0 - position) * force - 2.0 * force_bending - k_pq) / L[:, None]
    return CableState(force, stiffness if tangent else None, force_dlength)


def axial_force(q: np.ndarray, length: np.ndarray, axial_stiffness: np.ndarray, xi: float) -> np.ndarray:
    """Axial force EA ε at ``xi`` of each element, N; shape (E,)."""
    n_el = q.shape[0]
    qk = q.reshape(n_el, 4, 2)
    dh = hermite_dxi(np.full(n_el, xi), length) / length[:, None]
    rs = np.einsum("ek,ekd->ed", dh, qk)
    return axial_stiffness * (np.linalg.norm(rs, axis=1) - 1.0)


def gravity_load(length: np.ndarray, linear_weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Consistent nodal gravity load of cable elements and its derivative with respect to L.

    Parameters
    ----------
    length : ndarray, shape (E,)
        Reference lengths, m.
    linear_weight : ndarray, shape (E,)
        ρ g per reference length, N/m.

    Returns
    -------
    load, dload : ndarray, shape (E, 8)
        External (downward) nodal loads, N, and their derivative with respect to L, N/m.
    """
    n_el = length.shape[0]
    w = linear_weight
    load = np.zeros((n_el, 8))
    dload = np.zeros((n_el, 8))
    # ∫ H dξ = (1/2, L/12, 1/2, -L/12) on the z components.
    load[:, 1] = -w * length / 2
    load[:, 3] = -w * length**2 / 12
    load[:, 5] = -w * length / 2
    load[:, 7] = w * length**2 / 12
    dload[:, 1] = -w / 2
    dload[:, 3] = -w * length / 6
    dload[:, 5] = -w / 2
    dload[:, 7] = w * length / 6
    return load, dload


def mass_matrix(length: np.ndarray, linear_mass: np.ndarray) -> np.ndarray:
    """Constant consistent mass matrices ρ L ∫ Hᵀ H dξ ⊗ I₂, kg; shape (E, 8, 8)."""
    L = length[:, None, None]
    base = np.array([[156, 22, 54, -13], [22, 4, 13, -3], [54, 13, 156, -22], [-13, -3, -22, 4]], dtype=float)
    powers = np.array([[0, 1, 0, 1], [1, 2, 1, 2], [0, 1, 0, 1], [1, 2, 1, 2]])
    m4 = (linear_mass[:, None, None] * L / 420.0) * base[None] * L ** powers[None]
    # m4 ⊗ I₂ written in place (np.kron multiplies every entry by the identity's, several times slower).
    mass = np.zeros((length.size, 4, 2, 4, 2))
    mass[:, :, 0, :, 0] = m4
    mass[:, :, 1, :, 1] = m4
    return mass.reshape(-1, 8, 8)
