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

from ..contact_point import StartedPoint, initial_load, start_contact_point
from ..history import start_history, trajectory
from ..newmark import Trajectory
from ..protocol import Passage, choose_backend, run_in_chunks, single_contact_point
from . import loop
from .preparation import PreparedSpanModes, initial_acceleration
from .state import SpanModeState, start_state


def run(prepared: PreparedSpanModes, passage: Passage) -> Trajectory:
    """The passage on the span-mode model (the same rules as the exact one)."""
    backend = choose_backend(passage.backend, BACKENDS, _compiled_kernels() is not None)
    reduced = prepared.reduced
    system = reduced.system
    started = start_contact_point(
        system, single_contact_point(passage), prepared.constants, passage.speed, passage.n_steps
    )
    d = prepared.arrays
    first_span = d.element_span[started.arrays.element[0]]
    acceleration = initial_acceleration(reduced, d.kept[first_span], initial_load(system, started))
    history = start_history(
        started.time.size, system.support_z.size, system.dropper_force, started.force0, started.state.y[-1]
    )
    state = start_state(acceleration, d.coefficients.e3, d.coefficients.g3, started, history)
    BACKENDS[backend](prepared, started, state, passage.progress)
    return trajectory(history, started.time, started.position, system.static.layout.support_x)


def _run_numpy(
    prepared: PreparedSpanModes,
    started: StartedPoint,
    state: SpanModeState,
    progress: Callable[[float], None] | None,
) -> None:
    points = (started.arrays,)
    run_in_chunks(
        lambda first, stop: loop.run_steps(prepared.arrays, points, state, first, stop),
        started.time.size,
        progress,
    )


def _run_compiled(
    prepared: PreparedSpanModes,
    started: StartedPoint,
    state: SpanModeState,
    progress: Callable[[float], None] | None,
) -> None:
    kernels = _compiled_kernels()
    if kernels is None:
        raise ImportError("backend='numba' needs numba: pip install numba")
    points = (started.arrays,)
    run_in_chunks(
        lambda first, stop: kernels.run_steps(prepared.arrays, points, state, first, stop),
        started.time.size,
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
