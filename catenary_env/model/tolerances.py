"""Installation tolerances: random deviations of a built line from its design (docs/acceptance.md,
'Installation tolerances').

A line is built to tolerances: the contact-wire height at every dropper and every dropper's position
deviate at random, independently, in every span, so the spans of a built section are no longer equal.
:class:`Tolerances` gives the sizes as data (distribution, magnitude, source tag); :func:`draw_deviations`
draws one section's deviations, seeded so that draw ``k`` of seed ``s`` is the same for every design of
the same number of droppers (common random numbers when designs are compared).

Examples
--------
>>> tol = Tolerances(height=0.005, position=0.05)
>>> a = draw_deviations(tol, n_spans=4, n_droppers=9, seed=1, draw=3)
>>> b = draw_deviations(tol, n_spans=4, n_droppers=9, seed=1, draw=3)
>>> bool((a.height == b.height).all()), a.height.shape, float(abs(a.height).max()) <= 0.005
(True, (4, 9), True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .definition import DefinitionError

DISTRIBUTIONS = ("uniform", "normal")
"""``uniform``: on [-magnitude, magnitude]; ``normal``: standard deviation magnitude / 2 (so that about 95 %
of the deviations lie within ± magnitude), cut at ± magnitude."""


@dataclass(frozen=True)
class Tolerances:
    """Sizes of the random installation deviations.

    Attributes
    ----------
    height : float
        Magnitude of the contact-wire height deviation at each dropper, m (± this).
    position : float
        Magnitude of each dropper's position deviation along the track, m (± this).
    distribution : {"uniform", "normal"}
        See :data:`DISTRIBUTIONS`.
    provenance : dict
        Source tag of ``height`` and ``position`` (docs/model.md, 'Data and sources').
    """

    height: float
    position: float
    distribution: str = "uniform"
    provenance: dict[str, str] = field(default_factory=dict, compare=False, hash=False, repr=False)

    def __post_init__(self) -> None:
        for name, high in (("height", 0.05), ("position", 0.5)):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and 0.0 <= value <= high):
                raise DefinitionError(f"tolerances.{name} = {value!r}: must lie in [0, {high:g}] m")
        if self.distribution not in DISTRIBUTIONS:
            raise DefinitionError(
                f"tolerances.distribution = {self.distribution!r}: must be one of {', '.join(DISTRIBUTIONS)}"
            )

    def describe(self) -> str:
        return (
            f"height ±{1000 * self.height:g} mm, position ±{100 * self.position:g} cm ({self.distribution})"
        )


PRACTICE = Tolerances(
    height=0.002,
    position=0.05,
    provenance={
        "height": "A: the dropper-length tolerance, about ±1.5-2 mm (recalled, low confidence; no primary "
        "source found): what sets the height of one dropper's point against its neighbours'. The ±10 mm "
        "of design recalled for the contact-wire height includes long-wave errors (support heights), which "
        "independent per-dropper deviations would overstate",
        "position": "A: dropper position ±5 cm (an assumption; measured lines model it as Gaussian, "
        "Song et al. 2021)",
    },
)
"""The independent per-dropper deviations practice gives, as far as the project knows (docs/acceptance.md;
all tagged A)."""


@dataclass(frozen=True, eq=False)
class SectionDeviations:
    """One built section's deviations from its design, per span and dropper.

    Attributes
    ----------
    height : ndarray, shape (n_spans, n_droppers)
        Contact-wire height deviation at each dropper, m (positive = higher).
    position : ndarray, shape (n_spans, n_droppers)
        Dropper position deviation, m (positive = further along the track).
    """

    height: np.ndarray
    position: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        return self.height.shape  # type: ignore[return-value]


def draw_deviations(
    tolerances: Tolerances, n_spans: int, n_droppers: int, seed: int, draw: int
) -> SectionDeviations:
    """Draw ``draw`` of ``seed``: the same numbers for every design with ``n_droppers`` droppers a span."""
    rng = np.random.default_rng([int(seed), int(draw)])
    shape = (n_spans, n_droppers)
    if tolerances.distribution == "uniform":
        unit = rng.uniform(-1.0, 1.0, size=(2, *shape))
    else:
        unit = np.clip(0.5 * rng.standard_normal(size=(2, *shape)), -1.0, 1.0)
    return SectionDeviations(tolerances.height * unit[0], tolerances.position * unit[1])


def check_deviations(
    deviations: SectionDeviations,
    positions: tuple[float, ...],
    span_length: float,
    n_spans: int,
    stitch_half: float | None = None,
) -> None:
    """Refuse deviations of the wrong shape, or that move a dropper out of its span, past its neighbour or off
    its stitch wire.

    Raises
    ------
    DefinitionError
        Naming the span and dropper.
    """
    shape = (n_spans, len(positions))
    if deviations.height.shape != shape or deviations.position.shape != shape:
        raise DefinitionError(f"deviations: expected arrays of shape {shape} (spans, droppers)")
    if not (np.all(np.isfinite(deviations.height)) and np.all(np.isfinite(deviations.position))):
        raise DefinitionError("deviations: values must be finite numbers, m")
    x = np.asarray(positions)[None, :] + deviations.position
    close = np.diff(x, axis=1) < 0.05
    if np.any(close):
        span, dropper = (int(v[0]) for v in np.nonzero(close))
        raise DefinitionError(
            f"deviations: droppers {dropper + 1} and {dropper + 2} of span {span + 1} stand at "
            f"{x[span, dropper]:.3f} and {x[span, dropper + 1]:.3f} m, crossed or less than 0.05 m apart; "
            "give a smaller position tolerance"
        )
    outside = (x <= 0.0) | (x >= span_length)
    if stitch_half is not None:
        outside[:, 0] |= x[:, 0] >= stitch_half
        outside[:, -1] |= span_length - x[:, -1] >= stitch_half
    if np.any(outside):
        span, dropper = (int(v[0]) for v in np.nonzero(outside))
        raise DefinitionError(
            f"deviations: dropper {dropper + 1} of span {span + 1} moves to {x[span, dropper]:.3f} m, out of "
            "its span or off the stitch wire; give a smaller position tolerance"
        )
