"""What an optimiser needs from a design problem, and the integer grid it searches.

An optimiser never sees the physics: it sees a :class:`GridProblem` (names, bounds and grid steps in
physical units, and a picklable function that simulates one design at one speed) and searches the integer
grid ``k = round((x - lower) / step)``, ``0 <= k < n_levels``, described by :class:`GridSpace`.

:func:`optimizers.catenary_adapter.catenary_problem` adapts a design problem of ``catenary_env.problems``
(docs/problems.md, 'The eight problems') to that interface, and
:func:`optimizers.problem_registry.resolve_problem` finds a problem by name; the grid is ``catenary_env``'s
design grid, so a design is the same float in both packages.

Examples
--------
>>> from optimizers.synthetic import get_synthetic_problem
>>> space = GridSpace.from_problem(get_synthetic_problem("synthetic-quadratic"))
>>> space.n_levels.tolist()
[41, 41, 41]
>>> space.to_design([0, 20, 40]).tolist()
[-0.02, 0.0, 0.02]
>>> space.design_key([-0.02, 0.0, 0.02])
(-20, 0, 20)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from catenary_env.problems.grid import DesignGrid

__all__ = ["GridProblem", "GridSpace", "Outcome", "SimulateFunction", "constraint_names", "statistic_names"]


class Outcome(NamedTuple):
    """The result of simulating one design at one speed, as an optimiser sees it.

    Attributes
    ----------
    feasible : bool
        False when the design is statically or dynamically infeasible (docs/model.md, 'Statistics and
        feasibility').
    sigma : float or None
        Standard deviation of the filtered contact force, N; None where no dynamic run was made.
    reason : str
        Empty when feasible, otherwise why not.
    wall_time : float
        Seconds the simulation took.
    constraints : tuple of float
        The problem's constraint values (its ``constraint_names``), feasible when all are <= 0; NaN where
        not computed, empty where the problem or the store that served the outcome gives none.
    statistics : tuple of float
        The problem's other statistics of the outcome (its ``statistic_names``; for a catenary problem
        every field of ``ContactStatistics``, N, % and m), empty where not simulated or not given.
    """

    feasible: bool
    sigma: float | None
    reason: str
    wall_time: float
    constraints: tuple[float, ...] = ()
    statistics: tuple[float, ...] = ()


SimulateFunction = Callable[[tuple[float, ...], float, str], Outcome]
"""``simulate(x, speed_kmh, fidelity) -> Outcome``: a picklable callable (a module-level function or a
:func:`functools.partial` of one) so that it can be sent to worker processes and Dask workers."""


@runtime_checkable
class GridProblem(Protocol):
    """What an optimiser needs from a design problem.

    Attributes
    ----------
    name : str
        Problem id; part of the run store's cache key, so two problems must not share a name.
    variable_names : tuple of str
        One name per variable.
    lower, upper, step : ndarray, shape (n_variables,)
        Bounds and grid step of each variable, physical units (m); the bounds lie on the grid.
    simulate : SimulateFunction
        Picklable ``simulate(x, speed_kmh, fidelity) -> Outcome``; deterministic.

    A problem may also name the values of its outcomes' ``constraints`` in ``constraint_names`` and their
    ``statistics`` in ``statistic_names`` (tuples of str; :func:`constraint_names` and
    :func:`statistic_names` read them, empty when absent).
    """

    @property
    def name(self) -> str: ...

    @property
    def variable_names(self) -> tuple[str, ...]: ...

    @property
    def lower(self) -> NDArray[np.float64]: ...

    @property
    def upper(self) -> NDArray[np.float64]: ...

    @property
    def step(self) -> NDArray[np.float64]: ...

    @property
    def simulate(self) -> SimulateFunction: ...


@dataclass(frozen=True, eq=False)
class GridSpace(DesignGrid):
    """The integer grid of a problem: ``x = lower + k * step`` with ``0 <= k < n_levels``.

    The grid of :class:`~catenary_env.problems.grid.DesignGrid` (snapping, actions, design keys), with
    the fingerprint of the problem's model, which keys the run store.

    Attributes
    ----------
    name : str
        Problem id.
    variable_names : tuple of str
        One name per variable.
    lower, upper, step : ndarray, shape (n_variables,)
        Bounds and grid steps, physical units. Read-only.
    model : str
        Fingerprint of the problem's model; empty for a problem without one.
    """

    model: str = ""

    @classmethod
    def from_problem(cls, problem: GridProblem) -> GridSpace:
        """The grid of a :class:`GridProblem`."""
        return cls(
            problem.name,
            tuple(problem.variable_names),
            problem.lower,
            problem.upper,
            problem.step,
            str(getattr(problem, "model_fingerprint", "")),
        )

    @property
    def store_key(self) -> str:
        """The problem's name in the run store: with the model's fingerprint where the problem has one, so
        that results of another model (an edited preset, a simulator that computes other numbers,
        :mod:`catenary_env.fingerprint`) are never reused."""
        return f"{self.name}@{self.model}" if self.model else self.name

    def to_design(self, k: ArrayLike) -> NDArray[np.float64]:
        """Physical variables of grid coordinates ``k``, shape (n_variables,); refuses ``k`` off the grid."""
        index = np.asarray(k)
        if index.shape != (self.n_variables,):
            raise ValueError(f"grid point must have shape ({self.n_variables},), got {index.shape}")
        if not np.all(index == np.round(index)) or np.any(index < 0) or np.any(index >= self.n_levels):
            raise ValueError(
                f"grid point {index.tolist()} is not on the grid 0 <= k < {self.n_levels.tolist()}"
            )
        return self.from_index(index)


def constraint_names(problem: GridProblem) -> tuple[str, ...]:
    """The names of a problem's constraint values (:attr:`Outcome.constraints`), empty if it names none."""
    return tuple(getattr(problem, "constraint_names", ()))


def statistic_names(problem: GridProblem) -> tuple[str, ...]:
    """The names of a problem's statistics (:attr:`Outcome.statistics`), empty if it names none."""
    return tuple(getattr(problem, "statistic_names", ()))
