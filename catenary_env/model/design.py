"""Designs: the geometry a designer chooses on top of a catenary definition.

A design sets, for every span alike, where the droppers stand and the contact-wire height at each of them
(docs/problems.md, 'Design variables and grid'). Heights are given as offsets Δh from the level contact wire
(negative = lower), so a level wire, a parabolic pre-sag and free per-dropper offsets are the same record.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .definition import CatenaryDefinition, DefinitionError, check_dropper_positions, check_stitch_reach

GRAVITY = 9.81
"""Acceleration of gravity, m/s²."""


class DesignError(DefinitionError):
    """A design that cannot be built on its catenary; the message names the field and the allowed range."""


@dataclass(frozen=True)
class Design:
    """Dropper positions and contact-wire heights of one span (all spans are equal).

    Attributes
    ----------
    dropper_positions : tuple of float
        m from the span's first support, increasing, symmetric about mid-span.
    contact_wire_offsets : tuple of float
        Δh at each dropper: contact-wire height minus the level height, m (negative = lower).
    """

    dropper_positions: tuple[float, ...]
    contact_wire_offsets: tuple[float, ...]

    @property
    def n_droppers(self) -> int:
        return len(self.dropper_positions)


def level_design(catenary: CatenaryDefinition, dropper_positions: tuple[float, ...] | None = None) -> Design:
    """The level contact wire (the reference design), on the preset's droppers unless given."""
    positions = tuple(catenary.dropper_positions if dropper_positions is None else dropper_positions)
    return Design(positions, tuple(0.0 for _ in positions))


def presag_design(
    catenary: CatenaryDefinition, presag: float, dropper_positions: tuple[float, ...] | None = None
) -> Design:
    """A parabolic contact-wire profile, ``presag`` m below the level at mid-span (negative = raised).

    Δh(x) = -4 s x (L - x) / L², the usual pre-sag profile.
    """
    positions = tuple(catenary.dropper_positions if dropper_positions is None else dropper_positions)
    length = catenary.span_length
    return Design(positions, tuple(-4.0 * presag * x * (length - x) / length**2 for x in positions))


def symmetric_design(
    half_positions: tuple[float, ...], half_offsets: tuple[float, ...], span_length: float, mid_dropper: bool
) -> Design:
    """Build a symmetric design from the droppers of the first half span (support side first).

    Parameters
    ----------
    half_positions : tuple of float
        Positions of the droppers before mid-span, m, increasing.
    half_offsets : tuple of float
        Δh of those droppers, plus that of the mid-span dropper last when ``mid_dropper``, m.
    span_length : float
        m.
    mid_dropper : bool
        Whether a dropper stands at mid-span (odd number of droppers per span).
    """
    n_half = len(half_positions)
    if len(half_offsets) != n_half + int(mid_dropper):
        raise DesignError(
            f"half_offsets: expected {n_half + int(mid_dropper)} values, got {len(half_offsets)}"
        )
    positions = list(half_positions) + ([0.5 * span_length] if mid_dropper else [])
    positions += [span_length - x for x in reversed(half_positions)]
    offsets = list(half_offsets) + list(reversed(half_offsets[:n_half]))
    return Design(tuple(float(x) for x in positions), tuple(float(h) for h in offsets))


def estimated_messenger_height(catenary: CatenaryDefinition, x: np.ndarray) -> np.ndarray:
    """Parabolic estimate of the messenger-wire height in a span, m, before any solve.

    The messenger carries the weight of both wires (and the droppers, roughly); its sag is
    w L² / (8 T). Used only to refuse designs that would need a negative dropper length.
    """
    c = catenary
    weight = (c.messenger_wire.linear_mass + c.contact_wire.linear_mass) * GRAVITY
    sag = weight * c.span_length**2 / (8.0 * c.messenger_wire.tension)
    return c.messenger_height - 4.0 * sag * x * (c.span_length - x) / c.span_length**2


