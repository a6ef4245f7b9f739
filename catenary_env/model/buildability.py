"""Buildability limits: what a line builder would refuse although the model accepts it (docs/acceptance.md,
'Buildability limits').

The shape-finding forbids only droppers in compression (SPEC 3.3). A dropper that carries almost nothing
goes slack at the first disturbance, a dropper shorter than its two terminals cannot be made, and droppers
far apart leave the contact wire sagging between them: :class:`BuildabilityLimits` names such limits, and a
design that violates one is statically infeasible, with a reason naming the limit, before any dynamics.

:data:`NO_LIMITS` (the default of every problem and environment) keeps the reference study's problems as
they were; :data:`DEFAULT_BUILDABILITY` holds the documented defaults, each with its source tag in
:data:`BUILDABILITY_PROVENANCE`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .definition import DefinitionError


@dataclass(frozen=True)
class BuildabilityLimits:
    """Limits on a design's static state and geometry; a limit at its default does not bind.

    Attributes
    ----------
    min_dropper_force : float
        Smallest static dropper force, N (0: only compression is refused).
    min_dropper_length : float
        Shortest unstretched dropper, terminals included, m (0: only a negative length is refused).
    max_dropper_spacing : float
        Largest distance between neighbouring droppers of a span, m (inf: none).
    """

    min_dropper_force: float = 0.0
    min_dropper_length: float = 0.0
    max_dropper_spacing: float = math.inf

    def __post_init__(self) -> None:
        checks = (
            ("min_dropper_force", 0.0, 500.0, "N"),
            ("min_dropper_length", 0.0, 2.0, "m"),
            ("max_dropper_spacing", 1.0, math.inf, "m"),
        )
        for name, low, high, unit in checks:
            value = getattr(self, name)
            if not (isinstance(value, int | float) and low <= value <= high) or math.isnan(value):
                raise DefinitionError(
                    f"buildability.{name} = {value!r}: must lie in [{low:g}, {high:g}] {unit}"
                )

    @property
    def binding(self) -> bool:
        """Some limit is tighter than the model's own (compression, negative length)."""
        return self != NO_LIMITS

    def describe(self) -> str:
        """One line, e.g. ``"dropper force >= 30 N, dropper length >= 0.5 m, spacing <= 11 m"``."""
        if not self.binding:
            return "none (only compression and negative lengths are refused)"
        return (
            f"dropper force >= {self.min_dropper_force:g} N, "
            f"dropper length >= {self.min_dropper_length:g} m, "
            f"dropper spacing <= {self.max_dropper_spacing:g} m"
        )


NO_LIMITS = BuildabilityLimits()
"""No limit beyond the model's: the reference study's setting, under which every recorded result was made."""

DEFAULT_BUILDABILITY = BuildabilityLimits(
    min_dropper_force=30.0, min_dropper_length=0.5, max_dropper_spacing=11.0
)
"""The documented defaults (docs/acceptance.md, 'Buildability limits'); tags in
:data:`BUILDABILITY_PROVENANCE`."""

BUILDABILITY_PROVENANCE = {
    "min_dropper_force": "A: no published value found; about 40 % of a level wire's dropper force (75 N on "
    "the benchmark catenary), so that a dropper stays taut under the passing pantograph's first waves",
    "min_dropper_length": "S?: one infrastructure manager's design rule (Bane NOR): shortest dropper with "
    "terminals 500 mm",
    "max_dropper_spacing": "S?: one infrastructure manager's design rule (Bane NOR): dropper spacing <= 11 m",
}
"""Source tag of each default of :data:`DEFAULT_BUILDABILITY` (docs/model.md, 'Data and sources')."""


def buildability_named(name: str) -> BuildabilityLimits:
    """``"none"`` (:data:`NO_LIMITS`) or ``"default"`` (:data:`DEFAULT_BUILDABILITY`)."""
    table = {"none": NO_LIMITS, "default": DEFAULT_BUILDABILITY}
    if name not in table:
        raise DefinitionError(
            f"buildability = {name!r}: must be one of none, default or a BuildabilityLimits"
        )
    return table[name]
