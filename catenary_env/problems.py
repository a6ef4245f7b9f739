"""The eight design problems of SPEC 4: design variables, bounds, grid, and their mapping to a design.

A :class:`DesignProblem` is data (a catenary preset, the variables, their bounds and grid steps) plus the
mapping from a variable vector ``x`` (physical units, m) to a :class:`~catenary_env.design.Design`. Every
span is equal and symmetric about mid-span, so a variable sets a dropper and its mirror; dropper 1 stands
next to the span's first support, and the mid-span dropper never moves.

Variables are named ``s`` (pre-sag at mid-span), ``dh_i`` (contact-wire height change at dropper ``i``
from the level wire, negative = lower) and ``d_i`` (position of dropper ``i`` from the first support).
Heights live on a 1 mm grid, positions on a 1 cm grid (SPEC 4).

Every design of a problem is simulated with the same pantograph uplift force: the one for which the
problem's reference design (the level wire on the preset's droppers) has the EN 50367 mean contact force
at the speed (SPEC 3.5). It is calibrated once per catenary, speed and fidelity and cached in-process.

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

import difflib
import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import simulation
from .definition import CatenaryDefinition, PantographDefinition
from .design import Design, DesignError, check_design, check_speed, presag_design, symmetric_design
from .presets import load_catenary, load_pantograph
from .simulation import FIDELITIES, Evaluation, Fidelity, model_fingerprint

__all__ = [
    "HEIGHT_STEP",
    "POSITION_STEP",
    "PROBLEMS",
    "DesignProblem",
    "ProblemRegistry",
    "evaluate_problem",
    "get_problem",
    "register_problem",
    "resolve_fidelity",
]

HEIGHT_STEP = 0.001
"""Grid step of heights (pre-sag, Δh), m: 1 mm (SPEC 4)."""

POSITION_STEP = 0.01
"""Grid step of dropper positions, m: 1 cm (SPEC 4)."""

_BOUND_TOLERANCE = 1e-9
"""m; a value this close to a bound counts as on it (floating-point noise, not a design change)."""

_TIE_TOLERANCE = 1e-9
"""Grid steps; a value this close below a half step counts as the tie, which rounds up."""

_DECIMALS = 9
"""Grid values are rounded to this many decimals so that equal grid points are equal floats."""


@dataclass(frozen=True, eq=False)
class DesignProblem:
    """A catenary design problem: variables, bounds and grid, and the mapping to a design (SPEC 4).

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

    def __post_init__(self) -> None:
        n = len(self.variables)
        for field_name in ("lower", "upper", "step"):
            array = np.array(getattr(self, field_name), dtype=np.float64)
            if array.shape != (n,):
                raise ValueError(
                    f"problem {self.name!r}: {field_name} must have {n} values, one per variable"
                )
            array.setflags(write=False)  # frozen record: the bounds must not change under a user's feet
            object.__setattr__(self, field_name, array)
        if len(self.units) != n:
            raise ValueError(f"problem {self.name!r}: units must have {n} values, one per variable")
        if not (np.all(self.step > 0.0) and np.all(self.lower < self.upper)):
            raise ValueError(f"problem {self.name!r}: need step > 0 and lower < upper")
        for bound in (self.lower, self.upper):
            if not np.allclose(bound / self.step, np.round(bound / self.step), rtol=0.0, atol=1e-6):
                raise ValueError(f"problem {self.name!r}: bounds must lie on the grid")
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

    # -- data -------------------------------------------------------------------------------------------

    @property
    def n_variables(self) -> int:
        return len(self.variables)

    @property
    def n_levels(self) -> NDArray[np.int64]:
        """Number of grid points of each variable, bounds included."""
        return np.round((self.upper - self.lower) / self.step).astype(np.int64) + 1

    @property
    def catenary_definition(self) -> CatenaryDefinition:
        """The catenary preset (loaded once per process)."""
        return _catenary(self.catenary)

    @property
    def pantograph_definition(self) -> PantographDefinition:
        """The catenary's default pantograph preset (loaded once per process)."""
        return _pantograph(self.catenary_definition.pantograph)

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
        values = self._as_vector(x)
        clipped = np.clip(values, self.lower, self.upper)
        index = np.floor((clipped - self.lower) / self.step + 0.5 + _TIE_TOLERANCE)
        return np.asarray(
            np.round(np.minimum(self.lower + index * self.step, self.upper), _DECIMALS), np.float64
        )

    def out_of_bounds(self, x: ArrayLike) -> tuple[str, ...]:
        """Names of the variables of ``x`` that lie outside the bounds (what :meth:`snap` would clip)."""
        values = self._as_vector(x)
        outside = (values < self.lower - _BOUND_TOLERANCE) | (values > self.upper + _BOUND_TOLERANCE)
        return tuple(name for name, out in zip(self.variables, outside, strict=True) if out)

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
        return np.round((self.snap(x) - self.lower) / self.step).astype(np.int64)

    def from_grid_index(self, index: ArrayLike) -> NDArray[np.float64]:
        """Variables, m, of integer grid coordinates (inverse of :meth:`grid_index`; clipped to the grid)."""
        k = np.clip(np.asarray(index, dtype=np.int64), 0, self.n_levels - 1)
        return self.snap(self.lower + k * self.step)

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
            :func:`~catenary_env.design.check_design`.
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
        """The level contact wire on the preset's droppers (SPEC 4), also for B3 and SW3."""
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
        """Pantograph uplift force of the problem at a speed, N: set once on the reference design (SPEC 3.5).

        Calibrated so that the reference design's mean contact force equals the EN 50367 target at
        ``speed_kmh``; cached per catenary, speed and fidelity in this process.
        """
        return _calibrated_uplift(
            self.catenary, self.reference_design(), float(speed_kmh), resolve_fidelity(fidelity)
        )

    def fingerprint(self) -> str:
        """Hash of the catenary, pantograph and variables: results are reusable only under the same one."""
        return model_fingerprint(
            self.catenary_definition,
            self.pantograph_definition,
            self.variables,
            self.lower.tolist(),
            self.upper.tolist(),
            self.step.tolist(),
        )

    def reference_evaluation(
        self, speed_kmh: float = 300.0, fidelity: str | Fidelity = "study"
    ) -> Evaluation:
        """The reference design's evaluation at a speed (cached in this process)."""
        return _reference_evaluation(
            self.catenary, self.reference_design(), float(speed_kmh), resolve_fidelity(fidelity)
        )

    def evaluate(
        self,
        x: ArrayLike,
        speed_kmh: float = 300.0,
        fidelity: str | Fidelity = "study",
        uplift_force: float | None = None,
    ) -> Evaluation:
        """Simulate the design of ``x`` at a speed.

        Parameters
        ----------
        x : array_like, shape (n_variables,)
            Variables, m; rounded to the grid.
        speed_kmh : float
            Train speed, km/h.
        fidelity : str or Fidelity
            A name in :data:`~catenary_env.simulation.FIDELITIES` or a :class:`Fidelity`.
        uplift_force : float, optional
            Pantograph uplift force, N. Default: the problem's, :meth:`uplift_force` (pass it to spare
            worker processes their own calibration).

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
        design = self.design(x)
        resolved = resolve_fidelity(fidelity)
        catenary = self.catenary_definition
        check_speed(catenary, float(speed_kmh) / 3.6)
        force = self.uplift_force(speed_kmh, resolved) if uplift_force is None else float(uplift_force)
        try:
            check_design(catenary, design)
        except DesignError as error:
            return Evaluation(False, f"design: {error}", None, (), (), force, 0.0)
        return simulation.evaluate(
            catenary, self.pantograph_definition, design, float(speed_kmh) / 3.6, resolved, uplift_force=force
        )

    # -- helpers ----------------------------------------------------------------------------------------

    def _as_vector(self, x: ArrayLike) -> NDArray[np.float64]:
        try:
            values = np.asarray(x, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(
                f"problem {self.name}: x must be {self.n_variables} numbers "
                f"({', '.join(self.variables)}), got {x!r}"
            ) from None
        if values.shape != (self.n_variables,):
            raise ValueError(
                f"problem {self.name}: x must have shape ({self.n_variables},) "
                f"({', '.join(self.variables)}), got shape {values.shape}"
            )
        if not np.all(np.isfinite(values)):
            raise ValueError(f"problem {self.name}: x must be finite, got {values.tolist()}")
        return values

    def _split_names(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        positions = tuple(v for v in self.variables if v.startswith("d_"))
        heights = tuple(v for v in self.variables if v.startswith("dh_"))
        return positions, heights


class ProblemRegistry(dict[str, DesignProblem]):
    """The design problems by name: a dict that refuses to replace an entry."""

    def __setitem__(self, name: str, problem: DesignProblem) -> None:
        if name in self:
            raise ValueError(f"design problem {name!r} is already registered")
        if name != problem.name:
            raise ValueError(f"design problem registered as {name!r} is named {problem.name!r}")
        super().__setitem__(name, problem)

    def update(self, *args: Any, **kwargs: DesignProblem) -> None:  # type: ignore[override]
        # dict.update bypasses __setitem__: route it through the check.
        for name, problem in dict(*args, **kwargs).items():
            self[name] = problem

    def setdefault(self, name: str, problem: DesignProblem) -> DesignProblem:  # type: ignore[override]
        if name not in self:
            self[name] = problem
        return self[name]

    def __ior__(self, other: Any) -> ProblemRegistry:  # type: ignore[override, misc]
        self.update(other)
        return self


PROBLEMS = ProblemRegistry()
"""Every design problem by name, in the order of SPEC 4."""


def register_problem(problem: DesignProblem) -> DesignProblem:
    """Add a problem to :data:`PROBLEMS`; raises ValueError if the name is taken."""
    PROBLEMS[problem.name] = problem
    return problem


def get_problem(name: str) -> DesignProblem:
    """The registered problem called ``name``; raises KeyError naming the problems available."""
    if name not in PROBLEMS:
        by_lower = {known.lower(): known for known in PROBLEMS}
        close = difflib.get_close_matches(str(name).lower(), list(by_lower), n=1)
        hint = f" (did you mean {by_lower[close[0]]!r}?)" if close else ""
        raise KeyError(f"unknown design problem {name!r}{hint}; available: {', '.join(PROBLEMS)}")
    return PROBLEMS[name]


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
    return Fidelity(
        n_spans=int(n_spans),
        analysis_spans=min(resolved.analysis_spans, int(n_spans) - 2),
        contact_wire_element=resolved.contact_wire_element,
        messenger_wire_element=resolved.messenger_wire_element,
        time_step=resolved.time_step,
    )


def evaluate_problem(
    name: str,
    x: tuple[float, ...],
    speed_kmh: float,
    fidelity: str | Fidelity,
    uplift_force: float | None = None,
) -> Evaluation:
    """:meth:`DesignProblem.evaluate` of a registered problem, as a picklable function for process pools.

    Each worker process calibrates the uplift force once per catenary, speed and fidelity unless
    ``uplift_force`` (N) is given: pass :meth:`DesignProblem.uplift_force` from the parent to spare it.
    """
    return get_problem(name).evaluate(x, speed_kmh, fidelity, uplift_force=uplift_force)


def clear_caches() -> None:
    """Forget the calibrated uplift forces and reference evaluations of this process."""
    _calibrated_uplift.cache_clear()
    _reference_evaluation.cache_clear()


# -- process caches: a preset is read, and a pantograph set, once per process -------------------------------


@functools.lru_cache(maxsize=None)
def _catenary(name: str) -> CatenaryDefinition:
    return load_catenary(name)


@functools.lru_cache(maxsize=None)
def _pantograph(name: str) -> PantographDefinition:
    return load_pantograph(name)


@functools.lru_cache(maxsize=256)
def _calibrated_uplift(catenary_name: str, reference: Design, speed_kmh: float, fidelity: Fidelity) -> float:
    # Keyed by the catenary and its reference design, not by the problem: the problems on one catenary
    # share the pantograph setting (SPEC 3.5), so B1, B2, B3 calibrate once between them.
    catenary = _catenary(catenary_name)
    speed = speed_kmh / 3.6
    check_speed(catenary, speed)
    return float(
        simulation.calibrate_uplift(
            catenary,
            _pantograph(catenary.pantograph),
            reference,
            speed,
            fidelity,
            target_mean=simulation.en50367_mean_force(speed),
        )
    )


@functools.lru_cache(maxsize=256)
def _reference_evaluation(
    catenary_name: str, reference: Design, speed_kmh: float, fidelity: Fidelity
) -> Evaluation:
    catenary = _catenary(catenary_name)
    force = _calibrated_uplift(catenary_name, reference, speed_kmh, fidelity)
    return simulation.evaluate(
        catenary, _pantograph(catenary.pantograph), reference, speed_kmh / 3.6, fidelity, uplift_force=force
    )


# -- the problems of SPEC 4 ------------------------------------------------------------------------------


def _problem(
    name: str, catenary: str, n_droppers: int, bounds: Sequence[tuple[str, float, float]], description: str
) -> DesignProblem:
    names = tuple(b[0] for b in bounds)
    return DesignProblem(
        name=name,
        catenary=catenary,
        n_droppers=n_droppers,
        variables=names,
        units=("m",) * len(names),
        lower=np.array([b[1] for b in bounds]),
        upper=np.array([b[2] for b in bounds]),
        step=np.array([POSITION_STEP if v.startswith("d_") else HEIGHT_STEP for v in names]),
        description=description,
    )


def _heights(n: int) -> list[tuple[str, float, float]]:
    return [(f"dh_{i}", -0.02, 0.02) for i in range(1, n + 1)]


_BENCHMARK = "the benchmark simple catenary (55 m spans, 9 droppers in the reference)"
_STITCHED = "the stitched catenary (65 m spans, 7 droppers in the reference)"

for _p in (
    _problem(
        "BPresag",
        "benchmark",
        9,
        [("s", -0.02, 0.10)],
        f"Pre-sag of {_BENCHMARK}: parabolic contact-wire profile, s below the level at mid-span "
        "(negative = raised), on the preset's droppers.",
    ),
    _problem(
        "B1",
        "benchmark",
        9,
        _heights(5),
        f"Contact-wire heights of {_BENCHMARK}: dh_i is the height change at dropper i and its mirror "
        "(dropper 1 at the support side, 5 at mid-span), on the preset's droppers.",
    ),
    _problem(
        "B2",
        "benchmark",
        9,
        [("d_1", 0.1, 7.4), ("d_2", 7.5, 13.1), ("d_3", 13.2, 18.8), ("d_4", 18.9, 27.4)],
        f"Dropper positions of {_BENCHMARK}: d_i is the distance of dropper i (and, mirrored, of its "
        "twin) from the span's first support; the mid-span dropper stays; level contact wire.",
    ),
    _problem(
        "B3",
        "benchmark",
        5,
        [("d_1", 0.1, 13.0), ("d_2", 13.1, 27.4)] + _heights(3),
        f"Five droppers per span instead of nine on {_BENCHMARK}: positions d_1, d_2 (mirrored) and "
        "the mid-span dropper, with height changes dh_1..dh_3 (dh_3 at mid-span).",
    ),
    _problem(
        "SWPresag",
        "stitched",
        7,
        [("s", -0.02, 0.10)],
        f"Pre-sag of {_STITCHED}: parabolic contact-wire profile, s below the level at mid-span "
        "(negative = raised), on the preset's droppers.",
    ),
    _problem(
        "SW1",
        "stitched",
        7,
        _heights(4),
        f"Contact-wire heights of {_STITCHED}: dh_i is the height change at dropper i and its mirror "
        "(dropper 1, on the stitch wire, at the support side; 4 at mid-span).",
    ),
    _problem(
        "SW2",
        "stitched",
        7,
        [("d_1", 0.1, 8.9), ("d_2", 9.1, 20.4), ("d_3", 20.5, 32.4)],
        f"Dropper positions of {_STITCHED}: d_i is the distance of dropper i (and its mirror) from the "
        "span's first support; dropper 1 hangs from the stitch wire; level contact wire.",
    ),
    _problem(
        "SW3",
        "stitched",
        5,
        [("d_1", 2.0, 9.0), ("d_2", 10.0, 30.0)] + _heights(3),
        f"Five droppers per span instead of seven on {_STITCHED}: positions d_1 (on the stitch wire), "
        "d_2 (mirrored) and the mid-span dropper, with height changes dh_1..dh_3 (dh_3 at mid-span).",
    ),
):
    register_problem(_p)
del _p
