"""The span-mode model's passage (docs/performance.md, 'Model fidelities').

:func:`run` takes the design's part from :func:`~catenary_env.dynamics.span_modes.preparation.prepare` and a
:class:`~catenary_env.dynamics.protocol.Passage`, and runs one of two time loops (:data:`BACKENDS`):
``"numba"``, compiled (:mod:`~catenary_env.dynamics.span_modes.kernels`, optional, taken where numba is
installed), and ``"numpy"``, the same steps in numpy (:mod:`~catenary_env.dynamics.span_modes.loop`). Both
follow the exact model's Newmark scheme, superposition and active-set rules.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

import numpy as np

from ..contact_point import ContactPointArrays, initial_load, start_train
from ..history import start_history, trajectory
from ..newmark import Trajectory
from ..protocol import Passage, choose_backend, run_in_chunks
from . import loop
from .preparation import PreparedSpanModes, SpanModeArrays, initial_acceleration
from .state import SpanModeState, start_state


def run(prepared: PreparedSpanModes, passage: Passage) -> Trajectory:
    """The passage on the span-mode model (the same rules as the exact one)."""
    backend = choose_backend(passage.backend, BACKENDS, _compiled_kernels() is not None)
    reduced = prepared.reduced
    system = reduced.system
    started = start_train(system, passage, prepared.constants)
    d, configuration = _configurations(prepared, tuple(one.arrays for one in started))
    acceleration = initial_acceleration(reduced, d.kept[configuration[0]], initial_load(system, started))
    history = start_history(
        started[0].time.size,
        system.support_z.size,
        system.dropper_force,
        np.array([one.force0 for one in started]),
        np.array([one.state.y[-1] for one in started]),
    )
    state = start_state(acceleration, d.coefficients.e3, d.coefficients.g3, started, history)
    points = tuple(one.arrays for one in started)
    BACKENDS[backend](d, points, state, configuration, passage.progress)
    positions = tuple(one.position for one in started)
    return trajectory(history, started[0].time, positions, system.static.layout.support_x)


def _configurations(
    prepared: PreparedSpanModes, points: tuple[ContactPointArrays, ...]
) -> tuple[SpanModeArrays, np.ndarray]:
    """The design's arrays with the configurations the passage meets, and each step's configuration: the
    spans the pantographs are in (docs/model.md, 'Several pantographs')."""
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
    tuples, configuration = np.unique(spans.T, axis=0, return_inverse=True)
    return prepared.arrays_for(tuple(tuple(int(s) for s in row) for row in tuples)), configuration.ravel()


def _run_numpy(
    d: SpanModeArrays,
    points: tuple[ContactPointArrays, ...],
    state: SpanModeState,
    configuration: np.ndarray,
    progress: Callable[[float], None] | None,
) -> None:
    run_in_chunks(
        lambda first, stop: loop.run_steps(d, points, state, configuration, first, stop),
        points[0].element.size,
        progress,
    )


def _run_compiled(
    d: SpanModeArrays,
    points: tuple[ContactPointArrays, ...],
    state: SpanModeState,
    configuration: np.ndarray,
    progress: Callable[[float], None] | None,
) -> None:
    kernels = _compiled_kernels()
    if kernels is None:
        raise ImportError("backend='numba' needs numba: pip install numba")
    configuration = configuration.astype(np.int64)
    run_in_chunks(
        lambda first, stop: kernels.run_steps(d, points, state, configuration, first, stop),
        points[0].element.size,
        progress,
    )


BACKENDS = {"numba": _run_compiled, "numpy": _run_numpy}
"""The span-mode passage's time loops by name; ``"auto"`` takes numba where it is installed."""


def _compiled_kernels() -> ModuleType | None:
    """:mod:`catenary_env.dynamics.span_modes.kernels`, or None where numba is not installed."""
    try:
        from . import kernels
    except ImportError:
        return None
    return kernels
