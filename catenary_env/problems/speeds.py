"""A design's σ over several speeds: the objective of the environments' ``"mean_sigma_over_speeds"`` and
``"worst_sigma_over_speeds"`` and of the studies' mean-σ problem (docs/problems.md, 'Environments').

The design is simulated at each speed in turn; it is infeasible where it is infeasible at any speed, and the
speeds after the first infeasible one are not simulated (the objective is decided). σ over the speeds is
their mean, or their largest value.

Examples
--------
>>> from catenary_env.pipeline import Evaluation
>>> def fake(speed_kmh):
...     return Evaluation(speed_kmh < 300.0, "" if speed_kmh < 300.0 else "dynamic: contact lost",
...                       None, (), (), 150.0, 1.0)
>>> result = evaluate_over_speeds(fake, (200.0, 300.0, 320.0))
>>> result.feasible, result.reason, len(result.evaluations)
(False, 'at 300 km/h: dynamic: contact lost', 2)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..pipeline import Evaluation

__all__ = ["SpeedsEvaluation", "evaluate_over_speeds"]


@dataclass(frozen=True)
class SpeedsEvaluation:
    """A design's evaluations at several speeds, up to the first speed at which it is infeasible.

    Attributes
    ----------
    speeds_kmh : tuple of float
        The speeds of the objective, km/h.
    evaluations : tuple of Evaluation
        One per speed simulated, in the order of ``speeds_kmh``; shorter where the design is infeasible.
    """

    speeds_kmh: tuple[float, ...]
    evaluations: tuple[Evaluation, ...]

    @property
    def feasible(self) -> bool:
        """Feasible (and simulated) at every speed."""
        return len(self.evaluations) == len(self.speeds_kmh) and all(e.feasible for e in self.evaluations)

    @property
    def reason(self) -> str:
        """Why the design is infeasible (``"at V km/h: ..."`` over several speeds); empty when feasible."""
        for speed, evaluation in zip(self.speeds_kmh, self.evaluations, strict=False):
            if not evaluation.feasible:
                single = len(self.speeds_kmh) == 1
                return evaluation.reason if single else f"at {speed:g} km/h: {evaluation.reason}"
        return ""

    @property
    def wall_time(self) -> float:
        """Seconds of the simulations behind the result."""
        return float(sum(e.wall_time for e in self.evaluations))

    def sigma(self, worst: bool = False) -> float | None:
        """σ of the contact force over the speeds, N: their mean (``worst``: their largest); None when the
        design is infeasible. Each speed's σ is its evaluation's objective σ (:attr:`Evaluation.sigma`)."""
        if not self.feasible:
            return None
        sigmas = [e.sigma for e in self.evaluations if e.statistics is not None]
        return float(np.max(sigmas) if worst else np.mean(sigmas))


def evaluate_over_speeds(
    evaluate: Callable[[float], Evaluation], speeds_kmh: Sequence[float]
) -> SpeedsEvaluation:
    """Evaluate a design at each speed (km/h) with ``evaluate(speed_kmh)``, stopping at the first speed at
    which it is infeasible."""
    speeds = tuple(float(v) for v in speeds_kmh)
    if not speeds:
        raise ValueError("speeds_kmh: give at least one speed, km/h")
    evaluations: list[Evaluation] = []
    for speed in speeds:
        evaluations.append(evaluate(speed))
        if not evaluations[-1].feasible:
            break
    return SpeedsEvaluation(speeds, tuple(evaluations))
