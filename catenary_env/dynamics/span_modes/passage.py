"""The span-mode model's passage (docs/performance.md, 'Model fidelities').

:func:`run` takes the design's part from :func:`~catenary_env.dynamics.span_modes.preparation.prepare` and a
:class:`~catenary_env.dynamics.protocol.Passage`, and runs one of two time loops (:data:`BACKENDS`):
``"numba"``, compiled (:mod:`~catenary_env.dynamics.span_modes.kernels`, optional, taken where numba is
installed), and ``"numpy"``, the same steps in numpy (:mod:`~catenary_env.dynamics.span_modes.loop`). Both
follow the exact model's Newmark scheme, superposition and active-set rules.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import ModuleType

import numpy as np

from ...model.definition import CatenaryDefinition
from ..contact_point import ContactPointArrays, initial_load, start_train
from ..history import start_history, trajectory
from ..newmark import Trajectory
from ..protocol import Passage, choose_backend, run_in_chunks
from . import loop
from .preparation import PreparedSpanModes, initial_acceleration
from .state import start_state

FRONT_MARGIN = 200.0
"""m: a passage steps the spans that begin less than this beyond its wave front; those further ahead are at
rest to rounding and held there (docs/performance.md, 'The spans ahead of the wave front': set by a
convergence study: the first margin at which every case's contact force stays within 10⁻⁸ N of the passage
that steps every span, 10³ below what another processor's rounding moves it by)."""


def run(
    prepared: PreparedSpanModes, passage: Passage, front_margin: float | None = FRONT_MARGIN
) -> Trajectory:
    """The passage on the span-mode model (the same rules as the exact one), stepping the spans that begin
    less than ``front_margin`` (m) beyond its wave front (None: every span, every step)."""
    backend = choose_backend(passage.backend, BACKENDS, _compiled_kernels() is not None)
    reduced = prepared.reduced
    system = reduced.system
    started = start_train(system, passage, prepared.constants)
    points = tuple(one.arrays for one in started)
    configurations, configuration = _configurations(prepared, points)
    first = prepared.arrays_for(configurations[configuration[0]])
    acceleration = initial_acceleration(reduced, first.kept[0], initial_load(system, started))
    history = start_history(
        started[0].time.size,
        system.support_z.size,
        system.dropper_force,
        np.array([one.force0 for one in started]),
        np.array([one.state.y[-1] for one in started]),
    )
    state = start_state(acceleration, first.coefficients.e3, first.coefficients.g3, started, history)
    run_steps = BACKENDS[backend]()
    zero = np.zeros(configuration.size, dtype=np.int64)
    stepped = _stepped_spans(system, started, reduced.span_type.size, front_margin)
    changes = np.r_[np.flatnonzero(np.diff(configuration)) + 1, configuration.size]  # each segment's end
    current: list = [None, None]  # the configuration whose arrays the loop has, and the arrays

    def steps(begin: int, stop: int) -> None:
        """Steps ``begin`` to ``stop - 1``, a configuration at a time, each as configuration 0 of its own
        arrays (built, or taken from the design's, as the passage enters it): only one configuration's
        arrays at a time, which a long section's would otherwise fill the memory with."""
        k = begin
        while k < stop:
            c = configuration[k]
            end = min(stop, int(changes[np.searchsorted(changes, k, side="right")]))
            if current[0] != c:
                current[:] = c, prepared.arrays_for(configurations[c])
                state.configuration[0] = -1  # the loop enters it: drops the modes no longer kept
            run_steps(current[1], points, state, zero, stepped, k, end)
            k = end

    run_in_chunks(steps, configuration.size, passage.progress)
    positions = tuple(one.position for one in started)
    return trajectory(history, started[0].time, positions, system.static.layout.support_x)


def _stepped_spans(system, started, n_spans: int, front_margin: float | None) -> np.ndarray:  # noqa: ANN001
    """(steps,): how many spans, the first ones, each step advances: those that begin less than
    ``front_margin`` (m) beyond the wave front. The front leaves the foremost pantograph's starting point at
    :func:`front_speed` (a pantograph is slower: ``check_speed``), and the model's steps carry a
    disturbance beyond it only by a factor of ten to a hundred every 50 m. Extensible wires carry axial waves
    some 30 times faster, which cross a study section in a third of a second: there every span is stepped
    (docs/performance.md, 'The spans ahead of the wave front')."""
    steps = started[0].time.size
    catenary = system.static.layout.catenary
    if front_margin is None or catenary.modelling.linearisation == "extensible":
        return np.full(steps, n_spans, dtype=np.int64)
    time = started[0].time
    front = max(one.position[0] for one in started) + front_speed(catenary) * (time - time[0])
    begun = np.searchsorted(system.static.layout.support_x, front + front_margin, side="left")
    return np.clip(begun, 1, n_spans).astype(np.int64)


def front_speed(catenary: CatenaryDefinition) -> float:
    """The fastest transverse wave of the catenary's wires (contact, messenger and stitch wires), m/s."""
    wires = [catenary.contact_wire, catenary.messenger_wire]
    wires += [catenary.stitch_wire] if catenary.stitch_wire is not None else []
    return max(math.sqrt(w.tension / w.linear_mass) for w in wires)


def _configurations(
    prepared: PreparedSpanModes, points: tuple[ContactPointArrays, ...]
) -> tuple[list[tuple[int, ...]], np.ndarray]:
    """The configurations the passage meets, the spans the pantographs are in (docs/model.md, 'Several
    pantographs'), and each step's, as an index into them."""
    d = prepared.arrays
    spans = np.stack([np.where(p.element >= 0, d.element_span[np.maximum(p.element, 0)], -1) for p in points])
    on = spans >= 0
    for i in range(len(points)):
        for j in range(i + 1, len(points)):
            shared = on[i] & on[j] & (spans[i] == spans[j])
            if np.any(shared):
                raise ValueError(
                    f"passage.contact_points: pantographs {i + 1} and {j + 1} in one span "
                    f"(span {spans[i][shared][0]}); the span-mode model needs them a span length apart at "
                    "least (the exact model takes any spacing)"
                )
    if len(points) == 1:  # the same, some twenty times faster than numpy's unique by rows (3 ms a passage)
        values, configuration = np.unique(spans[0], return_inverse=True)
        return [(int(s),) for s in values], configuration.ravel()
    tuples, configuration = np.unique(spans.T, axis=0, return_inverse=True)
    return [tuple(int(s) for s in row) for row in tuples], configuration.ravel()


def _numpy_steps() -> Callable:
    return loop.run_steps


def _compiled_steps() -> Callable:
    kernels = _compiled_kernels()
    if kernels is None:
        raise ImportError("backend='numba' needs numba: pip install numba")
    return kernels.run_steps


BACKENDS = {"numba": _compiled_steps, "numpy": _numpy_steps}
"""The span-mode passage's time loops by name (each a function that gives the loop's ``run_steps``);
``"auto"`` takes numba where it is installed."""


def _compiled_kernels() -> ModuleType | None:
    """:mod:`catenary_env.dynamics.span_modes.kernels`, or None where numba is not installed."""
    try:
        from . import kernels
    except ImportError:
        return None
    return kernels
