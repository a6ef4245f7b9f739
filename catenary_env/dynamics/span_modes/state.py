"""The span-mode model's state during a passage, shared by its loops (docs/performance.md, 'Model
fidelities')."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..contact_point import PantographState, StartedPoint
from ..history import PassageHistory


class SpanModeState(NamedTuple):
    """What a loop updates: the state after the last step done, and the histories. n_r reduced coordinates
    (the spans' modes, then the interface DOFs), D droppers.

    Attributes
    ----------
    u, v, a : ndarray (n_r,)
        Displacement, velocity, acceleration.
    e, y : ndarray (n_r,)
        The next step's u_known is K̂⁻¹ M e + y (:class:`~catenary_env.dynamics.newmark.StepCoefficients`).
    Bu, Bv, Ba : ndarray (D,)
        The droppers' elongations of u, v, a.
    configuration : ndarray (1,) of int
        The configuration the state is in (the spans the pantographs are in; -1: none yet).
    slack : ndarray (D,) of bool
    pantographs : tuple of PantographState
        Each contact point's pantograph.
    history : PassageHistory
    """

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    e: np.ndarray
    y: np.ndarray
    Bu: np.ndarray
    Bv: np.ndarray
    Ba: np.ndarray
    configuration: np.ndarray
    slack: np.ndarray
    pantographs: tuple[PantographState, ...]
    history: PassageHistory


def start_state(
    acceleration: np.ndarray,
    e3: float,
    g3: float,
    started: tuple[StartedPoint, ...],
    history: PassageHistory,
) -> SpanModeState:
    """At rest with the initial ``acceleration`` (n_r,); e3 and g3 of the step coefficients give the first
    right-hand side."""
    n = acceleration.size
    n_drop = history.dropper_min.size
    return SpanModeState(
        u=np.zeros(n),
        v=np.zeros(n),
        a=acceleration,
        e=e3 * acceleration,
        y=g3 * acceleration,
        Bu=np.zeros(n_drop),
        Bv=np.zeros(n_drop),
        Ba=np.zeros(n_drop),
        configuration=np.array([-1], dtype=np.int64),
        slack=np.zeros(n_drop, dtype=np.bool_),
        pantographs=tuple(one.state for one in started),
        history=history,
    )
