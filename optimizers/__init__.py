"""Optimisers for the catenary design problems (docs/problems.md, 'Optimisers'): the published study's GA,
nevergrad, Optuna's model-based samplers, RL design policies, and any an installed package declares in the
``catenary_env.optimizers`` entry-point group (:mod:`optimizers.plugins`).

Every ask / tell optimiser is registered in :data:`OPTIMIZERS` and run by :func:`optimize`, which owns
the budget, the run store (resume, cache) and the parallel evaluation. The RL design policy is trained
by :func:`optimizers.rl.train_design_policy` (needs stable-baselines3). nevergrad, Optuna, Dask and
stable-baselines3 are imported only when used.

Examples
--------
>>> from optimizers import optimize
>>> result = optimize("synthetic-quadratic", "ga", budget=200, seed=0)
>>> result.n_simulations <= 200 and result.feasible
True
"""

from . import ga, nevergrad_adapters, optuna_adapters  # noqa: F401  (register the optimisers)
from .base import (
    OPTIMIZERS,
    EvaluationRecord,
    OptimizationResult,
    Optimizer,
    OptimizerSpec,
    register_optimizer,
)
from .catenary_adapter import catenary_problem
from .problem import GridProblem, GridSpace, Outcome
from .problem_registry import resolve_problem
from .runner import optimize
from .store import RunConfig, RunStore, StoreError

__all__ = [
    "OPTIMIZERS",
    "EvaluationRecord",
    "GridProblem",
    "GridSpace",
    "OptimizationResult",
    "Optimizer",
    "OptimizerSpec",
    "Outcome",
    "RunConfig",
    "RunStore",
    "StoreError",
    "catenary_problem",
    "optimize",
    "register_optimizer",
    "resolve_problem",
]
