"""The evaluation pipeline: definition + design -> statics -> dynamics -> statistics (docs/model.md, 'Data
flow').

This is the one entry point the environments and optimisers use: :func:`evaluate` never raises for
an infeasible design; it returns an :class:`Evaluation` whose ``feasible`` and ``reason`` say why.
Bad input (an invalid design or speed) raises :class:`~catenary_env.model.design.DesignError` before any
solve.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .analysis.acceptance import Acceptance, assess
from .analysis.buildability import buildability_violation
from .analysis.statistics import ContactStatistics, filtered_contact_force, passage_statistics
from .blas_threads import single_threaded
from .dynamics.exact import PreparedExact
from .dynamics.linear_system import LinearSystem, linearise
from .dynamics.models import DYNAMIC_MODELS
from .dynamics.newmark import Trajectory
from .dynamics.pantograph import frame_force
from .dynamics.protocol import ContactPoint, Passage
from .dynamics.span_modes import PreparedSpanModes
from .fem.layout import build_layout
from .model.acceptance_limits import AcceptanceLimits
from .model.buildability import NO_LIMITS, BuildabilityLimits
from .model.definition import CatenaryDefinition, DefinitionError, PantographDefinition
from .model.design import Design, DesignError, check_design, check_speed
from .model.presets import load_acceptance
from .model.tolerances import SectionDeviations, check_deviations
from .statics.equal_spans import find_equal_spans_shape
from .statics.shape_finding import ShapeFindingError, StaticSolution, find_shape
from .train import SINGLE, Train, objective_sigma

NEAR_CUTOFF = math.inf
"""Hz: modes kept near the pantograph: every one (the convergence study, docs/performance.md: a dropper
close to a support needs modes up to 1.5 kHz, and the few above 500 Hz cost nothing measurable)."""
FAR_CUTOFF = 50.0
"""Hz: modes kept in the spans away from the pantograph."""
NEAR_SPANS = 2
"""Spans on each side of the pantograph's that keep the near cut-off (the convergence study)."""
DYNAMICS = tuple(DYNAMIC_MODELS)


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
    dynamics : {"span-modes", "exact"}
        The passage's model: ``"exact"``, every DOF every step (the reference), or ``"span-modes"``,
        the reduced model with its accuracy contract (docs/performance.md, 'Model fidelities').
    near_cutoff, far_cutoff : float
        Span-mode model: the highest mode frequency kept in the spans near the pantograph and in the
        others, Hz (set once by the convergence study, ``benchmarks/fidelity_convergence.py``).
    near_spans : int
        Span-mode model: spans on each side of the pantograph's that keep the near cut-off.
    """

    n_spans: int = 20
    analysis_spans: int = 10
    contact_wire_element: float = 0.5
    messenger_wire_element: float = 1.0
    time_step: float = 1e-3
    dynamics: str = "span-modes"
    near_cutoff: float = NEAR_CUTOFF
    far_cutoff: float = FAR_CUTOFF
    near_spans: int = NEAR_SPANS


FIDELITIES: dict[str, Fidelity] = {
    # The design studies' setting: 20 spans, statistics on the 10 central ones, the span-mode model
    # (docs/performance.md, 'Model fidelities').
    "study": Fidelity(),
    # The same section on the exact model: the yardstick, and the confirmation of final designs.
    "reference": Fidelity(dynamics="exact"),
    # Small enough for unit tests: a short section and a coarse mesh; not for design conclusions.
    "test": Fidelity(
        n_spans=5,
        analysis_spans=1,
        contact_wire_element=1.5,
        messenger_wire_element=3.0,
        time_step=2e-3,
        dynamics="exact",
    ),
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
    trace_position, trace_force : tuple of float
        The filtered contact force (N) along the analysis section (m), at most
        :data:`TRACE_POINTS` samples, for pictures; empty when no passage was simulated.
    acceptance : Acceptance or None
        The EN 50367 acceptance block of the passage (docs/acceptance.md); None when no passage was
        simulated.
    constraints : tuple of float
        The values of the feasibility constraints named in :data:`CONSTRAINTS`, in that order; the design
        is feasible when every one is <= 0 (docs/model.md, 'Statistics and feasibility'). NaN where not
        computed: every one when shape-finding failed, the contact loss when no passage was simulated.
    pantograph_statistics : tuple of ContactStatistics
        Every pantograph's statistics, the leading one first (its ``statistics``); empty when unsimulated.
    objective_sigma : float or None
        The train's objective σ, N, where the train has several pantographs (:attr:`sigma` reads it).
    """

    feasible: bool
    reason: str
    statistics: ContactStatistics | None
    dropper_lengths: tuple[float, ...]
    dropper_forces: tuple[float, ...]
    uplift_force: float
    wall_time: float
    trace_position: tuple[float, ...] = ()
    trace_force: tuple[float, ...] = ()
    acceptance: Acceptance | None = None
    constraints: tuple[float, ...] = ()
    pantograph_statistics: tuple[ContactStatistics, ...] = ()
    objective_sigma: float | None = None

    @property
    def sigma(self) -> float | None:
        """The objective σ, N: the train's objective pantograph(s)' (:class:`~catenary_env.train.Train`), the
        leading one's by default; None when unsimulated."""
        if self.objective_sigma is not None:
            return self.objective_sigma
        return None if self.statistics is None else self.statistics.std


