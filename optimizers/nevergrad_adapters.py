"""nevergrad's optimisers on the problem's integer grid (``pip install catenary-env[optim]``).

The search space belongs to the parametrisation, as nevergrad intends: an ``ng.p.Array`` with bounds
``[0, n_levels − 1]`` per variable and integer casting, so a nevergrad optimiser proposes grid points
directly and never sees physical units; the driver maps them to designs. Each ask is a batch of
``batch_size`` candidates (nevergrad's ``num_workers``): they are evaluated together, in parallel, and
told in order. The batch size is a hyper-parameter, not the number of workers, so a run's history does
not depend on the hardware it ran on.

An infeasible design is told :data:`INFEASIBLE_LOSS`, a loss above any σ: these optimisers only compare
losses (rank-based CMA-ES, DE's and PSO's pairwise selection, the (1+1)'s acceptance), so a constant
penalty ranks infeasible designs below every feasible one, as the GA does.

Registered: ``cma``, ``de``, ``twopointsde``, ``pso``, ``oneplusone``, ``random``, ``ngopt`` (see
:class:`NGOpt` for the fault of nevergrad 1.0.12 with numpy >= 2.3, and why it does not touch the integer
grid). nevergrad is imported only when one of them is built.
"""

from __future__ import annotations

import importlib.metadata
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from catenary_env.errors import MissingDependency

from .base import Optimizer, OptimizerSpec, register_optimizer
from .problem import GridSpace

__all__ = [
    "INFEASIBLE_LOSS",
    "CMA",
    "DifferentialEvolution",
    "NGOpt",
    "NevergradOptimizer",
    "NevergradOptions",
    "OnePlusOne",
    "ParticleSwarm",
    "RandomSearch",
    "TwoPointsDE",
    "import_nevergrad",
    "ngopt_fault",
]

INFEASIBLE_LOSS = 1.0e6
"""Loss told to nevergrad for an infeasible design, N: above any σ a pantograph can produce."""


def import_nevergrad() -> Any:
    """The nevergrad module, or a MissingDependency (an ImportError) that says how to install it."""
    try:
        import nevergrad
    except ImportError as error:
        raise MissingDependency(
            "the nevergrad optimisers need nevergrad: pip install catenary-env[optim]"
        ) from error
    return nevergrad


@dataclass(frozen=True)
class NevergradOptions:
    """Hyper-parameters shared by the nevergrad adapters.

    Attributes
    ----------
    batch_size : int
        Candidates asked before telling (nevergrad's ``num_workers``); they are evaluated in parallel.
    """

    batch_size: int = 8


class NevergradOptimizer(Optimizer):
    """A nevergrad optimiser on the integer grid; a subclass names it in :attr:`nevergrad_name`.

    Parameters
    ----------
    space : GridSpace
        The grid searched.
    budget : int
        Simulations allowed; nevergrad's budget (some optimisers size their schedule with it).
    seed : int
        Seeds the parametrisation's random state, from which nevergrad draws everything.
    options : NevergradOptions, optional
        Hyper-parameters.
    """

    nevergrad_name: ClassVar[str]

    def __init__(
        self, space: GridSpace, budget: int, seed: int, options: NevergradOptions | None = None
    ) -> None:
        super().__init__(space, budget, seed)
        self.options = NevergradOptions() if options is None else options
        if self.options.batch_size < 1:
            raise ValueError(f"batch_size = {self.options.batch_size}: must be at least 1")
        ng = import_nevergrad()
        upper = (self.n_levels - 1).astype(np.float64)
        parametrization = ng.p.Array(init=upper / 2.0, lower=np.zeros_like(upper), upper=upper)
        parametrization.set_integer_casting()
        parametrization.random_state = np.random.RandomState(seed)
        optimizer_class = ng.optimizers.registry[self.nevergrad_name]
        self._optimizer = optimizer_class(
            parametrization=parametrization, budget=budget, num_workers=self.options.batch_size
        )
        self._candidates: list[Any] = []

    def _internal_ask(self) -> NDArray[np.int64]:
        self._candidates = [self._optimizer.ask() for _ in range(self.options.batch_size)]
        return np.array([np.asarray(candidate.value) for candidate in self._candidates], dtype=np.int64)

    def _internal_tell(self, points: NDArray[np.int64], losses: NDArray[np.float64]) -> None:
        for candidate, loss in zip(self._candidates, losses, strict=True):
            self._optimizer.tell(candidate, float(loss) if np.isfinite(loss) else INFEASIBLE_LOSS)
        self._candidates = []


