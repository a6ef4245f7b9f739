"""Shape-finding of equal spans from a short section's solution (docs/model.md, 'Shape-finding'): the same
equilibrium as from the parabolic start, to the tolerance both are held to."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from catenary_env.fem.layout import build_layout
from catenary_env.model.design import Design, level_design
from catenary_env.model.options import ModellingOptions
from catenary_env.statics import equal_spans
from catenary_env.statics.equal_spans import END_SPANS, find_equal_spans_shape, replicated_start
from catenary_env.statics.shape_finding import ShapeEquations, ShapeFindingError, find_shape

ELEMENTS = (1.0, 2.0)  # m: coarse elements keep a 16-span section quick
SPANS = 3 * END_SPANS + 1  # the shortest section started from a short one


def _designs(catenary) -> list[Design]:
    level = level_design(catenary)
    offsets = np.linspace(-0.04, 0.0, len(level.dropper_positions))  # a contact wire sloping in each span
    return [level, Design(level.dropper_positions, tuple(offsets))]


@pytest.mark.parametrize("name", ["benchmark_catenary", "stitched_catenary"])
def test_a_section_started_from_a_short_one_reaches_the_same_equilibrium(name, request):
    catenary = request.getfixturevalue(name)
    for design in _designs(catenary):
        layout = build_layout(catenary, design, SPANS, *ELEMENTS)
        parabolic = find_shape(layout)
        replicated = find_equal_spans_shape(layout, *ELEMENTS)
        history = np.array(replicated.residual_history)
        assert (replicated.start_spans, parabolic.start_spans) == (2 * END_SPANS + 1, 0)
        assert history[-1] < 1e-8 * replicated.load_scale
        # The start is within a Newton step of the equilibrium (its copies of the interior span were already
        # interior to some 1e-8): at most one step instead of the parabolic start's four or five.
        assert history.size <= 2 < len(parabolic.residual_history) - 1
        assert np.max(np.abs(replicated.positions - parabolic.positions)) < 1e-8  # m
        assert np.max(np.abs(replicated.lengths - parabolic.lengths)) < 1e-8  # m
        assert np.max(np.abs(replicated.bar_forces - parabolic.bar_forces)) < 1e-4  # N


def test_the_start_is_the_short_solution_span_by_span(benchmark_catenary):
    """Copied onto a section of its own length the short section's solution comes back as it is; copied onto
    a longer one, every interior span is its middle span moved along the track, and the ends are its ends."""
    design = level_design(benchmark_catenary)
    short = find_shape(build_layout(benchmark_catenary, design, 2 * END_SPANS + 1, *ELEMENTS))
    positions, lengths = replicated_start(short.layout, short)
    assert np.array_equal(positions, short.positions) and np.array_equal(lengths, short.lengths)

    section = build_layout(benchmark_catenary, design, SPANS, *ELEMENTS)
    positions, lengths = replicated_start(section, short)
    equations = ShapeEquations(section)
    residual, _ = equations.residual(equations.unknowns(positions, lengths))
    assert np.max(np.abs(residual)) < 1e-7 * short.load_scale
    L = section.span_length

    def heights(lay, X, span):  # the heights of the nodes from support ``span`` to the next support
        x = lay.node_x
        return X[lay.z_dof(np.flatnonzero((x >= span * L - 1e-6) & (x < (span + 1) * L - 1e-6)))]

    middle = heights(short.layout, short.positions, END_SPANS)
    for span in range(END_SPANS, SPANS - END_SPANS):
        assert np.array_equal(heights(section, positions, span), middle)
    for end in range(END_SPANS):
        assert np.array_equal(heights(section, positions, end), heights(short.layout, short.positions, end))
        far = SPANS - 1 - end
        assert np.array_equal(
            heights(section, positions, far), heights(short.layout, short.positions, 2 * END_SPANS - end)
        )


def test_a_hinged_messenger_is_copied_with_its_two_gradients(benchmark_catenary):
    catenary = dataclasses.replace(benchmark_catenary, modelling=ModellingOptions(messenger_support="hinge"))
    layout = build_layout(catenary, level_design(catenary), SPANS, *ELEMENTS)
    replicated = find_equal_spans_shape(layout, *ELEMENTS)
    assert len(replicated.residual_history) <= 2
    assert np.max(np.abs(replicated.positions - find_shape(layout).positions)) < 1e-8  # m


def test_a_section_too_short_to_gain_starts_from_the_parabola(benchmark_catenary, monkeypatch):
    solved = []
    monkeypatch.setattr(
        equal_spans,
        "find_shape",
        lambda layout, **kw: solved.append(layout.n_spans) or find_shape(layout, **kw),
    )
    layout = build_layout(benchmark_catenary, level_design(benchmark_catenary), SPANS - 1, *ELEMENTS)
    find_equal_spans_shape(layout, *ELEMENTS)
    assert solved == [SPANS - 1]


def test_a_short_section_that_fails_leaves_the_section_its_own_newton(benchmark_catenary, monkeypatch):
    """Where the short section has no equilibrium, the section is solved from the parabolic start, which
    gives its own answer or its own error."""

    def failing_short(layout, **kw):
        if layout.n_spans < SPANS:
            raise ShapeFindingError("short section: no equilibrium")
        return find_shape(layout, **kw)

    monkeypatch.setattr(equal_spans, "find_shape", failing_short)
    layout = build_layout(benchmark_catenary, level_design(benchmark_catenary), SPANS, *ELEMENTS)
    static = find_equal_spans_shape(layout, *ELEMENTS)
    assert len(static.residual_history) > 2 and static.start_spans == 0  # from the parabola
    assert np.array_equal(static.positions, find_shape(layout).positions)
