"""The exact model's state during a passage, shared by its loops (docs/model.md, 'Time integration and the
fast method')."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..contact_point import PantographState, StartedPoint
from ..history import PassageHistory


class ExactState(NamedTuple):
    """What a loop updates: the state after the last step done, and the histories. n DOFs, w the padded band
    width (the compiled loop's; the numpy loop leaves its own arrays empty).

    Attributes
    ----------
    u, v, a : ndarray (n,)
        Catenary displacement, velocity, acceleration (in the factor's DOF order for the compiled loop).
    x, y : ndarray (n,)
        Compiled loop: the next step's u_known is K̂⁻¹ M x + y (:class:`StepCoefficients`).
    work : ndarray (n + w,)
        Compiled loop: the right-hand side M x, then K̂⁻¹ M x, then u₁ - y.
    sweep : ndarray (n + w,)
        Compiled loop: the forward sweep's unknowns, in reverse order.
    unit : ndarray (P, n + w, 4)
        Compiled loop: unit responses of each contact point's current contact-wire element, non-zero in rows
        ``element[p, FIRST_ROW]`` to ``element[p, LAST_ROW]`` (:mod:`.kernels`).
    element : ndarray (P, 3) of int
        Compiled loop: each contact point's current contact-wire element (-1: none yet) and those rows.
    slack : ndarray (D,) of bool
    pantographs : tuple of PantographState
        Each contact point's pantograph.
    history : PassageHistory
    """

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    x: np.ndarray
    y: np.ndarray
    work: np.ndarray
    sweep: np.ndarray
    unit: np.ndarray
    element: np.ndarray
    slack: np.ndarray
    pantographs: tuple[PantographState, ...]
    history: PassageHistory


def start_state(
    acceleration: np.ndarray, width: int, started: tuple[StartedPoint, ...], history: PassageHistory
) -> ExactState:
    """The catenary at rest with the initial ``acceleration`` (n,); ``width`` 0 for the numpy loop, which
    needs no work space."""
    n = acceleration.size
    padded = n + width if width else 0
    return ExactState(
        u=np.zeros(n),
        v=np.zeros(n),
        a=acceleration,
        x=np.zeros(n if width else 0),
        y=np.zeros(n if width else 0),
        work=np.zeros(padded),
        sweep=np.zeros(padded),
        unit=np.zeros((len(started), padded, 4)),
        element=np.tile(np.array([-1, 0, -1], dtype=np.int64), (len(started), 1)),
        slack=np.zeros(history.dropper_min.size, dtype=np.bool_),
        pantographs=tuple(one.state for one in started),
        history=history,
    )
