"""What a passage records at every step, for every loop (docs/model.md, 'Statistics and feasibility').

Every loop, numpy or compiled, of either model, writes the same :class:`PassageHistory` arrays: the numpy
loops and the oracle through :func:`record`, the compiled loops through :func:`record_in_place` (the same
rules in scalar loops). :func:`trajectory` ends the passage in one
:class:`~catenary_env.dynamics.newmark.Trajectory`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .compilable import compilable
from .newmark import PantographTrace, Trajectory

SLACK_STEPS, UNRESOLVED_STEPS = range(2)
"""Slots of :attr:`PassageHistory.counts`."""


class PassageHistory(NamedTuple):
    """The time histories and extremes of a passage (see :class:`Trajectory`), written in place; P
    pantographs.

    Attributes
    ----------
    force, head_height, wire_uplift : ndarray (P, steps)
        Each pantograph's contact force (N), head height and contact-wire uplift under it (m).
    support_uplift : ndarray (steps, supports)
        m.
    dropper_min, dropper_max : ndarray (D,)
        The droppers' extreme forces, N (a slack dropper's counts as zero).
    counts : ndarray (2,) of int
        Steps with a slack dropper, and steps whose active set did not settle (slots
        :data:`SLACK_STEPS`, :data:`UNRESOLVED_STEPS`).
    """

    force: np.ndarray
    head_height: np.ndarray
    wire_uplift: np.ndarray
    support_uplift: np.ndarray
    dropper_min: np.ndarray
    dropper_max: np.ndarray
    counts: np.ndarray


def start_history(
    n_steps: int,
    n_supports: int,
    static_dropper_force: np.ndarray,
    force0: np.ndarray,
    head_height0: np.ndarray,
) -> PassageHistory:
    """An empty history with step 0's contact forces (N) and head heights (m), (P,); the droppers' extremes
    start from their static forces (N)."""
    n_points = len(force0)
    history = PassageHistory(
        force=np.zeros((n_points, n_steps)),
        head_height=np.zeros((n_points, n_steps)),
        wire_uplift=np.zeros((n_points, n_steps)),
        support_uplift=np.zeros((n_steps, n_supports)),
        dropper_min=np.array(static_dropper_force, dtype=float),
        dropper_max=np.array(static_dropper_force, dtype=float),
        counts=np.zeros(2, dtype=np.int64),
    )
    history.force[:, 0] = force0
    history.head_height[:, 0] = head_height0
    return history


def record(
    history: PassageHistory,
    k: int,
    force: np.ndarray,
    head_height: np.ndarray,
    wire_uplift: np.ndarray,
    support_uplift: np.ndarray,
    dropper_forces: np.ndarray,
    slack: np.ndarray,
    any_slack: bool,
    resolved: bool,
) -> None:
    """Step ``k``'s contact forces (N), head heights and wire uplifts (m), (P,), support uplifts (m), the
    droppers' forces (N; a slack dropper's counts as zero), whether the step solved for a slack dropper,
    and whether its active set settled."""
    history.force[:, k] = force
    history.head_height[:, k] = head_height
    history.wire_uplift[:, k] = wire_uplift
    history.support_uplift[k] = support_uplift
    transmitted = np.where(slack, 0.0, dropper_forces)
    np.minimum(history.dropper_min, transmitted, out=history.dropper_min)
    np.maximum(history.dropper_max, transmitted, out=history.dropper_max)
    history.counts[SLACK_STEPS] += bool(any_slack)
    history.counts[UNRESOLVED_STEPS] += not resolved


@compilable()
def record_in_place(history, k, dropper_forces, slack, any_slack, resolved):  # noqa: ANN001, ANN201
    """:func:`record` in scalar loops, for the compiled loops, which write the pantographs' histories and the
    support uplifts themselves."""
    for q in range(slack.size):
        transmitted = 0.0 if slack[q] else dropper_forces[q]
        history.dropper_min[q] = min(history.dropper_min[q], transmitted)
        history.dropper_max[q] = max(history.dropper_max[q], transmitted)
    history.counts[SLACK_STEPS] += 1 if any_slack else 0
    history.counts[UNRESOLVED_STEPS] += 0 if resolved else 1


def trajectory(
    history: PassageHistory, time: np.ndarray, positions: tuple[np.ndarray, ...], support_x: np.ndarray
) -> Trajectory:
    """The passage's :class:`Trajectory` at ``time`` (s) and the pantographs' ``positions`` (m, the first
    pantograph first); supports at ``support_x`` (m)."""
    traces = tuple(
        PantographTrace(position, history.force[i], history.head_height[i], history.wire_uplift[i])
        for i, position in enumerate(positions)
    )
    return Trajectory(
        time=time,
        position=positions[0],
        contact_force=history.force[0],
        head_height=history.head_height[0],
        wire_uplift=history.wire_uplift[0],
        support_x=support_x.copy(),
        support_uplift=history.support_uplift,
        dropper_force_min=history.dropper_min,
        dropper_force_max=history.dropper_max,
        slack_steps=int(history.counts[SLACK_STEPS]),
        unresolved_steps=int(history.counts[UNRESOLVED_STEPS]),
        pantographs=traces,
    )
