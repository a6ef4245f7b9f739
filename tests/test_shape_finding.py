"""Shape-finding (docs/model.md, 'Shape-finding'): equilibrium, tensions, design heights, load paths, closed
forms."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import SHORT, horizontal_tension
from scipy.optimize import brentq

from catenary_env.analysis.static_analysis import stiffness_profile
from catenary_env.fem.layout import CONTACT, MESSENGER, build_layout
from catenary_env.model.design import GRAVITY, Design, DesignError, check_design, level_design, presag_design
from catenary_env.pipeline import Fidelity, solve_static
from catenary_env.statics.shape_finding import ShapeEquations, ShapeFindingError, find_shape, initial_guess


@pytest.mark.parametrize("name", ["benchmark_static", "stitched_static"])
def test_equilibrium_residual_is_below_1e_8_of_the_tension(name, request):
    static = request.getfixturevalue(name)
    assert static.residual_history[-1] < 1e-8 * static.load_scale
    # Newton converges quadratically: the residual drops by orders of magnitude per step.
    assert static.residual_history[-2] < 1e-3 * static.residual_history[-4]


@pytest.mark.parametrize("name", ["benchmark_static", "stitched_static"])
def test_every_wire_element_carries_its_wire_tension(name, request):
    static = request.getfixturevalue(name)
    lay = static.layout
    c = lay.catenary
    horizontal = horizontal_tension(static)
    expected = np.where(lay.cable_wire == CONTACT, c.contact_wire.tension, c.messenger_wire.tension)
    if c.stitch_wire is not None:
        # Between its ends the stitch wire is tensioned against the messenger, which carries T - T_s there.
        middle = 0.5 * (lay.node_x[lay.cable_nodes[:, 0]] + lay.node_x[lay.cable_nodes[:, 1]])
        half = 0.5 * c.stitch_wire.length
        inside = np.any(np.abs(middle[:, None] - lay.support_x[None, 1:-1]) < half, axis=1)
        expected = np.where(
            inside & (lay.cable_wire == MESSENGER), expected - c.stitch_wire.tension, expected
        )
    assert np.max(np.abs(horizontal / expected - 1.0)) < 1e-6


def test_stitch_wire_carries_its_tension(stitched_static):
    lay = stitched_static.layout
    bars = lay.stitch_bars
    n = stitched_static.positions[lay.bar_dofs()[bars.ravel()]]
    dx = n[:, 2] - n[:, 0]
    length = np.hypot(dx, n[:, 3] - n[:, 1])
    horizontal = stitched_static.bar_forces[bars.ravel()] * dx / length
    assert np.allclose(horizontal, lay.catenary.stitch_wire.tension, rtol=1e-6)


@pytest.mark.parametrize("presag", [0.0, 0.05, -0.01])
def test_contact_wire_height_at_every_dropper_is_the_design(benchmark_catenary, presag):
    design = presag_design(benchmark_catenary, presag)
    static = solve_static(benchmark_catenary, design, SHORT)
    lay = static.layout
    cw_nodes = lay.bar_nodes[lay.dropper_bars, 1]
    heights = static.positions[lay.node_dof[cw_nodes] + 1]
    expected = benchmark_catenary.contact_wire_height + np.tile(design.contact_wire_offsets, lay.n_spans)
    assert np.max(np.abs(heights - expected)) < 1e-6
    assert np.allclose(
        static.positions[lay.node_dof[lay.contact_supports] + 1], benchmark_catenary.contact_wire_height
    )


def test_droppers_and_steady_arms_carry_the_weight_of_a_span(benchmark_static):
    lay = benchmark_static.layout
    c = lay.catenary
    span = lay.n_spans // 2
    x_mid = 0.5 * (lay.node_x[lay.cable_nodes[:, 0]] + lay.node_x[lay.cable_nodes[:, 1]])
    in_span = (
        (lay.cable_wire == CONTACT)
        & (x_mid > span * lay.span_length)
        & (x_mid < (span + 1) * lay.span_length)
    )
    n_c = lay.cable_nodes.shape[0]
    wire = c.contact_wire.linear_mass * GRAVITY * benchmark_static.lengths[:n_c][in_span].sum()
    droppers = lay.dropper_span == span
    clamps = droppers.sum() * c.dropper.clamp_mass_contact * GRAVITY
    dropper_halves = 0.5 * c.dropper.linear_mass * GRAVITY * benchmark_static.dropper_lengths[droppers].sum()
    supports = lay.node_dof[lay.contact_supports[[span, span + 1]]] + 1
    # An interior support sits between two equal spans: each takes half its reaction; the steady-arm
    # mass hangs there too.
    carried = (
        benchmark_static.dropper_forces[droppers].sum() + 0.5 * benchmark_static.reactions[supports].sum()
    )
    weight = wire + clamps + dropper_halves + c.supports.steady_arm_mass * GRAVITY
    assert carried == pytest.approx(weight, rel=1e-6)


@pytest.mark.parametrize(("support", "one_in", "two_in"), [("hinge", 1e-9, 1e-9), ("continuous", 1e-5, 1e-8)])
def test_spans_are_identical_away_from_the_ends(benchmark_catenary, support, one_in, two_in):
    catenary = dataclasses.replace(
        benchmark_catenary,
        modelling=dataclasses.replace(benchmark_catenary.modelling, messenger_support=support),
    )
    static = solve_static(catenary, level_design(catenary), dataclasses.replace(SHORT, n_spans=7))
    lengths = static.dropper_lengths.reshape(7, -1)
    departure = [np.max(np.abs(lengths[k] - lengths[3])) for k in range(3)]
    # The end spans differ (the wires end there). Past a hinge, one span in, every span is the same to
    # round-off; a continuous messenger carries the end's slope on, fading about a thousandfold per span.
    assert departure[0] > 1e-4
    assert departure[1] < one_in and departure[2] < two_in


def _elastic_catenary_sag(span: float, tension: float, weight: float, ea: float) -> float:
    """Mid-span sag of an elastic catenary with horizontal tension H between level supports (Irvine 1981)."""

    def span_of(unstretched: float) -> float:
        v = 0.5 * weight * unstretched
        return tension * unstretched / ea + 2.0 * tension / weight * np.arcsinh(v / tension) - span

    s0 = brentq(span_of, 0.9 * span, 1.1 * span)
    v = 0.5 * weight * s0
    return weight * s0**2 / (8.0 * ea) + tension / weight * (np.sqrt(1.0 + (v / tension) ** 2) - 1.0)


@pytest.mark.parametrize("element", [5.5, 2.75])
def test_single_tensioned_cable_sags_as_the_elastic_catenary(benchmark_catenary, element):
    # Two free-hanging wires, no droppers, perfectly flexible (EI = 0) as the closed form assumes.
    flexible = dataclasses.replace(
        benchmark_catenary,
        contact_wire=dataclasses.replace(benchmark_catenary.contact_wire, bending_stiffness=0.0),
        messenger_wire=dataclasses.replace(benchmark_catenary.messenger_wire, bending_stiffness=0.0),
    )
    layout = build_layout(flexible, Design((), ()), 1, element, element)
    static = find_shape(layout)
    for kind, wire, height in (
        (CONTACT, flexible.contact_wire, flexible.contact_wire_height),
        (MESSENGER, flexible.messenger_wire, flexible.messenger_height),
    ):
        mid = np.flatnonzero(
            (layout.node_kind == kind) & np.isclose(layout.node_x, 0.5 * layout.span_length)
        )[0]
        sag = height - static.positions[layout.node_dof[mid] + 1]
        expected = _elastic_catenary_sag(
            layout.span_length, wire.tension, wire.linear_mass * GRAVITY, wire.axial_stiffness
        )
        assert sag == pytest.approx(expected, rel=1e-6)


def test_analytic_jacobian_matches_finite_differences(stitched_catenary):
    layout = build_layout(stitched_catenary, level_design(stitched_catenary), 3, 6.0, 8.0)
    equations = ShapeEquations(layout)
    y = equations.unknowns(*initial_guess(layout))
    r, J = equations.evaluate(y)
    J = J.toarray()
    rng = np.random.default_rng(0)
    for column in rng.choice(y.size, 40, replace=False):
        h = 1e-6 * max(1.0, abs(y[column]))
        yp, ym = y.copy(), y.copy()
        yp[column] += h
        ym[column] -= h
        fd = (equations.evaluate(yp, False)[0] - equations.evaluate(ym, False)[0]) / (2 * h)
        assert np.allclose(fd, J[:, column], rtol=1e-5, atol=1e-5 * np.max(np.abs(J)))


def test_newton_factorises_a_jacobian_per_iteration_until_its_quadratic_phase(
    benchmark_catenary, monkeypatch
):
    """One residual per step; a Jacobian per iteration, but for the steps after two that each cut the residual
    a hundredfold (a chord step reuses the last factorisation), which end at the same solution as Newton's
    to round-off and at its floor."""
    layout = build_layout(benchmark_catenary, level_design(benchmark_catenary), 5, 1.0, 2.0)
    newton = find_shape(layout, chord=False)
    calls = {"residual": 0, "jacobian": 0}
    for name in calls:
        method = getattr(ShapeEquations, name)

        def counted(self, y, name=name, method=method):
            calls[name] += 1
            return method(self, y)

        monkeypatch.setattr(ShapeEquations, name, counted)
    static = find_shape(layout)
    history = np.array(static.residual_history)
    iterations = history.size - 1
    fast = history[1:] < 1e-2 * history[:-1]  # a step that cut the residual a hundredfold
    quadratic = [i for i in range(2, iterations) if fast[i - 2] and fast[i - 1]]
    assert quadratic, "no chord step here: the test shows nothing"
    # No step is cut back here: the initial residual plus one per step, and the final state is reused.
    assert calls == {"residual": iterations + 1, "jacobian": iterations - len(quadratic)}
    assert history[-1] < 1e-8 * static.load_scale
    assert np.max(np.abs(static.positions - newton.positions)) < 1e-10  # m
    assert np.allclose(static.bar_forces, newton.bar_forces, rtol=1e-9, atol=1e-9)


def test_stiffness_is_higher_at_the_supports_than_at_mid_span(benchmark_static):
    profile = stiffness_profile(benchmark_static, force=100.0, n_points=5)
    k = profile.stiffness
    assert k[0] > 1.5 * k[2] and k[-1] > 1.5 * k[2]
    assert 0.0 < profile.variability < 1.0
    assert profile.uplift[2] > 0.0


def test_a_dropper_below_its_neighbours_is_in_compression(benchmark_catenary):
    offsets = [0.0] * 9
    offsets[3] = offsets[5] = -0.05  # symmetric: droppers 4 and 6 pull the wire 5 cm below the others
    static = solve_static(
        benchmark_catenary, Design(benchmark_catenary.dropper_positions, tuple(offsets)), SHORT
    )
    reason = static.infeasibility()
    assert "compression" in reason and ("dropper 4" in reason or "dropper 6" in reason)
    central = static.layout.dropper_span == 2
    forces = static.dropper_forces[central]
    assert forces[3] < 0 and forces[5] < 0 and np.all(np.delete(forces, [3, 5]) > 0)


def test_a_design_needing_a_negative_dropper_length_is_refused_before_any_solve(benchmark_catenary):
    offsets = tuple([0.8] * 9)  # contact wire 0.8 m up: above the sagged messenger at mid-span
    with pytest.raises(DesignError, match=r"contact_wire_offsets\[\d\].*negative length"):
        check_design(benchmark_catenary, Design(benchmark_catenary.dropper_positions, offsets))


@pytest.mark.parametrize(
    ("positions", "match"),
    [
        ((0.0, 27.5, 55.0), r"dropper_positions\[0\].*inside the span"),
        ((10.0, 9.0, 46.0), r"must not cross"),
        ((4.5, 27.5, 60.0), r"inside the span"),
    ],
)
def test_bad_dropper_positions_are_refused(benchmark_catenary, positions, match):
    with pytest.raises(DesignError, match=match):
        check_design(benchmark_catenary, Design(positions, (0.0,) * len(positions)))


def test_a_long_section_stops_at_its_own_round_off_floor(benchmark_catenary):
    """The round-off floor grows with the section (some 2e-8 of the tension at 60 spans, 5e-8 at 120, above
    the tolerance): Newton stops once a step from its quadratic phase cuts the residual less than a
    hundredfold, and the equilibrium is that floor, not a failure to converge."""
    layout = build_layout(benchmark_catenary, level_design(benchmark_catenary), 120, 0.5, 1.0)
    static = find_shape(layout)
    history = np.array(static.residual_history) / static.load_scale
    assert history[-1] > 1e-8  # above the tolerance: the stall rule ends it, as it should
    assert history[-2] < 1e-6 and history[-1] > 1e-2 * history[-2]  # ... and only there
    assert history.size <= 6 and history[-1] < 1e-7


def test_a_floor_above_the_tolerance_ends_newton_with_no_step_to_confirm_it(benchmark_catenary, monkeypatch):
    """At 40 spans the floor (some 1.3e-8 of the tension) lies above the tolerance: the chord step that
    reaches it, cutting the residual less than a hundredfold, ends Newton, with as many factorisations as
    a 20-span section's (not one more whose step would only confirm the floor)."""
    factorised = []

    def counting(self, y):
        factorised.append(self.n_free)
        return jacobian(self, y)

    jacobian = ShapeEquations.jacobian
    monkeypatch.setattr(ShapeEquations, "jacobian", counting)
    counts = {}
    for spans in (20, 40):
        factorised.clear()
        layout = build_layout(benchmark_catenary, level_design(benchmark_catenary), spans, 0.5, 1.0)
        static = find_shape(layout)
        counts[spans] = len(factorised)
    history = np.array(static.residual_history) / static.load_scale
    assert history[-1] > 1e-8 and history[-1] > 1e-2 * history[-2]  # the floor, above the tolerance
    assert counts[40] == counts[20] == 3