TRACE_POINTS = 1000

CONSTRAINTS = ("dropper_compression_N", "dropper_length_shortfall_m", "contact_loss_percent")
"""The feasibility constraints of :attr:`Evaluation.constraints`, each feasible when <= 0: the largest
compression of a dropper at equilibrium over the section (N, minus the smallest dropper force), the
largest shortfall of an unstretched dropper length (m, minus the shortest length) and the share of the
analysis section's time in which contact is lost (%). Under buildability limits the first two are measured
from the limits' smallest dropper force and length (docs/acceptance.md, 'Buildability limits'); the widest
dropper spacing, a property of the design, has no constraint value."""


@dataclass(frozen=True)
class Simulation:
    """Everything one simulation computed, for plots and analysis.

    Attributes
    ----------
    static : StaticSolution
    system : LinearSystem
    trajectory : Trajectory
    statistics : ContactStatistics
    window : (float, float)
        Analysis section along the track, m.
    uplift_force : float
        N.
    filtered_force : ndarray, shape (n_steps,)
        The 20 Hz low-pass filtered contact force at every step, N (filtered once, here).
    acceptance : Acceptance or None
        The EN 50367 acceptance block of the passage (docs/acceptance.md).
    pantograph_statistics : tuple of ContactStatistics
        Every pantograph's statistics, the leading one first (``statistics``).
    filtered_forces : tuple of ndarray
        Every pantograph's filtered contact force, the leading one first (``filtered_force``).
    """

    static: StaticSolution
    system: LinearSystem
    trajectory: Trajectory
    statistics: ContactStatistics
    window: tuple[float, float]
    uplift_force: float
    filtered_force: NDArray[np.float64]
    acceptance: Acceptance | None = None
    pantograph_statistics: tuple[ContactStatistics, ...] = ()
    filtered_forces: tuple[NDArray[np.float64], ...] = ()


ACCEPTANCE = "en50367-ac"
"""The acceptance limits every simulation is assessed against unless told otherwise (docs/acceptance.md)."""


@functools.cache
def default_acceptance() -> AcceptanceLimits:
    """The :data:`ACCEPTANCE` preset, loaded once per process."""
    return load_acceptance(ACCEPTANCE)


def analysis_window(catenary: CatenaryDefinition, fidelity: Fidelity) -> tuple[float, float]:
    """Start and end of the central ``analysis_spans`` spans, m."""
    first = (fidelity.n_spans - fidelity.analysis_spans) // 2
    return first * catenary.span_length, (first + fidelity.analysis_spans) * catenary.span_length


