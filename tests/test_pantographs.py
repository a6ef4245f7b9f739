"""Several pantographs on one catenary (docs/model.md, 'Several pantographs').

EN 50318:2002 gives no accepted ranges for a trailing pantograph, so the physics is checked instead: a
second pantograph that never reaches the section leaves the first one's passage as it was alone; behind a
leader whose wake has died out the trailing pantograph sees what a lone one sees; at a crawl both heads are
in static balance, with the pantograph's springs and with the catenary's static compliance under both; with
every mode kept the span-mode model is the exact one, and the compiled loops are the numpy ones.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from catenary_env.analysis.statistics import passage_statistics
from catenary_env.dynamics import exact, span_modes
from catenary_env.dynamics.linear_system import linearise
from catenary_env.dynamics.protocol import ContactPoint, Passage
from catenary_env.dynamics.span_modes.reduction import reduce_system
from catenary_env.fem.layout import build_layout
from catenary_env.model.definition import RayleighDamping
from catenary_env.model.design import level_design
from catenary_env.model.options import FORMER_DEFAULTS, ModellingOptions
from catenary_env.pipeline import Fidelity
from catenary_env.statics.shape_finding import find_shape

SPEED = 300 / 3.6
DT = 2e-3
UPLIFT = 170.0  # N on the frame
DAMPED_ALPHA = 3.0
"""1/s: a catenary whose wake dies out within a few seconds (the presets' 0.0125 1/s keeps it ringing for
minutes, so that no realistic spacing lets it decay)."""


def train(pantograph, *offsets: float) -> tuple[ContactPoint, ...]:
    return tuple(ContactPoint(pantograph, UPLIFT, offset) for offset in (0.0, *offsets))


@pytest.fixture(scope="module")
def system(benchmark_catenary):
    """test_span_modes' 5-span section (its interior spans share one eigensolution)."""
    catenary = dataclasses.replace(benchmark_catenary, modelling=ModellingOptions(**FORMER_DEFAULTS))
    return linearise(find_shape(build_layout(catenary, level_design(catenary), 5, 1.0, 2.0)))


@pytest.fixture(scope="module")
def damped(benchmark_catenary):
    """A 12-span section of the benchmark catenary with strong mass-proportional damping."""
    catenary = dataclasses.replace(
        benchmark_catenary, damping=RayleighDamping(DAMPED_ALPHA, benchmark_catenary.damping.beta)
    )
    system = linearise(find_shape(build_layout(catenary, level_design(catenary), 12, 1.5, 3.0)))
    return system, exact.prepare(system, Fidelity(time_step=DT))


@pytest.mark.parametrize("model", ["exact", "span-modes"])
def test_a_pantograph_that_never_reaches_the_section_leaves_the_leading_one_alone(
    model, system, benchmark_pantograph_definition
):
    if model == "exact":
        prepared, run = exact.prepare(system, Fidelity(time_step=DT)), exact.run
    else:
        prepared, run = span_modes.prepare_reduced(reduce_system(system, 300.0, 50.0), DT, 1), span_modes.run
    length = system.static.layout.n_spans * system.static.layout.span_length
    alone = run(prepared, Passage(SPEED, train(benchmark_pantograph_definition)))
    two = run(prepared, Passage(SPEED, train(benchmark_pantograph_definition, length + 1.0)))
    assert alone.slack_steps > 0
    assert np.abs(two.contact_force - alone.contact_force).max() < 1e-9
    assert np.abs(two.support_uplift - alone.support_uplift).max() < 1e-12
    trailing = two.pantographs[1]
    assert np.all(trailing.position < 0.0) and np.all(trailing.contact_force == 0.0)


def test_behind_a_died_out_wake_the_trailing_pantograph_sees_what_a_lone_one_sees(
    damped, benchmark_pantograph_definition
):
    system, prepared = damped
    span = system.static.layout.span_length
    window = (3 * span, 4 * span)
    alone = passage_statistics(
        exact.run(prepared, Passage(SPEED, train(benchmark_pantograph_definition))), window
    )
    deviation = {}
    for spacing in (2 * span, 8 * span):
        two = exact.run(prepared, Passage(SPEED, train(benchmark_pantograph_definition, spacing)))
        trailing = passage_statistics(two.of_pantograph(1), window)
        deviation[spacing] = abs(trailing.std - alone.std) / alone.std
        assert trailing.mean == pytest.approx(alone.mean, rel=0.01)
    # Two spans behind, the trailing pantograph rides the leader's wake; eight spans (5.3 s) behind, the wake
    # has decayed as exp(-alpha t / 2) ~ 4e-4 and σ is the lone pantograph's to well within 1 %.
    assert deviation[2 * span] > 0.03
    assert deviation[8 * span] < 0.01


