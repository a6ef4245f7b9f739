"""A cheap design env with the catenary envs' contract, for trying the RL learners (needs gymnasium).

``SyntheticSpeedQuadratic-v0`` poses :data:`optimizers.synthetic.SYNTHETIC_PROBLEMS`'s
``synthetic-speed-quadratic`` as a one-step design env: its optimum moves with the speed, as a catenary's
does (0.1 mm per km/h in the first two variables), and σ is the problem's ``simulate``'s. It costs
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

__all__ = ["ENV_ID", "PENALTY", "PROBLEM", "SpeedQuadraticEnv"]

ENV_ID = "optimizers.synthetic_env:SyntheticSpeedQuadratic-v0"
PROBLEM = get_synthetic_problem("synthetic-speed-quadratic")
SPACE = GridSpace.from_problem(PROBLEM)
PENALTY = 100.0
"""Reward of an infeasible design, −N (σ of a feasible design is below 70 N within the bounds)."""


class SpeedQuadraticEnv(gymnasium.Env[NDArray[np.float32], NDArray[np.float32]]):
    """One step per episode: the action is the design; reward −σ (N), or −:data:`PENALTY` if infeasible.

    Observation: the speed / 500 km/h. Arguments as the catenary envs' (``speed_kmh``, ``speed_range``
    drawn on whole km/h at each reset outside the ``excluded_speeds`` bands, ``fidelity`` accepted and
    ignored).
    """

    def __init__(
        self,
        speed_kmh: float | None = None,
        speed_range: tuple[float, float] | None = None,
        fidelity: str = "test",
        excluded_speeds: tuple[tuple[float, float], ...] = (),
    ) -> None:
        self.speed_kmh = 300.0 if speed_kmh is None else float(speed_kmh)
        self.speeds = None
        if speed_range is not None:
            whole = np.arange(int(np.ceil(speed_range[0])), int(np.floor(speed_range[1])) + 1, dtype=float)
            self.speeds = [v for v in whole if not any(a <= v <= b for a, b in excluded_speeds)]
        self.action_space = gymnasium.spaces.Box(-1.0, 1.0, (PROBLEM.n_variables,), np.float32)
        self.observation_space = gymnasium.spaces.Box(0.0, 1.0, (1,), np.float32)
        self.evaluation_count = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        if options and "speed_kmh" in options:
            self.speed_kmh = float(options["speed_kmh"])
        elif self.speeds is not None:
            self.speed_kmh = float(self.speeds[self.np_random.integers(len(self.speeds))])
        return self._observation(), {"speed_kmh": self.speed_kmh}

    def step(self, action: Any) -> Any:
        x = SPACE.from_action(np.clip(action, -1.0, 1.0))
        outcome = PROBLEM.simulate(tuple(x.tolist()), self.speed_kmh, "test")
        self.evaluation_count += 1
        sigma = outcome.sigma if outcome.feasible else PENALTY
        info = {
            "feasible": outcome.feasible,
            "reason": outcome.reason,
            "speed_kmh": self.speed_kmh,
            "objective": sigma,
            "wall_time": outcome.wall_time,
        }
        return self._observation(), -float(sigma), True, False, info

    def _observation(self) -> NDArray[np.float32]:
        return np.array([self.speed_kmh / 500.0], dtype=np.float32)


if ENV_ID.split(":")[1] not in gymnasium.registry:
    gymnasium.register(id=ENV_ID.split(":")[1], entry_point=SpeedQuadraticEnv)
