"""The contract every registered optimiser keeps, the built-in ones, the model-based ones and an installed
package's (docs/problems.md, 'Optimisers'): the budget is kept, the same seed gives the same history,
every point is on the grid, and a run killed part-way resumes to the uninterrupted result."""

from __future__ import annotations

import dataclasses
import functools
import importlib.metadata
import importlib.util
from dataclasses import dataclass

import numpy as np
import pytest

from catenary_env.cli import main
from optimizers import OPTIMIZERS, RunStore, optimize
from optimizers.base import Optimizer
from optimizers.plugins import ENTRY_POINT_GROUP, get_optimizer, load_plugins
from optimizers.problem import GridSpace, Outcome
from optimizers.synthetic import QuadraticProblem, get_synthetic_problem, simulate_quadratic

BUDGET = 16  # past the model-based samplers' 10 random start-up trials, and cheap for the GP
PROBLEM = get_synthetic_problem("synthetic-quadratic")
NEEDS = {"cma": "nevergrad", "de": "nevergrad", "pso": "nevergrad", "random": "nevergrad",
         "twopointsde": "nevergrad", "oneplusone": "nevergrad", "ngopt": "nevergrad", "tpe": "optuna",
         "gp": "torch"}  # fmt: skip


class StepSearch(Optimizer):
    """Coordinate steps from the grid's centre, a plug-in's optimiser for the tests."""

    name = "stepsearch"

    def __init__(self, space, budget, seed, options=None):
        super().__init__(space, budget, seed)
        self._rng = np.random.default_rng(seed)
        self._best = (self.n_levels - 1) // 2
        self._best_loss = np.inf

    def _internal_ask(self):
        step = self._rng.integers(-3, 4, size=(4, len(self.n_levels)))
        return np.clip(self._best + step, 0, self.n_levels - 1)

    def _internal_tell(self, points, losses):
        if np.min(losses) < self._best_loss:
            self._best, self._best_loss = points[int(np.argmin(losses))], float(np.min(losses))


class _EntryPoint:
    name = "stepsearch"
    value = "test_optimizer_contract:StepSearch"
    group = ENTRY_POINT_GROUP

    def load(self):
        return StepSearch


@pytest.fixture
def plugged_in(monkeypatch):
    """An installed package declaring StepSearch in the entry-point group (importlib.metadata patched)."""
    real = importlib.metadata.entry_points

    def entry_points(**selection):
        if selection.get("group") == ENTRY_POINT_GROUP:
            return [_EntryPoint()]
        return real(**selection)

    monkeypatch.setattr(importlib.metadata, "entry_points", entry_points)
    yield
    OPTIMIZERS.pop("stepsearch", None)


def _names():
    return sorted([*OPTIMIZERS, "stepsearch"])


def _available(name):
    module = NEEDS.get(name)
    if module is not None and importlib.util.find_spec(module) is None:
        pytest.skip(f"{name} needs {module}")


class Interrupted(Exception):
    pass


@dataclass(frozen=True, eq=False)
class KilledAfter(QuadraticProblem):
    """The synthetic problem (same name, so the same store key) whose simulation dies after ``n_calls``."""

    n_calls: int = 0

    @property
    def simulate(self):
        return functools.partial(_die_after, self, [0])


def _die_after(problem, calls, x, speed_kmh, fidelity) -> Outcome:
    calls[0] += 1
    if calls[0] > problem.n_calls:
        raise Interrupted
    return simulate_quadratic(problem, x, speed_kmh, fidelity)


def _comparable(history):
    return [dataclasses.replace(record, wall_time=0.0) for record in history]


@pytest.mark.parametrize("name", _names())
def test_every_optimizer_keeps_the_contract(name, plugged_in, tmp_path):
    _available(name)
    spec = get_optimizer(name)  # the plug-in is found through the entry-point group
    assert spec.name == name
    first = optimize(PROBLEM, name, budget=BUDGET, seed=5, fidelity="test")
    again = optimize(PROBLEM, name, budget=BUDGET, seed=5, fidelity="test")
    # the budget: never more charged simulations than allowed, and each charged one a new design
    charged = [record for record in first.history if record.charged]
    assert first.n_simulations == len(charged) <= BUDGET
    assert len({record.x for record in charged}) == len(charged)
    # the same seed, the same history (constraint values included)
    assert _comparable(first.history) == _comparable(again.history)
    # on the grid, with the problem's constraint value beside σ
    space = GridSpace.from_problem(PROBLEM)
    for record in first.history:
        assert np.allclose(space.snap(record.x), record.x, atol=1e-12, rtol=0.0)
        assert len(record.constraints) == 1 and (record.constraints[0] <= 1e-12) == record.feasible
    # killed after 7 simulations, resumed: the uninterrupted result
    store = tmp_path / "runs.sqlite"
    with pytest.raises(Interrupted):
        optimize(KilledAfter(**vars(PROBLEM), n_calls=7), name, budget=BUDGET, seed=5, fidelity="test",
                 store=store)  # fmt: skip
    with RunStore(store) as opened:
        assert opened.count_evaluations() >= 7
    resumed = optimize(PROBLEM, name, budget=BUDGET, seed=5, fidelity="test", store=store, resume=True)
    assert _comparable(resumed.history) == _comparable(first.history)


def test_a_plugged_in_optimizer_runs_on_the_command_line(plugged_in, tmp_path, capsys):
    argv = ["optimize", "synthetic-quadratic", "--optimizer", "stepsearch", "--budget", "12", "--store",
            str(tmp_path / "runs.sqlite"), "--workers", "1", "--quiet"]  # fmt: skip
    assert main(argv) == 0
    assert "best sigma" in capsys.readouterr().out


def test_an_unknown_optimizer_is_one_line_naming_those_available(capsys):
    argv = ["optimize", "synthetic-quadratic", "--optimizer", "nosuch", "--budget", "5", "--store",
            ":memory:", "--workers", "1"]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "nosuch" in err and "ga" in err and len(err.strip().splitlines()) == 1


def test_a_broken_entry_point_is_skipped_with_a_warning(monkeypatch):
    class Broken(_EntryPoint):
        name = "broken"

        def load(self):
            return object()

    monkeypatch.setattr(importlib.metadata, "entry_points", lambda **selection: [Broken()])
    with pytest.warns(UserWarning, match="broken"):
        assert load_plugins() == ()
    assert "broken" not in OPTIMIZERS
