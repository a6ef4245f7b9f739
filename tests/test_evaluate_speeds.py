"""One design at several speeds (docs/performance.md, 'Speed'): the statics, the linear system and the
dynamic model's preparation are made once, and every evaluation equals the one-speed evaluation's, number
for number. Runs the simulator on the short, coarse test model."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from catenary_env import pipeline
from catenary_env.model.tolerances import Tolerances, draw_deviations
from catenary_env.problems import PROBLEMS
from catenary_env.problems.speeds import SpeedsEvaluation
from catenary_env.problems.tolerance import RobustObjective

SPEEDS = (200.0, 250.0)
FORCES = (112.0, 133.0)  # N, about the calibrated ones: given, so that nothing is calibrated
X = (0.004, 0.0, -0.003, 0.0, 0.002)


def _same(a: pipeline.Evaluation, b: pipeline.Evaluation) -> None:
    assert (a.feasible, a.reason, a.uplift_force) == (b.feasible, b.reason, b.uplift_force)
    assert a.statistics == b.statistics
    assert a.trace_force == b.trace_force
    assert a.constraints == b.constraints
    assert a.dropper_forces == b.dropper_forces


@pytest.mark.parametrize("dynamics", pipeline.DYNAMICS)
def test_each_speed_equals_its_own_evaluation_and_the_statics_is_found_once(
    dynamics: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    fidelity = dataclasses.replace(pipeline.FIDELITIES["test"], dynamics=dynamics)
    problem = PROBLEMS["B1"]
    alone = [problem.evaluate(X, v, fidelity, f) for v, f in zip(SPEEDS, FORCES, strict=True)]
    found = []
    real = pipeline._find_static
    monkeypatch.setattr(pipeline, "_find_static", lambda *a, **k: found.append(1) or real(*a, **k))
    together = problem.evaluate_speeds(X, SPEEDS, fidelity, FORCES)
    assert isinstance(together, SpeedsEvaluation) and together.speeds_kmh == SPEEDS
    assert len(found) == 1
    assert [e.feasible for e in alone] == [True, True]
    for a, b in zip(alone, together.evaluations, strict=True):
        _same(a, b)
    assert together.sigma() == pytest.approx(np.mean([e.sigma for e in alone]), rel=1e-15)


def test_it_stops_at_the_first_infeasible_speed() -> None:
    problem = PROBLEMS["B1"]
    speeds, forces = (250.0, 300.0, 320.0), (133.0, 159.0, 170.0)
    result = problem.evaluate_speeds(X, speeds, "test", forces)
    alone = [problem.evaluate(X, v, "test", f) for v, f in zip(speeds[:2], forces[:2], strict=True)]
    assert [e.feasible for e in alone] == [True, False]  # this design loses contact at 300 km/h
    assert len(result.evaluations) == 2 and not result.feasible and result.sigma() is None
    for a, b in zip(alone, result.evaluations, strict=True):
        _same(a, b)
    assert result.reason == f"at 300 km/h: {alone[1].reason}"


def test_a_statically_infeasible_design_is_one_evaluation() -> None:
    problem = PROBLEMS["B1"]
    compressed = (-0.02, -0.02, 0.02, 0.02, 0.02)  # 20 mm low by the supports, 20 mm high mid-span
    alone = problem.evaluate(compressed, SPEEDS[0], "test", FORCES[0])
    assert alone.reason.startswith("static:")
    result = problem.evaluate_speeds(compressed, SPEEDS, "test", FORCES)
    assert len(result.evaluations) == 1
    _same(alone, result.evaluations[0])


def test_a_built_section_and_the_robust_objective_at_several_speeds() -> None:
    problem = PROBLEMS["B1"]
    tolerances = Tolerances(0.002, 0.05)
    fidelity = pipeline.FIDELITIES["test"]
    deviations = draw_deviations(tolerances, fidelity.n_spans, problem.n_droppers, seed=1, draw=0)
    alone = [problem.evaluate(X, v, "test", f, deviations) for v, f in zip(SPEEDS, FORCES, strict=True)]
    together = problem.evaluate_speeds(X, SPEEDS, "test", FORCES, deviations)
    for a, b in zip(alone, together.evaluations, strict=True):
        _same(a, b)
    robust = problem.with_options(robust=RobustObjective(tolerances, 2, 1))
    alone = [robust.evaluate(X, v, "test", f) for v, f in zip(SPEEDS, FORCES, strict=True)]
    together = robust.evaluate_speeds(X, SPEEDS, "test", FORCES)
    assert [a.statistics for a in alone] == [b.statistics for b in together.evaluations]


def test_bad_input_is_refused_for_every_speed_before_any_solve(monkeypatch: pytest.MonkeyPatch) -> None:
    def no_solve(*args: object, **kwargs: object) -> None:
        raise AssertionError("solved before the input was checked")

    monkeypatch.setattr(pipeline, "_find_static", no_solve)
    problem = PROBLEMS["B1"]
    with pytest.raises(ValueError, match="km/h"):
        problem.evaluate_speeds([0.0] * 5, (300.0, 500.0), "test", (150.0, 150.0))  # above the wave speed
    with pytest.raises(ValueError, match="uplift_forces"):
        problem.evaluate_speeds([0.0] * 5, (250.0, 300.0), "test", (150.0,))
    with pytest.raises(ValueError, match="uplift_force"):
        problem.evaluate_speeds([0.0] * 5, (250.0, 300.0), "test", (150.0, -1.0))
    with pytest.raises(ValueError, match="speeds_kmh"):
        problem.evaluate_speeds([0.0] * 5, (), "test")
