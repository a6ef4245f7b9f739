"""The genetic algorithm of the published study: MATLAB's ``ga`` on integer variables (docs/problems.md,
'Optimisers').

MATLAB's ``ga`` with integer constraints replaces the user's operators by those of MI-LXPM (Deep, Singh,
Kansal and Mohan, "A real coded genetic algorithm for solving integer and mixed integer optimization
problems", Applied Mathematics and Computation 212 (2009) 505-518): Laplace crossover, power mutation,
and a truncation that puts every child on the integers; constraints are handled by a penalty under
which an infeasible individual ranks below every feasible one, and, while none is feasible, by its total
constraint violation (:func:`penalty_scores`), so that a run that starts where nothing is feasible closes
in on the constraints and its stall rule applies. Its generation loop (``stepGA``) is:
score the population, keep the elite, rank-scale the scores, select parents by stochastic-uniform
sampling, shuffle them, make ``round(CrossoverFraction × (PopulationSize − EliteCount))`` children by
crossover of two parents each and the rest by mutation of one parent each.

This module implements that loop on the problem's integer grid ``k = round((x − lower) / step)``. Every
operator acts on ``k``; since ``x = lower + k · step`` is an affine map per variable and the operators
are equivariant under it (Laplace crossover scales with ``|p1 − p2|``, power mutation with the distance
to the bounds, the truncation with integer shifts), running them on ``k`` is running them on the
design's own integer units (mm, cm), which is how the study posed its variables to MATLAB. MATLAB's
operator files are not published (p-code), so this follows the MI-LXPM paper and MATLAB's documented
options; where either is silent, the docstring of the operator says what is done and why.

Hyper-parameters (:class:`GAOptions`) default to the published study's settings: population size per problem
(:data:`POPULATION_SIZES`), 3 elite individuals, crossover fraction 0.8, stall window 50 generations,
function tolerance 1e-6, and MATLAB's generation limit of 100 × the number of variables.

Examples
--------
>>> from optimizers.runner import optimize
>>> result = optimize("synthetic-quadratic", "ga", budget=400, seed=1)
>>> result.n_simulations <= 400
True
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from .base import Optimizer, OptimizerSpec, register_optimizer
from .problem import GridSpace

__all__ = [
    "POPULATION_SIZES",
    "GAOptions",
    "GeneticAlgorithm",
    "elite_indices",
    "integer_truncation",
    "laplace_crossover",
    "penalty_scores",
    "power_mutation",
    "rank_expectation",
    "stochastic_uniform",
    "total_violation",
]

POPULATION_SIZES: dict[str, int] = {
    "BPresag": 15,
    "B1": 100,
    "B2": 80,
    "B3": 100,
    # The published study gives no population for the stitched catenary's pre-sag: like BPresag (one
    # variable).
    "SWPresag": 15,
    "SW1": 80,
    "SW2": 60,
    "SW3": 100,
}
"""Population size of the published study's GA runs per problem (docs/problems.md, 'Optimisers')."""


class RandomSource(Protocol):
    """The part of :class:`numpy.random.Generator` the operators use."""

    def random(self, size: int | tuple[int, ...] | None = None) -> NDArray[np.float64]: ...

    def permutation(self, x: NDArray[np.int64]) -> NDArray[np.int64]: ...


@dataclass(frozen=True)
class GAOptions:
    """Hyper-parameters of the genetic algorithm (MATLAB option names in brackets).

    Attributes
    ----------
    population_size : int or None
        Individuals per generation [PopulationSize]; None: :data:`POPULATION_SIZES` for the published study's
        problems, else MATLAB's default, 50 for up to 5 variables and 200 above.
    elite_count : int
        Best individuals copied unchanged into the next generation [EliteCount].
    crossover_fraction : float
        Share of the non-elite children made by crossover; the rest by mutation [CrossoverFraction].
    max_stall_generations : int
        Window of the stall rule, generations [MaxStallGenerations].
    function_tolerance : float
        Stop when the average relative change of the best σ over the window is at most this
        [FunctionTolerance].
    max_generations : int or None
        Generation limit [MaxGenerations]; None: 100 × the number of variables (MATLAB's default).
    laplace_location : float
        Location ``a`` of the Laplace crossover (MI-LXPM: 0).
    laplace_scale : float
        Scale ``b`` of the Laplace crossover on integer variables (MI-LXPM: 0.35).
    power_index : float
        Index ``p`` of the power mutation on integer variables (MI-LXPM: 4).
    """

    population_size: int | None = None
    elite_count: int = 3
    crossover_fraction: float = 0.8
    max_stall_generations: int = 50
    function_tolerance: float = 1e-6
    max_generations: int | None = None
    laplace_location: float = 0.0
    laplace_scale: float = 0.35
    power_index: float = 4.0


