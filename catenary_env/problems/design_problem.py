"""A design problem: design variables, bounds, grid, and their mapping to a design.

A :class:`DesignProblem` is data (a catenary preset, the variables, their bounds and grid steps) plus
the mapping from a variable vector ``x`` (physical units, m) to a :class:`~catenary_env.model.design.Design`.
Every span is equal and symmetric about mid-span, so a variable sets a dropper and its mirror; dropper 1
stands next to the span's first support, and the mid-span dropper never moves.

Variables are named ``s`` (pre-sag at mid-span), ``dh_i`` (contact-wire height change at dropper ``i``
from the level wire, negative = lower) and ``d_i`` (position of dropper ``i`` from the first support).
Heights live on a 1 mm grid, positions on a 1 cm grid (docs/problems.md, 'Design variables and grid').

Every design of a problem is simulated with the same pantograph uplift force: the one for which the problem's
reference design (the level wire on the preset's droppers) has the EN 50367 mean contact force at the speed
(docs/problems.md, 'Reference design and uplift'). It is calibrated once per model, speed and fidelity and
kept on disk for later processes and commands (:mod:`~catenary_env.calibration_cache`).

Examples
--------
>>> from catenary_env.problems import PROBLEMS
>>> problem = PROBLEMS["B1"]
>>> problem.variables
('dh_1', 'dh_2', 'dh_3', 'dh_4', 'dh_5')
>>> problem.snap([0.0104, -0.03, 0.0005, 0.0, 0.0]).tolist()
[0.01, -0.02, 0.001, 0.0, 0.0]
>>> problem.design([0.0, 0.0, 0.0, 0.0, -0.005]).contact_wire_offsets[4]
-0.005
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import pipeline
from ..fingerprint import model_fingerprint
from ..model.buildability import NO_LIMITS, BuildabilityLimits
from ..model.definition import CatenaryDefinition, DefinitionError, PantographDefinition
from ..model.design import Design, DesignError, check_design, check_speed, presag_design, symmetric_design
from ..model.tolerances import SectionDeviations, Tolerances
from ..pipeline import (
    FIDELITIES,
    Evaluation,
    Fidelity,
    check_fidelity,
    check_section_deviations,
    check_uplift,
)
from ..train import SINGLE, Train
from .best_known import BestKnown, best_known_table
from .grid import DesignGrid
from .reference import (
    calibrated_uplift,
    preset_catenary,
    preset_pantograph,
    problem_catenary,
    reference_evaluation,
)
from .speeds import SpeedsEvaluation, evaluate_over_speeds
from .tolerance import RobustObjective, ToleranceEvaluation, evaluate_under_tolerances, robust_evaluation

__all__ = ["TENSION_FRACTIONS", "DesignProblem", "resolve_fidelity"]

TENSION_FRACTIONS = (0.7, 1.3)
"""The contact-wire tensions a problem may be set to, as fractions of its preset's: a range around the
preset, within which its other figures (the messenger's tension, the droppers, the supports) still make one
catenary (docs/problems.md, 'Contact-wire tension')."""


@dataclass(frozen=True, eq=False)
class DesignProblem:
    """A catenary design problem: variables, bounds and grid, and the mapping to a design (docs/problems.md,
    'The eight problems').

    Attributes
    ----------
    name : str
        Problem id, e.g. ``"B1"``.
    catenary : str
        Name of the catenary preset (``"benchmark"`` or ``"stitched"``).
    n_droppers : int
        Droppers per span of the problem's designs.
    variables : tuple of str
        Variable names: ``"s"`` (pre-sag), ``"dh_i"`` (height change at dropper i), ``"d_i"``
        (position of dropper i); dropper 1 at the support side.
    units : tuple of str
        Unit of each variable (``"m"``).
    lower, upper : ndarray, shape (n_variables,)
        Bounds, m, on the grid. Read-only.
    step : ndarray, shape (n_variables,)
        Grid step of each variable, m. Read-only.
    description : str
        One paragraph for humans.
    grid : DesignGrid
        The variables' grid, set from the bounds and steps: snapping, actions, cache keys.
    buildability : BuildabilityLimits
        Limits a design must meet with its static state, before any dynamics (docs/acceptance.md,
        'Buildability limits'); default :data:`~catenary_env.model.buildability.NO_LIMITS`, the reference
        study's setting. ``problem.with_options(buildability=DEFAULT_BUILDABILITY)`` applies the defaults.
    robust : RobustObjective or None
        With it, :meth:`evaluate` returns the robust objective's evaluation: σ over seeded tolerance draws
        (:func:`~catenary_env.problems.tolerance.robust_evaluation`); None: the design as drawn.
    contact_wire_tension : float or None
        The contact wire's tension, N, within :data:`TENSION_FRACTIONS` of the preset's; None: the preset's
        (docs/problems.md, 'Contact-wire tension'). ``problem.with_contact_wire_tension(t)`` sets it. The
        designs are simulated under the preset's uplift force (:meth:`uplift_force`).
    """

    name: str
    catenary: str
    n_droppers: int
    variables: tuple[str, ...]
    units: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    step: NDArray[np.float64]
    description: str
    grid: DesignGrid = field(init=False, repr=False)
    buildability: BuildabilityLimits = NO_LIMITS
    robust: RobustObjective | None = None
    contact_wire_tension: float | None = None

    def __post_init__(self) -> None:
        n = len(self.variables)
        if len(self.units) != n:
            raise ValueError(f"problem {self.name!r}: units must have {n} values, one per variable")
        grid = DesignGrid(self.name, self.variables, self.lower, self.upper, self.step)
        object.__setattr__(self, "grid", grid)
        for field_name in ("lower", "upper", "step"):  # the grid's read-only arrays
            object.__setattr__(self, field_name, getattr(grid, field_name))
        positions, heights = self._split_names()
        if self.variables == ("s",):
            return
        mid = self.n_droppers % 2
        if positions and 2 * len(positions) + mid != self.n_droppers:
            raise ValueError(
                f"problem {self.name!r}: {len(positions)} positions cannot place {self.n_droppers} "
                "droppers symmetrically"
            )
        if heights and len(heights) != self.n_droppers // 2 + mid:
            raise ValueError(f"problem {self.name!r}: needs {self.n_droppers // 2 + mid} heights")
        if self.contact_wire_tension is not None:
            self._check_tension(self.contact_wire_tension)

    def _check_tension(self, tension: float) -> None:
        preset = preset_catenary(self.catenary).contact_wire.tension
        lo, hi = (f * preset for f in TENSION_FRACTIONS)
        if not lo <= tension <= hi:  # NaN too
            raise DefinitionError(
                f"contact_wire_tension = {tension!r} N: must be within [{lo:g}, {hi:g}] N, "
                f"{TENSION_FRACTIONS[0]:.0%} to {TENSION_FRACTIONS[1]:.0%} of the {self.catenary} "
                f"catenary's {preset:g} N"
            )

    # -- data -------------------------------------------------------------------------------------------

    @property
    def n_variables(self) -> int:
        return len(self.variables)

    @property
    def n_levels(self) -> NDArray[np.int64]:
        """Number of grid points of each variable, bounds included."""
        return self.grid.n_levels

    @property
    def catenary_definition(self) -> CatenaryDefinition:
        """The catenary preset (loaded once per process), with :attr:`contact_wire_tension` where set."""
        return problem_catenary(self.catenary, self.contact_wire_tension)

    @property
    def pantograph_definition(self) -> PantographDefinition:
        """The catenary's default pantograph preset (loaded once per process)."""
        return preset_pantograph(self.catenary_definition.pantograph)

    # -- grid -------------------------------------------------------------------------------------------

    def snap(self, x: ArrayLike) -> NDArray[np.float64]:
        """Clip ``x`` to the bounds and round it to the grid.

        Ties (a value half-way between two grid points) round up, towards the upper bound.

        Parameters
        ----------
        x : array_like, shape (n_variables,)
            Variables, m. Must be finite.

        Returns
        -------
        ndarray, shape (n_variables,)
            On the grid, m; equal grid points are equal floats.
        """
        return self.grid.snap(self._as_vector(x))

    def out_of_bounds(self, x: ArrayLike) -> tuple[str, ...]:
        """Names of the variables of ``x`` that lie outside the bounds (what :meth:`snap` would clip)."""
        return self.grid.out_of_bounds(self._as_vector(x))

    def check_variables(self, x: ArrayLike) -> NDArray[np.float64]:
        """Refuse ``x`` outside the bounds; return it rounded to the grid.

        Raises
        ------
        ValueError
            Wrong count, non-finite values, or a variable outside its bounds (named, with the bounds).
        """
        values = self._as_vector(x)
        outside = self.out_of_bounds(values)
        problems = [
            f"{name} = {value!r} {unit}: must lie in [{lo:g}, {hi:g}] {unit}"
            for name, unit, value, lo, hi in zip(
                self.variables, self.units, values.tolist(), self.lower, self.upper, strict=True
            )
            if name in outside
        ]
        if problems:
            raise ValueError(f"problem {self.name}: " + "; ".join(problems))
        return self.snap(values)

    def grid_index(self, x: ArrayLike) -> NDArray[np.int64]:
        """Integer grid coordinates of snapped ``x``: 0 at the lower bound, ``n_levels - 1`` at the upper."""
        return self.grid.to_index(self._as_vector(x))

    def from_grid_index(self, index: ArrayLike) -> NDArray[np.float64]:
        """Variables, m, of integer grid coordinates (inverse of :meth:`grid_index`; clipped to the grid)."""
        return self.grid.from_index(np.clip(np.asarray(index, dtype=np.int64), 0, self.n_levels - 1))

    # -- designs ----------------------------------------------------------------------------------------

    def design(self, x: ArrayLike) -> Design:
        """The design of ``x`` (checked against the bounds and rounded to the grid).

        Parameters
        ----------
        x : array_like, shape (n_variables,)
            Variables in the order of :attr:`variables`, m.

        Returns
        -------
        Design
            Symmetric, with ``n_droppers`` droppers per span. Not checked against the catenary: see
            :func:`~catenary_env.model.design.check_design`.
        """
        values = dict(zip(self.variables, self.check_variables(x).tolist(), strict=True))
        catenary = self.catenary_definition
        if self.variables == ("s",):
            return presag_design(catenary, values["s"])
        position_names, height_names = self._split_names()
        length = catenary.span_length
        mid_dropper = self.n_droppers % 2 == 1
        n_half = self.n_droppers // 2
        if position_names:
            half_positions = tuple(values[name] for name in position_names)
        else:
            half_positions = tuple(catenary.dropper_positions[:n_half])
        if height_names:
            half_offsets = tuple(values[name] for name in height_names)
        else:
            half_offsets = (0.0,) * (n_half + int(mid_dropper))
        return symmetric_design(half_positions, half_offsets, length, mid_dropper)

    def reference_design(self) -> Design:
        """The level contact wire on the preset's droppers (docs/problems.md, 'Reference design and uplift'),
        also for B3 and SW3."""
        positions = tuple(self.catenary_definition.dropper_positions)
        return Design(positions, (0.0,) * len(positions))

    def reference_x(self) -> NDArray[np.float64] | None:
        """The variables of the reference design, m, or None where the problem cannot express it (B3, SW3)."""
        if self.n_droppers != len(self.catenary_definition.dropper_positions):
            return None
        position_names, _ = self._split_names()
        half = self.catenary_definition.dropper_positions[: self.n_droppers // 2]
        positions = iter(half)
        x = np.array([next(positions) if name in position_names else 0.0 for name in self.variables])
        if self.out_of_bounds(x):
            return None
        return self.snap(x)

    # -- simulation -------------------------------------------------------------------------------------

    def uplift_force(self, speed_kmh: float = 300.0, fidelity: str | Fidelity = "study") -> float:
        """Pantograph uplift force of the problem at a speed, N: set once on the reference design.

        Calibrated so that the reference design's mean contact force equals the EN 50367 target at
        ``speed_kmh`` (a few passages: some 15 s at the study fidelity, announced on stderr); kept per
        model fingerprint (catenary and pantograph data), speed and fidelity in this process and on disk
        (:mod:`~catenary_env.calibration_cache`), so later processes and commands reuse it. With
        :attr:`contact_wire_tension` set, the preset's force: the pantograph is set once per catenary and
        speed, not per tension (docs/problems.md, 'Contact-wire tension').
        """
        return calibrated_uplift(
            self.catenary, self.reference_design(), float(speed_kmh), resolve_fidelity(fidelity)
        )

    def fingerprint(self) -> str:
        """Hash of the catenary, pantograph and variables (and of the buildability limits and the robust
        objective where set): results are reusable only under the same one."""
        options = [] if self.buildability == NO_LIMITS else [dataclasses.asdict(self.buildability)]
        if self.robust is not None:
            options.append(repr(self.robust))
        return model_fingerprint(
            self.catenary_definition,
            self.pantograph_definition,
            self.variables,
            self.lower.tolist(),
            self.upper.tolist(),
            self.step.tolist(),
            *options,
        )

    def with_options(
        self, buildability: BuildabilityLimits | None = None, robust: RobustObjective | None = None
    ) -> DesignProblem:
        """The same problem with buildability limits and (or) the robust objective."""
        return dataclasses.replace(
            self,
            buildability=self.buildability if buildability is None else buildability,
            robust=self.robust if robust is None else robust,
        )

    def with_contact_wire_tension(self, contact_wire_tension: float | None) -> DesignProblem:
        """The same problem on its catenary with the contact wire at ``contact_wire_tension``, N (None, or the
        preset's own tension: the problem on the preset); ValueError naming the allowed range outside
        :data:`TENSION_FRACTIONS` of the preset's."""
        tension = None if contact_wire_tension is None else float(contact_wire_tension)
        if tension == preset_catenary(self.catenary).contact_wire.tension:
            tension = None  # the preset itself: one name, one key in the run store
        if tension == self.contact_wire_tension:
            return self  # the evaluations of every worker pass through here: no new problem for nothing
        return dataclasses.replace(self, contact_wire_tension=tension)

    @property
    def best_known(self) -> BestKnown | None:
        """The best-known design of this problem (:mod:`~catenary_env.problems.best_known`), or None where
        none is recorded for this model (its :meth:`store_fingerprint`)."""
        best = best_known_table().get(self.name)
        return best if best is not None and best.model_fingerprint == self.store_fingerprint() else None

    def store_fingerprint(self) -> str:
        """:meth:`fingerprint` with the named fidelities' settings (mesh, time step, the span-mode model's
        cut-offs): the key of stored study results, which are never served after either changes."""
        fidelities = {name: dataclasses.asdict(f) for name, f in FIDELITIES.items()}
        return model_fingerprint(self.fingerprint(), fidelities)

    def reference_evaluation(
        self, speed_kmh: float = 300.0, fidelity: str | Fidelity = "study", train: Train = SINGLE
    ) -> Evaluation:
        """The reference design's evaluation at a speed (cached in this process), with the ``train``'s
        pantographs behind the leading one."""
        return reference_evaluation(
            self.catenary,
            self.reference_design(),
            float(speed_kmh),
            resolve_fidelity(fidelity),
            train,
            self.contact_wire_tension,
        )

    def evaluate(
        self,
        x: ArrayLike,
        speed_kmh: float = 300.0,
        fidelity: str | Fidelity = "study",
        uplift_force: float | None = None,
        deviations: SectionDeviations | None = None,
        train: Train = SINGLE,
    ) -> Evaluation:
        """Simulate the design of ``x`` at a speed, under the problem's :attr:`buildability` limits; with
        :attr:`robust`, the robust objective's evaluation (docs/acceptance.md).

        Parameters
        ----------
        x : array_like, shape (n_variables,)
            Variables, m; rounded to the grid.
        speed_kmh : float
            Train speed, km/h.
        fidelity : str or Fidelity
            A name in :data:`~catenary_env.pipeline.FIDELITIES` or a :class:`Fidelity`.
        uplift_force : float, optional
            Pantograph uplift force, N. Default: the problem's, :meth:`uplift_force` (pass it to spare
            worker processes their own calibration).
        deviations : SectionDeviations, optional
            Installation deviations of every span (not with :attr:`robust`, which draws its own).
        train : Train
            Pantographs behind the leading one (with the leading one's uplift force unless they set their
            own) and the objective's pantograph(s), :attr:`Evaluation.sigma` (docs/model.md, 'Several
            pantographs'); default one pantograph.

        Returns
        -------
        Evaluation
            A design that ``x`` within the bounds cannot build on the catenary (only SW3 with
            ``d_1 = 9.0`` m: dropper 1 at the stitch wire's end) comes back infeasible, with a reason
            starting ``"design:"``, unsimulated.

        Raises
        ------
        ValueError
            ``x`` of the wrong shape, not finite, or outside the bounds; a speed outside (0, wave speed).
        """
        # The boundary: every input is checked here once, then the pipeline's unchecked core runs.
        if self.robust is not None:
            if deviations is not None:
                raise ValueError("deviations: a robust problem draws its own; give none")
            robust = self.robust
            result = self.evaluate_tolerances(
                x, robust.tolerances, robust.draws, robust.seed, speed_kmh, fidelity, uplift_force
            )
            return robust_evaluation(result, robust, float(speed_kmh))
        forces = None if uplift_force is None else (uplift_force,)
        return self.evaluate_speeds(x, (speed_kmh,), fidelity, forces, deviations, train).evaluations[0]

    def evaluate_speeds(
        self,
        x: ArrayLike,
        speeds_kmh: Sequence[float],
        fidelity: str | Fidelity = "study",
        uplift_forces: Sequence[float] | None = None,
        deviations: SectionDeviations | None = None,
        train: Train = SINGLE,
    ) -> SpeedsEvaluation:
        """:meth:`evaluate` at each of ``speeds_kmh`` in turn, up to the first speed at which the design is
        infeasible (:class:`~catenary_env.problems.speeds.SpeedsEvaluation`).

        The design is built and shape-found once, and its linear system and the dynamic model's preparation
        made once, for all the speeds (they do not depend on the speed): the evaluations equal
        :meth:`evaluate`'s at each speed, and cost one passage each after the first (docs/performance.md,
        'Speed'). ``uplift_forces``: one per speed, N (default the problem's, :meth:`uplift_force`,
        calibrated when its speed is reached). With :attr:`robust`, each speed is its own robust
        evaluation. Raises ``ValueError`` as :meth:`evaluate` does, for every speed before any simulation.
        """
        speeds = tuple(float(v) for v in speeds_kmh)
        if not speeds:
            raise ValueError("speeds_kmh: give at least one speed (km/h)")
        if uplift_forces is not None and len(uplift_forces) != len(speeds):
            raise ValueError(
                f"uplift_forces: {len(uplift_forces)} given for {len(speeds)} speeds; give one per speed (N)"
            )
        catenary = self.catenary_definition
        for v in speeds:
            check_speed(catenary, v / 3.6)
        if self.robust is not None:
            if deviations is not None:
                raise ValueError("deviations: a robust problem draws its own; give none")
            forces = iter((None,) * len(speeds) if uplift_forces is None else uplift_forces)
            return evaluate_over_speeds(
                lambda v: self.evaluate(x, v, fidelity, next(forces), train=train), speeds
            )
        design = self.design(x)
        resolved = resolve_fidelity(fidelity)
        pantograph = self.pantograph_definition
        for force in uplift_forces or ():
            check_uplift(pantograph, float(force))
        try:
            check_design(catenary, design)
            check_section_deviations(catenary, design, resolved, deviations)
        except DesignError as error:
            force = (
                self.uplift_force(speeds[0], resolved) if uplift_forces is None else float(uplift_forces[0])
            )
            unknown = (np.nan,) * len(pipeline.CONSTRAINTS)
            design_error = Evaluation(
                False, f"design: {error}", None, (), (), force, 0.0, constraints=unknown
            )
            return SpeedsEvaluation(speeds, (design_error,))
        check_fidelity(catenary, resolved)
        train.check(catenary, resolved.n_spans, pipeline.analysis_window(catenary, resolved)[1])

        def passages() -> Iterator[tuple[float, float]]:
            for i, v in enumerate(speeds):
                force = self.uplift_force(v, resolved) if uplift_forces is None else float(uplift_forces[i])
                check_uplift(pantograph, force)
                yield v / 3.6, force

        evaluations = pipeline.evaluate_speeds_unchecked(
            catenary, pantograph, design, passages(), resolved, self.buildability, deviations, train
        )
        return SpeedsEvaluation(speeds, tuple(evaluations))

    def evaluate_tolerances(
        self,
        x: ArrayLike,
        tolerances: Tolerances,
        draws: int,
        seed: int = 0,
        speed_kmh: float = 300.0,
        fidelity: str | Fidelity = "study",
        uplift_force: float | None = None,
        progress: Callable[[int], None] | None = None,
    ) -> ToleranceEvaluation:
        """The design of ``x`` on draws 0 to ``draws - 1`` of ``seed`` of its built section
        (docs/acceptance.md, 'Installation tolerances'): the same draws for every design of the problem
        (common random numbers).

        A draw that moves a dropper off its span or past its neighbour comes back infeasible (``"design:"``).
        """
        plain = dataclasses.replace(self, robust=None)
        resolved = resolve_fidelity(fidelity)
        force = self.uplift_force(speed_kmh, resolved) if uplift_force is None else float(uplift_force)

        def one(deviations: SectionDeviations) -> Evaluation:
            return plain.evaluate(x, speed_kmh, resolved, force, deviations)

        return evaluate_under_tolerances(
            one, tolerances, resolved.n_spans, self.n_droppers, draws, seed, progress
        )

    # -- helpers ----------------------------------------------------------------------------------------

    def _as_vector(self, x: ArrayLike) -> NDArray[np.float64]:
        return self.grid.check_vector(x, "x")

    def _split_names(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        positions = tuple(v for v in self.variables if v.startswith("d_"))
        heights = tuple(v for v in self.variables if v.startswith("dh_"))
        return positions, heights


def resolve_fidelity(fidelity: str | Fidelity, n_spans: int | None = None) -> Fidelity:
    """A :class:`Fidelity` from a name or a record, optionally with another number of spans.

    With ``n_spans``, the analysis section keeps its number of spans where it fits, and shrinks to
    ``n_spans - 2`` otherwise (one span at each end stays out of the statistics).
    """
    if isinstance(fidelity, Fidelity):
        resolved = fidelity
    elif fidelity in FIDELITIES:
        resolved = FIDELITIES[fidelity]
    else:
        raise ValueError(f"fidelity = {fidelity!r}: must be one of {', '.join(FIDELITIES)} or a Fidelity")
    if n_spans is None:
        return resolved
    if isinstance(n_spans, bool) or not isinstance(n_spans, int | np.integer) or n_spans < 3:
        raise ValueError(f"n_spans = {n_spans!r}: must be an integer >= 3")
    return dataclasses.replace(
        resolved, n_spans=int(n_spans), analysis_spans=min(resolved.analysis_spans, int(n_spans) - 2)
    )
