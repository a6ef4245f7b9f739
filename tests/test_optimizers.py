"""Optimisers: the common contract, the GA's operators and stop rule, the run store and its cache.

Synthetic problems only (optimizers.synthetic): no physics here.
"""

from __future__ import annotations

import dataclasses
import functools
import io
import sqlite3
import subprocess
import sys
from dataclasses import dataclass

import numpy as np
import pytest
from conftest import requires

from catenary_env.cli.progress import ProgressDisplay
from optimizers import OPTIMIZERS, GridSpace, Outcome, RunStore, StoreError, optimize
from optimizers.base import OptimizerSpec, register_optimizer
from optimizers.ga import (
    GAOptions,
    GeneticAlgorithm,
    average_relative_change,
    elite_indices,
    integer_truncation,
    laplace_crossover,
    penalty_scores,
    power_mutation,
    rank_expectation,
    stochastic_uniform,
    total_violation,
)
from optimizers.nevergrad_adapters import NevergradOptimizer, NGOpt, ngopt_fault
from optimizers.synthetic import QuadraticProblem, get_synthetic_problem, simulate_quadratic


def optimizer_param(name: str) -> object:
    """An optimiser's name as a test parameter, skipped where nevergrad (the optim extra) is missing."""
    if issubclass(OPTIMIZERS[name].optimizer_class, NevergradOptimizer):
        return pytest.param(name, marks=requires("nevergrad"))
    return name


QUADRATIC = get_synthetic_problem("synthetic-quadratic")


def _comparable(history):
    """A history without wall times (the only field that may differ between two identical runs)."""
    return [dataclasses.replace(record, wall_time=0.0) for record in history]


# -- every registered optimiser: one contract, no skip list ---------------------------------------------


@pytest.mark.parametrize("name", [optimizer_param(name) for name in sorted(OPTIMIZERS)])
def test_optimizer_respects_budget_and_is_reproducible(name):
    budget = 24
    first = optimize(QUADRATIC, name, budget=budget, seed=5, fidelity="test")
    second = optimize(QUADRATIC, name, budget=budget, seed=5, fidelity="test")
    assert first.n_simulations <= budget
    assert sum(record.charged for record in first.history) == first.n_simulations
    if first.stop_reason == "budget":
        assert first.n_simulations == budget
    assert _comparable(first.history) == _comparable(second.history)
    assert first.best_sigma == second.best_sigma
    space = GridSpace.from_problem(QUADRATIC)
    for record in first.history:
        assert np.array_equal(space.snap(record.x), np.array(record.x))  # on the grid, within the bounds
    assert first.feasible and first.best_sigma == min(r.sigma for r in first.history if r.feasible)


@pytest.mark.parametrize("name", [optimizer_param(name) for name in sorted(OPTIMIZERS)])
def test_optimizer_depends_on_seed(name):
    a = optimize(QUADRATIC, name, budget=16, seed=1, fidelity="test")
    b = optimize(QUADRATIC, name, budget=16, seed=2, fidelity="test")
    assert [r.x for r in a.history] != [r.x for r in b.history]


def test_registry_refuses_duplicates():
    with pytest.raises(ValueError, match="already registered"):
        register_optimizer(OptimizerSpec("ga", GeneticAlgorithm, GAOptions, "again"))
    with pytest.raises(ValueError, match="already registered"):
        OPTIMIZERS.update({"cma": OPTIMIZERS["cma"]})


@requires("nevergrad")
def test_ngopt_selects_a_working_optimizer_on_the_grid():
    assert "ngopt" in OPTIMIZERS  # and the contract tests above run it
    for n in (1, 3, 5):
        space = GridSpace("grid", tuple("abcde"[:n]), np.zeros(n), np.full(n, 40.0), np.ones(n))
        assert "MetaModel" not in NGOpt(space, budget=500, seed=0).selected_optimizer


@pytest.mark.filterwarnings("ignore:num_workers")
def test_ngopt_fault_is_real_where_reported():
    """The documented fault: NGOpt on a continuous 4-variable space picks MetaModel, which fails."""
    if ngopt_fault() is None:
        pytest.skip("no NGOpt fault reported for the installed nevergrad and numpy")
    ng = pytest.importorskip("nevergrad")
    parametrization = ng.p.Array(shape=(4,), lower=-1.0, upper=1.0)
    parametrization.random_state = np.random.RandomState(0)
    optimizer = ng.optimizers.NGOpt(parametrization=parametrization, budget=200, num_workers=4)
    with pytest.raises(TypeError, match="0-dimensional"):
        optimizer.minimize(lambda x: float(np.sum((x - 0.3) ** 2)))