def test_at_a_crawl_both_heads_are_in_static_balance(damped, benchmark_pantograph_definition):
    system, prepared = damped
    pantograph = benchmark_pantograph_definition
    span = system.static.layout.span_length
    speed, spacing, lead_end = 2.0, span, 3 * span
    steps = int(lead_end / (speed * DT))
    run = exact.run(prepared, Passage(speed, train(pantograph, spacing), n_steps=steps))
    k0, series = pantograph.stiffnesses[0], sum(1.0 / k for k in pantograph.stiffnesses[1:])
    traces = run.pantographs
    # The pantograph: every spring of the chain carries the contact force f, y_h = (F - f) / k0 - f Σ 1/k_i,
    # on average over each one's last span (the head rings a little where the wire's height bends at a
    # dropper, and its dampers' mean force is nil over a span, the wire's height the same at both ends).
    last = slice(-int(span / (speed * DT)), None)
    for trace in traces:
        balance = (UPLIFT - k0 * trace.head_height[last]) / (1.0 + k0 * series)
        assert trace.contact_force[last].mean() == pytest.approx(balance.mean(), rel=1e-3)
    # The catenary: the wire's uplift under each head is its static response to both contact forces (the
    # other head's share is 3 % of it here; the drag alpha M u' of the moving uplift, some 0.3 %, is left).
    forces = np.array([trace.contact_force[-1] for trace in traces])
    wire = system.contact_wire
    element, shape, _ = wire.locate(np.array([trace.position[-1] for trace in traces]))
    load = np.zeros(system.n_dofs)
    for e, h, force in zip(element, shape, forces, strict=True):
        np.add.at(load, wire.z_dofs[e], h * force)
    static = spla.spsolve(system.stiffness.tocsc(), load)
    for trace, e, h in zip(traces, element, shape, strict=True):
        assert trace.wire_uplift[-1] == pytest.approx(h @ static[wire.z_dofs[e]], rel=5e-3)
    assert min(forces) > 100.0  # both heads press on the wire


def test_with_every_mode_kept_the_span_mode_model_is_the_exact_one(system, benchmark_pantograph_definition):
    passage = Passage(SPEED, train(benchmark_pantograph_definition, 80.0), backend="numpy")
    reference = exact.run(exact.prepare(system, Fidelity(time_step=DT)), passage)
    full = span_modes.run(span_modes.prepare_reduced(reduce_system(system, np.inf), DT, 1), passage)
    assert reference.slack_steps > 50
    assert full.slack_steps == reference.slack_steps
    for a, b in zip(full.pantographs, reference.pantographs, strict=True):
        assert np.abs(a.contact_force - b.contact_force).max() < 1e-5
        assert np.abs(a.wire_uplift - b.wire_uplift).max() < 1e-9
    assert np.abs(full.support_uplift - reference.support_uplift).max() < 1e-9


@pytest.mark.parametrize("model", ["exact", "span-modes"])
def test_the_compiled_loops_equal_the_numpy_ones_with_two_pantographs(
    model, system, benchmark_pantograph_definition
):
    pytest.importorskip("numba")
    if model == "exact":
        prepared, run = exact.prepare(system, Fidelity(time_step=DT)), exact.run
    else:
        prepared, run = span_modes.prepare_reduced(reduce_system(system, 300.0, 50.0), DT, 1), span_modes.run
    points = train(benchmark_pantograph_definition, 80.0)
    a = run(prepared, Passage(SPEED, points, backend="numpy"))
    b = run(prepared, Passage(SPEED, points, backend="numba"))
    assert a.slack_steps == b.slack_steps
    for pa, pb in zip(a.pantographs, b.pantographs, strict=True):
        # the trailing pantograph meets the moving wire with some 800 N: 1e-9 N at the leader's scale
        assert np.abs(pa.contact_force - pb.contact_force).max() < 1e-8
        assert np.abs(pa.wire_uplift - pb.wire_uplift).max() < 1e-10


