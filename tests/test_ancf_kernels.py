"""The cable elements' compiled loop (:mod:`catenary_env.fem.ancf_kernels`) equals the numpy code to rounding.

numba compiles the loop once (some seconds) and caches it on disk.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from catenary_env.fem import ancf
from catenary_env.fem.ancf import cable_state

FLAGS = list(itertools.product([False, True], repeat=3))
"""Every (tangent, dlength, axial_material); shape-finding asks for (False, False, True) and
(True, True, True), the linearisation for (True, False, True) and (True, False, False)."""

RTOL = 1e-13
"""Of the size of what each result sums (:func:`sizes`): rounding, summed in another order, stays below 1e-15
of it."""


@pytest.fixture(scope="module")
def kernels():
    return pytest.importorskip("catenary_env.fem.ancf_kernels", reason="the compiled loop needs numba")


def random_cables(seed: int, n: int, far: float = 1e3) -> tuple[np.ndarray, ...]:
    """``n`` elements of random length, stretch, slope and curvature, some compressed, starting up to ``far``
    (m) from the origin: far, the scaled coordinates cancel in the strains as in a long section; near, the
    rounding is small enough to show every term (the bending ones too)."""
    rng = np.random.default_rng(seed)
    length = rng.uniform(0.05, 2.0, n)
    angle = rng.uniform(-0.5, 0.5, n)
    stretch = 1.0 + rng.uniform(-0.02, 0.05, n)
    start = rng.uniform(-far, far, (n, 2))
    direction = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    end = start + (length * stretch)[:, None] * direction
    bend = rng.normal(0.0, 0.1, (n, 2))
    q = np.hstack([start, stretch[:, None] * direction + bend, end, stretch[:, None] * direction - bend])
    return q, length, rng.uniform(1e7, 2e8, n), rng.uniform(10.0, 2e3, n)


@pytest.fixture(scope="module")
def shape_found(benchmark_static) -> tuple[np.ndarray, ...]:
    """The cable elements of the shape-found short benchmark section (``conftest.benchmark_static``)."""
    static = benchmark_static
    lay = static.layout
    n_c = lay.cable_nodes.shape[0]
    q = static.positions[lay.cable_dofs()]
    return q, static.lengths[:n_c], lay.cable_axial_stiffness, lay.cable_bending_stiffness


def sizes(q: np.ndarray, length: np.ndarray, ea: np.ndarray, ei: np.ndarray) -> tuple[np.ndarray, ...]:
    """The size of what the force, the stiffness and the length derivative of each element sum, where their
    rounding starts: the strain r_s = Σ A0 q̃ of scaled coordinates q̃ some 1e3 to 1e4 (positions of hundreds
    of metres over lengths of a metre or less), which EA multiplies (the force on a gradient by L too);
    the largest entry of the tangent times Σ |q̃|; the largest of K P q / L, of positions times the tangent,
    some 1e3 times the length derivative (all per element: their size varies with the length)."""
    position = np.tile([1.0, 1.0, 0.0, 0.0], 2)
    scaled = np.abs(q) * np.where(position > 0, 1.0 / length[:, None], 1.0)
    strain = (ea + ei / length**2) * scaled.sum(axis=1)
    force = strain[:, None] * np.where(position > 0, 1.0, length[:, None])
    full = np.abs(cable_state(q, length, ea, ei, True, backend="numpy").stiffness)
    stiffness = (full.max(axis=(1, 2)) * scaled.sum(axis=1))[:, None, None]
    dlength = (np.einsum("eij,ej->ei", full, position * np.abs(q)).max(axis=1) / length)[:, None]
    return force, stiffness, dlength


def assert_rounding(q: np.ndarray, length: np.ndarray, ea: np.ndarray, ei: np.ndarray) -> None:
    """The compiled loop and the numpy code agree to :data:`RTOL` of :func:`sizes`, for every flag
    combination."""
    size = sizes(q, length, ea, ei)
    for flags in FLAGS:
        reference = cable_state(q, length, ea, ei, *flags, backend="numpy")
        compiled = cable_state(q, length, ea, ei, *flags, backend="numba")
        for got, want, scale in zip(compiled, reference, size, strict=True):
            assert (got is None) == (want is None), flags
            if want is not None:
                assert got.shape == want.shape, flags
                assert np.max(np.abs(got - want) / scale) < RTOL, flags


@pytest.mark.parametrize(("seed", "far"), [(0, 1e3), (1, 1e3), (2, 1.0)])
def test_compiled_loop_equals_numpy_on_random_elements(kernels, seed, far):
    assert_rounding(*random_cables(seed, 200, far))


def test_compiled_loop_equals_numpy_in_bending_alone(kernels):
    for far in (1e3, 1.0):
        q, length, ea, ei = random_cables(3, 200, far)
        assert_rounding(q, length, np.zeros_like(ea), ei)


def test_compiled_loop_equals_numpy_on_a_shape_found_section(kernels, shape_found):
    assert_rounding(*shape_found)


def test_compiled_loop_equals_numpy_near_the_shape(kernels, shape_found):
    q, *rest = shape_found
    rng = np.random.default_rng(4)
    assert_rounding(q + rng.normal(0.0, 1e-3, q.shape), *rest)


def test_the_force_is_the_numpy_codes_to_the_bit_where_the_blas_sums_in_order(kernels, shape_found):
    """Shape-finding stops at the round-off floor of its residual, so that the force's rounding moves σ
    (:mod:`catenary_env.fem.ancf_kernels`): it is the numpy code's to the bit where the BLAS sums the
    strains' product as the compiled loop does (in order, fused multiply-adds where the processor has
    them)."""
    q, length, ea, ei = shape_found
    scale = ancf._scale(length)
    scaled = q.reshape(-1, 4, 2) * scale.T[:, :, None]
    blas = ancf._S0.reshape(-1, 4) @ scaled[:100].transpose(1, 0, 2).reshape(4, -1)
    blas = blas.reshape(-1, 2, 100, 2).transpose(2, 0, 1, 3)  # (element, g, r_s | L r_ss, x | z)
    ordered = np.array(
        [
            [kernels._strains(ancf._S0, g, row.ravel()) for g in range(ancf.GAUSS_W.size)]
            for row in scaled[:100]
        ]
    )
    if not np.array_equal(ordered.reshape(blas.shape), blas):
        pytest.skip("this BLAS sums the strains' product in another order")
    for flags in FLAGS:
        reference = cable_state(q, length, ea, ei, *flags, backend="numpy").force
        np.testing.assert_array_equal(
            cable_state(q, length, ea, ei, *flags, backend="numba").force, reference
        )


def test_compiled_loop_takes_views_and_no_elements(kernels, shape_found):
    q, length, ea, ei = shape_found
    reference = cable_state(q[::2], length[::2], ea[::2], ei[::2], True, True, backend="numpy")
    compiled = cable_state(
        np.asfortranarray(q)[::2], length[::2], ea[::2], ei[::2], True, True, backend="numba"
    )
    assert np.max(np.abs(compiled.stiffness - reference.stiffness)) < RTOL * np.max(
        np.abs(reference.stiffness)
    )
    empty = cable_state(q[:0], length[:0], ea[:0], ei[:0], True, True, backend="numba")
    assert (
        empty.force.shape == (0, 8)
        and empty.stiffness.shape == (0, 8, 8)
        and empty.force_dlength.shape == (0, 8)
    )


def test_without_numba_auto_takes_numpy_and_numba_says_how_to_install(monkeypatch):
    q, length, ea, ei = random_cables(5, 20)
    numpy_state = cable_state(q, length, ea, ei, True, True, backend="numpy")
    monkeypatch.setattr(ancf, "_compiled_kernels", lambda: None)
    for got, want in zip(cable_state(q, length, ea, ei, True, True), numpy_state, strict=True):
        np.testing.assert_array_equal(got, want)
    with pytest.raises(ImportError, match="pip install numba"):
        cable_state(q, length, ea, ei, backend="numba")


def test_an_unknown_backend_is_refused():
    q, length, ea, ei = random_cables(6, 3)
    with pytest.raises(ValueError, match="backend"):
        cable_state(q, length, ea, ei, backend="cuda")