class CMA(NevergradOptimizer):
    """CMA-ES (nevergrad ``CMA``)."""

    name = "cma"
    nevergrad_name = "CMA"


class DifferentialEvolution(NevergradOptimizer):
    """Differential evolution (nevergrad ``DE``)."""

    name = "de"
    nevergrad_name = "DE"


class TwoPointsDE(NevergradOptimizer):
    """Differential evolution with two-point crossover (nevergrad ``TwoPointsDE``)."""

    name = "twopointsde"
    nevergrad_name = "TwoPointsDE"


class ParticleSwarm(NevergradOptimizer):
    """Particle swarm optimisation (nevergrad ``PSO``)."""

    name = "pso"
    nevergrad_name = "PSO"


class OnePlusOne(NevergradOptimizer):
    """The (1+1) evolution strategy with one-fifth rule (nevergrad ``OnePlusOne``)."""

    name = "oneplusone"
    nevergrad_name = "OnePlusOne"


class RandomSearch(NevergradOptimizer):
    """Uniform random search over the grid (nevergrad ``RandomSearch``): the baseline."""

    name = "random"
    nevergrad_name = "RandomSearch"


class NGOpt(NevergradOptimizer):
    """nevergrad's algorithm selector ``NGOpt``.

    Known fault: with nevergrad <= 1.0.12 and numpy >= 2.3, NGOpt on a *continuous* parametrisation of
    3 to 12 variables picks a ``MetaModel`` optimiser, and after some evaluations that optimiser raises
    ``TypeError: only 0-dimensional arrays can be converted to Python scalars``
    (``nevergrad/optimization/metamodel.py``: ``float(model.predict(...))`` of a one-element array,
    which numpy 2.3 stopped converting). Our parametrisation is integer-cast, and for it NGOpt 1.0.12
    selects ``DoubleFastGADiscreteOnePlusOne`` (for 1 to 7 variables, any batch size and budget), which
    works: NGOpt is registered, and runs the same contract tests as every optimiser. Should a nevergrad
    version route this parametrisation to a ``MetaModel`` while the fault is present (see
    :func:`ngopt_fault`), the constructor raises ``RuntimeError`` naming the fault instead of letting
    the run fail part-way. ``tests/test_optimizers.py`` checks both that the fault is real on a
    continuous parametrisation where reported, and which optimiser NGOpt selects here.
    """

    name = "ngopt"
    nevergrad_name = "NGOpt"

    def __init__(
        self, space: GridSpace, budget: int, seed: int, options: NevergradOptions | None = None
    ) -> None:
        super().__init__(space, budget, seed, options)
        fault = ngopt_fault()
        if fault is not None and "MetaModel" in self.selected_optimizer:
            raise RuntimeError(f"NGOpt selected {self.selected_optimizer}, which fails here: {fault}")

    @property
    def selected_optimizer(self) -> str:
        """Name of the optimiser NGOpt selected for this problem, budget and batch size."""
        optimizer = self._optimizer.optim
        return str(getattr(optimizer, "name", type(optimizer).__name__))


def _version(package: str) -> tuple[int, ...] | None:
    try:
        text = importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return None
    parts = []
    for part in text.split(".")[:3]:
        digits = "".join(c for c in part if c.isdigit())
        parts.append(int(digits) if digits else 0)
    return tuple(parts)


def ngopt_fault() -> str | None:
    """The NGOpt MetaModel fault of the installed packages, or None (read from their versions, no import)."""
    nevergrad, numpy = _version("nevergrad"), _version("numpy")
    if nevergrad is None or numpy is None:
        return None
    if nevergrad <= (1, 0, 12) and numpy >= (2, 3):
        return (
            f"nevergrad {'.'.join(map(str, nevergrad))} with numpy {'.'.join(map(str, numpy))}: NGOpt's "
            "MetaModel raises TypeError (float() of a one-element array, refused since numpy 2.3)"
        )
    return None


for _class in (CMA, DifferentialEvolution, TwoPointsDE, ParticleSwarm, OnePlusOne, RandomSearch, NGOpt):
    register_optimizer(
        OptimizerSpec(_class.name, _class, NevergradOptions, f"nevergrad {_class.nevergrad_name}")
    )
del _class
