"""The exact model's compiled loop (catenary_env.dynamics.exact.kernels) against its numpy loop
(docs/performance.md, 'Benchmark').

The two backends run the same method with the same arithmetic up to the order of sums, so they
must agree to rounding: the contact force to 1e-8 N, through contact losses and slack droppers.
numba compiles each kernel once per band width (some ten seconds) and caches it on disk.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from conftest import assert_recorded

from catenary_env.dynamics import exact
from catenary_env.dynamics.exact import kernel_preparation as preparation
from catenary_env.dynamics.exact import passage
from catenary_env.dynamics.linear_system import linearise
from catenary_env.dynamics.protocol import Passage
from catenary_env.fem.layout import build_layout
from catenary_env.model.design import level_design
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.pipeline import Fidelity
from catenary_env.statics.shape_finding import find_shape


@pytest.fixture(scope="module")
def kernels():
    return pytest.importorskip(
        "catenary_env.dynamics.exact.kernels", reason="the compiled backend needs numba"
    )


def prepare(system, time_step):
    return exact.prepare(system, Fidelity(time_step=time_step))


def simulate(prepared, pantograph, uplift, speed, n_steps=None, **options):
    """The exact passage of one pantograph, frame force ``uplift`` (N)."""
    return exact.run(prepared, Passage.one_pantograph(pantograph, uplift, speed, n_steps=n_steps, **options))


def _system(preset: str):
    catenary = load_catenary(preset)
    system = linearise(find_shape(build_layout(catenary, level_design(catenary), 3, 2.0, 4.0)))
    return system, load_pantograph(catenary.pantograph)


@pytest.fixture(scope="module")
def en50318():
    return _system("en50318-2002")


def _assert_same(fast, numpy_loop):
    assert fast.slack_steps == numpy_loop.slack_steps
    assert fast.unresolved_steps == numpy_loop.unresolved_steps == 0
    np.testing.assert_array_equal(fast.contact_force == 0.0, numpy_loop.contact_force == 0.0)
    assert np.max(np.abs(fast.contact_force - numpy_loop.contact_force)) < 1e-8
    for name in ("head_height", "wire_uplift", "support_uplift"):
        assert np.max(np.abs(getattr(fast, name) - getattr(numpy_loop, name))) < 1e-12, name
    assert np.max(np.abs(fast.dropper_force_min - numpy_loop.dropper_force_min)) < 1e-8
    assert np.max(np.abs(fast.dropper_force_max - numpy_loop.dropper_force_max)) < 1e-8


def test_compiled_passage_equals_the_numpy_backend_with_contact_loss_and_slack_droppers(
    kernels, en50318, recorded_passages
):
    system, pantograph = en50318
    # As the oracle test: at 350 km/h and 200 N droppers go slack and the head leaves the wire.
    speed, dt, uplift, steps = 350 / 3.6, 2e-3, 200.0, 520
    prepared = prepare(system, dt)
    args = (prepared, pantograph, uplift, speed, steps)
    numpy_loop = simulate(*args, backend="numpy")
    fast = simulate(*args, backend="numba")
    assert numpy_loop.slack_steps > 50
    assert np.sum(numpy_loop.contact_force == 0.0) >= 1
    _assert_same(fast, numpy_loop)
    assert_recorded(recorded_passages, "exact_en50318_numpy", numpy_loop)
    assert_recorded(recorded_passages, "exact_en50318_numba", fast)


def test_compiled_passage_in_the_reverse_cuthill_mckee_order(kernels, recorded_passages):
    # The stitched catenary's band is narrower after reordering: the loop then works in that order.
    system, pantograph = _system("stitched")
    speed, dt, uplift, steps = 300 / 3.6, 2e-3, 200.0, 300
    prepared = prepare(system, dt)
    assert prepared.factor.perm is not None
    args = (prepared, pantograph, uplift, speed, steps)
    numpy_loop = simulate(*args, backend="numpy")
    fast = simulate(*args, backend="numba")
    assert numpy_loop.slack_steps > 0
    _assert_same(fast, numpy_loop)
    assert_recorded(recorded_passages, "exact_stitched_numpy", numpy_loop)
    assert_recorded(recorded_passages, "exact_stitched_numba", fast)


def test_progress_reports_do_not_change_the_compiled_passage(kernels, en50318):
    # With progress the loop runs in a hundred calls, each picking the state up where the last left it.
    system, pantograph = en50318
    prepared = prepare(system, 2e-3)
    args = (prepared, pantograph, 200.0, 350 / 3.6, 400)
    fractions: list[float] = []
    chunked = simulate(*args, progress=fractions.append, backend="numba")
    whole = simulate(*args, backend="numba")
    assert len(fractions) > 50 and fractions[-1] == 1.0 and np.all(np.diff(fractions) > 0)
    np.testing.assert_array_equal(chunked.contact_force, whole.contact_force)
    np.testing.assert_array_equal(chunked.support_uplift, whole.support_uplift)


def test_an_unknown_backend_is_refused(en50318):
    system, pantograph = en50318
    with pytest.raises(ValueError, match="backend"):
        simulate(prepare(system, 2e-3), pantograph, 150.0, 80.0, 10, backend="cuda")


def test_without_numba_auto_falls_back_to_numpy_and_numba_says_how_to_install(en50318, monkeypatch):
    system, pantograph = en50318
    args = (prepare(system, 2e-3), pantograph, 150.0, 80.0, 20)
    numpy_loop = simulate(*args, backend="numpy")
    monkeypatch.setattr(passage, "_compiled_kernels", lambda: None)
    np.testing.assert_array_equal(simulate(*args).contact_force, numpy_loop.contact_force)
    with pytest.raises(ImportError, match="pip install numba"):
        simulate(*args, backend="numba")


def test_banded_solve_and_mass_product_equal_scipy(kernels, en50318):
    system, _ = en50318
    prepared = prepare(system, 2e-3)
    factor = prepared.factor
    w = preparation.padded_width(factor.bandwidth)
    unit = preparation.unit_factor(factor.factor, w)
    rng = np.random.default_rng(1)
    n = system.n_dofs
    rhs = rng.standard_normal(n)
    b, sweep = np.zeros(n + w), np.zeros(n + w)
    b[:n] = rhs
    kernels.solve(*unit, b, sweep, (0,) * w)
    exact = sla.cho_solve_banded((factor.factor, False), rhs)
    assert np.max(np.abs(b[:n] - exact)) < 1e-12 * np.max(np.abs(exact))
    assert np.all(b[n:] == 0.0) and np.all(sweep[n:] == 0.0)

    x = rng.standard_normal(n)
    out = np.ones(n + w)
    kernels.symmetric_product(*preparation.upper_rows(system.mass), x, out, (0,) * w)
    exact = system.mass @ x
    assert np.max(np.abs(out[:n] - exact)) < 1e-12 * np.max(np.abs(exact))
    assert np.all(out[n:] == 0.0)


def test_rayleigh_identity_gives_the_newmark_right_hand_side(en50318):
    # The compiled loop solves K̂ u = M x + K y as u = K̂⁻¹ M (x - (c_m / c_k) y) + y / c_k.
    system, _ = en50318
    prepared = prepare(system, 2e-3)
    nm = prepared.constants
    c_k, c_m = 1.0 + system.beta * nm.a1, nm.a0 + system.alpha * nm.a1
    rng = np.random.default_rng(2)
    x, y = rng.standard_normal(system.n_dofs), 1e-3 * rng.standard_normal(system.n_dofs)
    direct = prepared.factor.solve(system.mass @ x + system.stiffness @ y)
    identity = prepared.factor.solve(system.mass @ (x - (c_m / c_k) * y)) + y / c_k
    assert np.max(np.abs(identity - direct)) < 1e-12 * np.max(np.abs(direct))


def test_unit_responses_are_the_full_solve_where_they_are_kept(kernels):
    # Ten spans, so that a mid-section element's responses fall below 1e-30 of their peak on both sides.
    catenary = load_catenary("benchmark")
    system = linearise(find_shape(build_layout(catenary, level_design(catenary), 10, 2.0, 4.0)))
    factor = prepare(system, 1e-3).factor
    w = preparation.padded_width(factor.bandwidth)
    unit_factor = preparation.unit_factor(factor.factor, w)
    n = system.n_dofs
    # The kernel works in the factor's order (reverse Cuthill-McKee where that narrows the band).
    order = np.arange(n) if factor.perm is None else factor.perm
    position = np.empty(n, dtype=int)
    position[order] = np.arange(n)
    natural = system.contact_wire.z_dofs[len(system.contact_wire.z_dofs) // 2]
    dofs = position[natural]
    unit = np.zeros((n + w, 4))
    first, last = kernels.unit_responses(unit_factor.upper, unit_factor.scale, unit, dofs, (0,) * w)
    exact = np.zeros((n, 4))
    exact[natural, np.arange(4)] = 1.0
    exact = factor.solve(exact)[order]
    assert 0 < first < dofs.min() and dofs.max() < last < n - 1
    assert np.max(np.abs(unit[:n] - exact)) < 1e-12 * np.max(np.abs(exact))
    assert np.all(unit[:first] == 0.0) and np.all(unit[last + 1 :] == 0.0)
    left_out = np.r_[exact[:first], exact[last + 1 :]]
    assert np.max(np.abs(left_out)) < 1e-25 * np.max(np.abs(exact))