def check_fidelity(catenary: CatenaryDefinition, fidelity: Fidelity) -> None:
    """Refuse a fidelity outside the model's range, naming the field."""
    f = fidelity
    if not (isinstance(f.n_spans, int) and 3 <= f.n_spans <= 200):
        raise DesignError(f"fidelity.n_spans = {f.n_spans!r}: must be an integer in [3, 200]")
    if not (isinstance(f.analysis_spans, int) and 1 <= f.analysis_spans <= f.n_spans - 2):
        raise DesignError(
            f"fidelity.analysis_spans = {f.analysis_spans!r}: must be an integer in [1, n_spans - 2]"
        )
    for name in ("contact_wire_element", "messenger_wire_element"):
        value = getattr(f, name)
        if not (0.05 <= value <= 0.5 * catenary.span_length):
            raise DesignError(
                f"fidelity.{name} = {value!r}: must lie in [0.05, {0.5 * catenary.span_length}] m"
            )
    if not (1e-5 <= f.time_step <= 0.01):
        raise DesignError(f"fidelity.time_step = {f.time_step!r}: must lie in [1e-5, 0.01] s")
    if f.dynamics not in DYNAMICS:
        raise DesignError(f"fidelity.dynamics = {f.dynamics!r}: must be one of {', '.join(DYNAMICS)}")
    if f.dynamics == "span-modes" and not catenary.modelling.rayleigh_only:
        raise DesignError(
            "fidelity.dynamics = 'span-modes': the span-mode model integrates C = alpha M + beta K with "
            f"slack droppers dropping their damping; modelling {catenary.modelling.changed()} needs "
            "dynamics = 'exact'"
        )
    if f.dynamics == "span-modes":
        if not (0.0 < f.far_cutoff <= f.near_cutoff):
            raise DesignError(
                f"fidelity.far_cutoff = {f.far_cutoff!r}: must lie in (0, near_cutoff = {f.near_cutoff!r}] Hz"
            )
        if not (isinstance(f.near_spans, int) and 0 <= f.near_spans < f.n_spans):
            raise DesignError(
                f"fidelity.near_spans = {f.near_spans!r}: must be an integer in [0, n_spans - 1]"
            )


@single_threaded
def solve_static(
    catenary: CatenaryDefinition,
    design: Design,
    fidelity: Fidelity,
    deviations: SectionDeviations | None = None,
) -> StaticSolution:
    """Check the design and find its static shape (raises ShapeFindingError if Newton fails); ``deviations``:
    installation tolerances of every span (docs/acceptance.md)."""
    check_design(catenary, design)
    check_fidelity(catenary, fidelity)
    check_section_deviations(catenary, design, fidelity, deviations)
    return _find_static(catenary, design, fidelity, deviations)


def check_section_deviations(
    catenary: CatenaryDefinition, design: Design, fidelity: Fidelity, deviations: SectionDeviations | None
) -> None:
    """Refuse deviations that do not fit the section
    (:func:`~catenary_env.model.tolerances.check_deviations`)."""
    if deviations is None:
        return
    stitch = None if catenary.stitch_wire is None else 0.5 * catenary.stitch_wire.length
    try:
        check_deviations(deviations, design.dropper_positions, catenary.span_length, fidelity.n_spans, stitch)
    except DefinitionError as error:
        raise DesignError(str(error)) from None


def _find_static(
    catenary: CatenaryDefinition,
    design: Design,
    fidelity: Fidelity,
    deviations: SectionDeviations | None = None,
) -> StaticSolution:
    elements = (fidelity.contact_wire_element, fidelity.messenger_wire_element)
    layout = build_layout(catenary, design, fidelity.n_spans, *elements, deviations)
    if deviations is None:  # equal spans
        return find_equal_spans_shape(layout, *elements)
    return find_shape(layout)


def check_uplift(pantograph: PantographDefinition, uplift_force: float | None) -> float:
    """The uplift force to use, N: ``uplift_force``, else the pantograph's; refuses none or one <= 0."""
    force = pantograph.uplift_force if uplift_force is None else uplift_force
    if force is None:
        raise DesignError(
            f"uplift_force: pantograph '{pantograph.name}' sets none; give one (N > 0) or calibrate it to a "
            "target mean contact force with calibrate_uplift"
        )
    if not (math.isfinite(force) and force > 0.0):
        raise DesignError(f"uplift_force = {force!r}: must be a finite number > 0 N")
    return force