# -- the train in the pipeline, the problems, the envs and the command line ---------------------------------


def _fidelity(n_spans: int = 8):
    from catenary_env.problems import resolve_fidelity

    return resolve_fidelity("test", n_spans)


def test_an_evaluation_carries_every_pantographs_statistics_and_its_objective(
    benchmark_catenary, benchmark_pantograph_definition
):
    from catenary_env.pipeline import evaluate
    from catenary_env.train import OBJECTIVES, Train

    design = level_design(benchmark_catenary)
    p = benchmark_pantograph_definition
    alone = evaluate(benchmark_catenary, p, design, SPEED, _fidelity(), 160.0)
    assert alone.sigma == alone.statistics.std and alone.pantograph_statistics == (alone.statistics,)
    sigmas = {}
    for objective in OBJECTIVES:
        two = evaluate(
            benchmark_catenary,
            p,
            design,
            SPEED,
            _fidelity(),
            160.0,
            train=Train.behind([p], 110.0, objective),
        )
        leading, trailing = two.pantograph_statistics
        assert two.statistics == leading
        assert two.feasible == (leading.contact_loss_percent == trailing.contact_loss_percent == 0.0)
        sigmas[objective] = two.sigma
    assert leading.std != trailing.std
    assert sigmas == {
        "leading": leading.std,
        "trailing": trailing.std,
        "worst": max(leading.std, trailing.std),
        "mean": (leading.std + trailing.std) / 2,
    }


def test_a_spacing_the_section_cannot_take_is_refused_naming_the_range(
    benchmark_catenary, benchmark_pantograph_definition
):
    from catenary_env.model.design import DesignError
    from catenary_env.pipeline import evaluate
    from catenary_env.train import Train

    p = benchmark_pantograph_definition
    design = level_design(benchmark_catenary)
    for spacing in (20.0, 300.0):  # less than a span; the leading pantograph would leave 8 spans too soon
        with pytest.raises(DesignError, match="55 m apart at least and 165 m at most"):
            evaluate(
                benchmark_catenary, p, design, SPEED, _fidelity(), 160.0, train=Train.behind([p], spacing)
            )
    with pytest.raises(DesignError, match="train.objective = 'best'"):
        Train.behind([p], 100.0, "best")


def test_a_problem_and_its_env_take_a_train(benchmark_pantograph_definition):
    gym = pytest.importorskip("gymnasium")
    from catenary_env.envs import register_envs
    from catenary_env.problems import get_problem
    from catenary_env.train import Train

    train = Train.behind([benchmark_pantograph_definition], 110.0, "worst")
    problem = get_problem("B1")
    evaluation = problem.evaluate(problem.reference_x(), 300.0, _fidelity(), uplift_force=160.0, train=train)
    assert len(evaluation.pantograph_statistics) == 2
    register_envs()
    env = gym.make("Catenary-B1-v0", fidelity=_fidelity(), train=train)
    env.reset(seed=0)
    _, _, _, _, info = env.step(env.unwrapped.x_to_action(problem.reference_x()))
    blocks = info["pantograph_statistics"]
    assert len(blocks) == 2 and blocks[0]["std"] == info["std"]
    if info["feasible"]:
        assert info["objective"] == pytest.approx(max(b["std"] for b in blocks))


def test_simulate_on_the_command_line_prints_each_pantograph(capsys):
    from catenary_env.cli import main

    argv = [
        "simulate",
        "benchmark",
        "--speed",
        "300",
        "--uplift",
        "160",
        "--fidelity",
        "test",
        "--spans",
        "8",
    ]
    assert main([*argv, "--pantographs", "benchmark,benchmark", "--spacing", "110", "--json"]) == 0
    import json

    result = json.loads(capsys.readouterr().out)
    assert [p["offset"] for p in result["pantographs"]] == [0.0, 110.0]
    assert result["statistics"] == result["pantographs"][0]["statistics"]
    assert main([*argv, "--pantographs", "benchmark,benchmark", "--spacing", "400"]) == 2
    assert "at most" in capsys.readouterr().err
