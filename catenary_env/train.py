"""The train: the pantographs behind the leading one, and which of them a design's objective reads
(docs/model.md, 'Several pantographs').

A :class:`Train` of the default kind is one pantograph, the project's setting everywhere. With trailing
pantographs every pantograph crosses the same section at the train's speed, each with its own pantograph
data, uplift force and offset behind the leading one; the objective σ is the leading one's, the trailing
one's, the worse of all (``"worst"``) or their mean (:data:`OBJECTIVES`); the feasibility check covers every
pantograph.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from .analysis.statistics import ContactStatistics
from .model.definition import CatenaryDefinition, PantographDefinition
from .model.design import DesignError

__all__ = ["OBJECTIVES", "SINGLE", "TrailingPantograph", "Train", "objective_sigma"]

OBJECTIVES = ("leading", "trailing", "worst", "mean")
"""Which pantograph's σ a design's objective is: the leading one's, the last one's, the largest, the mean."""


@dataclass(frozen=True)
class TrailingPantograph:
    """A pantograph behind the leading one.

    Attributes
    ----------
    pantograph : PantographDefinition
    offset : float
        Its distance behind the leading pantograph, m.
    uplift_force : float or None
        Its static uplift force, N; None: the leading one's (the same pantograph type set once, docs/model.md,
        'Several pantographs').
    """

    pantograph: PantographDefinition
    offset: float
    uplift_force: float | None = None


@dataclass(frozen=True)
class Train:
    """The pantographs behind the leading one, and the objective's pantograph(s).

    Attributes
    ----------
    trailing : tuple of TrailingPantograph
        In order behind the leading one; empty: one pantograph.
    objective : str
        One of :data:`OBJECTIVES`.
    """

    trailing: tuple[TrailingPantograph, ...] = ()
    objective: str = "leading"

    def __post_init__(self) -> None:
        if self.objective not in OBJECTIVES:
            raise DesignError(f"train.objective = {self.objective!r}: one of {', '.join(OBJECTIVES)}")
        offsets = [t.offset for t in self.trailing]
        if any(not (math.isfinite(a) and a > 0.0) for a in offsets) or offsets != sorted(offsets):
            raise DesignError(f"train spacing: offsets {offsets} m must be finite, > 0 m and in order")
        for t in self.trailing:
            if t.uplift_force is not None and not (math.isfinite(t.uplift_force) and t.uplift_force > 0.0):
                raise DesignError(
                    f"trailing uplift_force = {t.uplift_force!r}: must be a finite number > 0 N"
                )

    @classmethod
    def behind(
        cls, pantographs: Sequence[PantographDefinition], spacing: float, objective: str = "leading"
    ) -> Train:
        """The leading pantograph and ``pantographs`` behind it, ``spacing`` m apart each (the leading one's
        uplift force for all)."""
        if not (math.isfinite(spacing) and spacing > 0.0):
            raise DesignError(f"spacing = {spacing!r}: must be a finite number > 0 m")
        trailing = tuple(TrailingPantograph(p, spacing * (i + 1)) for i, p in enumerate(pantographs))
        return cls(trailing, objective)

    @property
    def n_pantographs(self) -> int:
        return 1 + len(self.trailing)

    def spacing_range(
        self, catenary: CatenaryDefinition, n_spans: int, analysis_end: float
    ) -> tuple[float, float]:
        """The offsets a section of ``n_spans`` spans takes, m: a span at least (the span-mode model's
        near fields are per span), and at most so far that the leading pantograph is still on the section
        when the last one is a span past the analysis section (ending at ``analysis_end`` m)."""
        return catenary.span_length, n_spans * catenary.span_length - analysis_end - catenary.span_length

    def check(self, catenary: CatenaryDefinition, n_spans: int, analysis_end: float) -> None:
        """Refuse offsets the section cannot take, naming the range (:meth:`spacing_range`)."""
        if not self.trailing:
            return
        low, high = self.spacing_range(catenary, n_spans, analysis_end)
        offsets = [t.offset for t in self.trailing]
        gaps = [b - a for a, b in zip([0.0, *offsets[:-1]], offsets, strict=True)]
        if min(gaps) < low - 1e-9 or offsets[-1] > high + 1e-9:
            raise DesignError(
                f"spacing: offsets {offsets} m must be {low:g} m apart at least and {high:g} m at most "
                f"behind the leading pantograph on {n_spans} spans (raise fidelity.n_spans for a longer "
                "train)"
            )


SINGLE = Train()
"""One pantograph: the default everywhere."""


def objective_sigma(statistics: Sequence[ContactStatistics], objective: str) -> float:
    """The objective σ (N) of every pantograph's statistics, the leading one first (:data:`OBJECTIVES`)."""
    sigmas = [s.std for s in statistics]
    if objective == "leading":
        return sigmas[0]
    if objective == "trailing":
        return sigmas[-1]
    if objective == "worst":
        return max(sigmas)
    return sum(sigmas) / len(sigmas)
