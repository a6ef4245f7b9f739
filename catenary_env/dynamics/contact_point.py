"""A pantograph on the track: what every loop reads of it and its state (docs/model.md, 'Time integration and
the fast method').

A passage's contact points (:class:`~catenary_env.dynamics.protocol.ContactPoint`) become, once the time
step and speed are known, :class:`ContactPointArrays` (where the pantograph is at every step, its matrices)
and a :class:`PantographState`. Both models' loops, numpy and compiled, read these same named fields; the
pantograph's part of a step is written here once, in numpy (:func:`known_response`,
:func:`advance_pantograph`) and in scalar loops for the compiled loops (:func:`known_response_in_place`,
:func:`advance_pantograph_in_place`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .compilable import compilable
from .linear_system import LinearSystem
from .newmark import NewmarkConstants, StepCoefficients, passage_positions
from .pantograph import pantograph_matrices, static_contact
from .protocol import ContactPoint, Passage


class ContactPointArrays(NamedTuple):
    """One pantograph along the passage. p masses, the head last.

    Attributes
    ----------
    element : ndarray (steps,) of int
        The contact-wire element under the pantograph at each step.
    shape : ndarray (steps, 4)
        The element's shape row h there: the wire height is h · (z_i, z'_i, z_j, z'_j).
    wire_z : ndarray (steps,)
        Static contact-wire height at the pantograph, m above nominal.
    mass, damping, inverse : ndarray (p, p)
        M_p (kg), C_p (N·s/m) and K̂_p⁻¹ = (K_p + a1 C_p + a0 M_p)⁻¹ (m/N).
    y_star : ndarray (p,)
        Pantograph response to a unit downward head force (negated), m/N.
    load : ndarray (p,)
        The force on the frame, N.
    """

    element: np.ndarray
    shape: np.ndarray
    wire_z: np.ndarray
    mass: np.ndarray
    damping: np.ndarray
    inverse: np.ndarray
    y_star: np.ndarray
    load: np.ndarray


class PantographState(NamedTuple):
    """The pantograph after the last step done: coordinates y (m), ẏ, ÿ (p,), and ``contact`` (1,): 1 while
    the head touches the wire."""

    y: np.ndarray
    yd: np.ndarray
    ydd: np.ndarray
    contact: np.ndarray


class StartedPoint(NamedTuple):
    """A contact point at the start of a passage: its arrays and state, the passage's times (s) and the
    pantograph's positions (m), and the initial (static) contact force, N."""

    arrays: ContactPointArrays
    state: PantographState
    time: np.ndarray
    position: np.ndarray
    force0: float


def start_contact_point(
    system: LinearSystem,
    point: ContactPoint,
    nm: NewmarkConstants,
    speed: float,
    n_steps: int | None,
) -> StartedPoint:
    """The pantograph's positions (at ``speed`` m/s, ``n_steps`` steps at most), contact-wire elements and
    heights, matrices, and its static contact on the wire where it enters the section.

    The train's first pantograph runs from the section's start to its end; this one follows it
    ``point.offset`` m behind (docs/model.md, 'Several pantographs'). Before it reaches the section it
    touches nothing (its element is -1 there): it waits in its static contact on the wire at the section's
    start, which it meets in that state.
    """
    lay = system.static.layout
    cat = lay.catenary
    pm = pantograph_matrices(point.pantograph)
    head = pm.head
    inverse = np.linalg.inv(pm.stiffness + nm.a1 * pm.damping + nm.a0 * pm.mass)
    load = np.zeros(pm.mass.shape[0])
    load[0] = point.frame_force
    length = lay.n_spans * lay.span_length
    time, position = passage_positions(length, speed, nm.dt)
    if n_steps is not None:
        time, position = time[:n_steps], position[:n_steps]
    if point.offset:
        position = position - point.offset
    on = np.flatnonzero((position >= 0.0) & (position <= length * (1.0 + 1e-12)))
    element = np.full(position.size, -1, dtype=np.int64)
    shape = np.zeros((position.size, 4))
    wire_z = np.zeros(position.size)
    if on.size == position.size:
        element, shape, wire_z = system.contact_wire.locate(position)
    elif on.size:
        element[on], shape[on], wire_z[on] = system.contact_wire.locate(position[on])
    wire_z[on] -= cat.contact_wire_height  # static height above nominal
    kh = cat.contact_stiffness
    entry = int(on[0]) if on.size else 0
    y0 = static_contact(pm, point.frame_force, kh, wire_z[entry])[0]
    force0 = kh * max(0.0, y0[head] - wire_z[0]) if entry == 0 and on.size else 0.0
    arrays = ContactPointArrays(
        element=element.astype(np.int64),
        shape=np.ascontiguousarray(shape, dtype=float),
        wire_z=wire_z.astype(float),
        mass=np.ascontiguousarray(pm.mass, dtype=float),
        damping=np.ascontiguousarray(pm.damping, dtype=float),
        inverse=inverse,
        y_star=inverse[:, head].copy(),
        load=load,
    )
    state = PantographState(
        y=y0,
        yd=np.zeros(head + 1),
        ydd=np.zeros(head + 1),
        contact=np.array([force0 > 0.0 or entry > 0], dtype=np.int64),
    )
    return StartedPoint(arrays, state, time, position, force0)


