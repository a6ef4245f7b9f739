"""The exact model's passage: every DOF every step (docs/model.md, 'Time integration and the fast method').

:func:`run` takes the design's part from :func:`~catenary_env.dynamics.exact.preparation.prepare` and a
:class:`~catenary_env.dynamics.protocol.Passage`, and runs one of three time loops (:data:`BACKENDS`; docs/
performance.md, 'Benchmark'): ``"numba"``, compiled (:mod:`~catenary_env.dynamics.exact.kernels`, optional,
taken where numba is installed), ``"numpy"``, the same steps and arithmetic in numpy
(:mod:`~catenary_env.dynamics.exact.loop`), and ``"oracle"``, the straightforward loop
(:mod:`~catenary_env.dynamics.exact.oracle`), which also integrates the systems the other two do not
(:attr:`~catenary_env.dynamics.linear_system.LinearSystem.rayleigh` False; ``"auto"`` takes it there). The
numba and numpy loops' contact forces agree to about 1e-9 N, and the oracle's to 1e-6 N.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

import numpy as np
import scipy.sparse.linalg as spla

from ..contact_point import StartedPoint, initial_load, start_contact_point, start_train
from ..history import PassageHistory, start_history, trajectory
from ..newmark import Trajectory
from ..protocol import ContactPoint, Passage, choose_backend, run_in_chunks, single_contact_point
from . import loop, oracle
from .preparation import PreparedExact
from .state import start_state


def run(prepared: PreparedExact, passage: Passage) -> Trajectory:
    """The passage on the exact model.

    Examples
    --------
    >>> from catenary_env.dynamics.exact import prepare, run
    >>> from catenary_env.dynamics.linear_system import linearise
    >>> from catenary_env.dynamics.protocol import ContactPoint, Passage
    >>> from catenary_env.fem.layout import build_layout
    >>> from catenary_env.model.design import level_design
    >>> from catenary_env.model.presets import load_catenary, load_pantograph
    >>> from catenary_env.pipeline import Fidelity
    >>> from catenary_env.statics.shape_finding import find_shape
    >>> catenary = load_catenary("benchmark")
    >>> system = linearise(find_shape(build_layout(catenary, level_design(catenary), 3, 2.0, 4.0)))
    >>> prepared = prepare(system, Fidelity(time_step=2e-3))
    >>> pantograph = ContactPoint(load_pantograph(catenary.pantograph), frame_force=150.0)
    >>> trajectory = run(prepared, Passage(250 / 3.6, (pantograph,)))
    >>> bool(trajectory.contact_force.max() > 150.0)
    True
    """
    system = prepared.system
    if passage.backend == "auto" and not system.rayleigh:
        backend = "oracle"
    else:
        backend = choose_backend(passage.backend, BACKENDS, _compiled_kernels() is not None)
    if backend != "oracle" and not system.rayleigh:
        raise ValueError(
            f"backend = {backend!r}: integrates C = alpha M + beta K with slack droppers dropping their "
            "whole force only; this system needs backend = 'oracle'"
        )
    if backend == "oracle":
        point = single_contact_point(passage)
        started = (start_contact_point(system, point, prepared.constants, passage.speed, passage.n_steps),)
    else:
        point = passage.contact_points[0]
        started = start_train(system, passage, prepared.constants)
    history = start_history(
        started[0].time.size,
        system.support_z.size,
        system.dropper_force,
        np.array([one.force0 for one in started]),
        np.array([one.state.y[-1] for one in started]),
    )
    BACKENDS[backend](prepared, point, started, history, passage.progress)
    positions = tuple(one.position for one in started)
    return trajectory(history, started[0].time, positions, system.static.layout.support_x)


def _run_numpy(
    prepared: PreparedExact,
    point: ContactPoint,
    started: tuple[StartedPoint, ...],
    history: PassageHistory,
    progress: Callable[[float], None] | None,
) -> None:
    system = prepared.system
    acceleration = spla.spsolve(system.mass.tocsc(), initial_load(system, started))
    state = start_state(acceleration, 0, started, history)
    points = tuple(one.arrays for one in started)
    run_in_chunks(
        lambda first, stop: loop.run_steps(prepared, points, state, first, stop),
        started[0].time.size,
        progress,
    )


def _run_compiled(
    prepared: PreparedExact,
    point: ContactPoint,
    started: tuple[StartedPoint, ...],
    history: PassageHistory,
    progress: Callable[[float], None] | None,
) -> None:
    """The compiled loop (:mod:`~catenary_env.dynamics.exact.kernels`), in the factor's DOF order."""
    kernels = _compiled_kernels()
    if kernels is None:
        raise ImportError("backend='numba' needs numba: pip install numba")
    system = prepared.system
    data, width, order = prepared.compiled
    acceleration = spla.spsolve(system.mass.tocsc(), initial_load(system, started))
    state = start_state(acceleration[order], len(width), started, history)
    points = tuple(one.arrays for one in started)
    run_in_chunks(
        lambda first, stop: kernels.run_steps(data, points, state, first, stop, width),
        started[0].time.size,
        progress,
    )


def _run_oracle(
    prepared: PreparedExact,
    point: ContactPoint,
    started: tuple[StartedPoint, ...],
    history: PassageHistory,
    progress: Callable[[float], None] | None,
) -> None:
    oracle.run_steps(prepared, point, started[0], history, progress)


BACKENDS = {"numba": _run_compiled, "numpy": _run_numpy, "oracle": _run_oracle}
"""The exact passage's time loops by name; ``"auto"`` takes numba where it is installed (the oracle for a
system the other two do not integrate)."""


def _compiled_kernels() -> ModuleType | None:
    """:mod:`catenary_env.dynamics.exact.kernels`, or None where numba is not installed."""
    try:
        from . import kernels
    except ImportError:
        return None
    return kernels