def test_ask_tell_contract_is_checked():
    optimizer = GeneticAlgorithm(GridSpace.from_problem(QUADRATIC), budget=10, seed=0)
    points = optimizer.ask()
    with pytest.raises(RuntimeError, match="tell the previous batch"):
        optimizer.ask()
    with pytest.raises(RuntimeError, match="exactly the batch"):
        optimizer.tell(points[:-1], np.zeros(len(points) - 1))


# -- the genetic algorithm: operators --------------------------------------------------------------------


def test_rank_expectation_scales_by_rank_and_excludes_infeasible():
    losses = np.array([3.0, np.inf, 1.0, 2.0, np.inf])
    expectation = rank_expectation(losses, n_parents=10)
    assert expectation.sum() == pytest.approx(10.0)
    assert expectation[1] == expectation[4] == 0.0
    raw = np.array([1 / np.sqrt(3), 0.0, 1.0, 1 / np.sqrt(2), 0.0])  # 1 / sqrt(rank)
    assert expectation == pytest.approx(10 * raw / raw.sum())
    assert rank_expectation(np.full(4, np.inf), 6) == pytest.approx(np.full(4, 1.5))
    # No feasible individual: MATLAB's penalty ranks them by their total violation (unknown ones last).
    violations = np.array([0.5, np.nan, 0.1, 2.0])
    expectation = rank_expectation(np.full(4, np.inf), 6, violations)
    raw = np.array([1 / np.sqrt(2), 0.0, 1.0, 1 / np.sqrt(3)])
    assert expectation == pytest.approx(6 * raw / raw.sum())
    assert rank_expectation(np.full(2, np.inf), 6, np.full(2, np.nan)) == pytest.approx([3.0, 3.0])


def test_the_penalty_is_the_worst_feasible_loss_plus_the_total_violation():
    assert total_violation((-1.0, 0.25, np.nan, 0.5)) == pytest.approx(0.75)
    assert total_violation((-1.0,)) == 0.0 and np.isnan(total_violation((np.nan,)))
    losses = np.array([3.0, np.inf, 1.0, np.inf])
    scores = penalty_scores(losses, np.array([0.0, 0.5, 0.0, np.nan]))
    assert scores == pytest.approx([3.0, 3.5, 1.0, np.inf])
    assert penalty_scores(np.full(2, np.inf), np.array([0.2, 0.1])) == pytest.approx([0.2, 0.1])