def check_design(catenary: CatenaryDefinition, design: Design) -> None:
    """Check a design against its catenary before any solve.

    Raises
    ------
    DesignError
        Naming the field and the allowed range: droppers outside the span, crossing or asymmetric,
        a dropper that would not hang from the stitch wire, offsets of the wrong count, or a
        contact-wire height that would need a negative (or shorter than 0.1 m) dropper.
    """
    where = "design.dropper_positions"
    try:
        check_dropper_positions(design.dropper_positions, catenary.span_length, where)
        if catenary.stitch_wire is not None:
            check_stitch_reach(
                design.dropper_positions, catenary.stitch_wire.length, catenary.span_length, "design"
            )
    except DesignError:
        raise
    except DefinitionError as error:
        raise DesignError(str(error)) from None
    if len(design.contact_wire_offsets) != design.n_droppers:
        raise DesignError(
            f"design.contact_wire_offsets: expected {design.n_droppers} values (one per dropper), "
            f"got {len(design.contact_wire_offsets)}"
        )
    offsets = np.asarray(design.contact_wire_offsets, dtype=float)
    if not np.all(np.isfinite(offsets)):
        raise DesignError("design.contact_wire_offsets: values must be finite numbers")
    mirrored = offsets[::-1]
    if np.max(np.abs(offsets - mirrored)) > 1e-9:
        raise DesignError("design.contact_wire_offsets: must be symmetric about mid-span")
    x = np.asarray(design.dropper_positions)
    room = estimated_messenger_height(catenary, x) - (catenary.contact_wire_height + offsets)
    minimum = 0.1
    for i, r in enumerate(room):
        if r + offsets[i] < minimum:  # even a level contact wire would not leave room for this dropper
            raise DesignError(
                f"catenary '{catenary.name}'.system_height = {catenary.system_height!r}: too small for its "
                f"span and messenger sag: the dropper at {x[i]} m would be shorter than {minimum} m even "
                "with a level contact wire; raise system_height or the messenger_wire tension"
            )
        if r < minimum:
            limit = catenary.contact_wire_height + float(room[i] + offsets[i]) - minimum
            raise DesignError(
                f"design.contact_wire_offsets[{i}] = {float(offsets[i])!r}: the dropper at {x[i]} m would be "
                f"shorter "
                f"than {minimum} m (negative length); the contact-wire height there must stay below "
                f"{limit:.3f} m"
            )


WAVE_SPEED_WARNING = 0.9
"""Fraction of the contact wire's wave speed above which a speed is warned about: the Doppler factor
(c - v) / (c + v) is below 0.05 there, and contact-force statistics grow without bound as v -> c."""

UPLIFT_PLAUSIBLE = (20.0, 400.0)
"""Static uplift forces, N, outside which one is warned about: EN 50367 asks mean contact forces of
70 to about 230 N up to 360 km/h, which a static uplift of a few tens to a few hundred newtons gives."""


def physical_warnings(catenary: CatenaryDefinition, speed: float, uplift_force: float | None) -> list[str]:
    """Warnings for input that is valid but physically odd: speed near the wave speed, odd uplift.

    Parameters
    ----------
    catenary : CatenaryDefinition
        The catenary (its contact wire's wave speed).
    speed : float
        Train speed, m/s.
    uplift_force : float or None
        Static uplift force, N (None: calibrated, not checked).

    Examples
    --------
    >>> from catenary_env.model.presets import load_catenary
    >>> physical_warnings(load_catenary("benchmark"), 300 / 3.6, 120.0)
    []
    """
    warnings = []
    c = catenary.wave_speed
    if speed > WAVE_SPEED_WARNING * c:
        warnings.append(
            f"speed = {speed * 3.6:.1f} km/h is {speed / c:.3f} of the contact wire's wave speed "
            f"({c * 3.6:.1f} km/h): above {WAVE_SPEED_WARNING:g} of it the contact force is dominated by "
            "the wave-speed singularity; raise the contact_wire tension for such speeds"
        )
    low, high = UPLIFT_PLAUSIBLE
    # A force that is not positive is refused as an error where it is used: no warning before that.
    if uplift_force is not None and uplift_force > 0.0 and not low <= uplift_force <= high:
        warnings.append(
            f"uplift_force = {uplift_force:g} N is outside the plausible {low:g} to {high:g} N of a "
            "pantograph's static uplift"
        )
    return warnings


def check_speed(catenary: CatenaryDefinition, speed: float) -> None:
    """Refuse a train speed (m/s) that is not positive or not below the contact wire's wave speed."""
    c = catenary.wave_speed
    if not (math.isfinite(speed) and 0.0 < speed < c):
        raise DesignError(
            f"speed = {speed * 3.6:.1f} km/h: must lie in (0, {c * 3.6:.1f}) km/h, below the contact wire's "
            f"wave speed sqrt(T / rho A)"
        )
