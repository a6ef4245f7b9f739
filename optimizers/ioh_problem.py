"""A design problem as an IOHexperimenter problem, for users who run their own ``ioh`` loops
(``pip install catenary-env[ioh]``).

:func:`ioh_problem` wraps a problem (a catenary design problem or a synthetic one, by name) with
``ioh.wrap_problem`` as a *real* problem on the unit box ``[0, 1]^n``: variable ``u_i`` maps to
``lower_i + u_i (upper_i - lower_i)``, rounded to the problem's grid (heights 1 mm, positions 1 cm),
so any real-valued optimiser of IOH's ecosystem can search it. The objective is σ (N, minimised) of a
feasible design and :data:`INFEASIBLE_Y`, 10⁶ N, of an infeasible one,
the convention of the project's IOHprofiler files (:mod:`experiments.iohprofiler`). No optimum is
declared (the best-known σ, ``problem.best_known``, is not a proven optimum). Each call simulates (about
a second at the study fidelity); nothing is cached: for resumable, cached runs use
:func:`optimizers.optimize`.

Examples
--------
>>> problem = ioh_problem("synthetic-quadratic", fidelity="test")  # doctest: +SKIP
>>> problem([0.5, 0.5, 0.5])  # doctest: +SKIP
21.745
"""

from __future__ import annotations

from typing import Any

import numpy as np

from catenary_env.errors import MissingDependency

from .problem import GridSpace
from .problem_registry import resolve_problem

__all__ = ["INFEASIBLE_Y", "ioh_problem"]

INFEASIBLE_Y = 1.0e6
"""Objective of an infeasible design, N (the IOHprofiler files' convention)."""


def ioh_problem(name: str, speed_kmh: float = 300.0, fidelity: str = "study") -> Any:
    """The problem ``name`` as an ``ioh`` real problem on ``[0, 1]^n`` named ``catenary-NAME``.

    Parameters
    ----------
    name : str
        A catenary design problem (``"B1"``) or a synthetic one.
    speed_kmh : float
        Train speed, km/h.
    fidelity : str
        ``"study"`` or ``"test"``.

    Raises
    ------
    MissingDependency
        ``ioh`` is not installed.
    """
    try:
        import ioh
    except ImportError as error:
        raise MissingDependency("the ioh wrapper needs ioh: pip install catenary-env[ioh]") from error
    problem = resolve_problem(name)
    space = GridSpace.from_problem(problem)
    simulate = problem.simulate

    def sigma(u: np.ndarray) -> float:
        x = space.snap(space.lower + np.clip(u, 0.0, 1.0) * (space.upper - space.lower))
        outcome = simulate(tuple(float(v) for v in x), float(speed_kmh), fidelity)
        return float(outcome.sigma) if outcome.feasible and outcome.sigma is not None else INFEASIBLE_Y

    return ioh.wrap_problem(
        sigma,
        f"catenary-{problem.name}",
        ioh.ProblemClass.REAL,
        dimension=space.n_variables,
        optimization_type=ioh.OptimizationType.MIN,
        lb=0.0,
        ub=1.0,
    )
