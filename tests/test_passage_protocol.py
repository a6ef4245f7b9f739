"""The passage protocol (docs/model.md, 'Time integration and the fast method'): both dynamic models from one
table, a passage of several pantographs refused clearly where a loop cannot take it, and the numbers the time
loops gave before the protocol (tests/data/recorded_passages.npz) reproduced through it."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from conftest import assert_recorded

from catenary_env.dynamics import exact, span_modes
from catenary_env.dynamics.models import DYNAMIC_MODELS
from catenary_env.dynamics.protocol import ContactPoint, Passage
from catenary_env.dynamics.span_modes.passage import _configurations
from catenary_env.model.design import level_design
from catenary_env.pipeline import DYNAMICS, FIDELITIES, Fidelity, run_passage, solve_static

SPEED = 300 / 3.6


def test_one_table_names_the_fidelities_models():
    assert DYNAMICS == tuple(DYNAMIC_MODELS) == ("span-modes", "exact")
    assert DYNAMIC_MODELS["exact"][:2] == (exact.prepare, exact.run)
    assert DYNAMIC_MODELS["span-modes"][:2] == (span_modes.prepare, span_modes.run)
    assert {fidelity.dynamics for fidelity in FIDELITIES.values()} <= set(DYNAMIC_MODELS)


def test_the_exact_model_reproduces_the_recorded_level_design_on_the_test_fidelity(
    benchmark_catenary, benchmark_pantograph_definition, recorded_passages
):
    pytest.importorskip("numba")  # recorded with the compiled loop, which "auto" takes
    fidelity = FIDELITIES["test"]
    static = solve_static(benchmark_catenary, level_design(benchmark_catenary), fidelity)
    sim = run_passage(static, benchmark_pantograph_definition, SPEED, fidelity, 170.0)
    assert_recorded(recorded_passages, "exact_b1_test_numba", sim.trajectory, sim.statistics.std)


def test_the_span_mode_model_reproduces_the_recorded_evaluation_passage(
    benchmark_catenary, benchmark_pantograph_definition, recorded_passages
):
    pytest.importorskip("numba")
    fidelity = Fidelity(
        n_spans=4, analysis_spans=2, contact_wire_element=1.0, messenger_wire_element=2.0, time_step=2e-3
    )
    static = solve_static(benchmark_catenary, level_design(benchmark_catenary), fidelity)
    sim = run_passage(static, benchmark_pantograph_definition, SPEED, fidelity, 190.0, statistics_only=True)
    assert_recorded(recorded_passages, "span_modes_pipeline_numba", sim.trajectory, sim.statistics.std)


def test_the_oracle_refuses_a_second_pantograph_by_name(benchmark_static, benchmark_pantograph_definition):
    from catenary_env.dynamics.linear_system import linearise

    model = DYNAMIC_MODELS["exact"]
    prepared = model.prepare(
        linearise(benchmark_static), Fidelity(n_spans=5, time_step=2e-3, dynamics="exact")
    )
    first = ContactPoint(benchmark_pantograph_definition, 170.0)
    second = ContactPoint(benchmark_pantograph_definition, 170.0, offset=20.0)
    with pytest.raises(ValueError, match="passage.contact_points: 2 pantographs; this loop takes one"):
        model.run(prepared, Passage(SPEED, (first, second), n_steps=5, backend="oracle"))


def test_the_span_mode_model_refuses_two_pantographs_in_one_span(
    benchmark_static, benchmark_pantograph_definition
):
    from catenary_env.dynamics.linear_system import linearise

    model = DYNAMIC_MODELS["span-modes"]
    prepared = model.prepare(linearise(benchmark_static), Fidelity(n_spans=5, time_step=2e-3))
    first = ContactPoint(benchmark_pantograph_definition, 170.0)
    second = ContactPoint(benchmark_pantograph_definition, 170.0, offset=20.0)
    with pytest.raises(ValueError, match="pantographs 1 and 2 in one span"):
        model.run(prepared, Passage(SPEED, (first, second), n_steps=200))


def test_a_passage_names_its_wrong_field(benchmark_pantograph_definition):
    point = ContactPoint(benchmark_pantograph_definition, 170.0)
    with pytest.raises(ValueError, match="passage.speed"):
        Passage(0.0, (point,))
    with pytest.raises(ValueError, match="passage.contact_points"):
        Passage(SPEED, ())
    with pytest.raises(ValueError, match="the first pantograph's 0"):
        Passage(SPEED, (ContactPoint(benchmark_pantograph_definition, 170.0, offset=5.0),))
    with pytest.raises(ValueError, match="in order behind it"):
        Passage(SPEED, (point, ContactPoint(benchmark_pantograph_definition, 170.0, offset=-5.0)))
    with pytest.raises(ValueError, match="passage.n_steps"):
        Passage(SPEED, (point,), n_steps=0)


def test_one_pantograph_s_configurations_are_those_of_the_rows():
    """The single pantograph's shortcut gives the configurations, and each step's, that numpy's unique by
    rows gives (the general path, which a train takes)."""
    element_span = np.repeat(np.arange(7), 5)
    element = np.r_[np.full(4, -1), np.arange(35), np.arange(35)[::-1], np.full(3, -1)]
    prepared = SimpleNamespace(arrays=SimpleNamespace(element_span=element_span))
    tuples, configuration = _configurations(prepared, (SimpleNamespace(element=element),))
    spans = np.where(element >= 0, element_span[np.maximum(element, 0)], -1)
    rows, expected = np.unique(spans[:, None], axis=0, return_inverse=True)
    assert tuples == [tuple(int(s) for s in row) for row in rows]
    np.testing.assert_array_equal(configuration, expected.ravel())