class _CountingRng:
    """A numpy Generator that counts its uniform draws."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)
        self.calls = 0

    def random(self, size=None):
        self.calls += 1
        return self.rng.random(size)


def test_stochastic_uniform_counts_follow_expectation():
    expectation = np.array([2.6, 0.0, 1.3, 0.7, 3.4])  # sums to 8 parents
    counts = np.zeros(5)
    n_draws = 4000
    for seed in range(n_draws):
        rng = _CountingRng(seed)
        selected = stochastic_uniform(expectation, 8, rng)
        assert rng.calls == 1  # one random start...
        count = np.bincount(selected, minlength=5)
        # ...and equally spaced pointers: each count is floor(e) or ceil(e)
        assert np.all(count >= np.floor(expectation)) and np.all(count <= np.ceil(expectation))
        assert np.all(np.diff(selected) >= 0)
        counts += count
    assert counts / n_draws == pytest.approx(expectation, abs=0.03)


def test_stochastic_uniform_pointers_are_equally_spaced():
    class Fixed:
        def random(self, size=None):
            return 0.5

    # wheel ends: 0.25, 0.5, 1.0; pointers at (0.5 + i) / 4 = 0.125, 0.375, 0.625, 0.875
    selected = stochastic_uniform(np.array([1.0, 1.0, 2.0]), 4, Fixed())
    assert selected.tolist() == [0, 1, 2, 2]


def test_integer_truncation_is_floor_or_ceiling_with_equal_odds():
    rng = np.random.default_rng(0)
    values = np.full(20000, 3.3)
    result = integer_truncation(values, rng)
    assert set(np.unique(result)) == {3, 4}
    assert np.mean(result == 4) == pytest.approx(0.5, abs=0.02)
    assert integer_truncation(np.array([2.0, -1.0]), rng).tolist() == [2, -1]  # integers stay


def test_laplace_crossover_stays_on_grid_around_the_first_parent():
    rng = np.random.default_rng(1)
    n_levels = np.array([41, 41, 100_001])
    m = 20000
    first = np.tile([10, 40, 50_000], (m, 1))
    second = np.tile([30, 0, 51_000], (m, 1))
    children = laplace_crossover(first, second, n_levels, rng, location=0.0, scale=0.35)
    assert children.dtype.kind == "i"
    assert np.all(children >= 0) and np.all(children <= n_levels - 1)
    # Around the first parent, spread b |p1 - p2| (E|beta| = b for a Laplace of scale b), symmetric:
    offsets = (children[:, 2] - 50_000) / 1000.0
    assert np.mean(np.abs(offsets)) == pytest.approx(0.35, abs=0.02)
    assert np.mean(offsets) == pytest.approx(0.0, abs=0.02)
    # A gene on which the parents agree is inherited.
    same = laplace_crossover(np.array([[7, 3]]), np.array([[7, 9]]), np.array([41, 41]), rng)
    assert same[0, 0] == 7


def test_power_mutation_stays_on_grid_within_bounds():
    rng = np.random.default_rng(2)
    n_levels = np.array([41, 121])
    parents = np.tile([20, 60], (5000, 1))
    mutants = power_mutation(parents, n_levels, rng, index=4.0)
    assert mutants.dtype.kind == "i"
    assert np.all(mutants >= 0) and np.all(mutants <= n_levels - 1)
    assert np.any(mutants[:, 0] < 20) and np.any(mutants[:, 0] > 20)  # both directions
    # s has the power distribution of index 4 (mean 4/5): from mid-range the mean jump is 0.8 x 20 levels.
    assert np.mean(np.abs(mutants[:, 0] - 20)) == pytest.approx(0.8 * 20, abs=0.6)
    on_bounds = power_mutation(np.array([[0, 120]] * 100), n_levels, rng)
    assert np.all(on_bounds == [0, 120])  # a gene on a bound stays (documented)


def test_elitism_keeps_the_best_three_unchanged():
    space = GridSpace.from_problem(QUADRATIC)
    ga = GeneticAlgorithm(space, budget=10_000, seed=3, options=GAOptions(population_size=20))
    loss = functools.partial(_quadratic_losses, QUADRATIC, space)
    points = ga.ask()
    ga.tell(points, loss(points))
    for _ in range(5):
        assert ga.population is not None and ga.losses is not None
        best = elite_indices(ga.losses, 3)
        elite_points, elite_losses = ga.population[best].copy(), ga.losses[best].copy()
        children = ga.ask()
        assert len(children) == 17  # 20 - 3 elite: the elite is not re-evaluated
        ga.tell(children, loss(children))
        assert np.array_equal(ga.population[:3], elite_points)
        assert np.array_equal(ga.losses[:3], elite_losses)
        assert np.min(ga.losses) <= np.min(elite_losses)


def test_generation_split_follows_crossover_fraction():
    space = GridSpace.from_problem(QUADRATIC)
    ga = GeneticAlgorithm(space, budget=1000, seed=0, options=GAOptions(population_size=15))
    points = ga.ask()
    ga.tell(points, _quadratic_losses(QUADRATIC, space, points))
    assert len(ga.ask()) == 12  # round(0.8 x 12) = 10 by crossover, 2 by mutation


def _quadratic_losses(problem: QuadraticProblem, space: GridSpace, points: np.ndarray) -> np.ndarray:
    x = np.array([space.to_design(k) for k in points])
    return np.where(problem.feasible(x), problem.sigma(x), np.inf)


def test_average_relative_change():
    assert average_relative_change([5.0, 4.0], window=2) == np.inf  # window not yet full
    assert average_relative_change([9.0, 3.0, 1.0, 1.0], window=2) == pytest.approx((2 / 4 + 0) / 2)
    assert average_relative_change([np.inf, 1.0, 1.0], window=2) == np.inf


# -- the genetic algorithm: search and stop rule --------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ga_finds_the_constrained_optimum_and_stops_by_stall(seed):
    x_best, sigma_best = QUADRATIC.grid_optimum()
    result = optimize(QUADRATIC, "ga", budget=10_000, seed=seed, fidelity="test")
    assert result.stop_reason == "stall"
    assert result.n_simulations < 10_000
    assert result.best_sigma == pytest.approx(sigma_best)
    assert np.allclose(result.best_x, x_best)
    assert any(not record.feasible for record in result.history)  # the constraint was met on the way


def test_ga_with_no_feasible_design_closes_in_on_the_constraint_and_stalls():
    # x1 + x3 <= -0.05 m cannot be met within the bounds (at best -0.04 m): the GA follows MATLAB's penalty,
    # the smallest violation, to the corner that comes closest, and stops by stall, not by the budget.
    impossible = dataclasses.replace(QUADRATIC, name="synthetic-impossible", limit=-0.05)
    result = optimize(impossible, "ga", budget=10_000, seed=0, fidelity="test")
    assert result.stop_reason == "stall" and result.n_simulations < 10_000
    assert result.best_x is None and not any(record.feasible for record in result.history)
    closest = min(record.constraints[0] for record in result.history)
    assert closest == pytest.approx(0.01)


def test_ga_population_sizes_of_the_study():
    sizes = {"BPresag": 15, "B1": 100, "B2": 80, "B3": 100, "SWPresag": 15, "SW1": 80, "SW2": 60, "SW3": 100}
    for name, size in sizes.items():
        space = GridSpace(name, ("a",), np.zeros(1), np.ones(1), np.full(1, 0.1))
        assert GeneticAlgorithm(space, budget=10, seed=0).population_size == size
    assert GeneticAlgorithm(GridSpace.from_problem(QUADRATIC), budget=10, seed=0).population_size == 50


def test_ga_stops_at_generation_limit():
    options = GAOptions(population_size=10, max_generations=4)
    result = optimize(QUADRATIC, "ga", budget=10_000, seed=0, options=options, fidelity="test")
    assert result.stop_reason == "generations"


# -- the run store ----------------------------------------------------------------------------------------


def test_corrupt_store_is_refused(tmp_path):
    path = tmp_path / "runs.sqlite"
    path.write_bytes(np.random.default_rng(0).bytes(4096))
    with pytest.raises(StoreError, match="not an SQLite database"):
        RunStore(path)
    assert path.read_bytes() == np.random.default_rng(0).bytes(4096)  # untouched
    with pytest.raises(StoreError, match="not an SQLite database"):
        optimize(QUADRATIC, "random", budget=5, seed=0, store=path)


def test_truncated_sqlite_store_is_refused(tmp_path):
    path = tmp_path / "runs.sqlite"
    RunStore(path).close()
    path.write_bytes(path.read_bytes()[:100] + b"\x00garbage" * 50)
    with pytest.raises(StoreError):
        RunStore(path)


def test_foreign_sqlite_file_is_refused(tmp_path):
    path = tmp_path / "other.sqlite"
    with sqlite3.connect(path) as connection:
        connection.execute("CREATE TABLE customers (name TEXT)")
    with pytest.raises(StoreError, match="not a catenary-env run store"):
        RunStore(path)


def test_other_schema_version_is_refused(tmp_path):
    path = tmp_path / "runs.sqlite"
    RunStore(path).close()
    with sqlite3.connect(path) as connection:
        connection.execute("PRAGMA user_version = 99")
    with pytest.raises(StoreError, match="schema version 99"):
        RunStore(path)


@requires("nevergrad")
def test_store_keeps_every_evaluation(tmp_path):
    path = tmp_path / "runs.sqlite"
    result = optimize(QUADRATIC, "de", budget=30, seed=0, store=path)
    with RunStore(path) as store:
        stored = store.evaluations(result.run_id)
        assert [stored[i].record for i in range(len(stored))] == list(result.history)
        (run,) = store.runs()
        assert run["stop_reason"] == "budget" and run["budget"] == 30


@dataclass(frozen=True, eq=False)
class _CountingProblem:
    """A synthetic problem whose simulations are counted (in-process only)."""

    inner: QuadraticProblem
    calls: list

    name = "synthetic-quadratic"

    @property
    def variable_names(self):
        return self.inner.variable_names

    @property
    def lower(self):
        return self.inner.lower

    @property
    def upper(self):
        return self.inner.upper

    @property
    def step(self):
        return self.inner.step

    @property
    def simulate(self):
        return self._simulate

    def _simulate(self, x, speed_kmh, fidelity) -> Outcome:
        self.calls.append(tuple(x))
        return simulate_quadratic(self.inner, x, speed_kmh, fidelity)


@requires("nevergrad")
def test_cache_simulates_a_grid_design_once(tmp_path):
    problem = _CountingProblem(QUADRATIC, [])
    path = tmp_path / "runs.sqlite"
    first = optimize(problem, "random", budget=20, seed=7, store=path)
    assert len(problem.calls) == 20
    # The same designs in a new run of the same store: served from the cache, still charged.
    again = optimize(problem, "random", budget=20, seed=7, store=path)
    assert len(problem.calls) == 20
    assert all(record.cached and record.charged for record in again.history)
    assert [r.sigma for r in again.history] == [r.sigma for r in first.history]
    # Another speed or fidelity is another evaluation.
    optimize(problem, "random", budget=20, seed=7, store=path, speed_kmh=250.0)
    assert len(problem.calls) == 40


def test_repeated_design_within_a_run_is_free():
    problem = _CountingProblem(QUADRATIC, [])
    result = optimize(problem, "ga", budget=300, seed=0)
    assert len(problem.calls) == result.n_simulations == len({r.x for r in result.history})
    repeats = [r for r in result.history if not r.charged]
    assert repeats and all(r.cached and r.wall_time == 0.0 for r in repeats)


def test_grid_keys_ignore_float_noise():
    space = GridSpace.from_problem(QUADRATIC)
    assert space.design_key([0.0030000001, -0.007, 0.009]) == space.design_key([0.003, -0.0069999999, 0.009])
    assert space.snap([0.0025, 0.5, -1.0]).tolist() == [0.003, 0.02, -0.02]  # ties up, clipped


@pytest.mark.parametrize("name", [optimizer_param(name) for name in ("ga", "cma", "de")])
def test_resume_replays_a_truncated_run(tmp_path, name):
    path = tmp_path / "runs.sqlite"
    full = optimize(QUADRATIC, name, budget=200, seed=4, store=path)
    # As if killed in the middle of a batch: the last evaluations, and one that was still in flight while
    # the next completed (unless the next is its duplicate, which is stored only with it).
    gap = 121 if full.history[122].x != full.history[121].x else 123
    with sqlite3.connect(path) as connection:
        connection.execute("DELETE FROM evaluations WHERE idx >= 123 OR idx = ?", (gap,))
    problem = _CountingProblem(QUADRATIC, [])
    resumed = optimize(problem, name, budget=200, seed=4, store=path, resume=True)
    assert resumed.run_id == full.run_id
    assert _comparable(resumed.history) == _comparable(full.history)
    lost = [r for r in full.history if r.index >= 123 or r.index == gap]
    assert len(problem.calls) == sum(r.charged and not r.cached for r in lost)


@requires("nevergrad")
def test_a_resumed_run_that_asks_another_design_branches_off_there(tmp_path, capsys):
    """A run resumed on another processor may ask another design than it stored (rounding turns a choice
    between near-equal designs): it keeps what it replayed, drops the rest and goes on from there."""
    path = tmp_path / "runs.sqlite"
    full = optimize(QUADRATIC, "random", budget=10, seed=4, store=path)
    with sqlite3.connect(path) as connection:
        connection.execute(
            "UPDATE evaluations SET design_key = '1,2,3' WHERE idx = 3 AND run_id = ?", (full.run_id,)
        )
        connection.execute("DELETE FROM evaluations WHERE idx > 5")
    problem = _CountingProblem(QUADRATIC, [])
    resumed = optimize(problem, "random", budget=10, seed=4, store=path, resume=True, quiet=False)
    assert "branches off its stored history at evaluation 3" in capsys.readouterr().err
    assert resumed.run_id == full.run_id
    assert _comparable(resumed.history) == _comparable(full.history)  # deterministic here: the same run
    assert len(problem.calls) == 7  # evaluations 3 to 9: 0-2 replayed, 4 and 5 dropped with 3
    with RunStore(path) as store:
        assert sorted(store.evaluations(full.run_id)) == list(range(10))


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_display_shows_best_sigma_on_a_terminal():
    terminal = _Terminal()
    display = ProgressDisplay("ga on B1", 100, "simulations", stream=terminal)
    display.update(40, "55 evaluations, best sigma 23.456 N", force=True)
    display.finish("stopped (budget)")
    assert "40/100 simulations" in terminal.getvalue() and "23.456 N" in terminal.getvalue()
    assert terminal.getvalue().startswith("\r")


def test_progress_display_writes_plain_periodic_lines_to_a_log():
    log = io.StringIO()
    display = ProgressDisplay("ga on B1", 100, "simulations", stream=log, interval=0.0)
    display.update(40, "55 evaluations, best sigma 23.456 N")
    display.update(60, "70 evaluations, best sigma 21.000 N")
    lines = log.getvalue().splitlines()
    assert len(lines) == 2 and "\r" not in log.getvalue()
    assert lines[1].startswith("ga on B1: 60/100 simulations, 70 evaluations, best sigma 21.000 N")
    assert "s elapsed" in lines[1] and "simulations/s" in lines[1]
    slow = io.StringIO()
    ProgressDisplay("x", 10, "simulations", stream=slow, interval=3600.0).update(1)
    assert slow.getvalue() == ""  # not yet time for a line


def test_quiet_silences_the_terminal_line_and_the_log_lines():
    terminal, log = _Terminal(), io.StringIO()
    for stream in (terminal, log):
        display = ProgressDisplay("x", 10, "simulations", quiet=True, stream=stream, interval=0.0)
        display.update(1, "1 evaluation", force=True)
        display.note("resuming")
        display.finish("stopped")
    assert terminal.getvalue() == log.getvalue() == ""


def test_a_run_logged_to_a_file_prints_progress_lines(tmp_path):
    command = [
        sys.executable, "-m", "catenary_env.cli", "optimize", "synthetic-quadratic-slow", "--budget", "60",
        "--workers", "1", "--store", str(tmp_path / "runs.sqlite"), "--progress-every", "0.05",
    ]  # fmt: skip
    log = tmp_path / "log.txt"
    with log.open("w") as stderr:
        subprocess.run(command, stdout=subprocess.DEVNULL, stderr=stderr, check=True, timeout=120)
    lines = log.read_text().splitlines()
    progress = [line for line in lines if line.startswith("ga on synthetic-quadratic-slow: ")]
    assert len(progress) >= 3, lines
    assert any("best sigma" in line and "simulations/s" in line for line in progress)
    assert "stopped (budget)" in lines[-1]
    quiet = subprocess.run([*command, "--quiet"], capture_output=True, text=True, check=True, timeout=120)
    assert quiet.stderr == ""


def test_resume_says_what_it_resumed_and_refuses_when_nothing_matches(tmp_path, capsys):
    from catenary_env.cli import main

    store = str(tmp_path / "runs.sqlite")
    command = ["optimize", "synthetic-quadratic", "--budget", "20", "--workers", "1", "--store", store]
    assert main([*command, "--seed", "1", "--quiet"]) == 0
    capsys.readouterr()
    assert main([*command, "--seed", "2", "--resume"]) == 2
    err = capsys.readouterr().err
    assert "no run to resume" in err and "run 1: ga on synthetic-quadratic" in err and store in err
    assert main([*command, "--seed", "1", "--resume"]) == 0
    assert "resuming run 1 of" in capsys.readouterr().err
    assert main([*command, "--seed", "2", "--resume-or-start", "--quiet"]) == 0
    assert "run 2 in" in capsys.readouterr().out


def test_unknown_problem_lists_the_choices():
    with pytest.raises(KeyError, match="synthetic-quadratic"):
        optimize("B9", "ga", budget=10, seed=0)


def test_bad_options_are_refused():
    with pytest.raises(TypeError, match="GAOptions"):
        optimize(QUADRATIC, "ga", budget=10, seed=0, options=object())
    with pytest.raises(KeyError, match="unknown optimizer"):
        optimize(QUADRATIC, "nope", budget=10, seed=0)
    with pytest.raises(ValueError, match="budget"):
        optimize(QUADRATIC, "ga", budget=0, seed=0)


@pytest.mark.parametrize(
    "module",
    [
        "base",
        "evaluation",
        "ga",
        "problem",
        pytest.param("runner", marks=requires("nevergrad")),
        "store",
        "synthetic",
        "rl",
        "__init__",
    ],
)
def test_docstring_examples_run(module):
    import doctest
    import importlib

    name = "optimizers" if module == "__init__" else f"optimizers.{module}"
    failures, _ = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert failures == 0
