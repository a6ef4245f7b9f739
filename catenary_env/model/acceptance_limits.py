"""Acceptance limits of a contact line's current collection (EN 50367), as data (docs/acceptance.md).

The limits are read from a TOML preset (``model/presets/acceptance/en50367-ac.toml``) that a user can copy
and edit, with a ``[provenance]`` table of source tags like the catenary presets. The assessment of a
simulation against them lives in :mod:`catenary_env.analysis.acceptance`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .definition import DefinitionError


@dataclass(frozen=True)
class AcceptanceLimits:
    """The EN 50367 criteria this project can evaluate on a simulated passage, for one kind of line.

    Attributes
    ----------
    name : str
        Identifier, e.g. ``"en50367-ac"``.
    max_std_over_mean : float
        Largest σ / Fm, dimensionless (0.3).
    upper_mean_force : tuple of float
        (a, b) of the largest mean contact force a v² + b, N with v in km/h (0.00097, 70).
    lower_mean_force : tuple of float
        (a, b) of the smallest mean contact force a v² + b, N with v in km/h (0.00047, 60).
    mean_force_speeds : tuple of float
        (low, high], km/h: the speeds at which both mean-force curves apply (200, 320).
    min_statistical_force : float
        Smallest statistical minimum Fm - 3σ, N (0: it must stay positive).
    max_contact_force : float
        Largest filtered contact force, N (about 350 N on AC lines above 200 km/h).
    max_contact_loss_percent : float
        Largest share of time without contact, % (the simulation's proxy of the measured arcing NQ).
    contact_loss_min_speed : float
        Speed above which the contact-loss limit applies, km/h.
    uplift_free_space_factor : float
        Free space to leave for the steady arm's uplift, as a multiple of the simulated uplift (2).
    provenance : dict
        Source tag of each figure, keyed by field name (``S``, ``S?``, ``A``; docs/model.md, 'Data and
        sources').
    """

    name: str
    max_std_over_mean: float
    upper_mean_force: tuple[float, ...]
    lower_mean_force: tuple[float, ...]
    mean_force_speeds: tuple[float, ...]
    min_statistical_force: float
    max_contact_force: float
    max_contact_loss_percent: float
    contact_loss_min_speed: float
    uplift_free_space_factor: float
    provenance: dict[str, str] = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        where = f"acceptance '{self.name}'"
        for name in ("upper_mean_force", "lower_mean_force", "mean_force_speeds"):
            values = getattr(self, name)
            if len(values) != 2 or not all(math.isfinite(v) and v >= 0.0 for v in values):
                raise DefinitionError(f"{where}.{name} = {list(values)!r}: must be two finite numbers >= 0")
        if not self.mean_force_speeds[0] < self.mean_force_speeds[1]:
            raise DefinitionError(f"{where}.mean_force_speeds: the low speed must be below the high one")
        checks = (
            ("max_std_over_mean", 0.0, 1.0),
            ("min_statistical_force", -1e3, 1e3),
            ("max_contact_force", 0.0, 2e3),
            ("max_contact_loss_percent", 0.0, 100.0),
            ("contact_loss_min_speed", 0.0, 1e3),
            ("uplift_free_space_factor", 1.0, 10.0),
        )
        for name, low, high in checks:
            value = getattr(self, name)
            if not (math.isfinite(value) and low <= value <= high):
                raise DefinitionError(f"{where}.{name} = {value!r}: must lie in [{low:g}, {high:g}]")

    def mean_force_range(self, speed_kmh: float) -> tuple[float, float] | None:
        """(lowest, highest) mean contact force at a speed, N; None where the curves do not apply."""
        low, high = self.mean_force_speeds
        if not low < speed_kmh <= high:
            return None
        (a_lo, b_lo), (a_hi, b_hi) = self.lower_mean_force, self.upper_mean_force
        return a_lo * speed_kmh**2 + b_lo, a_hi * speed_kmh**2 + b_hi
