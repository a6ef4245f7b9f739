"""The common interface of the optimisers: ask / tell on the integer grid, result records, the registry.

An optimiser (:class:`Optimizer`) proposes batches of integer grid points (:meth:`Optimizer.ask`) and is
told their losses (:meth:`Optimizer.tell`); it never simulates and never handles physical units. The
driver :func:`optimizers.runner.optimize` evaluates the batches (in parallel, through the run store's
cache) and returns an :class:`OptimizationResult`.

Budget
------
The budget counts *simulations charged to the run*: the first evaluation of each distinct grid design in a
run is charged, whether it is simulated now or served from the store's cache (a previous run in the same
store simulated it), so that a run's history and result do not depend on what else the store holds.
A design the run has already evaluated is a cache hit that costs nothing: it is not a simulation (and the
genetic algorithm's elites are not re-evaluated at all). The number of charged evaluations never exceeds
the budget: a batch that would overrun it is cut short and the run stops. Since cache hits are free, a
run may hold more evaluations than its budget, at most ``max_evaluations`` (10 × budget by default), a
guard against an optimiser that keeps proposing the designs it has already seen.

Determinism
-----------
An optimiser's proposals depend only on its seed and on the losses it has been told, so re-running a run
with the same seed replays it exactly; this is what makes an interrupted run resumable.

Examples
--------
>>> sorted(OPTIMIZERS)[:3]
['cma', 'de', 'ga']
"""

from __future__ import annotations

import abc
import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from catenary_env.errors import UsageError
from catenary_env.registry import Registry

from .problem import GridSpace

__all__ = [
    "OPTIMIZERS",
    "EvaluationRecord",
    "OptimizationResult",
    "Optimizer",
    "OptimizerRegistry",
    "OptimizerSpec",
    "register_optimizer",
]


@dataclass(frozen=True)
class EvaluationRecord:
    """One evaluation of a run, in the order the optimiser asked for it.

    Attributes
    ----------
    index : int
        Position in the run's history, from 0.
    x : tuple of float
        The design's variables, physical units (m), on the grid.
    feasible : bool
        Statically and dynamically feasible.
    sigma : float or None
        σ of the filtered contact force, N (None where not simulated dynamically).
    reason : str
        Why infeasible; empty when feasible.
    wall_time : float
        Seconds this run spent on it (0 for a cache hit).
    cached : bool
        Served from the store's cache (an earlier evaluation of the same design), not simulated.
    charged : bool
        Counted against the budget: the run's first evaluation of this design.
    speed_kmh : float
        Train speed, km/h.
    constraints : tuple of float
        The problem's constraint values (feasible when all are <= 0; NaN where not computed); empty where
        the problem gives none, or the store that served it predates them.
    statistics : tuple of float
        The problem's other statistics of the design (for a catenary problem every field of
        ``ContactStatistics``); empty where not simulated dynamically, or not stored.
    """

    index: int
    x: tuple[float, ...]
    feasible: bool
    sigma: float | None
    reason: str
    wall_time: float
    cached: bool
    charged: bool
    speed_kmh: float
    constraints: tuple[float, ...] = ()
    statistics: tuple[float, ...] = ()

    @property
    def loss(self) -> float:
        """σ for a feasible design, +inf otherwise: what an optimiser is told."""
        if self.feasible and self.sigma is not None:
            return float(self.sigma)
        return float("inf")


