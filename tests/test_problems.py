"""Design problems (docs/problems.md, 'The eight problems'): variables, bounds, grid, the mapping to designs,
and the registry.

Nothing here runs the simulator, except where a test replaces it to count calls (marked).
"""

from __future__ import annotations

import itertools
import pickle
from pathlib import Path

import numpy as np
import pytest

from catenary_env import pipeline
from catenary_env.analysis.statistics import ContactStatistics
from catenary_env.model.design import Design, DesignError, check_design
from catenary_env.model.presets import load_catenary
from catenary_env.pipeline import FIDELITIES, Evaluation, Fidelity
from catenary_env.problems import (
    HEIGHT_STEP,
    POSITION_STEP,
    PROBLEMS,
    DesignProblem,
    ProblemRegistry,
    clear_caches,
    evaluate_problem,
    get_problem,
    register_problem,
    resolve_fidelity,
)
from catenary_env.problems.speeds import evaluate_over_speeds
from catenary_env.problems.table import problem_table

# The table of docs/problems.md, 'The eight problems', written out again so that a change to either is seen.
SPEC_TABLE = {
    "BPresag": ("benchmark", 9, ["s"], [-0.02], [0.10]),
    "B1": ("benchmark", 9, [f"dh_{i}" for i in range(1, 6)], [-0.02] * 5, [0.02] * 5),
    "B2": ("benchmark", 9, ["d_1", "d_2", "d_3", "d_4"], [0.1, 7.5, 13.2, 18.9], [7.4, 13.1, 18.8, 27.4]),
    "B3": (
        "benchmark",
        5,
        ["d_1", "d_2", "dh_1", "dh_2", "dh_3"],
        [0.1, 13.1, -0.02, -0.02, -0.02],
        [13.0, 27.4, 0.02, 0.02, 0.02],
    ),
    "SWPresag": ("stitched", 7, ["s"], [-0.02], [0.10]),
    "SW1": ("stitched", 7, [f"dh_{i}" for i in range(1, 5)], [-0.02] * 4, [0.02] * 4),
    "SW2": ("stitched", 7, ["d_1", "d_2", "d_3"], [0.1, 9.1, 20.5], [8.9, 20.4, 32.4]),
    "SW3": (
        "stitched",
        5,
        ["d_1", "d_2", "dh_1", "dh_2", "dh_3"],
        [2.0, 10.0, -0.02, -0.02, -0.02],
        [9.0, 30.0, 0.02, 0.02, 0.02],
    ),
}


