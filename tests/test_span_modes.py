"""The span-mode (reduced) model against the exact one (docs/performance.md, 'Model fidelities').

With every mode kept the reduction is a change of basis, so the reduced passage must equal the exact
one to rounding, slack droppers and contact loss included; with a cut-off it must approach it as the
cut-off rises.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from catenary_env.dynamics.linear_system import linearise
from catenary_env.dynamics.passage import simulate_passage
from catenary_env.dynamics.reduced_passage import prepare_reduced_passage, simulate_reduced_passage
from catenary_env.dynamics.span_modes import reduce_system, reduced_matrices
from catenary_env.model.design import DesignError, level_design
from catenary_env.pipeline import FIDELITIES, Fidelity, check_fidelity, evaluate

SPEED = 300 / 3.6
DT = 2e-3


@pytest.fixture(scope="module")
def system(benchmark_static):
    return linearise(benchmark_static)


@pytest.fixture(scope="module")
def exact(system, benchmark_pantograph_definition):
    return simulate_passage(system, benchmark_pantograph_definition, 190.0, SPEED, DT, backend="numpy")


@pytest.fixture(scope="module")
def full_basis(system):
    return prepare_reduced_passage(reduce_system(system, np.inf), DT, near_spans=1)


def test_interior_spans_share_one_eigensolution(system):
    reduced = reduce_system(system, 200.0)
    # first span, the interior ones, last span
    assert reduced.span_type.tolist() == [0, 1, 1, 1, 2]
    assert len(reduced.types) == 3


def test_reduced_matrices_are_the_projection(system):
    reduced = reduce_system(system, 150.0)
    T = reduced.rows(np.arange(system.n_dofs))
    M, K = reduced_matrices(reduced)
    assert np.abs(T.T @ system.mass @ T - M).max() < 1e-9 * abs(M).max()
    assert np.abs(T.T @ system.stiffness @ T - K).max() < 1e-9 * abs(K).max()
    # fixed-interface modes: mass-normalised, no stiffness coupling to the interface
    n_q = reduced.n_modal
    assert np.allclose(M[:n_q, :n_q].diagonal(), 1.0)
    assert abs(K[:n_q, n_q:]).max() < 1e-6 * abs(K).max()


def test_every_mode_kept_equals_the_exact_passage(full_basis, exact, benchmark_pantograph_definition):
    reduced = simulate_reduced_passage(
        full_basis, benchmark_pantograph_definition, 190.0, SPEED, backend="numpy"
    )
    assert exact.slack_steps > 50  # the case exercises slack droppers
    assert reduced.slack_steps == exact.slack_steps
    assert np.abs(reduced.contact_force - exact.contact_force).max() < 1e-5
    assert np.abs(reduced.support_uplift - exact.support_uplift).max() < 1e-9
    assert np.abs(reduced.dropper_force_min - exact.dropper_force_min).max() < 1e-5


def test_contact_loss_is_handled_as_in_the_exact_passage(system, full_basis, benchmark_pantograph_definition):
    # A weak uplift at 350 km/h: the pantograph leaves the wire.
    pantograph = benchmark_pantograph_definition
    exact = simulate_passage(system, pantograph, 60.0, 350 / 3.6, DT, backend="numpy")
    reduced = simulate_reduced_passage(full_basis, pantograph, 60.0, 350 / 3.6, backend="numpy")
    lost = exact.contact_force == 0.0
    assert lost.sum() > 10
    assert np.array_equal(reduced.contact_force == 0.0, lost)
    assert np.abs(reduced.contact_force - exact.contact_force).max() < 1e-5


def test_the_reduced_model_approaches_the_exact_one_as_the_cutoff_rises(
    system, exact, benchmark_pantograph_definition
):
    window = slice(exact.time.size // 3, 2 * exact.time.size // 3)
    errors = []
    for cutoff in (100.0, 200.0, 400.0):
        prepared = prepare_reduced_passage(reduce_system(system, cutoff), DT, near_spans=1)
        reduced = simulate_reduced_passage(
            prepared, benchmark_pantograph_definition, 190.0, SPEED, backend="numpy"
        )
        difference = reduced.contact_force[window] - exact.contact_force[window]
        errors.append(np.sqrt(np.mean(difference**2)) / np.std(exact.contact_force[window]))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.05


def test_compiled_loop_equals_the_numpy_loop(system, benchmark_pantograph_definition):
    pytest.importorskip("numba")
    prepared = prepare_reduced_passage(reduce_system(system, 300.0, 50.0), DT, near_spans=1)
    a = simulate_reduced_passage(prepared, benchmark_pantograph_definition, 190.0, SPEED, backend="numpy")
    b = simulate_reduced_passage(prepared, benchmark_pantograph_definition, 190.0, SPEED, backend="numba")
    assert np.abs(a.contact_force - b.contact_force).max() < 1e-7
    assert np.abs(a.wire_uplift - b.wire_uplift).max() < 1e-10
    assert a.slack_steps == b.slack_steps


def test_fidelities_name_both_models():
    assert FIDELITIES["study"].dynamics == "span-modes"
    assert FIDELITIES["reference"].dynamics == "exact"
    assert dataclasses.replace(FIDELITIES["study"], dynamics="exact") == FIDELITIES["reference"]


def test_bad_reduced_fidelity_is_refused(benchmark_catenary):
    with pytest.raises(DesignError, match="fidelity.dynamics"):
        check_fidelity(benchmark_catenary, Fidelity(dynamics="modal"))
    with pytest.raises(DesignError, match="fidelity.far_cutoff"):
        check_fidelity(benchmark_catenary, Fidelity(near_cutoff=100.0, far_cutoff=200.0))


def test_pipeline_runs_the_span_mode_model(benchmark_catenary, benchmark_pantograph_definition):
    fidelity = Fidelity(
        n_spans=4, analysis_spans=2, contact_wire_element=1.0, messenger_wire_element=2.0, time_step=2e-3
    )
    design = level_design(benchmark_catenary)
    study = evaluate(benchmark_catenary, benchmark_pantograph_definition, design, SPEED, fidelity, 190.0)
    exact = evaluate(
        benchmark_catenary,
        benchmark_pantograph_definition,
        design,
        SPEED,
        dataclasses.replace(fidelity, dynamics="exact"),
        190.0,
    )
    assert study.feasible == exact.feasible
    assert study.statistics.std == pytest.approx(exact.statistics.std, rel=0.02)
    assert study.statistics.mean == pytest.approx(exact.statistics.mean, rel=0.005)


def test_evaluation_stops_one_span_after_the_analysis_section_without_changing_it(
    benchmark_catenary, benchmark_pantograph_definition
):
    from catenary_env.pipeline import simulate_static, solve_static

    fidelity = Fidelity(
        n_spans=7, analysis_spans=3, contact_wire_element=1.0, messenger_wire_element=2.0, time_step=2e-3
    )
    static = solve_static(benchmark_catenary, level_design(benchmark_catenary), fidelity)
    args = (static, benchmark_pantograph_definition, SPEED, fidelity, 190.0)
    whole = simulate_static(*args)
    short = simulate_static(*args, statistics_only=True)
    assert short.trajectory.position[-1] == pytest.approx(6 * benchmark_catenary.span_length, abs=1.0)
    for name, value in whole.statistics.as_dict().items():
        assert getattr(short.statistics, name) == pytest.approx(value, rel=1e-6, abs=1e-9), name
