"""The evaluation pipeline: definition + design -> statics -> dynamics -> statistics (SPEC 2).

This is the one entry point the environments and optimisers use: :func:`evaluate` never raises for
an infeasible design; it returns an :class:`Evaluation` whose ``feasible`` and ``reason`` say why.
Bad input (an invalid design or speed) raises :class:`~catenary_env.design.DesignError` before any
solve.
"""

from __future__ import annotations

from dataclasses import dataclass

from .definition import CatenaryDefinition, PantographDefinition
from .design import Design
from .statistics import ContactStatistics


@dataclass(frozen=True)
class Fidelity:
    """Model size and resolution.

    Attributes
    ----------
    n_spans : int
        Spans in the section.
    analysis_spans : int
        Central spans over which statistics are taken.
    contact_wire_element : float
        Largest contact-wire element length, m.
    messenger_wire_element : float
        Largest messenger-wire element length, m.
    time_step : float
        Newmark time step, s.
    """

    n_spans: int = 20
    analysis_spans: int = 10
    contact_wire_element: float = 0.5
    messenger_wire_element: float = 1.0
    time_step: float = 1e-3


FIDELITIES: dict[str, Fidelity] = {
    # The design studies' setting: 20 spans, statistics on the 10 central ones (SPEC 4).
    "study": Fidelity(),
    # Small enough for unit tests: a short section and a coarse mesh; not for design conclusions.
    "test": Fidelity(n_spans=5, analysis_spans=1, contact_wire_element=1.5, messenger_wire_element=3.0,
                     time_step=2e-3),
}


@dataclass(frozen=True)
class Evaluation:
    """The outcome of simulating one design at one speed.

    Attributes
    ----------
    feasible : bool
        False when a dropper is in compression at equilibrium (static) or contact is lost in the
        analysis section (dynamic).
    reason : str
        Empty when feasible, otherwise why not, e.g. ``"static: dropper 3 in compression (-12.3 N)"``.
    statistics : ContactStatistics or None
        None when the design is statically infeasible (no dynamic run is made).
    dropper_lengths : tuple of float
        Unstretched lengths of the droppers of one central span, m (empty when shape-finding failed).
    dropper_forces : tuple of float
        Static dropper forces of one central span, N.
    uplift_force : float
        Static uplift force of the pantograph used, N.
    wall_time : float
        s.
    """

    feasible: bool
    reason: str
    statistics: ContactStatistics | None
    dropper_lengths: tuple[float, ...]
    dropper_forces: tuple[float, ...]
    uplift_force: float
    wall_time: float


def evaluate(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    speed: float,
    fidelity: Fidelity,
    uplift_force: float | None = None,
) -> Evaluation:
    """Simulate one design at one speed (m/s) and return its feasibility and statistics."""
    raise NotImplementedError


def calibrate_uplift(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    speed: float,
    fidelity: Fidelity,
    target_mean: float,
) -> float:
    """The static uplift force (N) for which the mean contact force of ``design`` equals ``target_mean`` (N)."""
    raise NotImplementedError


def en50367_mean_force(speed: float) -> float:
    """EN 50367 target mean contact force for AC systems, N, at ``speed`` m/s: 0.00097 v² + 70, v in km/h."""
    v_kmh = speed * 3.6
    return 0.00097 * v_kmh**2 + 70.0
