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

from typing import NamedTuple

import numpy as np

# Gauss–Legendre points on [0, 1]; five points integrate the polynomial parts exactly.
_GP, _GW = np.polynomial.legendre.leggauss(5)
GAUSS_XI = 0.5 * (_GP + 1.0)
GAUSS_W = 0.5 * _GW

# Derivative coefficients of the four nodal vectors (r_i, r'_i, r_j, r'_j), split as A0 / L**pa
# for d r / ds and B0 / L**pb for d² r / ds².
_XI = GAUSS_XI[:, None]
_A0 = np.hstack(
    [-6 * _XI + 6 * _XI**2, 1 - 4 * _XI + 3 * _XI**2, 6 * _XI - 6 * _XI**2, -2 * _XI + 3 * _XI**2]
)
_PA = np.array([1.0, 0.0, 1.0, 0.0])
_B0 = np.hstack([-6 + 12 * _XI, -4 + 6 * _XI, 6 - 12 * _XI, -2 + 6 * _XI])
_PB = np.array([2.0, 1.0, 2.0, 1.0])
_J = np.array([[0.0, 1.0], [-1.0, 0.0]])


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


def cable_state(
    q: np.ndarray,
    length: np.ndarray,
    axial_stiffness: np.ndarray,
    bending_stiffness: np.ndarray,
    tangent: bool = True,
    dlength: bool = False,
) -> CableState:
    """Internal forces, tangent stiffness and length derivative of cable elements.

    Parameters
    ----------
    q : ndarray, shape (E, 8)
        Element nodal coordinates, m (gradients dimensionless).
    length : ndarray, shape (E,)
        Reference (unstretched) lengths, m.
    axial_stiffness, bending_stiffness : ndarray, shape (E,)
        EA (N) and EI (N·m²).
    """
    n_el = q.shape[0]
    qk = q.reshape(n_el, 4, 2)
    L = length[:, None, None]  # (E, 1, 1)
    a = _A0[None] / L**_PA  # (E, G, 4)
    b = _B0[None] / L**_PB
    rs = np.einsum("egk,ekd->egd", a, qk)
    rss = np.einsum("egk,ekd->egd", b, qk)
    nrm = np.sqrt(np.einsum("egd,egd->eg", rs, rs))
    eps = nrm - 1.0
    t = rs / nrm[..., None]
    kappa = rs[..., 0] * rss[..., 1] - rs[..., 1] * rss[..., 0]
    p = rss @ _J.T  # J rss
    s = rs @ _J  # J^T rs
    ea = axial_stiffness[:, None]
    ei = bending_stiffness[:, None]
    wl = GAUSS_W[None, :] * length[:, None]  # (E, G)
    v = a[..., None] * p[:, :, None, :] + b[..., None] * s[:, :, None, :]  # (E, G, 4, 2) = dκ/dq_k
    phi = (ea * eps)[..., None, None] * a[..., None] * t[:, :, None, :] + (ei * kappa)[..., None, None] * v
    force = np.einsum("eg,egkd->ekd", wl, phi).reshape(n_el, 8)

    stiffness = None
    if tangent:
        tt = t[..., :, None] * t[..., None, :]
        eye = np.eye(2)
        d_ax = ea[..., None, None] * (tt + (eps / nrm)[..., None, None] * (eye - tt))  # (E, G, 2, 2)
        k_ax = np.einsum("eg,egk,egm,egcd->ekcmd", wl, a, a, d_ax)
        k_v = np.einsum("eg,egkc,egmd->ekcmd", wl * ei, v, v)
        ab = np.einsum("egk,egm->egkm", a, b)
        geo = np.einsum("eg,egkm,cd->ekcmd", wl * ei * kappa, ab, _J) + np.einsum(
            "eg,egmk,cd->ekcmd", wl * ei * kappa, ab, _J.T
        )
        stiffness = (k_ax + k_v + geo).reshape(n_el, 8, 8)

    force_dlength = None
    if dlength:
        aL = -_PA * a / L
        bL = -_PB * b / L
        rsL = np.einsum("egk,ekd->egd", aL, qk)
        rssL = np.einsum("egk,ekd->egd", bL, qk)
        tt = t[..., :, None] * t[..., None, :]
        d_ax = ea[..., None, None] * (tt + (eps / nrm)[..., None, None] * (np.eye(2) - tt))
        d_ax_rsL = np.einsum("egcd,egd->egc", d_ax, rsL)
        dphi_ax = (ea * eps)[..., None, None] * aL[..., None] * t[:, :, None, :] + a[..., None] * d_ax_rsL[
            :, :, None, :
        ]
        kappaL = np.einsum("egd,egd->eg", rsL, p) + np.einsum("egd,egd->eg", s, rssL)
        pL = rssL @ _J.T
        sL = rsL @ _J
        vL = (
            aL[..., None] * p[:, :, None, :]
            + a[..., None] * pL[:, :, None, :]
            + bL[..., None] * s[:, :, None, :]
            + b[..., None] * sL[:, :, None, :]
        )
        dphi_b = (ei * kappaL)[..., None, None] * v + (ei * kappa)[..., None, None] * vL
        force_dlength = (
            np.einsum("g,egkd->ekd", GAUSS_W, phi) + np.einsum("eg,egkd->ekd", wl, dphi_ax + dphi_b)
        ).reshape(n_el, 8)
    return CableState(force, stiffness, force_dlength)


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
    return np.kron(m4, np.eye(2)[None])
