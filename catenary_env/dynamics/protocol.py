"""The passage protocol: what a passage asks of a dynamic model, and what every model implements
(docs/model.md, 'Time integration and the fast method').

A dynamic model is two steps, ``prepare(system, fidelity) -> Prepared`` (the design's part, computed once per
design and time step) and ``run(prepared, passage) -> Trajectory``; the models are chosen by name from one
table, :data:`catenary_env.dynamics.models.DYNAMIC_MODELS`. A :class:`Passage` names the train: its speed
and its contact points (pantographs), each with its own pantograph and frame force, and how to run it (the
time loop's backend, a stop, a progress callback). The exact model's straightforward loop (its oracle) takes
one contact point (:func:`single_contact_point`), the other loops any number (docs/model.md, 'Several
pantographs').
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol

import numpy as np

from ..model.definition import PantographDefinition
from .linear_system import LinearSystem
from .newmark import Trajectory


@dataclass(frozen=True)
class ContactPoint:
    """A pantograph of the train.

    Attributes
    ----------
    pantograph : PantographDefinition
    frame_force : float
        The static force on its frame, N (:func:`~catenary_env.dynamics.pantograph.frame_force` of the
        uplift force).
    offset : float
        Its distance behind the train's first pantograph, m (0 for the first). The first pantograph runs
        from the section's start to its end, the others enter the section behind it (docs/model.md,
        'Several pantographs').
    """

    pantograph: PantographDefinition
    frame_force: float
    offset: float = 0.0


@dataclass(frozen=True)
class Passage:
    """A train's passage over the whole section at constant speed.

    Attributes
    ----------
    speed : float
        m/s.
    contact_points : tuple of ContactPoint
        The train's pantographs, the first one first.
    n_steps : int, optional
        Stop after this many time steps (the whole section by default).
    backend : str
        Where the time loop runs: ``"auto"`` or one of the model's backends (``"numba"``, the loop compiled by
        numba, ``"numpy"``, the same loop in numpy; the exact model also has ``"oracle"``, the straightforward
        loop). ``"auto"`` takes numba where it is installed.
    progress : callable, optional
        Called with the fraction done, about a hundred times.
    """

    speed: float
    contact_points: tuple[ContactPoint, ...]
    n_steps: int | None = None
    backend: str = "auto"
    progress: Callable[[float], None] | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.speed) and self.speed > 0.0):
            raise ValueError(f"passage.speed = {self.speed!r}: must be a finite number > 0 m/s")
        if not self.contact_points:
            raise ValueError("passage.contact_points: at least one pantograph")
        offsets = [p.offset for p in self.contact_points]
        if offsets[0] != 0.0 or any(not (b >= a) for a, b in zip(offsets, offsets[1:], strict=False)):
            raise ValueError(
                f"passage.contact_points: offsets {offsets} m: the first pantograph's 0, then in order "
                "behind it"
            )
        if self.n_steps is not None and self.n_steps < 1:
            raise ValueError(f"passage.n_steps = {self.n_steps!r}: must be >= 1")

    @classmethod
    def one_pantograph(
        cls, pantograph: PantographDefinition, frame_force: float, speed: float, **options: Any
    ) -> Passage:
        """The passage of a train with one pantograph, frame force in N, speed in m/s; ``options`` as the
        other attributes (``n_steps``, ``backend``, ``progress``)."""
        return cls(speed, (ContactPoint(pantograph, frame_force),), **options)


class DynamicsSettings(Protocol):
    """What a model's ``prepare`` reads of a fidelity (:class:`catenary_env.pipeline.Fidelity` has it)."""

    time_step: float
    near_cutoff: float
    far_cutoff: float
    near_spans: int


class DynamicModel(NamedTuple):
    """One dynamic model: its two steps, and whether an evaluation may stop its passage one span after the
    analysis section (the exact model runs the whole section: its σ is the recorded yardstick)."""

    prepare: Callable[[LinearSystem, DynamicsSettings], Any]
    run: Callable[[Any, Passage], Trajectory]
    stops_early: bool


def single_contact_point(passage: Passage) -> ContactPoint:
    """The passage's only pantograph, for the loop that takes one (the exact model's oracle)."""
    if len(passage.contact_points) != 1:
        raise ValueError(
            f"passage.contact_points: {len(passage.contact_points)} pantographs; this loop takes one"
        )
    return passage.contact_points[0]


def choose_backend(backend: str, backends: Mapping[str, object], compiled_available: bool) -> str:
    """``backend``, or for ``"auto"`` numba where it is installed and numpy otherwise; refuses an unknown
    one."""
    if backend == "auto":
        return "numba" if compiled_available else "numpy"
    if backend not in backends:
        raise ValueError(f"backend = {backend!r}: one of auto, {', '.join(backends)}")
    return backend


def run_in_chunks(
    steps: Callable[[int, int], None], n_steps: int, progress: Callable[[float], None] | None
) -> None:
    """Steps 1 to ``n_steps - 1`` through ``steps(first, stop)``: in one call, or in about a hundred with a
    ``progress`` report after each (each call picks the state up where the last left it)."""
    bounds = np.unique(np.linspace(1, n_steps, 101 if progress is not None else 2).round().astype(int))
    for first, stop in zip(bounds[:-1], bounds[1:], strict=True):
        steps(int(first), int(stop))
        if progress is not None:
            progress(stop / n_steps)