@single_threaded
def run_passage(
    static: StaticSolution,
    pantograph: PantographDefinition,
    speed: float,
    fidelity: Fidelity,
    uplift_force: float,
    system: LinearSystem | None = None,
    progress: Callable[[float], None] | None = None,
    prepared: PreparedExact | PreparedSpanModes | None = None,
    statistics_only: bool = False,
    train: Train = SINGLE,
) -> Simulation:
    """The pantograph's dynamic passage at ``speed`` (m/s) over a solved static state (the design must be
    statically feasible), on the fidelity's dynamic model
    (:data:`~catenary_env.dynamics.models.DYNAMIC_MODELS`).

    ``system`` and ``prepared`` (from :func:`prepare_dynamics`) may be passed to reuse them across
    passages. With ``statistics_only``, the span-mode model stops one span after the analysis
    section: nothing later changes the statistics (the zero-phase filter's end effect has decayed
    over that span), and the trajectory ends there. The force on the pantograph's frame follows the
    catenary's ``modelling.uplift_definition``; a system that is not Rayleigh-damped
    (:attr:`LinearSystem.rayleigh`) runs the exact model's straightforward loop (its oracle), minutes rather
    than seconds. ``train`` adds pantographs behind this one (docs/model.md, 'Several pantographs'); the
    statistics are then taken for each.
    """
    catenary = static.layout.catenary
    system = linearise(static) if system is None else system
    if not system.rayleigh:
        check_fidelity(catenary, fidelity)  # the span-mode model refuses it
    model = DYNAMIC_MODELS[fidelity.dynamics]
    prepared = model.prepare(system, fidelity) if prepared is None else prepared
    window = analysis_window(catenary, fidelity)
    train.check(catenary, fidelity.n_spans, window[1])
    last = train.trailing[-1].offset if train.trailing else 0.0
    n_steps = (
        _statistics_steps(catenary, fidelity, speed, last) if statistics_only and model.stops_early else None
    )
    points = [ContactPoint(pantograph, frame_force(system, pantograph, uplift_force))]
    for t in train.trailing:
        force = uplift_force if t.uplift_force is None else t.uplift_force
        points.append(ContactPoint(t.pantograph, frame_force(system, t.pantograph, force), t.offset))
    trajectory = model.run(prepared, Passage(speed, tuple(points), n_steps=n_steps, progress=progress))
    filtered = tuple(filtered_contact_force(trajectory.of_pantograph(i)) for i in range(len(points)))
    stats = tuple(passage_statistics(trajectory.of_pantograph(i), window, f) for i, f in enumerate(filtered))
    acceptance = assess(stats[0], speed * 3.6, default_acceptance())
    return Simulation(
        static,
        system,
        trajectory,
        stats[0],
        window,
        uplift_force,
        filtered[0],
        acceptance,
        pantograph_statistics=stats,
        filtered_forces=filtered,
    )


def _statistics_steps(catenary: CatenaryDefinition, fidelity: Fidelity, speed: float, offset: float) -> int:
    """Steps until the last pantograph, ``offset`` m behind the first, is one span past the analysis
    section."""
    end = analysis_window(catenary, fidelity)[1] + catenary.span_length + offset
    return int(np.floor(end / (speed * fidelity.time_step))) + 1


@single_threaded
def prepare_dynamics(system: LinearSystem, fidelity: Fidelity) -> PreparedExact | PreparedSpanModes:
    """The design's part of the passage on the fidelity's model: the exact model's factorisation (none for a
    system only its straightforward loop integrates, :attr:`LinearSystem.rayleigh`), or the span modes and
    their Schur complements (docs/performance.md, 'Model fidelities')."""
    return DYNAMIC_MODELS[fidelity.dynamics].prepare(system, fidelity)


@single_threaded
def simulate(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    speed: float,
    fidelity: Fidelity,
    uplift_force: float | None = None,
    progress: Callable[[float], None] | None = None,
    buildability: BuildabilityLimits = NO_LIMITS,
    deviations: SectionDeviations | None = None,
    train: Train = SINGLE,
) -> Simulation:
    """Shape-finding, linearisation and the pantograph passage at ``speed`` (m/s), with the ``train``'s
    pantographs behind this one; ``buildability`` and ``deviations`` as in :func:`evaluate`.

    Raises
    ------
    DesignError
        Invalid design, speed, fidelity or uplift force (before any solve).
    ShapeFindingError
        Shape-finding did not converge.
    ValueError
        The design is statically infeasible (a dropper in compression or of negative length, or a
        buildability limit violated).
    """
    check_speed(catenary, speed)
    force = check_uplift(pantograph, uplift_force)
    static = solve_static(catenary, design, fidelity, deviations)
    reason = static.infeasibility() or buildability_violation(static, buildability)
    if reason:
        raise ValueError(f"design is infeasible: {reason}")
    return run_passage(static, pantograph, speed, fidelity, force, progress=progress, train=train)


