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
from .preparation import PreparedSpanModes, initial_acceleration
from .state import start_state


def run(prepared: PreparedSpanModes, passage: Passage) -> Trajectory:
    """The passage on the span-mode model (the same rules as the exact one)."""
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
            run_steps(current[1], points, state, zero, k, end)
            k = end

    run_in_chunks(steps, configuration.size, passage.progress)
    positions = tuple(one.position for one in started)
    return trajectory(history, started[0].time, positions, system.static.layout.support_x)


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
