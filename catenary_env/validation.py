"""Validation against EN 50318:2002: the reference model's results against the accepted ranges.

The ranges are data (``model/presets/validation/en50318-2002.toml``); the model is the "en50318-2002"
catenary and pantograph presets, simulated as given. Nothing is tuned to land in a range: a
quantity outside its range is reported as such, with the margin.
"""

from __future__ import annotations

import dataclasses
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .errors import UsageError
from .model.design import level_design
from .model.options import ModellingOptions
from .model.presets import load_catenary, load_pantograph
from .pipeline import Fidelity, simulate

VALIDATION_DIR = Path(__file__).parent / "model" / "presets" / "validation"

QUANTITIES = (
    "mean",
    "std",
    "statistical_max",
    "statistical_min",
    "actual_max",
    "actual_min",
    "max_support_uplift",
    "contact_loss_percent",
)


@dataclass(frozen=True)
class ValidationRow:
    """One quantity at one speed.

    Attributes
    ----------
    speed_kmh : float
    quantity : str
        A field of :class:`~catenary_env.analysis.statistics.ContactStatistics`.
    value : float
        Simulated value (N; m for the uplift; % for contact loss).
    low, high : float
        Accepted range.
    """

    speed_kmh: float
    quantity: str
    value: float
    low: float
    high: float

    @property
    def passed(self) -> bool:
        return self.low <= self.value <= self.high

    @property
    def margin(self) -> float:
        """Distance outside the range (0 inside), in the quantity's unit."""
        return max(self.low - self.value, self.value - self.high, 0.0)

    def as_dict(self) -> dict[str, float | str | bool]:
        """The row with its verdict and margin (the JSON of ``catenary validate``, the study's CSV)."""
        return {**dataclasses.asdict(self), "passed": self.passed, "margin": self.margin}

    def markdown(self) -> str:
        """The row of :func:`markdown_table`: value and range in the quantity's unit, pass or the margin."""
        scale, unit = DISPLAY_UNITS.get(self.quantity, (1.0, "N"))
        verdict = "pass" if self.passed else f"FAIL (by {scale * self.margin:.2f} {unit})"
        return (
            f"| {self.speed_kmh:g} | {self.quantity} | {scale * self.value:.2f} {unit} | "
            f"{scale * self.low:g} – {scale * self.high:g} | {verdict} |"
        )


DISPLAY_UNITS = {"max_support_uplift": (1e3, "mm"), "contact_loss_percent": (1.0, "%")}
"""Scale from SI and unit of the quantities the table does not show in N."""

ROW_UNITS = {
    "speed_kmh": "km/h",
    "value, low, high, margin": "N; m for max_support_uplift; % for contact_loss_percent",
}
"""Units of the numbers of :meth:`ValidationRow.as_dict`."""


def markdown_table(rows: tuple[ValidationRow, ...] | list[ValidationRow]) -> str:
    """The EN 50318:2002 table as Markdown: speed, quantity, value, accepted range, result (README.md,
    'Validation')."""
    header = ["| speed (km/h) | quantity | value | accepted range | result |", "|---|---|---|---|---|"]
    return "\n".join(header + [row.markdown() for row in rows])


@dataclass(frozen=True)
class ValidationReport:
    """The validation table.

    Attributes
    ----------
    rows : tuple of ValidationRow
    fidelity : Fidelity
    uplift_force : float
        N.
    """

    rows: tuple[ValidationRow, ...]
    fidelity: Fidelity
    uplift_force: float

    @property
    def passed(self) -> bool:
        return all(row.passed for row in self.rows)

    def table(self) -> str:
        """The table as Markdown (:func:`markdown_table`)."""
        return markdown_table(self.rows)


def load_ranges(name: str = "en50318-2002") -> dict[float, dict[str, tuple[float, float]]]:
    """Accepted ranges by speed (km/h) and quantity."""
    with open(VALIDATION_DIR / f"{name}.toml", "rb") as handle:
        data = tomllib.load(handle)
    return {
        float(speed): {q: (float(lo), float(hi)) for q, (lo, hi) in table.items()}
        for speed, table in data["ranges"].items()
    }


def validate(
    speeds_kmh: tuple[float, ...] = (250.0, 300.0),
    fidelity: Fidelity | None = None,
    modelling: ModellingOptions | None = None,
    progress: Callable[[float], None] | None = None,
) -> ValidationReport:
    """Simulate the EN 50318:2002 reference model and compare with the accepted ranges.

    Parameters
    ----------
    speeds_kmh : tuple of float
        Speeds with ranges in the data file, km/h.
    fidelity : Fidelity, optional
        Defaults to the section of the preset (10 spans, central 2 analysed) with a converged mesh.
    modelling : ModellingOptions, optional
        Modelling choices in place of the preset's (the ablation study, docs/model.md, 'Modelling choices').
    progress : callable, optional
        Called with the fraction of the passages done, 0 to 1.
    """
    catenary = load_catenary("en50318-2002")
    if modelling is not None:
        catenary = dataclasses.replace(catenary, modelling=modelling)
    pantograph = load_pantograph("en50318-2002")
    if fidelity is None:
        fidelity = Fidelity(
            n_spans=catenary.n_spans,
            analysis_spans=catenary.analysis_spans,
            contact_wire_element=0.5,
            messenger_wire_element=1.0,
            time_step=1e-3,
            dynamics="exact",
        )
    ranges = load_ranges()
    rows = []
    for speed in speeds_kmh:
        if speed not in ranges:
            raise UsageError(f"speed {speed:g} km/h: the standard gives ranges at {sorted(ranges)} km/h only")
    for i, speed in enumerate(speeds_kmh):
        part = None if progress is None else _part(progress, i, len(speeds_kmh))
        stats = simulate(
            catenary, pantograph, level_design(catenary), speed / 3.6, fidelity, progress=part
        ).statistics.as_dict()
        for quantity in QUANTITIES:
            low, high = ranges[speed][quantity]
            rows.append(ValidationRow(speed, quantity, stats[quantity], low, high))
    assert pantograph.uplift_force is not None
    return ValidationReport(tuple(rows), fidelity, pantograph.uplift_force)


def _part(progress: Callable[[float], None], index: int, count: int) -> Callable[[float], None]:
    """The progress callback of passage ``index`` of ``count``: its fraction, as a fraction of them all."""
    return lambda fraction: progress((index + fraction) / count)
