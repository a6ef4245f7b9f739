"""What an optimiser needs from a design problem, the integer grid it searches, and the catenary adapter.

An optimiser never sees the physics: it sees a :class:`GridProblem` (names, bounds and grid steps in
physical units, and a picklable function that simulates one design at one speed) and searches the integer
grid ``k = round((x - lower) / step)``, ``0 <= k < n_levels``, described by :class:`GridSpace`.

:func:`catenary_problem` adapts a design problem of ``catenary_env.problems`` (SPEC 4) to that interface;
``catenary_env`` is imported only when such a problem is used, so the optimisers can be developed and
tested on the synthetic problems of :mod:`optimizers.synthetic` alone.

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

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "CatenaryProblem",
    "GridProblem",
    "GridSpace",
    "Outcome",
    "SimulateFunction",
    "catenary_problem",
    "resolve_problem",
    "simulate_catenary_design",
]

_DECIMALS = 12
"""Designs are rounded to this many decimals so that equal grid points are equal floats."""

_TIE_TOLERANCE = 1e-9
"""Grid steps; a value this close below a half step counts as the tie, which rounds up."""


class Outcome(NamedTuple):
    """The result of simulating one design at one speed, as an optimiser sees it.

    Attributes
    ----------
    feasible : bool
        False when the design is statically or dynamically infeasible (SPEC 3.3, 3.7).
    sigma : float or None
        Standard deviation of the filtered contact force, N; None where no dynamic run was made.
    reason : str
        Empty when feasible, otherwise why not.
    wall_time : float
        Seconds the simulation took.
    """

    feasible: bool
    sigma: float | None
    reason: str
    wall_time: float


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
class GridSpace:
    """The integer grid of a problem: ``x = lower + k * step`` with ``0 <= k < n_levels``.

    Attributes
    ----------
    name : str
        Problem id.
    variable_names : tuple of str
        One name per variable.
    lower, upper, step : ndarray, shape (n_variables,)
        Bounds and grid steps, physical units. Read-only.
    """

    name: str
    variable_names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    step: NDArray[np.float64]
    model: str = ""

    def __post_init__(self) -> None:
        n = len(self.variable_names)
        for field_name in ("lower", "upper", "step"):
            array = np.array(getattr(self, field_name), dtype=np.float64)
            if array.shape != (n,):
                raise ValueError(f"problem {self.name!r}: {field_name} needs {n} values, one per variable")
            array.setflags(write=False)
            object.__setattr__(self, field_name, array)
        if not (np.all(self.step > 0.0) and np.all(self.lower < self.upper)):
            raise ValueError(f"problem {self.name!r}: need step > 0 and lower < upper")

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
        that results of another model (an edited preset, another simulator revision) are never reused."""
        return f"{self.name}@{self.model}" if self.model else self.name

    @property
    def n_variables(self) -> int:
        return len(self.variable_names)

    @property
    def n_levels(self) -> NDArray[np.int64]:
        """Grid points of each variable, bounds included."""
        return np.round((self.upper - self.lower) / self.step).astype(np.int64) + 1

    def to_design(self, k: ArrayLike) -> NDArray[np.float64]:
        """Physical variables of grid coordinates ``k``, shape (n_variables,); refuses ``k`` off the grid."""
        index = np.asarray(k)
        if index.shape != (self.n_variables,):
            raise ValueError(f"grid point must have shape ({self.n_variables},), got {index.shape}")
        if not np.all(index == np.round(index)) or np.any(index < 0) or np.any(index >= self.n_levels):
            raise ValueError(
                f"grid point {index.tolist()} is not on the grid 0 <= k < {self.n_levels.tolist()}"
            )
        x = self.lower + index.astype(np.int64) * self.step
        return np.asarray(np.round(np.minimum(x, self.upper), _DECIMALS), dtype=np.float64)

    def to_index(self, x: ArrayLike) -> NDArray[np.int64]:
        """Integer grid coordinates of physical ``x``: clipped to the bounds, rounded to the nearest point.

        A value half-way between two points rounds up (as ``DesignProblem.snap`` and the envs do).
        """
        values = np.clip(np.asarray(x, dtype=np.float64), self.lower, self.upper)
        index = np.floor((values - self.lower) / self.step + 0.5 + _TIE_TOLERANCE).astype(np.int64)
        return np.minimum(index, self.n_levels - 1)

    def action_to_design(self, action: ArrayLike) -> NDArray[np.float64]:
        """The design of an env action in [-1, 1] (clipped): affine onto the bounds, then the grid."""
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        return self.snap(self.lower + 0.5 * (a + 1.0) * (self.upper - self.lower))

    def snap(self, x: ArrayLike) -> NDArray[np.float64]:
        """``x`` clipped to the bounds and rounded to the grid, physical units."""
        return self.to_design(self.to_index(x))

    def design_key(self, x: ArrayLike) -> tuple[int, ...]:
        """The cache key of a design on the grid: ``round(x / step)``, integers independent of the bounds."""
        return tuple(int(v) for v in np.round(np.asarray(x, dtype=np.float64) / self.step))


