"""Cheap synthetic design problems: a demo of the optimiser interface and the test bed of the optimisers.

A :class:`QuadraticProblem` looks like catenary problem B1 from the outside (contact-wire height changes
on a 1 mm grid, a "σ" in newtons, an infeasible region) but costs microseconds, and its optimum on the
grid is known by enumeration (:meth:`QuadraticProblem.grid_optimum`). Its ``simulate`` is picklable, so
it also runs in worker processes and on Dask workers.

Examples
--------
>>> problem = get_synthetic_problem("synthetic-quadratic")
>>> problem.simulate((0.004, -0.007, 0.011), 300.0, "test").feasible  # the unconstrained optimum...
False
>>> x, sigma = problem.grid_optimum()  # ...lies beyond the constraint x_1 + x_3 <= 0.012 m
>>> x.tolist(), round(sigma, 3)
([0.003, -0.007, 0.009], 20.03)
"""

from __future__ import annotations

import functools
import itertools
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from catenary_env.errors import UnknownNameError
from catenary_env.problems.grid import DesignGrid

from .problem import Outcome, SimulateFunction

__all__ = [
    "CENTRE_SPEED_KMH",
    "SYNTHETIC_PROBLEMS",
    "QuadraticProblem",
    "get_synthetic_problem",
    "simulate_quadratic",
]


CENTRE_SPEED_KMH = 260.0
"""The speed at which a speed-dependent synthetic problem's minimiser is ``centre``, km/h."""


