"""Element kernels: analytic derivatives against finite differences, invariances, mass."""

from __future__ import annotations

import numpy as np

from catenary_env.fem.ancf import GAUSS_W, GAUSS_XI, cable_state, mass_matrix
from catenary_env.fem.bar import bar_state


def _cables(seed: int = 0, n: int = 4) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    length = rng.uniform(0.5, 2.0, n)
    q = np.zeros((n, 8))
    for e in range(n):
        angle, stretch = rng.uniform(-0.3, 0.3), 1.0 + rng.uniform(-0.01, 0.02)
        end = length[e] * stretch * np.array([np.cos(angle), np.sin(angle)])
        q[e] = [
            0,
            0,
            stretch * np.cos(angle) + 0.05 * rng.normal(),
            stretch * np.sin(angle) + 0.05 * rng.normal(),
            end[0],
            end[1],
            stretch * np.cos(angle + 0.1),
            stretch * np.sin(angle + 0.1),
        ]
    return q, length


def test_cable_tangent_matches_finite_differences():
    q, length = _cables()
    ea, ei = np.full(len(length), 1.8e7), np.full(len(length), 195.0)
    state = cable_state(q, length, ea, ei, tangent=True, dlength=True)
    h = 1e-7
    fd = np.zeros_like(state.stiffness)
    for k in range(8):
        dq = np.zeros(8)
        dq[k] = h
        fd[:, :, k] = (
            cable_state(q + dq, length, ea, ei, False).force
            - cable_state(q - dq, length, ea, ei, False).force
        ) / (2 * h)
    assert np.max(np.abs(fd - state.stiffness)) < 1e-7 * np.max(np.abs(state.stiffness))
    fd_len = (
        cable_state(q, length + h, ea, ei, False).force - cable_state(q, length - h, ea, ei, False).force
    ) / (2 * h)
    assert np.max(np.abs(fd_len - state.force_dlength)) < 1e-7 * np.max(np.abs(fd_len))


def _direct_force(q: np.ndarray, length: np.ndarray, ea: np.ndarray, ei: np.ndarray) -> np.ndarray:
    """dU/dq of each element, U integrated point by point from the Hermite polynomials themselves.

    Slow and plain on purpose: the reference for the vectorised kernel. U is analytic in q, so a
    complex step differentiates it exactly (no subtraction, no step-size error).
    """
    poly = np.polynomial.polynomial
    # H1, H2, H3, H4 as coefficients of (1, ξ, ξ², ξ³); the gradient ones carry a factor L.
    hermite = [[1, 0, -3, 2], [0, 1, -2, 1], [0, 0, 3, -2], [0, 0, -1, 1]]

    def energy(r: np.ndarray, L: float, ea: float, ei: float) -> complex:
        total = 0.0
        for xi, w in zip(GAUSS_XI, GAUSS_W, strict=True):
            factor = np.array([1.0, L, 1.0, L])
            d1 = factor * [poly.polyval(xi, poly.polyder(h)) for h in hermite] / L
            d2 = factor * [poly.polyval(xi, poly.polyder(h, 2)) for h in hermite] / L**2
            rs, rss = d1 @ r, d2 @ r
            strain = np.sqrt(rs @ rs) - 1.0  # no abs: analytic for the complex step
            curvature = rs[0] * rss[1] - rs[1] * rss[0]
            total += w * L * (0.5 * ea * strain**2 + 0.5 * ei * curvature**2)
        return total

    h = 1e-30
    force = np.zeros_like(q)
    for e in range(q.shape[0]):
        for k in range(8):
            dq = np.zeros(8, dtype=complex)
            dq[k] = 1j * h
            force[e, k] = energy((q[e] + dq).reshape(4, 2), length[e], ea[e], ei[e]).imag / h
    return force


def test_cable_force_and_length_derivative_match_a_direct_integration_of_the_energy():
    q, length = _cables(3)
    ea, ei = np.full(len(length), 1.8e7), np.full(len(length), 195.0)
    state = cable_state(q, length, ea, ei, tangent=True, dlength=True)
    force = _direct_force(q, length, ea, ei)
    assert np.max(np.abs(state.force - force)) < 1e-12 * np.max(np.abs(force))
    h = 1e-6
    dlength = (_direct_force(q, length + h, ea, ei) - _direct_force(q, length - h, ea, ei)) / (2 * h)
    assert np.max(np.abs(state.force_dlength - dlength)) < 1e-8 * np.max(np.abs(dlength))
    # The tangent is a Hessian: symmetric.
    assert np.max(np.abs(state.stiffness - state.stiffness.transpose(0, 2, 1))) < 1e-12 * np.max(
        np.abs(state.stiffness)
    )


def test_cable_forces_vanish_for_rigid_translation_and_unstretched_straight_state():
    q, length = _cables(1)
    ea, ei = np.full(len(length), 1.8e7), np.full(len(length), 195.0)
    f = cable_state(q, length, ea, ei, False).force.reshape(-1, 4, 2)
    # Internal forces are self-equilibrated: position forces sum to zero per element.
    assert np.allclose(f[:, [0, 2]].sum(axis=1), 0.0, atol=1e-6)
    straight = np.array([[0, 0, 1, 0, 2.0, 0, 1, 0]])
    assert np.allclose(cable_state(straight, np.array([2.0]), ea[:1], ei[:1], False).force, 0.0, atol=1e-6)


def test_cable_mass_matrix_carries_the_element_mass():
    length, rho = np.array([1.7]), np.array([1.35])
    m = mass_matrix(length, rho)[0]
    for axis in (0, 1):
        e = np.zeros(8)
        e[[axis, 4 + axis]] = 1.0
        assert np.isclose(e @ m @ e, rho[0] * length[0])


def test_bar_tangent_and_length_derivative_match_finite_differences():
    rng = np.random.default_rng(2)
    q = rng.normal(size=(3, 4))
    reference = np.linalg.norm(q[:, 2:] - q[:, :2], axis=1) * 0.99
    stiffness = np.array([1e5, np.nan, np.nan])
    ea = np.array([np.nan, 2e5, 3.5e6])
    state = bar_state(q, reference, stiffness, ea)
    h = 1e-7
    for k in range(4):
        dq = np.zeros(4)
        dq[k] = h
        fd = (
            bar_state(q + dq, reference, stiffness, ea).force
            - bar_state(q - dq, reference, stiffness, ea).force
        ) / (2 * h)
        assert np.allclose(fd, state.stiffness[:, :, k], rtol=1e-6, atol=1e-3)
    fd_len = (
        bar_state(q, reference + h, stiffness, ea).force - bar_state(q, reference - h, stiffness, ea).force
    ) / (2 * h)
    assert np.allclose(fd_len, state.force_dlength, rtol=1e-6, atol=1e-3)