def evaluate(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    speed: float,
    fidelity: Fidelity,
    uplift_force: float | None = None,
    buildability: BuildabilityLimits = NO_LIMITS,
    deviations: SectionDeviations | None = None,
    train: Train = SINGLE,
) -> Evaluation:
    """Simulate one design at one speed (m/s) and return its feasibility and statistics (of every pantograph
    of the ``train``; contact lost by any makes it infeasible).

    Bad input raises :class:`DesignError` before any solve; an infeasible design (static: compressed
    dropper, negative dropper length, or a shape-finding that does not converge; a buildability limit
    violated, ``"buildability: ..."``; dynamic: contact loss in the analysis section) returns
    ``feasible=False`` with the reason. ``deviations`` are the installation deviations of every span
    (docs/acceptance.md, 'Installation tolerances'; None: the design as drawn).
    """
    check_speed(catenary, speed)
    force = check_uplift(pantograph, uplift_force)
    check_design(catenary, design)
    check_fidelity(catenary, fidelity)
    check_section_deviations(catenary, design, fidelity, deviations)
    train.check(catenary, fidelity.n_spans, analysis_window(catenary, fidelity)[1])
    return evaluate_unchecked(
        catenary, pantograph, design, speed, fidelity, force, buildability, deviations, train
    )


@single_threaded
def evaluate_unchecked(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    speed: float,
    fidelity: Fidelity,
    uplift_force: float,
    buildability: BuildabilityLimits = NO_LIMITS,
    deviations: SectionDeviations | None = None,
    train: Train = SINGLE,
) -> Evaluation:
    """:func:`evaluate` without its input checks, for a caller that has made them (a design problem).

    The design must pass :func:`~catenary_env.model.design.check_design`, the speed
    :func:`~catenary_env.model.design.check_speed`, the fidelity :func:`check_fidelity` and the uplift
    force (N) :func:`check_uplift`: a design is validated once, at the boundary.
    """
    (evaluation,) = _evaluate_speeds(
        catenary, pantograph, design, [(speed, uplift_force)], fidelity, buildability, deviations, train
    )
    return evaluation


def _evaluate_speeds(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    passages: Iterable[tuple[float, float]],
    fidelity: Fidelity,
    buildability: BuildabilityLimits = NO_LIMITS,
    deviations: SectionDeviations | None = None,
    train: Train = SINGLE,
) -> list[Evaluation]:
    """:func:`evaluate_unchecked` at several speeds: one design's evaluation for each (speed m/s, uplift
    force N) of ``passages``, in order, up to the first at which the design is infeasible.

    The statics, the linear system and the dynamic model's preparation do not depend on the speed or the
    uplift force, so they are made once and every passage runs on them (docs/performance.md, 'Speed'): the
    evaluations are those of :func:`evaluate_unchecked` at each speed, number for number. A statically
    infeasible design gives one evaluation. ``passages`` is read one pair at a time, so a caller may
    calibrate each uplift force only when its speed is reached. Each evaluation's ``wall_time`` is its
    passage's; the first's also the shared part's.
    """
    start = time.perf_counter()
    passages = iter(passages)
    speed, force = next(passages)
    try:
        static = _find_static(catenary, design, fidelity, deviations)
    except ShapeFindingError as error:
        unknown = (math.nan,) * len(CONSTRAINTS)
        wall_time = time.perf_counter() - start
        return [Evaluation(False, f"static: {error}", None, (), (), force, wall_time, constraints=unknown)]
    lengths, forces = _central_span(static, design)
    reason = static.infeasibility() or buildability_violation(static, buildability)
    if reason:
        wall_time = time.perf_counter() - start
        constraints = _constraints(static, math.nan, buildability)
        return [Evaluation(False, reason, None, lengths, forces, force, wall_time, constraints=constraints)]
    system = linearise(static)
    prepared = prepare_dynamics(system, fidelity)
    evaluations: list[Evaluation] = []
    while True:
        sim = run_passage(
            static, pantograph, speed, fidelity, force, system, prepared=prepared, statistics_only=True,
            train=train,
        )  # fmt: skip
        evaluations.append(_dynamic_evaluation(sim, lengths, forces, buildability, train, start))
        pair = next(passages, None)
        if not evaluations[-1].feasible or pair is None:
            return evaluations
        speed, force = pair
        start = time.perf_counter()


# Public under its own name, so that a test may replace it without touching evaluate_unchecked (which the
# fingerprint's canaries call).
evaluate_speeds_unchecked = single_threaded(_evaluate_speeds)


