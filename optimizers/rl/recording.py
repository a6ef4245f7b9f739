"""The vector env of an RL run: it logs every step into the run's history and store, in the order of the
envs, and serves from the store the steps it holds (a resumed run's, another RL run's on the same env)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..base import EvaluationRecord
from ..problem import GridSpace
from ..recorder import RunRecorder


class _Workers:
    """The envs behind a stable-baselines3 vector env, stepped one by one: each either simulates its
    action or only starts its next episode (a step served from the store), and then starts its next
    episode, as SB3's vector envs do after a terminated episode. The envs of a ``SubprocVecEnv`` work at
    once, each in its process."""

    def __init__(self, venv: Any) -> None:
        self.venv = venv
        self.remotes = getattr(venv, "remotes", None)  # SubprocVecEnv: one pipe per worker process

    def run(self, actions: list[NDArray[np.float32] | None]) -> list[tuple[Any, float, dict[str, Any], Any]]:
        """(observation of the next episode, reward, step info, reset info) per env; an env given None is
        only reset (reward 0, info empty)."""
        if self.remotes is None:
            return [self._local(env, action) for env, action in zip(self.venv.envs, actions, strict=True)]
        for remote, action in zip(self.remotes, actions, strict=True):
            remote.send(("env_method", ("reset", [], {})) if action is None else ("step", action))
        out = []
        for remote, action in zip(self.remotes, actions, strict=True):
            answer = remote.recv()
            if action is None:
                out.append((answer[0], 0.0, {}, answer[1]))
            else:
                observation, reward, _, info, reset_info = answer
                out.append((observation, float(reward), info, reset_info))
        return out

    @staticmethod
    def _local(env: Any, action: NDArray[np.float32] | None) -> tuple[Any, float, dict[str, Any], Any]:
        reward, info = 0.0, {}
        if action is not None:
            _, reward, _, _, info = env.step(action)
        observation, reset_info = env.reset()
        return observation, float(reward), info, reset_info


def recording_vec_env_class() -> type:
    """The recording vector env class, built on first use so that stable-baselines3 is imported only here."""
    from stable_baselines3.common.vec_env import VecEnvWrapper

    class RecordingVecEnv(VecEnvWrapper):
        """Log every env step into the run (history, store), in order of the envs; serve from the store the
        steps a resumed run has stored and those an RL run on the same env (``env_key``: its EnvSpec as
        JSON) made, at the same speed (and tension): their envs are not stepped, only reset, so that the
        speeds drawn stay those of an uninterrupted run. ``problem_key(tension)``: the store key of the
        problem at a contact-wire tension (N), for an env that draws the tension (None: the run's)."""

        def __init__(
            self,
            venv: Any,
            recorder: RunRecorder,
            space: GridSpace,
            env_key: str,
            problem_key: Callable[[float], str] | None = None,
        ) -> None:
            super().__init__(venv)
            self.recorder, self.space, self.env_key = recorder, space, env_key
            self.problem_key = problem_key
            self.workers = _Workers(venv)
            self._actions: NDArray[np.float32] | None = None
            self._observations: list[Any] = []
            self._speeds: list[float | None] = []
            self._problems: list[str] = []

        def reset(self) -> Any:
            observations = self.venv.reset()
            self._observations = list(observations)
            self._speeds = [self._speed(info) for info in self.venv.reset_infos]
            self._problems = [self._problem(info) for info in self.venv.reset_infos]
            return observations

        def step_async(self, actions: NDArray[np.float32]) -> None:
            self._actions = np.asarray(actions)

        def step_wait(self) -> Any:
            assert self._actions is not None
            base = self.recorder.next_index
            xs = [self.space.from_action(a) for a in self._actions]
            keys = [self.space.design_key(x) for x in xs]
            served = [
                self._served(base + i, x, key, i) for i, (x, key) in enumerate(zip(xs, keys, strict=True))
            ]
            answers = self.workers.run(
                [a if s is None else None for a, s in zip(self._actions, served, strict=True)]
            )
            rewards, infos = np.zeros(self.num_envs, dtype=np.float32), []
            for i, (x, key, stored, answer) in enumerate(zip(xs, keys, served, answers, strict=True)):
                observation, reward, info, reset_info = answer
                if stored is None:
                    record = _record(base + i, x, reward, info, 0.0, self._speeds[i])
                    self.recorder.persist(record, key, reward=reward, problem=self._problems[i])
                else:
                    record, reward, persist = stored
                    info = {"feasible": record.feasible, "reason": record.reason, "served": True}
                    if persist:
                        self.recorder.persist(record, key, reward=reward, problem=self._problems[i])
                self.recorder.append(record)
                rewards[i] = reward
                info.update({"terminal_observation": self._observations[i], "TimeLimit.truncated": False})
                infos.append(info)
                self._observations[i], self._speeds[i] = observation, self._speed(reset_info)
                self._problems[i] = self._problem(reset_info)
            return np.stack(self._observations), rewards, np.ones(self.num_envs, dtype=bool), infos

        def _speed(self, reset_info: dict[str, Any]) -> float | None:
            return _scalar(reset_info.get("speed_kmh"), self.recorder.config.speed_kmh)

        def _problem(self, reset_info: dict[str, Any]) -> str:
            if self.problem_key is None:
                return self.recorder.config.problem
            return self.problem_key(float(reset_info["contact_wire_tension"]))

        def _served(
            self, index: int, x: NDArray[np.float64], key: tuple[int, ...], env: int
        ) -> tuple[EvaluationRecord, float, bool] | None:
            """(record, reward, to persist) of a step the store holds: this run's (replayed) or another RL
            run's on the same env (charged, not simulated); None: simulate it."""
            stored = self.recorder.stored(index, key)
            if stored is not None:
                reward = float(stored.reward if stored.reward is not None else -stored.record.loss)
                return stored.record, reward, False
            speed, config = self._speeds[env], self.recorder.config
            hit = None  # an env that reports no speed breaks its contract: _record says so
            if speed is not None:
                hit = self.recorder.store.lookup_env(
                    self._problems[env], key, speed, config.fidelity, self.env_key
                )
            if hit is None:
                return None
            outcome, reward = hit
            record = EvaluationRecord(
                index, tuple(float(v) for v in x), outcome.feasible, outcome.sigma, outcome.reason, 0.0,
                True, True, speed,
            )  # fmt: skip
            return record, float(reward), True

    return RecordingVecEnv


def _scalar(value: Any, default: float | None) -> float | None:
    if value is None or np.ndim(value) != 0:
        return default
    return float(value)


def _record(
    index: int,
    x: NDArray[np.float64],
    reward: float,
    info: dict[str, Any],
    elapsed: float,
    speed: float | None,
) -> EvaluationRecord:
    feasible = bool(info.get("feasible", True))
    sigma = _scalar(info.get("objective"), -reward) if feasible else None
    speed_kmh = _scalar(info.get("speed_kmh"), speed)
    if speed_kmh is None:
        raise ValueError("the env reports no speed: with a speed range, its info must carry 'speed_kmh'")
    return EvaluationRecord(
        index=index,
        x=tuple(float(v) for v in x),
        feasible=feasible,
        sigma=sigma,
        reason=str(info.get("reason", "")),
        wall_time=float(_scalar(info.get("wall_time"), elapsed) or 0.0),
        cached=False,
        charged=True,
        speed_kmh=speed_kmh,
    )