def test_a_non_converging_solve_reports_its_residual(benchmark_catenary):
    layout = build_layout(benchmark_catenary, level_design(benchmark_catenary), 3, 2.0, 4.0)
    with pytest.raises(ShapeFindingError, match=r"residual \d\.\d+e[+-]\d+ N"):
        find_shape(layout, max_iterations=2)


def test_fidelity_out_of_range_is_refused(benchmark_catenary):
    with pytest.raises(DesignError, match="fidelity.contact_wire_element"):
        solve_static(benchmark_catenary, level_design(benchmark_catenary), Fidelity(contact_wire_element=0.0))


def test_wire_tensions_are_the_tension_along_the_slope(benchmark_static):
    lay = benchmark_static.layout
    c = lay.catenary
    tensions = benchmark_static.wire_tensions
    # The axial force is the horizontal tension divided by the cosine of the slope: a little above it. Where
    # a continuous messenger bends over a support (within 4 bending lengths) the wire also carries shear.
    middle = lay.node_x[lay.cable_nodes].mean(axis=1)
    bend = 4.0 * np.sqrt(c.messenger_wire.bending_stiffness / c.messenger_wire.tension)
    near = np.min(np.abs(middle[:, None] - lay.support_x[None, 1:-1]), axis=1) < bend
    for wire, definition, kind in (
        ("contact_wire", c.contact_wire, CONTACT),
        ("messenger_wire", c.messenger_wire, MESSENGER),
    ):
        t = tensions[wire][~near[lay.cable_wire == kind]]
        assert np.all(t >= definition.tension * (1 - 1e-6)) and np.all(t < definition.tension * 1.01)


def test_designs_of_one_topology_share_the_planned_jacobian_and_solve_as_with_their_own(
    benchmark_catenary, monkeypatch
):
    """The Jacobian's pattern and the solver's ordering are planned once per topology: another design of the
    same section takes the plan again, and finds the same shape, bit for bit, as with a plan of its own; a
    section of another length gets another plan."""
    from catenary_env.statics import shape_finding

    def layout(design, n_spans=5):
        return build_layout(benchmark_catenary, design, n_spans, 1.0, 2.0)

    level, presag = level_design(benchmark_catenary), presag_design(benchmark_catenary, 0.05)
    first = ShapeEquations(layout(level))
    again = ShapeEquations(layout(presag))
    assert again._jacobian is first._jacobian and again._solver is first._solver
    assert ShapeEquations(layout(level, 4))._solver is not first._solver
    shared = find_shape(layout(presag))
    monkeypatch.setattr(shape_finding, "_PLANS", shape_finding.RecentPlans())  # nothing planned yet
    own = find_shape(layout(presag))
    assert np.array_equal(shared.positions, own.positions) and np.array_equal(shared.lengths, own.lengths)
