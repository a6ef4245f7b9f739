"""A design under installation tolerances: σ over seeded draws of the built section (docs/acceptance.md,
'Installation tolerances'), and the robust objective built on it.

Draw ``k`` of seed ``s`` (:func:`~catenary_env.model.tolerances.draw_deviations`) is the same for every
design with the same number of droppers a span, so designs compared on the same draws differ by their
geometry only (common random numbers).

Examples
--------
>>> from catenary_env.pipeline import Evaluation
>>> from catenary_env.model.tolerances import Tolerances
>>> def fake(deviations):
...     return Evaluation(True, "", None, (), (), 120.0, 0.1)
>>> result = evaluate_under_tolerances(fake, Tolerances(0.002, 0.05), 5, 9, draws=3, seed=0)
>>> len(result.evaluations), result.infeasible_share
(3, 0.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from ..analysis.acceptance import assess
from ..analysis.statistics import ContactStatistics
from ..model.tolerances import PRACTICE, SectionDeviations, Tolerances, draw_deviations
from ..pipeline import Evaluation, default_acceptance

__all__ = [
    "RobustObjective",
    "ToleranceEvaluation",
    "evaluate_under_tolerances",
    "robust_evaluation",
    "worst_constraints",
]


@dataclass(frozen=True)
class RobustObjective:
    """The robust objective of a problem or env: σ over ``draws`` tolerance draws of seed ``seed``.

    Attributes
    ----------
    tolerances : Tolerances
        Sizes of the deviations (default: :data:`~catenary_env.model.tolerances.PRACTICE`).
    draws : int
        K, the draws per design (the same K draws for every design of a run).
    seed : int
    quantile : float or None
        None: the mean of σ over the draws; a number in (0, 1): that quantile (0.9: the σ nine built
        sections in ten stay below).
    """

    tolerances: Tolerances = PRACTICE
    draws: int = 8
    seed: int = 0
    quantile: float | None = None

    def __post_init__(self) -> None:
        if isinstance(self.draws, bool) or not isinstance(self.draws, int) or not 1 <= self.draws <= 10000:
            raise ValueError(f"robust.draws = {self.draws!r}: must be an integer in [1, 10000]")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"robust.seed = {self.seed!r}: must be an integer >= 0")
        if self.quantile is not None and not (0.0 < self.quantile < 1.0):
            raise ValueError(f"robust.quantile = {self.quantile!r}: must be None (the mean) or in (0, 1)")

    def describe(self) -> str:
        what = "mean" if self.quantile is None else f"{100 * self.quantile:g}th percentile"
        return f"{what} of σ over {self.draws} draws (seed {self.seed}) of {self.tolerances.describe()}"


@dataclass(frozen=True)
class ToleranceEvaluation:
    """One design's evaluations on seeded tolerance draws.

    Attributes
    ----------
    tolerances : Tolerances
    seed : int
    evaluations : tuple of Evaluation
        One per draw, draw 0 first.
    """

    tolerances: Tolerances
    seed: int
    evaluations: tuple[Evaluation, ...]

    @property
    def sigmas(self) -> np.ndarray:
        """σ of the feasible draws, N."""
        return np.array([e.statistics.std for e in self.evaluations if e.feasible and e.statistics])

    @property
    def infeasible_share(self) -> float:
        """Share of the draws that are infeasible (static, buildability or contact loss), 0 to 1."""
        return float(np.mean([not e.feasible for e in self.evaluations]))

    @property
    def acceptance_pass_rate(self) -> float:
        """Share of the draws that are feasible and pass every acceptance criterion, 0 to 1."""
        return float(
            np.mean(
                [e.feasible and e.acceptance is not None and e.acceptance.passed for e in self.evaluations]
            )
        )

    def percentiles(self) -> tuple[float, float, float]:
        """(p10, median, p90) of σ over the feasible draws, N (NaN when none is feasible)."""
        if self.sigmas.size == 0:
            return math.nan, math.nan, math.nan
        p10, p50, p90 = np.percentile(self.sigmas, [10.0, 50.0, 90.0])
        return float(p10), float(p50), float(p90)

    def as_dict(self) -> dict[str, Any]:
        """For JSON: the tolerances, the σ percentiles (N), the shares, every draw's σ (None: infeasible)."""
        p10, p50, p90 = self.percentiles()
        return {
            "tolerances": {
                "height": self.tolerances.height,
                "position": self.tolerances.position,
                "distribution": self.tolerances.distribution,
            },
            "seed": self.seed,
            "draws": len(self.evaluations),
            "sigma_p10": p10,
            "sigma_median": p50,
            "sigma_p90": p90,
            "infeasible_share": self.infeasible_share,
            "acceptance_pass_rate": self.acceptance_pass_rate,
            "sigma_per_draw": [
                e.statistics.std if e.feasible and e.statistics else None for e in self.evaluations
            ],
            "reasons": [e.reason for e in self.evaluations if not e.feasible][:5],
        }

    def text_lines(self, indent: str = "  ") -> list[str]:
        """The summary as text, as the command line prints it."""
        p10, p50, p90 = self.percentiles()
        lines = [
            f"{len(self.evaluations)} draws of {self.tolerances.describe()}, seed {self.seed}",
            f"{indent}{'σ median (p10 - p90)':<26} {p50:10.3f} N  ({p10:.3f} - {p90:.3f})",
            f"{indent}{'infeasible draws':<26} {100 * self.infeasible_share:10.1f} %",
            f"{indent}{'acceptance pass rate':<26} {100 * self.acceptance_pass_rate:10.1f} %",
        ]
        reasons = [e.reason for e in self.evaluations if not e.feasible]
        if reasons:
            lines.append(f"{indent}first infeasible draw: {reasons[0]}")
        return lines


