"""A cheap design env with the catenary envs' contract, for trying the RL learners (needs gymnasium).

``SyntheticSpeedQuadratic-v0`` poses :data:`optimizers.synthetic.SYNTHETIC_PROBLEMS`'s
``synthetic-quadratic`` as a one-step design env whose optimum moves with the speed, as a catenary's does:
the minimiser of σ shifts by ``SHIFT_PER_KMH`` m per km/h in its first two variables. It costs
microseconds a step, so tests train policies on it, in worker processes too: ``gymnasium.make`` of
:data:`ENV_ID` (``"optimizers.synthetic_env:SyntheticSpeedQuadratic-v0"``) imports this module, which
registers the env, in any process.

Examples
--------
>>> import gymnasium
>>> env = gymnasium.make(ENV_ID, speed_range=(200.0, 320.0))
>>> observation, info = env.reset(seed=0, options={"speed_kmh": 250.0})
>>> float(info["speed_kmh"])
250.0
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from numpy.typing import NDArray

from .problem import GridSpace
from .synthetic import get_synthetic_problem

__all__ = ["ENV_ID", "PENALTY", "SHIFT_PER_KMH", "SpeedQuadraticEnv", "optimum_centre"]

ENV_ID = "optimizers.synthetic_env:SyntheticSpeedQuadratic-v0"
PROBLEM = get_synthetic_problem("synthetic-quadratic")
SPACE = GridSpace.from_problem(PROBLEM)
PENALTY = 100.0
"""Reward of an infeasible design, −N (σ of a feasible design is below 70 N within the bounds)."""
SHIFT_PER_KMH = 1e-4
"""How far the unconstrained minimiser moves per km/h from 260 km/h, m (6 mm at 200 and 320 km/h)."""


def optimum_centre(speed_kmh: float) -> NDArray[np.float64]:
    """The unconstrained minimiser of σ at a speed, m."""
    return PROBLEM.centre + SHIFT_PER_KMH * (speed_kmh - 260.0) * np.array([1.0, -1.0, 0.0])


class SpeedQuadraticEnv(gymnasium.Env[NDArray[np.float32], NDArray[np.float32]]):
    """One step per episode: the action is the design; reward −σ (N), or −:data:`PENALTY` if infeasible.

    Observation: the speed / 500 km/h. Arguments as the catenary envs' (``speed_kmh``, ``speed_range``
    drawn on whole km/h at each reset, ``fidelity`` accepted and ignored).
    """

    def __init__(
        self,
        speed_kmh: float | None = None,
        speed_range: tuple[float, float] | None = None,
        fidelity: str = "test",
    ) -> None:
        self.speed_kmh = 300.0 if speed_kmh is None else float(speed_kmh)
        self.speed_range = speed_range
        self.action_space = gymnasium.spaces.Box(-1.0, 1.0, (PROBLEM.n_variables,), np.float32)
        self.observation_space = gymnasium.spaces.Box(0.0, 1.0, (1,), np.float32)
        self.evaluation_count = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        if options and "speed_kmh" in options:
            self.speed_kmh = float(options["speed_kmh"])
        elif self.speed_range is not None:
            lo, hi = self.speed_range
            self.speed_kmh = float(self.np_random.integers(int(lo), int(hi), endpoint=True))
        return self._observation(), {"speed_kmh": self.speed_kmh}

    def step(self, action: Any) -> Any:
        x = SPACE.from_action(np.clip(action, -1.0, 1.0))
        terms = PROBLEM.weights * ((x - optimum_centre(self.speed_kmh)) / PROBLEM.scale) ** 2
        sigma = PROBLEM.base_sigma + float(np.sum(terms))
        feasible = bool(PROBLEM.feasible(x))
        self.evaluation_count += 1
        info = {
            "feasible": feasible,
            "reason": "" if feasible else "synthetic: x_1 + x_3 > 0.012 m",
            "speed_kmh": self.speed_kmh,
            "objective": sigma if feasible else PENALTY,
            "wall_time": 0.0,
        }
        return self._observation(), -sigma if feasible else -PENALTY, True, False, info

    def _observation(self) -> NDArray[np.float32]:
        return np.array([self.speed_kmh / 500.0], dtype=np.float32)


if ENV_ID.split(":")[1] not in gymnasium.registry:
    gymnasium.register(id=ENV_ID.split(":")[1], entry_point=SpeedQuadraticEnv)