# -- operators -------------------------------------------------------------------------------------------


def rank_expectation(
    losses: NDArray[np.float64], n_parents: int, violations: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """Rank fitness scaling with the penalty of MATLAB's integer ``ga``: expected parent counts.

    MATLAB's ``fitscalingrank``: sort the scores (ties in population order), give the individual of rank
    ``r`` the raw value ``1 / sqrt(r)``, and scale so that the expectations sum to ``n_parents``.
    Infeasible individuals (loss +inf) rank below every feasible one under MATLAB's penalty; here they
    get expectation 0, i.e. they are excluded from selection, as the study asks. If no individual is
    feasible, MATLAB's penalty is the total constraint violation alone, so they are ranked by
    ``violations`` (:func:`penalty_scores`); where those are unknown all get the same expectation.

    Parameters
    ----------
    losses : ndarray, shape (n,)
        σ, N; +inf for an infeasible individual.
    n_parents : int
        Parents to select.
    violations : ndarray, shape (n,), optional
        Each individual's total constraint violation (0 when feasible, NaN where unknown).

    Returns
    -------
    ndarray, shape (n,)
        Expected number of times each individual is selected; sums to ``n_parents``.
    """
    feasible = np.isfinite(losses)
    n = len(losses)
    if not np.any(feasible):
        if violations is None or not np.any(np.isfinite(violations)):
            return np.full(n, n_parents / n)
        losses = penalty_scores(losses, violations)
        feasible = np.isfinite(losses)
    ranks = np.empty(n)
    ranks[np.argsort(losses, kind="stable")] = np.arange(1, n + 1)
    raw = np.where(feasible, 1.0 / np.sqrt(ranks), 0.0)
    return np.asarray(n_parents * raw / raw.sum(), dtype=np.float64)


def stochastic_uniform(
    expectation: NDArray[np.float64], n_parents: int, rng: RandomSource
) -> NDArray[np.int64]:
    """Stochastic uniform selection (MATLAB's ``selectionstochunif``; Baker's stochastic universal sampling).

    Lay the individuals out on a line, each with a section of length proportional to its expectation;
    one random start ``u · (1 / n_parents)``, ``u`` uniform in [0, 1), then ``n_parents`` equally spaced
    pointers, one step ``1 / n_parents`` apart; each pointer selects the individual whose section it
    falls in. An individual of expectation ``e`` is selected ``floor(e)`` or ``ceil(e)`` times, and
    ``e`` times on average; one of expectation 0 is never selected.

    Parameters
    ----------
    expectation : ndarray, shape (n,)
        Expected counts (>= 0), e.g. from :func:`rank_expectation`.
    n_parents : int
        Parents to select.
    rng : numpy.random.Generator
        Draws the one random start.

    Returns
    -------
    ndarray, shape (n_parents,)
        Indices of the selected individuals, in pointer order (the caller shuffles them).
    """
    total = float(np.sum(expectation))
    if total <= 0.0:
        raise ValueError("stochastic_uniform: expectations must have a positive sum")
    wheel = np.cumsum(expectation) / total
    step = 1.0 / n_parents
    pointers = rng.random() * step + step * np.arange(n_parents)
    # First section whose end lies beyond the pointer; zero-length sections are never hit.
    return np.minimum(np.searchsorted(wheel, pointers, side="right"), len(wheel) - 1).astype(np.int64)


def integer_truncation(values: NDArray[np.float64], rng: RandomSource) -> NDArray[np.int64]:
    """MI-LXPM's truncation: a non-integer value becomes its floor or its ceiling with probability 1/2 each.

    This keeps the integer restriction without the bias of always rounding to the nearest integer
    (Deep et al. 2009, section 2.4). A random number is drawn for every entry, integer or not, so the
    number of draws never depends on the values.
    """
    floor = np.floor(values)
    up = (values > floor) & (rng.random(np.shape(values)) < 0.5)
    return (floor + up).astype(np.int64)


def laplace_crossover(
    first: NDArray[np.int64],
    second: NDArray[np.int64],
    n_levels: NDArray[np.int64],
    rng: RandomSource,
    location: float = 0.0,
    scale: float = 0.35,
) -> NDArray[np.int64]:
    """Laplace crossover (Deep and Thakur 2007; MI-LXPM), one child per pair of parents.

    For each gene draw ``u, r`` uniform in (0, 1] and [0, 1) and set the Laplace-distributed
    ``β = a − b ln u`` if ``r <= 1/2`` else ``β = a + b ln u``; the child is
    ``y = p1 + β |p1 − p2|``, then put on the integers by :func:`integer_truncation` and clipped to the
    bounds ``[0, n_levels − 1]``. With ``a = 0`` the child lies around the first parent at a distance
    that scales with the parents' distance (``E|β| = b``, so ``E|y − p1| ≈ b |p1 − p2|``): near each
    other, parents make children near them; where the parents agree on a gene, the child inherits it.
    MI-LXPM makes two children ``p1 + β|p1 − p2|`` and ``p2 + β|p1 − p2|`` per pair; MATLAB counts two
    parents per crossover child, so one child (the first) is made per pair. The paper does not say what
    to do with a child beyond a bound; clipping to the bound keeps every individual in the box, as
    MATLAB's integer ``ga`` does.

    Parameters
    ----------
    first, second : ndarray, shape (m, n_variables)
        Integer grid coordinates of the parents of each child.
    n_levels : ndarray, shape (n_variables,)
        Grid points of each variable.
    rng : numpy.random.Generator
        Random source.
    location, scale : float
        ``a`` and ``b`` of the Laplace distribution (MI-LXPM for integer variables: 0 and 0.35).

    Returns
    -------
    ndarray, shape (m, n_variables)
        The children, integer grid coordinates within the bounds.
    """
    shape = np.shape(first)
    u = 1.0 - rng.random(shape)  # in (0, 1]: ln u is finite
    r = rng.random(shape)
    beta = np.where(r <= 0.5, location - scale * np.log(u), location + scale * np.log(u))
    child = first + beta * np.abs(first - second)
    return np.clip(integer_truncation(child, rng), 0, n_levels - 1)


def power_mutation(
    parents: NDArray[np.int64], n_levels: NDArray[np.int64], rng: RandomSource, index: float = 4.0
) -> NDArray[np.int64]:
    """Power mutation (Deep and Thakur 2007; MI-LXPM), every gene of each parent.

    With bounds ``l = 0`` and ``u = n_levels − 1``: draw ``s`` from the power distribution of index
    ``p`` (density ``p s^(p−1)`` on [0, 1], drawn as ``s = v^(1/p)``, ``v`` uniform) and ``r`` uniform,
    and let ``t = (x − l) / (u − l)`` be the gene's position in its range; the mutant is
    ``x − s (x − l)`` if ``t < r`` (towards the lower bound) else ``x + s (u − x)`` (towards the upper),
    then :func:`integer_truncation`. It always stays within the bounds; a gene nearer a bound is more
    likely to move towards it, by a fraction ``s`` of the room left; a gene on a bound stays there
    (crossover can move it). MATLAB does not publish its per-gene mutation rate for integer problems and
    MI-LXPM applies the operator gene by gene with a probability; here every gene of a mutation child is
    mutated, so that a child by mutation differs from its parent wherever it can.

    Parameters
    ----------
    parents : ndarray, shape (m, n_variables)
        Integer grid coordinates.
    n_levels : ndarray, shape (n_variables,)
        Grid points of each variable.
    rng : numpy.random.Generator
        Random source.
    index : float
        ``p`` (MI-LXPM for integer variables: 4).

    Returns
    -------
    ndarray, shape (m, n_variables)
        The mutants, integer grid coordinates within the bounds.
    """
    shape = np.shape(parents)
    upper = (n_levels - 1).astype(np.float64)
    x = np.asarray(parents, dtype=np.float64)
    s = rng.random(shape) ** (1.0 / index)
    r = rng.random(shape)
    t = x / upper
    mutant = np.where(t < r, x - s * x, x + s * (upper - x))
    return np.clip(integer_truncation(mutant, rng), 0, n_levels - 1)


def total_violation(constraints: tuple[float, ...]) -> float:
    """MATLAB's penalty term: the sum of the constraint values above 0 (feasible when all are <= 0); NaN
    where none is known (a design the simulator could not assess)."""
    known = [c for c in constraints if np.isfinite(c)]
    return float(sum(max(c, 0.0) for c in known)) if known else float("nan")


def penalty_scores(losses: NDArray[np.float64], violations: NDArray[np.float64]) -> NDArray[np.float64]:
    """MATLAB's penalty function: a feasible individual's loss; an infeasible one's, the largest feasible loss
    of the population (0 if none) plus its total violation (+inf where unknown)."""
    feasible = np.isfinite(losses)
    worst = float(np.max(losses[feasible])) if np.any(feasible) else 0.0
    penalised = np.where(np.isfinite(violations), worst + violations, np.inf)
    return np.where(feasible, losses, penalised)


def elite_indices(losses: NDArray[np.float64], count: int) -> NDArray[np.int64]:
    """The ``count`` individuals of lowest loss (ties in population order): copied unchanged (elitism)."""
    return np.argsort(losses, kind="stable")[:count].astype(np.int64)


def _round_half_away(value: float) -> int:
    """MATLAB's ``round`` (half away from zero), for counts."""
    return int(np.floor(value + 0.5))


def average_relative_change(best: list[float], window: int) -> float:
    """MATLAB's stall measure: mean of ``|b_{g+1} − b_g| / (|b_g| + 1)`` over the last ``window`` generations.

    ``b_g`` is the best loss of generation ``g``. Returns +inf while fewer than ``window + 1``
    generations exist or while the window holds a generation with no feasible individual.
    (MATLAB's code of 2005 weighted the terms by ``0.5^(window − i)``; its documentation since then
    speaks of the average relative change, which is what is computed here.)
    """
    if len(best) <= window:
        return float("inf")
    values = np.asarray(best[-(window + 1) :])
    if not np.all(np.isfinite(values)):
        return float("inf")
    return float(np.mean(np.abs(np.diff(values)) / (np.abs(values[:-1]) + 1.0)))


# -- the algorithm ---------------------------------------------------------------------------------------


class GeneticAlgorithm(Optimizer):
    """MATLAB's integer ``ga`` as ask / tell: the first batch is the initial population, then one batch
    of children per generation (the elite is kept with its scores and not evaluated again).

    Parameters
    ----------
    space : GridSpace
        The grid searched.
    budget : int
        Simulations allowed (the driver enforces it; the GA stops itself by its own rules too).
    seed : int
        Random seed.
    options : GAOptions, optional
        Hyper-parameters; the published study's defaults.
    """

    name = "ga"

    def __init__(self, space: GridSpace, budget: int, seed: int, options: GAOptions | None = None) -> None:
        super().__init__(space, budget, seed)
        self.options = GAOptions() if options is None else options
        self.population_size = _population_size(space, self.options)
        self.max_generations = self.options.max_generations or 100 * space.n_variables
        if not 0 <= self.options.elite_count < self.population_size:
            raise ValueError(f"elite_count = {self.options.elite_count}: must lie in [0, population size)")
        if not 0.0 <= self.options.crossover_fraction <= 1.0:
            raise ValueError(f"crossover_fraction = {self.options.crossover_fraction}: must lie in [0, 1]")
        self.rng = np.random.default_rng(seed)
        self.generation = 0
        """Generations completed after the initial population."""
        self.population: NDArray[np.int64] | None = None
        self.losses: NDArray[np.float64] | None = None
        self.violations = np.zeros(0)
        """Each individual's total constraint violation (:func:`total_violation`)."""
        self.best_history: list[float] = []
        """Best loss of the initial population and of each generation."""
        self.penalty_history: list[float] = []
        """Best penalty score (:func:`penalty_scores`) of each: MATLAB's stall measure reads it."""
        self._elite: tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]] | None = None

    def _internal_ask(self) -> NDArray[np.int64]:
        if self.population is None:
            # MATLAB's integer creation: uniform over the integers within the bounds.
            size = (self.population_size, self.space.n_variables)
            return self.rng.integers(0, self.n_levels, size=size).astype(np.int64)
        assert self.losses is not None
        # The elite by loss; with no feasible individual, by MATLAB's penalty (the smallest violations).
        feasible = np.any(np.isfinite(self.losses))
        ranking = self.losses if feasible else penalty_scores(self.losses, self.violations)
        elite = elite_indices(ranking, self.options.elite_count)
        self._elite = (self.population[elite], self.losses[elite], self.violations[elite])
        return self._children(self.population, self.losses)

    def _children(self, population: NDArray[np.int64], losses: NDArray[np.float64]) -> NDArray[np.int64]:
        """Crossover and mutation children of one generation (``stepGA``)."""
        n_children = self.population_size - self.options.elite_count
        n_crossover = _round_half_away(self.options.crossover_fraction * n_children)
        n_mutation = n_children - n_crossover
        n_parents = 2 * n_crossover + n_mutation
        expectation = rank_expectation(losses, n_parents, self.violations)
        parents = self.rng.permutation(stochastic_uniform(expectation, n_parents, self.rng))
        pairs = parents[: 2 * n_crossover]
        crossover = laplace_crossover(
            population[pairs[0::2]], population[pairs[1::2]], self.n_levels, self.rng,
            self.options.laplace_location, self.options.laplace_scale,
        )  # fmt: skip
        mutation = power_mutation(
            population[parents[2 * n_crossover :]], self.n_levels, self.rng, self.options.power_index
        )
        return np.vstack([crossover, mutation]).astype(np.int64)

    def _internal_tell(self, points: NDArray[np.int64], losses: NDArray[np.float64]) -> None:
        self._internal_tell_constrained(points, losses, ((),) * len(losses))

    def _internal_tell_constrained(
        self,
        points: NDArray[np.int64],
        losses: NDArray[np.float64],
        constraints: tuple[tuple[float, ...], ...],
    ) -> None:
        violations = np.array([total_violation(c) for c in constraints], dtype=np.float64)
        if self._elite is None:
            self.population, self.losses, self.violations = points, losses, violations
        else:
            self.population = np.vstack([self._elite[0], points])
            self.losses = np.concatenate([self._elite[1], losses])
            self.violations = np.concatenate([self._elite[2], violations])
            self.generation += 1
        self.best_history.append(float(np.min(self.losses)))
        # MATLAB's stall measure follows the penalty: with no feasible individual, the smallest violation.
        self.penalty_history.append(float(np.min(penalty_scores(self.losses, self.violations))))
        change = average_relative_change(self.penalty_history, self.options.max_stall_generations)
        if change <= self.options.function_tolerance:
            self._stop_reason = "stall"
        elif self.generation >= self.max_generations:
            self._stop_reason = "generations"


def _population_size(space: GridSpace, options: GAOptions) -> int:
    if options.population_size is not None:
        return int(options.population_size)
    if space.name in POPULATION_SIZES:
        return POPULATION_SIZES[space.name]
    return 50 if space.n_variables <= 5 else 200


register_optimizer(
    OptimizerSpec(
        "ga", GeneticAlgorithm, GAOptions, "the published study's genetic algorithm (MATLAB ga, integer)"
    )
)