@dataclass(frozen=True, eq=False)
class QuadraticProblem:
    """A separable quadratic "σ" with one linear feasibility constraint, on an integer grid.

    ``sigma(x) = base_sigma + sum_i weights_i ((x_i - centre_i) / scale)^2`` N, feasible iff
    ``constraint @ x <= limit``. Independent of the speed and the fidelity.

    Attributes
    ----------
    name : str
        Problem id (part of the run store's cache key).
    variable_names : tuple of str
        One name per variable.
    lower, upper, step : ndarray, shape (n,)
        Bounds and grid step, m.
    centre : ndarray, shape (n,)
        Unconstrained minimiser, m.
    weights : ndarray, shape (n,)
        Curvature of each term, N.
    scale : float
        Length that makes a term equal to its weight, m.
    base_sigma : float
        σ at the unconstrained minimiser, N.
    constraint : ndarray, shape (n,)
        Coefficients of the feasibility constraint ``constraint @ x <= limit``.
    limit : float
        Right-hand side of the constraint, m.
    delay : float
        Seconds each evaluation sleeps, to stand in for an expensive simulation (0 for none).
    shift_per_kmh : ndarray, shape (n,), or None
        How the minimiser moves with the speed, m per km/h from :data:`CENTRE_SPEED_KMH` (None: it does
        not), as a catenary's optimum does: the test bed of speed-conditioned policies.
    constraint_names : tuple of str
        The one constraint value of an outcome: ``constraint @ x - limit``, m (feasible when <= 0, up to
        1e-12 m of rounding).
    """

    name: str
    variable_names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    step: NDArray[np.float64]
    centre: NDArray[np.float64]
    weights: NDArray[np.float64]
    scale: float
    base_sigma: float
    constraint: NDArray[np.float64]
    limit: float
    delay: float = 0.0
    shift_per_kmh: NDArray[np.float64] | None = None
    constraint_names: tuple[str, ...] = ("constraint_excess_m",)

    @property
    def simulate(self) -> SimulateFunction:
        return functools.partial(simulate_quadratic, self)

    def sigma(self, x: NDArray[np.float64], speed_kmh: float = CENTRE_SPEED_KMH) -> NDArray[np.float64]:
        """σ of designs ``x`` (shape (..., n)) at a speed (km/h), N, feasible or not."""
        terms = self.weights * ((np.asarray(x) - self.centre_at(speed_kmh)) / self.scale) ** 2
        return np.asarray(self.base_sigma + np.sum(terms, axis=-1), dtype=np.float64)

    def feasible(self, x: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Whether designs ``x`` (shape (..., n)) meet the constraint (1e-12 m of rounding allowed)."""
        return np.asarray(x) @ self.constraint <= self.limit + 1e-12

    def centre_at(self, speed_kmh: float) -> NDArray[np.float64]:
        """The unconstrained minimiser at a speed (km/h), m."""
        if self.shift_per_kmh is None:
            return self.centre
        return self.centre + self.shift_per_kmh * (float(speed_kmh) - CENTRE_SPEED_KMH)

    @property
    def n_variables(self) -> int:
        return len(self.variable_names)

    def reference_x(self) -> NDArray[np.float64]:
        """The design the studies compare against, m: every variable 0 (the level wire, as B1's)."""
        return np.zeros(self.n_variables)

    def grid_optimum(self, speed_kmh: float = CENTRE_SPEED_KMH) -> tuple[NDArray[np.float64], float]:
        """The best feasible design on the grid and its σ at a speed (km/h), by enumeration (small grids
        only)."""
        grid = DesignGrid(self.name, self.variable_names, self.lower, self.upper, self.step)
        levels = grid.n_levels
        if np.prod(levels) > 5_000_000:
            raise ValueError(f"{self.name}: grid of {int(np.prod(levels))} points is too large to enumerate")
        k = np.array(list(itertools.product(*(range(n) for n in levels))))
        x = grid.from_index(k)
        sigma = np.where(self.feasible(x), self.sigma(x, speed_kmh), np.inf)
        best = int(np.argmin(sigma))
        return x[best], float(sigma[best])


def simulate_quadratic(
    problem: QuadraticProblem, x: tuple[float, ...], speed_kmh: float, fidelity: str
) -> Outcome:
    """Evaluate a :class:`QuadraticProblem` design as if it were simulated (picklable)."""
    start = time.perf_counter()
    if problem.delay > 0.0:
        time.sleep(problem.delay)
    values = np.asarray(x, dtype=np.float64)
    excess = (float(values @ problem.constraint - problem.limit),)
    if not problem.feasible(values):
        reason = f"synthetic: constraint {problem.constraint.tolist()} @ x > {problem.limit} m"
        return Outcome(False, None, reason, time.perf_counter() - start, excess)
    return Outcome(True, float(problem.sigma(values, speed_kmh)), "", time.perf_counter() - start, excess)


def _quadratic(name: str, delay: float, shift_per_kmh: NDArray[np.float64] | None = None) -> QuadraticProblem:
    n = 3
    return QuadraticProblem(
        name=name,
        variable_names=tuple(f"dh_{i}" for i in range(1, n + 1)),
        lower=np.full(n, -0.02),
        upper=np.full(n, 0.02),
        step=np.full(n, 0.001),
        centre=np.array([0.004, -0.007, 0.011]),
        weights=np.array([1.0, 2.0, 0.5]),
        scale=0.01,
        base_sigma=20.0,
        constraint=np.array([1.0, 0.0, 1.0]),
        limit=0.012,  # cuts off the unconstrained minimiser: the optimum lies on the constraint
        delay=delay,
        shift_per_kmh=shift_per_kmh,
    )


SYNTHETIC_PROBLEMS: dict[str, QuadraticProblem] = {
    "synthetic-quadratic": _quadratic("synthetic-quadratic", 0.0),
    # The same problem at 5 ms an evaluation: long enough to interrupt a run in the middle.
    "synthetic-quadratic-slow": _quadratic("synthetic-quadratic-slow", 0.005),
    # Its minimiser moves 0.1 mm per km/h (6 mm from 260 to 200 or 320 km/h): speed-conditioned policies.
    "synthetic-speed-quadratic": _quadratic("synthetic-speed-quadratic", 0.0, np.array([1e-4, -1e-4, 0.0])),
}
"""The synthetic problems by name; the optimisers' command line accepts these names too."""


def get_synthetic_problem(name: str) -> QuadraticProblem:
    """The synthetic problem ``name``; KeyError lists those available."""
    if name not in SYNTHETIC_PROBLEMS:
        raise UnknownNameError(
            f"unknown synthetic problem {name!r}; available: {', '.join(SYNTHETIC_PROBLEMS)}"
        )
    return SYNTHETIC_PROBLEMS[name]
