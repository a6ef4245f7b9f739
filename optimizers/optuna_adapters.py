"""Optuna's model-based samplers on the problem's integer grid (``pip install catenary-env[bayes]``).

The class of method a practitioner tries first on a one-second, five-variable, constrained black box:
a surrogate of σ (a Gaussian process, or TPE's density ratio) chooses each next design. Registered:

- ``tpe``: :class:`optuna.samplers.TPESampler` at Optuna 5.0's defaults (multivariate, constant liar);
- ``gp``: :class:`optuna.samplers.GPSampler` (Matérn 5/2 Gaussian process, log expected improvement;
  needs torch).

Both search ``IntDistribution(0, n_levels - 1)`` per variable, so every proposal is a grid point. They are
*constraint-aware*: each trial carries the problem's constraint values (:attr:`Outcome.constraints`;
for a catenary problem the dropper compression, the dropper-length shortfall and the contact-loss share,
``catenary_env.pipeline.CONSTRAINTS``) through Optuna 5.0's ``trial.set_constraint`` (the samplers'
``constraints_func`` is deprecated there): TPE ranks feasible trials first, the GP multiplies the expected
improvement by its model of the probability of feasibility. A constraint value that was not computed (NaN:
no passage after a static failure) is set to :data:`UNKNOWN_VIOLATION`, a violation.

A design without σ (statically infeasible) still needs an objective value: it is told the largest σ
told so far (never better than a feasible design), and, before any σ is known, the trial is told
failed (the samplers leave failed trials out of their models). The seed seeds the sampler, and the
proposals depend only on it and on what was told, so a run replays and resumes exactly
(:mod:`optimizers.base`). Optuna is imported only when one of them is built. Version tested: 5.0.0
(pinned in the ``bayes`` extra).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from catenary_env.errors import MissingDependency, UsageError

from .base import Optimizer, OptimizerSpec, register_optimizer
from .problem import GridSpace

__all__ = ["UNKNOWN_VIOLATION", "GaussianProcess", "OptunaOptimizer", "OptunaOptions", "TreeParzen"]

UNKNOWN_VIOLATION = 1.0
"""Constraint value set for one that was not computed (NaN): violated."""


def import_optuna() -> Any:
    """The optuna module (its logging quietened), or a MissingDependency that says how to install it."""
    try:
        import optuna
    except ImportError as error:
        raise MissingDependency("the optuna samplers need optuna: pip install catenary-env[bayes]") from error
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna


@dataclass(frozen=True)
class OptunaOptions:
    """Hyper-parameters of the Optuna adapters.

    Attributes
    ----------
    batch_size : int
        Trials asked before telling (evaluated in parallel). 1, Optuna's own sequential mode, by default;
        more uses the samplers' handling of running trials (TPE's constant liar, the GP's Kriging
        believer).
    n_startup_trials : int
        Random trials before the model is used (Optuna's default, 10).
    constraint_aware : bool
        Tell the samplers the constraint values (else only σ, and infeasible designs as above).
    patience : int
        Stop (``"stall"``) after this many proposals in a row of designs the run has already evaluated: a
        converged Gaussian process proposes its optimum again and again, and each repeat is free but costs
        a model fit.
    """

    batch_size: int = 1
    n_startup_trials: int = 10
    constraint_aware: bool = True
    patience: int = 30


class OptunaOptimizer(Optimizer):
    """An Optuna sampler on the integer grid; a subclass builds it in :meth:`_sampler`."""

    summary: ClassVar[str]

    def __init__(
        self, space: GridSpace, budget: int, seed: int, options: OptunaOptions | None = None
    ) -> None:
        super().__init__(space, budget, seed)
        self.options = OptunaOptions() if options is None else options
        if self.options.batch_size < 1:
            raise UsageError(f"batch_size = {self.options.batch_size}: must be at least 1")
        if self.options.n_startup_trials < 1:
            raise UsageError(f"n_startup_trials = {self.options.n_startup_trials}: must be at least 1")
        self._optuna = import_optuna()
        distributions = self._optuna.distributions
        self._distributions = {
            name: distributions.IntDistribution(0, int(n) - 1)
            for name, n in zip(space.variable_names, space.n_levels, strict=True)
        }
        self._study = self._optuna.create_study(direction="minimize", sampler=self._sampler())
        self._trials: list[Any] = []
        self._worst = -math.inf  # the largest σ told so far
        self._n_constraints: int | None = None
        self._asked: set[tuple[int, ...]] = set()
        self._repeats = 0

    def _sampler(self) -> Any:
        raise NotImplementedError

    def _internal_ask(self) -> NDArray[np.int64]:
        self._trials = [self._study.ask(self._distributions) for _ in range(self.options.batch_size)]
        names = self.space.variable_names
        points = np.array([[trial.params[name] for name in names] for trial in self._trials], dtype=np.int64)
        for point in map(tuple, points.tolist()):
            self._repeats = self._repeats + 1 if point in self._asked else 0
            self._asked.add(point)
        if self._repeats >= self.options.patience:
            self._stop_reason = "stall"
        return points

    def _internal_tell(self, points: NDArray[np.int64], losses: NDArray[np.float64]) -> None:
        self._internal_tell_constrained(points, losses, tuple(() for _ in losses))

    def _internal_tell_constrained(
        self,
        points: NDArray[np.int64],
        losses: NDArray[np.float64],
        constraints: tuple[tuple[float, ...], ...],
    ) -> None:
        finite = [float(v) for v in losses if np.isfinite(v)]
        self._worst = max([self._worst, *finite])
        for trial, loss, values in zip(self._trials, losses, constraints, strict=True):
            feasible = bool(np.isfinite(loss))
            if self.options.constraint_aware:
                for number, value in enumerate(self._constraint_values(values, feasible)):
                    trial.set_constraint(f"c{number}", value)
            if feasible:
                self._study.tell(trial, float(loss))
            elif math.isfinite(self._worst):
                self._study.tell(trial, self._worst)
            else:
                self._study.tell(trial, state=self._optuna.trial.TrialState.FAIL)
        self._trials = []

    def _constraint_values(self, values: tuple[float, ...], feasible: bool) -> list[float]:
        """A fixed number of constraint values per trial: the problem's (NaN: :data:`UNKNOWN_VIOLATION`),
        or, where it gives none (an outcome stored before constraints were), one value saying feasible."""
        if self._n_constraints is None:
            self._n_constraints = len(values) or 1
        if len(values) != self._n_constraints:
            return [0.0 if feasible else UNKNOWN_VIOLATION] * self._n_constraints
        return [UNKNOWN_VIOLATION if math.isnan(v) else float(v) for v in values]


class TreeParzen(OptunaOptimizer):
    """Optuna's tree-structured Parzen estimator (``TPESampler``, Optuna 5.0 defaults)."""

    name = "tpe"
    summary = "Optuna TPESampler (model-based, constraint-aware)"

    def _sampler(self) -> Any:
        return self._optuna.samplers.TPESampler(
            seed=self.seed, n_startup_trials=self.options.n_startup_trials
        )


class GaussianProcess(OptunaOptimizer):
    """Bayesian optimisation with Optuna's Gaussian process (``GPSampler``; needs torch)."""

    name = "gp"
    summary = "Optuna GPSampler (Bayesian optimisation, constraint-aware)"

    def _sampler(self) -> Any:
        try:
            import torch  # noqa: F401
        except ImportError as error:
            raise MissingDependency("the gp optimiser needs torch: pip install torch") from error
        with warnings.catch_warnings():  # deterministic_objective is 'experimental': σ is deterministic
            warnings.simplefilter("ignore", self._optuna.exceptions.ExperimentalWarning)
            return self._optuna.samplers.GPSampler(
                seed=self.seed, n_startup_trials=self.options.n_startup_trials, deterministic_objective=True
            )


for _class in (TreeParzen, GaussianProcess):
    register_optimizer(OptimizerSpec(_class.name, _class, OptunaOptions, _class.summary))
del _class