# -- the catenary design problems (catenary_env.problems), imported lazily ------------------------------


def simulate_catenary_design(
    problem_name: str, x: tuple[float, ...], speed_kmh: float, fidelity: str
) -> Outcome:
    """Simulate a design of a registered catenary design problem: picklable, for worker processes.

    Parameters
    ----------
    problem_name : str
        A name in ``catenary_env.problems.PROBLEMS``.
    x : tuple of float
        Variables, physical units (m), on the grid.
    speed_kmh : float
        Train speed, km/h.
    fidelity : str
        ``"study"`` or ``"test"``.
    """
    from catenary_env.problems import evaluate_problem

    evaluation = evaluate_problem(problem_name, tuple(x), float(speed_kmh), fidelity)
    statistics = evaluation.statistics
    sigma = None if statistics is None else float(statistics.std)
    return Outcome(bool(evaluation.feasible), sigma, str(evaluation.reason), float(evaluation.wall_time))


@dataclass(frozen=True, eq=False)
class CatenaryProblem:
    """A catenary design problem of SPEC 4 as a :class:`GridProblem` (built by :func:`catenary_problem`)."""

    name: str
    variable_names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    step: NDArray[np.float64]
    model_fingerprint: str = ""

    @property
    def simulate(self) -> SimulateFunction:
        return functools.partial(simulate_catenary_design, self.name)


def catenary_problem(name: str) -> CatenaryProblem:
    """Adapt the design problem ``name`` of ``catenary_env.problems`` (e.g. ``"B1"``).

    Raises
    ------
    KeyError
        No such problem (the message lists those available).
    """
    from catenary_env.problems import get_problem

    problem = get_problem(name)
    # The problem module calls its names `variables`; the interface agreed in the issue says
    # `variable_names`: accept either, so that a rename there does not break the optimisers.
    names = getattr(problem, "variable_names", None) or problem.variables
    return CatenaryProblem(
        problem.name,
        tuple(names),
        np.array(problem.lower, dtype=np.float64),
        np.array(problem.upper, dtype=np.float64),
        np.array(problem.step, dtype=np.float64),
        problem.fingerprint(),
    )


def resolve_problem(problem: GridProblem | str) -> GridProblem:
    """A problem object from a problem or a name: a synthetic problem's name, else a catenary problem's."""
    if not isinstance(problem, str):
        if not isinstance(problem, GridProblem):
            raise TypeError(
                f"{problem!r} is not a GridProblem (needs name, variable_names, bounds, step, simulate)"
            )
        return problem
    from .synthetic import SYNTHETIC_PROBLEMS

    if problem in SYNTHETIC_PROBLEMS:
        return SYNTHETIC_PROBLEMS[problem]
    try:
        return catenary_problem(problem)
    except KeyError as error:
        message = error.args[0] if error.args else repr(problem)
        raise KeyError(f"{message}; or a synthetic problem: {', '.join(SYNTHETIC_PROBLEMS)}") from None