def _dynamic_evaluation(
    sim: Simulation,
    lengths: tuple[float, ...],
    forces: tuple[float, ...],
    buildability: BuildabilityLimits,
    train: Train,
    start: float,
) -> Evaluation:
    """The evaluation of a statically feasible design's passage ``sim`` (``start``: its wall clock, s)."""
    reason = ""
    for i, stats in enumerate(sim.pantograph_statistics):
        if stats.contact_loss_percent > 0.0 and not reason:
            which = f"pantograph {i + 1}: " if train.trailing else ""
            reason = (
                f"dynamic: {which}contact lost {stats.contact_loss_percent:.3f} % of the time in the "
                "analysis section"
            )
    position, filtered = _trace(sim)
    blocks = sim.pantograph_statistics
    objective = objective_sigma(blocks, train.objective) if train.trailing else None
    constraints = _constraints(sim.static, max(stats.contact_loss_percent for stats in blocks), buildability)
    wall_time = time.perf_counter() - start
    return Evaluation(
        not reason,
        reason,
        sim.statistics,
        lengths,
        forces,
        sim.uplift_force,
        wall_time,
        position,
        filtered,
        acceptance=sim.acceptance,
        constraints=constraints,
        pantograph_statistics=blocks,
        objective_sigma=objective,
    )


def _constraints(
    static: StaticSolution, contact_loss_percent: float, buildability: BuildabilityLimits = NO_LIMITS
) -> tuple[float, ...]:
    """The values of :data:`CONSTRAINTS` (feasible when <= 0), measured from the buildability limits' smallest
    dropper force and length (0 without limits)."""
    compression = buildability.min_dropper_force - float(np.min(static.dropper_forces))
    shortfall = buildability.min_dropper_length - float(np.min(static.dropper_lengths))
    return compression, shortfall, float(contact_loss_percent)


def _trace(sim: Simulation) -> tuple[tuple[float, ...], tuple[float, ...]]:
    tr = sim.trajectory
    inside = np.flatnonzero((tr.position >= sim.window[0]) & (tr.position <= sim.window[1]))
    every = max(1, inside.size // TRACE_POINTS)
    pick = inside[::every]
    filtered = sim.filtered_force[pick]
    return tuple(float(v) for v in tr.position[pick]), tuple(float(v) for v in filtered)


def _central_span(static: StaticSolution, design: Design) -> tuple[tuple[float, ...], tuple[float, ...]]:
    lay = static.layout
    central = lay.dropper_span == lay.n_spans // 2
    return (
        tuple(float(v) for v in static.dropper_lengths[central]),
        tuple(float(v) for v in static.dropper_forces[central]),
    )


@single_threaded
def calibrate_uplift(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    speed: float,
    fidelity: Fidelity,
    target_mean: float,
    tolerance: float = 0.01,
) -> float:
    """The static uplift force (N) for which the mean contact force of ``design`` equals ``target_mean`` (N).

    The mean force is nearly affine in the uplift (the frame spring takes a part), so a secant
    iteration from ``target_mean`` converges in two or three passages; the static solution and the
    linear system are computed once.

    Parameters
    ----------
    tolerance : float
        Accepted error of the mean contact force, N.
    """
    check_speed(catenary, speed)
    if not (math.isfinite(target_mean) and target_mean > 0.0):
        raise DesignError(f"target_mean = {target_mean!r}: must be a finite number > 0 N")
    static = solve_static(catenary, design, fidelity)
    reason = static.infeasibility()
    if reason:
        raise ValueError(f"cannot calibrate the uplift on an infeasible design: {reason}")
    system = linearise(static)
    prepared = prepare_dynamics(system, fidelity)

    def mean_force(uplift: float) -> float:
        return run_passage(
            static, pantograph, speed, fidelity, uplift, system, prepared=prepared, statistics_only=True
        ).statistics.mean

    x0, f0 = target_mean, mean_force(target_mean) - target_mean
    x1 = x0 - f0
    for _ in range(8):
        f1 = mean_force(x1) - target_mean
        if abs(f1) < tolerance:
            return x1
        slope = (f1 - f0) / (x1 - x0) if x1 != x0 else 1.0
        x0, f0, x1 = x1, f1, x1 - f1 / slope
    raise RuntimeError(f"uplift calibration did not reach {tolerance} N: last error {f1:.3f} N at {x1:.2f} N")


def en50367_mean_force(speed: float) -> float:
    """EN 50367 target mean contact force for AC systems, N, at ``speed`` m/s: 0.00097 v² + 70, v in km/h."""
    v_kmh = speed * 3.6
    return 0.00097 * v_kmh**2 + 70.0