@dataclass(frozen=True)
class OptimizationResult:
    """The outcome of an optimisation run.

    Attributes
    ----------
    optimizer : str
        Registry name of the optimiser (``"ppo"`` for the RL design policy).
    problem : str
        Problem id.
    variable_names : tuple of str
        Names of the variables of ``best_x``.
    budget : int
        Simulations allowed.
    seed : int
        Random seed.
    speed_kmh : float or None
        Design speed, km/h (None for a policy trained over a speed range).
    fidelity : str
        Model fidelity, ``"study"`` or ``"test"``.
    best_x : tuple of float or None
        Best feasible design found, m; None if no feasible design was found.
    best_sigma : float or None
        Its σ, N.
    feasible : bool
        Whether a feasible design was found.
    history : tuple of EvaluationRecord
        Every evaluation, in the order asked.
    stop_reason : str
        Why the run stopped: ``"budget"``, ``"stall"``, ``"generations"``, ``"max_evaluations"``.
    n_simulations : int
        Evaluations charged against the budget (<= budget).
    run_id : int or None
        The run's id in its store.
    best_speed_kmh : float or None
        The speed ``best_x`` was simulated at, km/h: ``speed_kmh``, or with a speed range (a ppo run) the
        episode's, so that ``best_sigma`` is the lowest σ met over speeds (not comparable from one speed
        to another: a policy's design at a speed is ``catenary propose POLICY --speed V``).
    """

    optimizer: str
    problem: str
    variable_names: tuple[str, ...]
    budget: int
    seed: int
    speed_kmh: float | None
    fidelity: str
    best_x: tuple[float, ...] | None
    best_sigma: float | None
    feasible: bool
    history: tuple[EvaluationRecord, ...]
    stop_reason: str
    n_simulations: int
    run_id: int | None
    best_speed_kmh: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (history entries as dicts; a constraint value or statistic not computed, NaN,
        as None)."""
        data = dataclasses.asdict(self)
        data["history"] = [dataclasses.asdict(record) for record in self.history]
        for entry in data["history"]:
            for key in ("constraints", "statistics"):
                entry[key] = [None if np.isnan(v) else v for v in entry[key]]
        return data


def best_record(history: Sequence[EvaluationRecord]) -> EvaluationRecord | None:
    """The feasible record of lowest σ (the earliest on ties), or None."""
    feasible = [record for record in history if np.isfinite(record.loss)]
    return min(feasible, key=lambda record: (record.loss, record.index)) if feasible else None


class Optimizer(abc.ABC):
    """Base class of ask / tell optimisers on an integer grid.

    A subclass implements :meth:`_internal_ask` and :meth:`_internal_tell` (and may set
    :attr:`_stop_reason`); the public methods own the checks and counters. Every random draw comes from
    ``seed``, so the proposals depend only on the seed and the losses told.

    Parameters
    ----------
    space : GridSpace
        The grid searched: point ``k`` has ``0 <= k < space.n_levels``.
    budget : int
        Simulations the run may charge (some optimisers size their schedule with it).
    seed : int
        Random seed, >= 0.
    """

    name: ClassVar[str]
    """Registry name."""

    def __init__(self, space: GridSpace, budget: int, seed: int) -> None:
        if budget < 1:
            raise UsageError(f"budget = {budget}: must be at least 1 simulation")
        if seed < 0:
            raise UsageError(f"seed = {seed}: must be >= 0")
        self.space = space
        self.n_levels = space.n_levels
        self.budget = int(budget)
        self.seed = int(seed)
        self.num_ask = 0
        self.num_tell = 0
        self._pending: NDArray[np.int64] | None = None
        self._stop_reason: str | None = None

    @property
    def stop_reason(self) -> str | None:
        """Why the optimiser has stopped by its own rule, or None while it goes on."""
        return self._stop_reason

    def ask(self) -> NDArray[np.int64]:
        """The next batch of grid points to evaluate, shape (batch, n_variables).

        Raises
        ------
        RuntimeError
            The previous batch has not been told, or a subclass proposed a point off the grid.
        """
        if self._pending is not None:
            raise RuntimeError(f"{self.name}: tell the previous batch before asking again")
        points = np.asarray(self._internal_ask())
        if points.ndim != 2 or points.shape[1] != self.space.n_variables or len(points) == 0:
            raise RuntimeError(f"{self.name}: asked a batch of shape {points.shape}")
        if not np.all(points == np.round(points)) or np.any(points < 0) or np.any(points >= self.n_levels):
            raise RuntimeError(f"{self.name}: proposed points off the grid: {points.tolist()}")
        self._pending = points.astype(np.int64)
        self.num_ask += len(points)
        return self._pending.copy()

    def tell(
        self,
        points: ArrayLike,
        losses: ArrayLike,
        constraints: Sequence[Sequence[float]] | None = None,
    ) -> None:
        """Tell the losses of the batch last asked: σ in N, +inf for an infeasible design; optionally the
        constraint values of each point (:attr:`EvaluationRecord.constraints`), which a constraint-aware
        optimiser uses (:meth:`_internal_tell_constrained`) and the others ignore.

        Raises
        ------
        RuntimeError
            ``points`` is not the batch last asked, or the losses do not match it.
        """
        batch = np.asarray(points)
        values = np.asarray(losses, dtype=np.float64)
        if (
            self._pending is None
            or batch.shape != self._pending.shape
            or not np.array_equal(batch, self._pending)
        ):
            raise RuntimeError(f"{self.name}: tell exactly the batch last asked")
        if values.shape != (len(batch),) or np.any(np.isnan(values)):
            raise RuntimeError(f"{self.name}: need one loss (not NaN) per point, got {values.shape}")
        if constraints is not None and len(constraints) != len(batch):
            raise RuntimeError(f"{self.name}: need one tuple of constraint values per point")
        self._pending = None
        self.num_tell += len(batch)
        if constraints is None:
            self._internal_tell(batch, values)
        else:
            self._internal_tell_constrained(batch, values, tuple(tuple(map(float, c)) for c in constraints))

    @abc.abstractmethod
    def _internal_ask(self) -> NDArray[np.int64]:
        """Propose a batch, shape (batch, n_variables), integer grid coordinates."""

    @abc.abstractmethod
    def _internal_tell(self, points: NDArray[np.int64], losses: NDArray[np.float64]) -> None:
        """Learn from the losses of the batch last proposed (+inf: infeasible)."""

    def _internal_tell_constrained(
        self,
        points: NDArray[np.int64],
        losses: NDArray[np.float64],
        constraints: tuple[tuple[float, ...], ...],
    ) -> None:
        """Learn from the losses and the constraint values (per point; feasible when all are <= 0, NaN
        where not computed, empty where unknown); by default from the losses alone."""
        self._internal_tell(points, losses)


class OptimizerSpec(NamedTuple):
    """A registry entry.

    Attributes
    ----------
    name : str
        Registry (command-line) name.
    optimizer_class : type
        The :class:`Optimizer` subclass; built as ``optimizer_class(space, budget, seed, options)``.
    options_class : type
        Its frozen dataclass of hyper-parameters (every field has a default).
    summary : str
        One line for ``--help``.
    """

    name: str
    optimizer_class: type[Optimizer]
    options_class: type
    summary: str


class OptimizerRegistry(Registry[OptimizerSpec]):
    """The optimisers by name: a dict that refuses to replace an entry."""

    kind = "optimizer"


OPTIMIZERS = OptimizerRegistry()
"""Every ask / tell optimiser by name (filled on ``import optimizers``)."""


def register_optimizer(spec: OptimizerSpec) -> OptimizerSpec:
    """Add an optimiser to :data:`OPTIMIZERS`; ValueError if the name is taken."""
    return OPTIMIZERS.register(spec)
