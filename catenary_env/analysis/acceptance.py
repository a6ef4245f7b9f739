"""The EN 50367 acceptance of a simulated passage: each criterion the simulation can evaluate, its limit,
the value and pass or fail (docs/acceptance.md).

The limits are data (:class:`~catenary_env.model.acceptance_limits.AcceptanceLimits`, loaded from a TOML
preset with source tags); this module compares the statistics of docs/model.md, 'Statistics and
feasibility' with them.

Examples
--------
>>> from catenary_env.model.presets import load_acceptance
>>> from catenary_env.analysis.statistics import ContactStatistics
>>> stats = ContactStatistics(157.3, 30.0, 30.0 / 157.3, 247.3, 67.3, 240.0, 80.0, 0.0, 0.05)
>>> acceptance = assess(stats, 300.0, load_acceptance())
>>> acceptance.passed, [c.name for c in acceptance.criteria if c.passed is False]
(True, [])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..model.acceptance_limits import AcceptanceLimits
from .statistics import ContactStatistics


@dataclass(frozen=True)
class Criterion:
    """One acceptance criterion of a passage.

    Attributes
    ----------
    name : str
        The criterion, e.g. ``"σ / Fm"``.
    value : float
        The simulated value, in ``unit``.
    limit : str
        The limit as text, e.g. ``"<= 0.3"``.
    unit : str
    passed : bool or None
        None for a requirement the simulation informs but cannot decide (the steady arm's free space).
    tag : str
        The limit's source tag (``S``, ``S?``, ``A``; docs/model.md, 'Data and sources').
    """

    name: str
    value: float
    limit: str
    unit: str
    passed: bool | None
    tag: str


@dataclass(frozen=True)
class Acceptance:
    """The acceptance block of a passage: every criterion that applies at its speed.

    Attributes
    ----------
    limits : str
        Name of the limits used (e.g. ``"en50367-ac"``).
    speed_kmh : float
    criteria : tuple of Criterion
    """

    limits: str
    speed_kmh: float
    criteria: tuple[Criterion, ...]

    @property
    def passed(self) -> bool:
        """Every decided criterion passed."""
        return all(c.passed is not False for c in self.criteria)

    @property
    def failed(self) -> tuple[str, ...]:
        """Names of the criteria that failed."""
        return tuple(c.name for c in self.criteria if c.passed is False)

    @property
    def passed_by_the_catenary(self) -> bool:
        """Every decided criterion passed but the mean-force window (:data:`MEAN_FORCE_CRITERIA`), which the
        pantograph's uplift force decides: a study that sets the uplift so that Fm is the upper curve at the
        design speed (docs/problems.md) leaves that verdict to hundredths of a newton either way."""
        return all(c.passed is not False for c in self.criteria if c.name not in MEAN_FORCE_CRITERIA)

    def as_dict(self) -> dict[str, Any]:
        """For JSON: the limits' name, overall verdict and one object per criterion."""
        return {
            "limits": self.limits,
            "passed": self.passed,
            "criteria": [
                {
                    "name": c.name,
                    "value": c.value,
                    "limit": c.limit,
                    "unit": c.unit,
                    "passed": c.passed,
                    "tag": c.tag,
                }
                for c in self.criteria
            ],
        }

    def text_lines(self, indent: str = "  ") -> list[str]:
        """The block as text, one criterion a line: name, value, limit, verdict and source tag."""
        verdicts = {True: "pass", False: "FAIL", None: "info"}
        lines = [
            f"acceptance ({self.limits} at {self.speed_kmh:g} km/h): {'pass' if self.passed else 'FAIL'}"
        ]
        for c in self.criteria:
            value = f"{c.value:10.3f} {c.unit:<3}"
            lines.append(f"{indent}{c.name:<26} {value} {c.limit:<18} {verdicts[c.passed]:<5} [{c.tag}]")
        return lines


def _tag(limits: AcceptanceLimits, name: str) -> str:
    return limits.provenance.get(name, "A").split(":")[0]


MEAN_FORCE_CRITERIA = ("mean force Fm (upper)", "mean force Fm (lower)")
"""The criteria of the mean contact force's window, which the pantograph's uplift force sets."""


def assess(statistics: ContactStatistics, speed_kmh: float, limits: AcceptanceLimits) -> Acceptance:
    """The acceptance block of a passage's statistics at a speed (km/h)."""
    s = statistics
    criteria = [
        Criterion(
            "σ / Fm",
            s.std_over_mean,
            f"<= {limits.max_std_over_mean:g}",
            "-",
            s.std_over_mean <= limits.max_std_over_mean,
            _tag(limits, "max_std_over_mean"),
        ),
    ]
    mean_range = limits.mean_force_range(speed_kmh)
    if mean_range is not None:
        low, high = mean_range
        criteria += [
            Criterion(
                MEAN_FORCE_CRITERIA[0],
                s.mean,
                f"<= {high:.1f} N",
                "N",
                s.mean <= high,
                _tag(limits, "upper_mean_force"),
            ),
            Criterion(
                MEAN_FORCE_CRITERIA[1],
                s.mean,
                f">= {low:.1f} N",
                "N",
                s.mean >= low,
                _tag(limits, "lower_mean_force"),
            ),
        ]
    criteria += [
        Criterion(
            "statistical min Fm - 3σ",
            s.statistical_min,
            f"> {limits.min_statistical_force:g} N",
            "N",
            s.statistical_min > limits.min_statistical_force,
            _tag(limits, "min_statistical_force"),
        ),
        Criterion(
            "largest contact force",
            s.actual_max,
            f"<= {limits.max_contact_force:g} N",
            "N",
            s.actual_max <= limits.max_contact_force,
            _tag(limits, "max_contact_force"),
        ),
    ]
    if speed_kmh > limits.contact_loss_min_speed:
        criteria.append(
            Criterion(
                "contact loss (arcing proxy)",
                s.contact_loss_percent,
                f"<= {limits.max_contact_loss_percent:g} %",
                "%",
                s.contact_loss_percent <= limits.max_contact_loss_percent,
                _tag(limits, "max_contact_loss_percent"),
            )
        )
    free_space = limits.uplift_free_space_factor * s.max_support_uplift * 1000.0
    criteria.append(
        Criterion(
            "steady-arm free space",
            free_space,
            f"{limits.uplift_free_space_factor:g} x uplift",
            "mm",
            None,
            _tag(limits, "uplift_free_space_factor"),
        )
    )
    return Acceptance(limits.name, float(speed_kmh), tuple(criteria))
