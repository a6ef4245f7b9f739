"""What a passage records at every step, for every backend (docs/model.md, 'Statistics and feasibility').

The numpy loops record through :meth:`PassageHistory.record`; the compiled loops write the same arrays
in their state, which :meth:`PassageHistory.from_arrays` takes over. Either way the passage ends in one
:class:`~catenary_env.dynamics.newmark.Trajectory`.
"""

from __future__ import annotations

import numpy as np

from .newmark import Trajectory


class PassageHistory:
    """The time histories and extremes of a passage of ``n_steps`` steps (see :class:`Trajectory`).

    Parameters
    ----------
    n_steps : int
    n_supports : int
    static_dropper_force : ndarray (D,)
        N; the droppers' extremes start from it.
    force0, head_height0 : float
        The contact force (N) and head height (m) at the start.
    """

    def __init__(
        self,
        n_steps: int,
        n_supports: int,
        static_dropper_force: np.ndarray,
        force0: float,
        head_height0: float,
    ) -> None:
        self.force = np.zeros(n_steps)
        self.head_height = np.zeros(n_steps)
        self.wire_uplift = np.zeros(n_steps)
        self.support_uplift = np.zeros((n_steps, n_supports))
        self.dropper_min = np.array(static_dropper_force, dtype=float)
        self.dropper_max = np.array(static_dropper_force, dtype=float)
        self.slack_steps = 0
        self.unresolved_steps = 0
        self.force[0] = force0
        self.head_height[0] = head_height0

    @classmethod
    def from_arrays(cls, arrays: object, slack_steps: int, unresolved_steps: int) -> PassageHistory:
        """The history a compiled loop wrote into its state ``arrays`` (same field names)."""
        history = cls.__new__(cls)
        for name in ("force", "head_height", "wire_uplift", "support_uplift"):
            setattr(history, name, getattr(arrays, name))
        history.dropper_min = arrays.dropper_min
        history.dropper_max = arrays.dropper_max
        history.slack_steps = int(slack_steps)
        history.unresolved_steps = int(unresolved_steps)
        return history

    def record(
        self,
        k: int,
        force: float,
        head_height: float,
        wire_uplift: float,
        support_uplift: np.ndarray,
        dropper_forces: np.ndarray,
        slack: np.ndarray,
        any_slack: bool,
        resolved: bool,
    ) -> None:
        """Step ``k``'s contact force (N), head height and wire uplift (m), support uplifts (m), the
        droppers' forces (N; a slack dropper's counts as zero), whether the step solved for a slack
        dropper, and whether its active set settled."""
        self.force[k] = force
        self.head_height[k] = head_height
        self.wire_uplift[k] = wire_uplift
        self.support_uplift[k] = support_uplift
        transmitted = np.where(slack, 0.0, dropper_forces)
        np.minimum(self.dropper_min, transmitted, out=self.dropper_min)
        np.maximum(self.dropper_max, transmitted, out=self.dropper_max)
        self.slack_steps += bool(any_slack)
        self.unresolved_steps += not resolved

    def trajectory(self, time: np.ndarray, position: np.ndarray, support_x: np.ndarray) -> Trajectory:
        return Trajectory(
            time=time,
            position=position,
            contact_force=self.force,
            head_height=self.head_height,
            wire_uplift=self.wire_uplift,
            support_x=support_x.copy(),
            support_uplift=self.support_uplift,
            dropper_force_min=self.dropper_min,
            dropper_force_max=self.dropper_max,
            slack_steps=self.slack_steps,
            unresolved_steps=self.unresolved_steps,
        )
