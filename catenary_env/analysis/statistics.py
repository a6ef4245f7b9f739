"""Statistics of the contact force over the analysis section (docs/model.md, 'Statistics and feasibility';
EN 50318:2002 clause 6).

The contact force is low-pass filtered at 20 Hz with a zero-phase filter (forward-backward
Butterworth), then its statistics are taken while the pantograph is inside the analysis section,
the central spans of the section, so that the entry and exit transients do not count.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np

from .butterworth import butterworth_sections, zero_phase

if TYPE_CHECKING:
    from ..dynamics.newmark import Trajectory

CUTOFF_HZ = 20.0
"""Low-pass cut-off of the contact force, Hz (EN 50318:2002; EN 50367)."""

FILTER_ORDER = 4
"""Butterworth order of one pass; the forward-backward (zero-phase) filter doubles it: -3 dB at
the cut-off, -21 dB at 30 Hz, -41 dB at 40 Hz."""


@dataclass(frozen=True)
class ContactStatistics:
    """Contact-force statistics over the analysis section.

    Attributes
    ----------
    mean : float
        Fm, mean of the filtered contact force, N.
    std : float
        σ, standard deviation of the filtered contact force, N.
    std_over_mean : float
        σ / Fm, dimensionless (EN 50367 asks for less than 0.3).
    statistical_max, statistical_min : float
        Fm ± 3σ, N.
    actual_max, actual_min : float
        Extremes of the filtered contact force, N.
    contact_loss_percent : float
        Percentage of time steps with zero raw contact force, %.
    max_support_uplift : float
        Largest upward displacement of the contact wire at a support inside the analysis section, m.
    """

    mean: float
    std: float
    std_over_mean: float
    statistical_max: float
    statistical_min: float
    actual_max: float
    actual_min: float
    contact_loss_percent: float
    max_support_uplift: float

    def as_dict(self) -> dict[str, float]:
        return asdict(self)

    def text_lines(self, indent: str = "  ") -> list[str]:
        """The statistics as text, one per line with its name and unit (the support uplift in mm), as the
        command line prints them."""
        lines = []
        for key, label, unit, scale in STATISTICS_ROWS:
            value = scale * getattr(self, key)
            text = f"{value:10.3f}" if math.isfinite(value) else f"{value!s:>10}"
            lines.append(f"{indent}{label:<26} {text} {unit}")
        return lines


STATISTICS_ROWS = (
    ("mean", "mean contact force Fm", "N", 1.0),
    ("std", "standard deviation σ", "N", 1.0),
    ("std_over_mean", "σ / Fm", "-", 1.0),
    ("statistical_max", "statistical max Fm + 3σ", "N", 1.0),
    ("statistical_min", "statistical min Fm - 3σ", "N", 1.0),
    ("actual_max", "actual max", "N", 1.0),
    ("actual_min", "actual min", "N", 1.0),
    ("contact_loss_percent", "contact loss", "%", 1.0),
    ("max_support_uplift", "max uplift at a support", "mm", 1000.0),
)
"""Each statistic's field, label, unit and scale from SI in :meth:`ContactStatistics.text_lines`."""

STATISTICS_UNITS = {
    "statistics.mean, std, statistical_max, statistical_min, actual_max, actual_min": "N",
    "statistics.std_over_mean": "1",
    "statistics.contact_loss_percent": "%",
    "statistics.max_support_uplift": "m",
}
"""Units of the statistics in the command line's JSON output (SI, as :meth:`ContactStatistics.as_dict`)."""


def lowpass(force: np.ndarray, time_step: float, cutoff: float = CUTOFF_HZ) -> np.ndarray:
    """Zero-phase low-pass filter of a force history.

    Parameters
    ----------
    force : ndarray, shape (n,)
        Sampled every ``time_step`` seconds, N.
    time_step : float
        s.
    cutoff : float
        -3 dB frequency of the applied (forward-backward) filter, Hz.
    """
    # Forward and backward passes square the magnitude response; set each pass's cut-off so that
    # the applied (zero-phase) filter is -3 dB at ``cutoff``, the usual meaning of a cut-off
    # frequency. A pass at ``cutoff`` itself would put the applied filter at -6 dB there.
    per_pass = cutoff / (np.sqrt(2.0) - 1.0) ** (1.0 / (2 * FILTER_ORDER))
    return zero_phase(butterworth_sections(FILTER_ORDER, per_pass, 1.0 / time_step), force)


def contact_statistics(
    position: np.ndarray,
    force: np.ndarray,
    filtered: np.ndarray,
    window: tuple[float, float],
    support_positions: np.ndarray,
    support_uplift: np.ndarray,
) -> ContactStatistics:
    """The statistics of docs/model.md, 'Statistics and feasibility' over the analysis window.

    Parameters
    ----------
    position : ndarray, shape (n,)
        Pantograph position along the track at each step, m.
    force : ndarray, shape (n,)
        Raw contact force, N.
    filtered : ndarray, shape (n,)
        The same, low-pass filtered (:func:`lowpass`), N.
    window : (float, float)
        Start and end of the analysis section along the track, m.
    support_positions : ndarray, shape (s,)
        Positions of the supports whose uplift is recorded, m.
    support_uplift : ndarray, shape (n, s)
        Upward displacement of the contact wire at those supports at each step, m.
    """
    inside = (position >= window[0]) & (position <= window[1])
    if not np.any(inside):
        raise ValueError(f"no time step inside the analysis window {window}")
    f = filtered[inside]
    mean = float(np.mean(f))
    std = float(np.std(f))
    supports = (support_positions >= window[0] - 1e-9) & (support_positions <= window[1] + 1e-9)
    uplift = float(np.max(support_uplift[:, supports])) if np.any(supports) else float("nan")
    return ContactStatistics(
        mean=mean,
        std=std,
        std_over_mean=std / mean if mean != 0.0 else float("inf"),
        statistical_max=mean + 3.0 * std,
        statistical_min=mean - 3.0 * std,
        actual_max=float(np.max(f)),
        actual_min=float(np.min(f)),
        contact_loss_percent=100.0 * float(np.mean(force[inside] <= 0.0)),
        max_support_uplift=uplift,
    )


def filtered_contact_force(trajectory: Trajectory) -> np.ndarray:
    """The contact force of a passage, low-pass filtered (:func:`lowpass`), N, shape (n_steps,)."""
    return lowpass(trajectory.contact_force, trajectory.time[1] - trajectory.time[0])


def passage_statistics(
    trajectory: Trajectory, window: tuple[float, float], filtered: np.ndarray | None = None
) -> ContactStatistics:
    """:func:`contact_statistics` of a pantograph passage over the analysis window (m).

    ``filtered`` is the passage's :func:`filtered_contact_force` where the caller has it already.
    """
    tr = trajectory
    filtered = filtered_contact_force(tr) if filtered is None else filtered
    return contact_statistics(
        tr.position, tr.contact_force, filtered, window, tr.support_x, tr.support_uplift
    )