def random_grid_points(problem: DesignProblem, n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    index = rng.integers(0, problem.n_levels, size=(n, problem.n_variables))
    return np.array([problem.from_grid_index(k) for k in index])


# ---------------------------------------------------------------------------------------------------------
# Table and grid


def test_registry_holds_exactly_the_problems_of_spec_4_in_order() -> None:
    assert list(PROBLEMS) == list(SPEC_TABLE)


@pytest.mark.parametrize("name", list(SPEC_TABLE))
def test_variables_and_bounds_follow_spec_4(name: str) -> None:
    catenary, n_droppers, variables, lower, upper = SPEC_TABLE[name]
    problem = PROBLEMS[name]
    assert (problem.catenary, problem.n_droppers, list(problem.variables)) == (
        catenary,
        n_droppers,
        variables,
    )
    np.testing.assert_array_equal(problem.lower, lower)
    np.testing.assert_array_equal(problem.upper, upper)
    expected_step = [POSITION_STEP if v.startswith("d_") else HEIGHT_STEP for v in variables]
    np.testing.assert_array_equal(problem.step, expected_step)
    assert problem.units == ("m",) * len(variables)


def test_bounds_cannot_be_changed() -> None:
    with pytest.raises(ValueError):
        PROBLEMS["B1"].lower[0] = -1.0


@pytest.mark.parametrize(
    ("given", "expected"),
    [
        (0.02, 0.02),  # exactly at the upper bound
        (-0.02, -0.02),  # exactly at the lower bound
        (0.5, 0.02),  # beyond the upper bound
        (-0.0201, -0.02),  # just beyond the lower bound
        (0.0005, 0.001),  # half step: ties round up
        (-0.0005, 0.0),  # half step below zero: also up
        (0.00049, 0.0),
        (0.00051, 0.001),
        (0.0195, 0.02),  # tie next to the upper bound stays on it
        (-0.0195, -0.019),
        (0.0104, 0.01),
    ],
)
def test_heights_snap_to_the_millimetre(given: float, expected: float) -> None:
    snapped = PROBLEMS["B1"].snap([given, 0.0, 0.0, 0.0, 0.0])
    assert snapped[0] == expected  # exactly: equal grid points are equal floats


@pytest.mark.parametrize(
    ("given", "expected"),
    [
        (0.1, 0.1),
        (7.4, 7.4),
        (0.0, 0.1),
        (8.0, 7.4),
        (0.105, 0.11),
        (7.395, 7.4),
        (4.504, 4.5),
        (4.5049, 4.5),
    ],
)
def test_positions_snap_to_the_centimetre(given: float, expected: float) -> None:
    snapped = PROBLEMS["B2"].snap([given, 10.0, 16.0, 21.0])
    assert snapped[0] == expected


@pytest.mark.parametrize("name", list(SPEC_TABLE))
def test_grid_index_runs_from_lower_to_upper(name: str) -> None:
    problem = PROBLEMS[name]
    np.testing.assert_array_equal(problem.grid_index(problem.lower), 0)
    np.testing.assert_array_equal(problem.grid_index(problem.upper), problem.n_levels - 1)
    np.testing.assert_array_equal(problem.from_grid_index(problem.n_levels - 1), problem.upper)
    x = random_grid_points(problem, 20)
    for point in x:
        np.testing.assert_array_equal(problem.from_grid_index(problem.grid_index(point)), point)


def test_out_of_bounds_and_check_name_the_variable_and_its_bounds() -> None:
    problem = PROBLEMS["B2"]
    assert problem.out_of_bounds([0.05, 10.0, 16.0, 30.0]) == ("d_1", "d_4")
    assert problem.out_of_bounds([0.1, 7.5, 13.2, 27.4]) == ()
    with pytest.raises(ValueError, match=r"d_4 = 30\.0 m: must lie in \[18\.9, 27\.4\] m"):
        problem.check_variables([0.1, 10.0, 16.0, 30.0])


@pytest.mark.parametrize(
    "bad",
    [[0.0] * 4, [0.0] * 6, [[0.0] * 5], [float("nan"), 0, 0, 0, 0], [float("inf"), 0, 0, 0, 0], ["a"] * 5],
)
def test_bad_variable_vectors_are_refused(bad: list) -> None:
    with pytest.raises(ValueError, match="problem B1: x must"):
        PROBLEMS["B1"].snap(bad)
    with pytest.raises(ValueError, match="problem B1: action must"):  # the env's actions: the same check
        PROBLEMS["B1"].grid.check_vector(bad, "action")


def test_the_docs_problem_table_is_the_problems_own() -> None:
    """docs/problems.md prints the one problem table (README and the env's docstring link to it)."""
    docs = (Path(__file__).resolve().parents[1] / "docs" / "problems.md").read_text(encoding="utf-8")
    assert problem_table(PROBLEMS.values()) + "\n" in docs
    assert docs.count("| problem | catenary |") == 1


# ---------------------------------------------------------------------------------------------------------
# σ over several speeds (the multi-speed objectives of the envs and the studies)


def _evaluation(feasible: bool, sigma: float) -> Evaluation:
    statistics = ContactStatistics(150.0, sigma, sigma / 150.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    return Evaluation(feasible, "" if feasible else "dynamic: contact lost", statistics, (), (), 150.0, 2.0)


def test_sigma_over_speeds_is_the_mean_or_the_largest_and_stops_at_an_infeasible_speed() -> None:
    sigmas = {200.0: 20.0, 260.0: 26.0, 320.0: 23.0}
    asked: list[float] = []

    def evaluate(speed_kmh: float) -> Evaluation:
        asked.append(speed_kmh)
        return _evaluation(speed_kmh in sigmas, sigmas.get(speed_kmh, 30.0))

    result = evaluate_over_speeds(evaluate, (200.0, 260.0, 320.0))
    assert result.feasible and result.reason == "" and result.wall_time == 6.0
    assert result.sigma() == pytest.approx(23.0) and result.sigma(worst=True) == 26.0
    asked.clear()
    result = evaluate_over_speeds(evaluate, (200.0, 300.0, 320.0))
    assert asked == [200.0, 300.0]  # decided at 300 km/h: 320 km/h is not simulated
    assert not result.feasible and result.sigma() is None
    assert result.reason == "at 300 km/h: dynamic: contact lost"
    assert evaluate_over_speeds(evaluate, (300.0,)).reason == "dynamic: contact lost"  # one speed
    with pytest.raises(ValueError, match="speeds_kmh"):
        evaluate_over_speeds(evaluate, ())


# ---------------------------------------------------------------------------------------------------------
# Designs


def test_b1_moves_heights_on_the_presets_droppers() -> None:
    problem = PROBLEMS["B1"]
    design = problem.design([0.001, 0.002, 0.003, 0.004, -0.005])
    assert design.dropper_positions == load_catenary("benchmark").dropper_positions
    assert design.contact_wire_offsets == (0.001, 0.002, 0.003, 0.004, -0.005, 0.004, 0.003, 0.002, 0.001)


def test_b2_moves_droppers_over_a_level_wire() -> None:
    design = PROBLEMS["B2"].design([1.0, 8.0, 14.0, 20.0])
    assert design.dropper_positions == (1.0, 8.0, 14.0, 20.0, 27.5, 35.0, 41.0, 47.0, 54.0)
    assert design.contact_wire_offsets == (0.0,) * 9


def test_b3_has_five_droppers_with_heights() -> None:
    design = PROBLEMS["B3"].design([5.0, 20.0, -0.01, 0.0, 0.005])
    assert design.dropper_positions == (5.0, 20.0, 27.5, 35.0, 50.0)
    assert design.contact_wire_offsets == (-0.01, 0.0, 0.005, 0.0, -0.01)


def test_sw3_has_five_droppers_with_heights() -> None:
    design = PROBLEMS["SW3"].design([3.0, 20.0, 0.01, 0.0, -0.003])
    assert design.dropper_positions == (3.0, 20.0, 32.5, 45.0, 62.0)
    assert design.contact_wire_offsets == (0.01, 0.0, -0.003, 0.0, 0.01)


@pytest.mark.parametrize("name", ["BPresag", "SWPresag"])
def test_presag_is_a_parabola_through_the_presets_droppers(name: str) -> None:
    problem = PROBLEMS[name]
    catenary = problem.catenary_definition
    design = problem.design([0.05])
    x = np.asarray(catenary.dropper_positions)
    length = catenary.span_length
    np.testing.assert_allclose(
        design.contact_wire_offsets, -4 * 0.05 * x * (length - x) / length**2, atol=1e-15
    )
    assert min(design.contact_wire_offsets) == pytest.approx(-0.05)  # s at the mid-span dropper


@pytest.mark.parametrize("name", list(SPEC_TABLE))
def test_reference_design_is_the_level_wire_on_the_presets_droppers(name: str) -> None:
    problem = PROBLEMS[name]
    catenary = problem.catenary_definition
    reference = problem.reference_design()
    assert reference.dropper_positions == catenary.dropper_positions
    assert reference.contact_wire_offsets == (0.0,) * len(catenary.dropper_positions)
    x = problem.reference_x()
    if problem.n_droppers != len(catenary.dropper_positions):  # B3, SW3 remove droppers
        assert x is None
    else:
        assert x is not None
        assert problem.design(x) == reference


def test_reference_x_of_the_height_problems_is_zero() -> None:
    for name in ("B1", "SW1", "BPresag", "SWPresag"):
        np.testing.assert_array_equal(PROBLEMS[name].reference_x(), 0.0)


def test_sw3_upper_d1_puts_dropper_1_at_the_stitch_wire_end() -> None:
    # The one corner of a box that the catenary cannot build: SW3 bounds d_1 by 9 m, the stitch wire's
    # half-length, and dropper 1 must hang from the stitch wire (strictly inside it).
    problem = PROBLEMS["SW3"]
    with pytest.raises(DesignError, match="stitch wire"):
        check_design(problem.catenary_definition, problem.design([9.0, 20.0, 0.0, 0.0, 0.0]))
    check_design(problem.catenary_definition, problem.design([8.99, 20.0, 0.0, 0.0, 0.0]))


def test_invalid_design_in_bounds_is_infeasible_without_simulating(monkeypatch: pytest.MonkeyPatch) -> None:
    # Replaces the simulator to show that it is not called (and the uplift force to avoid calibrating).
    clear_caches()
    monkeypatch.setattr(pipeline, "calibrate_uplift", lambda *args, **kwargs: 160.0)

    def no_simulation(*args: object, **kwargs: object) -> Evaluation:
        raise AssertionError("an invalid design must not be simulated")

    monkeypatch.setattr(pipeline, "evaluate", no_simulation)
    monkeypatch.setattr(pipeline, "evaluate_unchecked", no_simulation)
    monkeypatch.setattr(pipeline, "evaluate_speeds_unchecked", no_simulation)
    try:
        evaluation = PROBLEMS["SW3"].evaluate([9.0, 20.0, 0.0, 0.0, 0.0], 300.0, "test")
    finally:
        clear_caches()  # the fake uplift must not reach other tests
    assert not evaluation.feasible
    assert evaluation.reason.startswith("design:")
    assert evaluation.statistics is None
    assert evaluation.uplift_force == 160.0


# ---------------------------------------------------------------------------------------------------------
# Evaluation plumbing


def test_out_of_bounds_or_bad_speed_is_refused_before_any_solve() -> None:
    with pytest.raises(ValueError, match="dh_2"):
        PROBLEMS["B1"].evaluate([0.0, 0.05, 0.0, 0.0, 0.0], 300.0, "test")
    with pytest.raises(ValueError, match="km/h"):
        PROBLEMS["B1"].evaluate([0.0] * 5, 500.0, "test")  # above the wave speed, 459.6 km/h
    with pytest.raises(ValueError, match="fidelity"):
        PROBLEMS["B1"].evaluate([0.0] * 5, 300.0, "fine")


def test_uplift_is_calibrated_once_per_catenary_speed_and_fidelity_on_the_reference(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Replaces the simulator: the subject is which calls the problems make, not their results.
    calls: list[tuple[str, Design, float, Fidelity, float]] = []
    used: list[float | None] = []

    def calibrate(catenary, pantograph, design, speed, fidelity, target_mean):  # type: ignore[no-untyped-def]
        calls.append((catenary.name, design, speed, fidelity, target_mean))
        return target_mean + 3.0

    def evaluate(catenary, pantograph, design, speed, fidelity, uplift_force=None, *options, train=None):  # type: ignore[no-untyped-def]
        used.append(uplift_force)
        return Evaluation(True, "", None, (), (), float(uplift_force), 0.0)

    def evaluate_speeds(catenary, pantograph, design, passages, fidelity, *options, train=None):  # type: ignore[no-untyped-def]
        return [evaluate(catenary, pantograph, design, v, fidelity, force) for v, force in passages]

    clear_caches()
    monkeypatch.setattr(pipeline, "calibrate_uplift", calibrate)
    monkeypatch.setattr(pipeline, "evaluate", evaluate)
    monkeypatch.setattr(pipeline, "evaluate_unchecked", evaluate)
    monkeypatch.setattr(pipeline, "evaluate_speeds_unchecked", evaluate_speeds)
    try:
        PROBLEMS["B1"].evaluate([0.0] * 5, 300.0, "test")
        PROBLEMS["B3"].evaluate(
            [5.0, 20.0, 0.0, 0.0, 0.0], 300.0, "test"
        )  # same catenary: no new calibration
        PROBLEMS["B2"].evaluate([1.0, 8.0, 14.0, 20.0], 250.0, "test")
        PROBLEMS["SW3"].evaluate([3.0, 20.0, 0.0, 0.0, 0.0], 300.0, FIDELITIES["test"])
        evaluate_problem("B1", (0.0,) * 5, 300.0, "test")
    finally:
        clear_caches()
    assert [(c[0], c[2] * 3.6) for c in calls] == [
        ("benchmark", pytest.approx(300.0)),
        ("benchmark", pytest.approx(250.0)),
        ("stitched", pytest.approx(300.0)),
    ]
    benchmark = load_catenary("benchmark")
    assert calls[0][1] == Design(
        benchmark.dropper_positions, (0.0,) * 9
    )  # B3 too uses the 9-dropper reference
    assert calls[0][4] == pytest.approx(157.3, abs=0.05)  # EN 50367 at 300 km/h
    assert used == [pytest.approx(c) for c in (160.3, 160.3, calls[1][4] + 3.0, 160.3, 160.3)]


def test_evaluate_problem_pickles_for_process_pools() -> None:
    assert pickle.loads(pickle.dumps(evaluate_problem)) is evaluate_problem


def test_resolve_fidelity() -> None:
    assert resolve_fidelity("test") is FIDELITIES["test"]
    assert resolve_fidelity("study", n_spans=12) == Fidelity(n_spans=12, analysis_spans=10)
    assert resolve_fidelity("study", n_spans=8).analysis_spans == 6  # shrinks to n_spans - 2
    assert resolve_fidelity("test", n_spans=5) == FIDELITIES["test"]
    for bad in (2, 0, 4.5, True):
        with pytest.raises(ValueError, match="n_spans"):
            resolve_fidelity("test", n_spans=bad)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------------------------------------
# Registry


def test_registry_refuses_duplicates() -> None:
    registry = ProblemRegistry()
    registry["B1"] = PROBLEMS["B1"]
    with pytest.raises(ValueError, match="already registered"):
        registry["B1"] = PROBLEMS["B1"]
    with pytest.raises(ValueError, match="already registered"):
        registry.update({"B1": PROBLEMS["B1"]})
    with pytest.raises(ValueError, match="already registered"):
        registry |= {"B1": PROBLEMS["B1"]}
    with pytest.raises(ValueError, match="named"):
        registry["B9"] = PROBLEMS["B2"]
    assert registry.setdefault("B1", PROBLEMS["B2"]) is PROBLEMS["B1"]
    with pytest.raises(ValueError, match="already registered"):
        register_problem(PROBLEMS["SW1"])  # the package's registry too
    assert list(PROBLEMS) == list(SPEC_TABLE)


def test_unknown_problem_names_the_available_ones() -> None:
    with pytest.raises(KeyError, match="did you mean 'B1'"):
        get_problem("b1")


# ---------------------------------------------------------------------------------------------------------
# Conformance: every registered problem, no skip list


@pytest.mark.parametrize("name", list(PROBLEMS))
def test_every_problem_conforms(name: str) -> None:
    problem = PROBLEMS[name]
    catenary = problem.catenary_definition
    length = catenary.span_length
    n = problem.n_variables
    assert problem.name == name and problem.description
    assert len(problem.units) == len(problem.lower) == len(problem.upper) == len(problem.step) == n
    assert np.all(problem.lower < problem.upper)
    np.testing.assert_array_equal(problem.snap(problem.lower), problem.lower)  # bounds on the grid
    np.testing.assert_array_equal(problem.snap(problem.upper), problem.upper)
    inside = random_grid_points(problem, 50, seed=1)
    inside = np.clip(
        inside, problem.lower + problem.step, problem.upper - problem.step
    )  # off the box's faces
    corners = np.array(list(itertools.product(*zip(problem.lower, problem.upper, strict=True))))
    for x in np.concatenate([inside, corners, [0.5 * (problem.lower + problem.upper)]]):
        design = problem.design(x)
        positions = np.asarray(design.dropper_positions)
        offsets = np.asarray(design.contact_wire_offsets)
        assert design.n_droppers == problem.n_droppers
        np.testing.assert_allclose(positions, length - positions[::-1], atol=1e-12)  # symmetric spans
        np.testing.assert_allclose(offsets, offsets[::-1], atol=1e-12)
        if problem.n_droppers % 2:
            assert positions[problem.n_droppers // 2] == 0.5 * length  # the mid-span dropper never moves
        assert np.all(np.diff(positions) > 0.05) and 0.0 < positions[0]
        is_corner = bool(np.any(x == problem.lower) or np.any(x == problem.upper))
        try:
            check_design(catenary, design)
        except DesignError:
            assert is_corner, f"{name}: design inside the bounds refused: {x}"
    check_design(catenary, problem.reference_design())
    x_reference = problem.reference_x()
    assert x_reference is None or problem.design(x_reference) == problem.reference_design()