def evaluate_under_tolerances(
    evaluate: Callable[[SectionDeviations], Evaluation],
    tolerances: Tolerances,
    n_spans: int,
    n_droppers: int,
    draws: int,
    seed: int,
    progress: Callable[[int], None] | None = None,
) -> ToleranceEvaluation:
    """Evaluate a design on ``draws`` seeded draws of its built section.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(deviations) -> Evaluation`` of the design with a section's deviations.
    tolerances : Tolerances
    n_spans, n_droppers : int
        The section's spans and the design's droppers a span.
    draws, seed : int
        Draws 0 to ``draws - 1`` of ``seed``.
    progress : callable, optional
        Called with the number of draws done.
    """
    evaluations = []
    for k in range(draws):
        evaluations.append(evaluate(draw_deviations(tolerances, n_spans, n_droppers, seed, k)))
        if progress is not None:
            progress(k + 1)
    return ToleranceEvaluation(tolerances, seed, tuple(evaluations))


def robust_evaluation(result: ToleranceEvaluation, robust: RobustObjective, speed_kmh: float) -> Evaluation:
    """The robust objective's evaluation: feasible when every draw is; its statistics are each statistic's
    mean over the draws (or the chosen quantile), so ``statistics.std`` is the robust σ; its constraint values
    the worst draw's (feasible when every draw is)."""
    evaluations = result.evaluations
    first = evaluations[0]
    wall = float(sum(e.wall_time for e in evaluations))
    constraints = worst_constraints(evaluations)
    bad = [(k, e) for k, e in enumerate(evaluations) if not e.feasible]
    if bad:
        k, e = bad[0]
        reason = f"tolerance draw {k} of {len(evaluations)}: {e.reason}"
        return Evaluation(
            False, reason, None, first.dropper_lengths, first.dropper_forces, first.uplift_force, wall,
            constraints=constraints,
        )  # fmt: skip
    stats = [e.statistics for e in evaluations if e.statistics is not None]
    values = {}
    for f in fields(ContactStatistics):
        column = np.array([getattr(s, f.name) for s in stats])
        values[f.name] = float(
            np.mean(column) if robust.quantile is None else np.quantile(column, robust.quantile)
        )
    aggregated = ContactStatistics(**values)
    acceptance = assess(aggregated, speed_kmh, default_acceptance())
    return Evaluation(
        True,
        "",
        aggregated,
        first.dropper_lengths,
        first.dropper_forces,
        first.uplift_force,
        wall,
        acceptance=acceptance,
        constraints=constraints,
    )


def worst_constraints(evaluations: Sequence[Evaluation]) -> tuple[float, ...]:
    """Each constraint value's largest over the draws (NaN where no draw computed it)."""
    known = [e.constraints for e in evaluations if e.constraints]
    if not known:
        return ()
    values = np.array(known, dtype=np.float64)
    computed = np.isfinite(values)
    return tuple(
        float(np.max(column[ok])) if ok.any() else float("nan")
        for column, ok in zip(values.T, computed.T, strict=True)
    )