def start_train(system: LinearSystem, passage: Passage, nm: NewmarkConstants) -> tuple[StartedPoint, ...]:
    """Every pantograph of the passage (:func:`start_contact_point`)."""
    return tuple(
        start_contact_point(system, point, nm, passage.speed, passage.n_steps)
        for point in passage.contact_points
    )


def initial_load(system: LinearSystem, started: tuple[StartedPoint, ...]) -> np.ndarray:
    """The catenary's load (n,) under the initial contact forces, N: it starts at rest under them."""
    load = np.zeros(system.n_dofs)
    for one in started:
        point = one.arrays
        if point.element[0] >= 0:
            np.add.at(load, system.contact_wire.z_dofs[point.element[0]], point.shape[0] * one.force0)
    return load


def known_response(point: ContactPointArrays, cf: StepCoefficients, state: PantographState) -> np.ndarray:
    """The pantograph at the end of the step without the step's contact force: K̂_p y_known = M_p (a0 y + a2 ẏ
    + a3 ÿ) + C_p (a1 y + a4 ẏ + a5 ÿ) + load."""
    y, yd, ydd = state.y, state.yd, state.ydd
    rhs = point.mass @ (cf.a0 * y + cf.a2 * yd + cf.a3 * ydd) + point.damping @ (
        cf.a1 * y + cf.a4 * yd + cf.a5 * ydd
    )
    return point.inverse @ (rhs + point.load)


def advance_pantograph(
    point: ContactPointArrays, cf: StepCoefficients, state: PantographState, y_known: np.ndarray, force: float
) -> None:
    """Newmark update of the pantograph to y_known - f y* under the step's contact force f (N), in place."""
    du = y_known - force * point.y_star - state.y
    acceleration = cf.a0 * du - cf.a2 * state.yd - cf.a3 * state.ydd
    state.yd[:] = cf.a1 * du - cf.a4 * state.yd - cf.a5 * state.ydd
    state.ydd[:] = acceleration
    state.y[:] += du


@compilable()
def known_response_in_place(point, cf, state, rhs, y_known):  # noqa: ANN001, ANN201 - compilable
    """:func:`known_response` in scalar loops, into ``y_known``; ``rhs`` (p,) is work space."""
    n_p = state.y.size
    for i in range(n_p):
        t = point.load[i]
        for j in range(n_p):
            t += point.mass[i, j] * (cf.a0 * state.y[j] + cf.a2 * state.yd[j] + cf.a3 * state.ydd[j])
            t += point.damping[i, j] * (cf.a1 * state.y[j] + cf.a4 * state.yd[j] + cf.a5 * state.ydd[j])
        rhs[i] = t
    for i in range(n_p):
        t = 0.0
        for j in range(n_p):
            t += point.inverse[i, j] * rhs[j]
        y_known[i] = t


@compilable()
def advance_pantograph_in_place(point, cf, state, y_known, force):  # noqa: ANN001, ANN201 - compilable
    """:func:`advance_pantograph` in scalar loops."""
    for i in range(state.y.size):
        du = y_known[i] - force * point.y_star[i] - state.y[i]
        acceleration = cf.a0 * du - cf.a2 * state.yd[i] - cf.a3 * state.ydd[i]
        state.yd[i] = cf.a1 * du - cf.a4 * state.yd[i] - cf.a5 * state.ydd[i]
        state.ydd[i] = acceleration
        state.y[i] += du
