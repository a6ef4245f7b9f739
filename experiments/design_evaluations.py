"""Given designs simulated through a run store, and the mean-σ-over-speeds objective as a problem.

The studies compare designs that no optimiser asks for (the reference design at each speed, an optimum
at other speeds, a policy's design): :func:`evaluate_designs` serves them from the run store's cache where
any run of the store simulated them, and simulates the rest, committing each result to the store as a run
of its own (``"given-designs"``, one per problem and fidelity), so that a study run again, or another
study on the same store, simulates nothing twice.

:class:`MeanSigmaProblem` poses the environments' ``objective="mean_sigma_over_speeds"``
(docs/problems.md, 'Environments') as an optimisation problem for :func:`optimizers.runner.optimize`: one
evaluation simulates the design at every speed and returns the mean σ; the design is infeasible where it
is infeasible at any speed (one definition, :mod:`catenary_env.problems.speeds`, for both).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from catenary_env.problems import get_problem
from catenary_env.problems.design_problem import DesignProblem
from optimizers.base import EvaluationRecord
from optimizers.catenary_adapter import catenary_problem
from optimizers.evaluation import make_backend
from optimizers.problem import GridProblem, GridSpace, Outcome, SimulateFunction
from optimizers.problem_registry import resolve_problem
from optimizers.recorder import package_version
from optimizers.store import RunConfig, RunStore
from optimizers.synthetic import SYNTHETIC_PROBLEMS, QuadraticProblem

__all__ = [
    "GIVEN_DESIGNS",
    "MeanSigmaProblem",
    "evaluate_designs",
    "mean_sigma_problem",
    "simulate_mean_sigma",
    "stored_outcome",
    "study_problem",
]

GIVEN_DESIGNS = "given-designs"
"""The run under which :func:`evaluate_designs` stores its simulations (the store's ``optimizer`` column)."""


def evaluate_designs(
    store: RunStore,
    problem: str | GridProblem,
    requests: Sequence[tuple[Sequence[float], float]],
    fidelity: str,
    n_workers: int = 1,
) -> list[Outcome]:
    """The outcomes of designs of a problem at speeds, from the store's cache or simulated.

    Parameters
    ----------
    store : RunStore
        Its cache is read; the new simulations are written to it.
    problem : str or GridProblem
        A catenary design problem (docs/problems.md, 'The eight problems') or a synthetic one
        (``optimizers/synthetic.py``), or the problem itself (one at another contact-wire tension).
    requests : sequence of (x, speed_kmh)
        Designs (variables, m, on the grid) and the speed of each, km/h.
    fidelity : str
        ``"study"``, ``"test"`` or ``"reference"``.
    n_workers : int
        Local worker processes for the simulations.

    Returns
    -------
    list of Outcome
        In the order of ``requests``.
    """
    resolved = resolve_problem(problem) if isinstance(problem, str) else problem
    space = GridSpace.from_problem(resolved)
    outcomes: dict[int, Outcome] = {}
    missing: dict[tuple[tuple[int, ...], float], list[int]] = {}
    for position, (x, speed) in enumerate(requests):
        key = space.design_key(space.snap(x))
        found = store.lookup(space.store_key, key, float(speed), fidelity)
        if found is not None:
            outcomes[position] = found
        else:
            missing.setdefault((key, float(speed)), []).append(position)
    if missing:
        config = RunConfig(
            GIVEN_DESIGNS, space.store_key, 0, 0, None, fidelity, json.dumps({}), package_version()
        )
        run_id = store.find_run(config) or store.start_run(config)
        index = store.count_evaluations(run_id)
        keys = list(missing)
        arguments = [(tuple(space.snap(requests[missing[k][0]][0]).tolist()), k[1], fidelity) for k in keys]
        with make_backend(n_workers) as backend:
            for number, outcome in backend.run(resolved.simulate, arguments):
                x, speed, _ = arguments[number]
                record = EvaluationRecord(
                    index, x, outcome.feasible, outcome.sigma, outcome.reason, outcome.wall_time,
                    cached=False, charged=True, speed_kmh=speed,
                )  # fmt: skip
                store.add_evaluation(run_id, space.store_key, fidelity, keys[number][0], record)
                index += 1
                for position in missing[keys[number]]:
                    outcomes[position] = outcome
    return [outcomes[position] for position in range(len(requests))]


def stored_outcome(
    store: RunStore, problem: str, x: Sequence[float], speed_kmh: float, fidelity: str
) -> Outcome | None:
    """The outcome of a design (variables, m) of a problem at a speed (km/h) where any run of the store
    simulated it, else None: :func:`evaluate_designs` without simulating."""
    space = GridSpace.from_problem(resolve_problem(problem))
    return store.lookup(space.store_key, space.design_key(space.snap(x)), float(speed_kmh), fidelity)


def study_problem(problem: str) -> DesignProblem | QuadraticProblem:
    """A problem by name, as the studies read it (its ``reference_x()``, its ``n_variables``; no model
    fingerprint, so that a report reads it without simulating): a synthetic problem
    (``optimizers/synthetic.py``), else a catalogue one (docs/problems.md, 'The eight problems')."""
    return SYNTHETIC_PROBLEMS[problem] if problem in SYNTHETIC_PROBLEMS else get_problem(problem)


def simulate_mean_sigma(
    problem: str, speeds_kmh: tuple[float, ...], x: tuple[float, ...], speed_kmh: float, fidelity: str
) -> Outcome:
    """The mean σ of a design over ``speeds_kmh``
    (:meth:`~catenary_env.problems.DesignProblem.evaluate_speeds`): picklable, for worker processes.

    ``speed_kmh`` (the driver's) is not used: the speeds are the problem's.
    """
    result = get_problem(problem).evaluate_speeds(x, speeds_kmh, fidelity)
    return Outcome(result.feasible, result.sigma(), result.reason, result.wall_time)


@dataclass(frozen=True, eq=False)
class MeanSigmaProblem:
    """A catenary design problem whose objective is the mean σ over several speeds (a :class:`GridProblem`).

    Attributes
    ----------
    base : str
        The design problem, e.g. ``"B1"``.
    speeds_kmh : tuple of float
        The speeds the mean is taken over, km/h.
    name : str
        ``"{base}-mean-sigma-{lowest}-{highest}-{count}"``: the store key of its evaluations.
    variable_names : tuple of str
        The base problem's variables.
    lower, upper, step : ndarray
        The base problem's bounds and grid, m.
    model_fingerprint : str
        The base problem's.
    """

    base: str
    speeds_kmh: tuple[float, ...]
    name: str
    variable_names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    step: NDArray[np.float64]
    model_fingerprint: str

    @property
    def simulate(self) -> SimulateFunction:
        return functools.partial(simulate_mean_sigma, self.base, self.speeds_kmh)


def mean_sigma_problem(base: str, speeds_kmh: Sequence[float]) -> MeanSigmaProblem:
    """The problem ``base`` with the mean σ over ``speeds_kmh`` as its objective."""
    speeds = tuple(float(v) for v in speeds_kmh)
    if not speeds:
        raise ValueError("speeds_kmh: give at least one speed, km/h")
    problem = catenary_problem(base)
    name = f"{base}-mean-sigma-{min(speeds):g}-{max(speeds):g}-{len(speeds)}"
    return MeanSigmaProblem(
        base, speeds, name, problem.variable_names, problem.lower, problem.upper, problem.step,
        problem.model_fingerprint,
    )  # fmt: skip
