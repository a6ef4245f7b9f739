"""RL design policies: stable-baselines3 PPO or SAC trained on a design env (``pip install
catenary-env[rl]``).

A design env (docs/problems.md, 'Environments') has one-step episodes: the observation carries the task
context (the normalised speed), the action in ``Box(-1, 1)`` is the whole design, the reward is −σ. Trained
with a speed range, the policy is speed-conditioned: ``design = policy(speed)``, something no single-speed
optimiser gives.

The env contract this module relies on, and nothing else, so it works on any Gymnasium env with it:

- ``gymnasium.make(env_id, speed_kmh=..., speed_range=..., fidelity=...)`` builds it;
- ``reset(options={"speed_kmh": v})`` sets the speed of the episode (used by :func:`design_for_speed`);
- the action maps to the design affinely onto the bounds and then onto the grid (ties up);
- ``step`` returns the reward −σ (or a penalty) and ``info["feasible"]``; ``info["reason"]``,
  ``info["objective"]`` (σ behind the reward, N), ``info["wall_time"]`` (s) and ``info["speed_kmh"]``
  are used where present (σ falls back to −reward, the speed to the run's).

Two learners (:data:`LEARNERS`): PPO, on-policy, and SAC, off-policy, which learns from every step it has
made (a replay buffer) and suits one-step episodes, where a step is costly and its reward is the whole
return. Both start where a designer starts, at the reference design with a small spread
(:data:`POLICY_SPREAD`; :class:`PPOOptions`, :class:`SACOptions`).

Every step is a simulation and is charged: ``total_timesteps`` is the budget, and training stops after
exactly ``budget`` steps. The envs are stepped ``n_envs`` at a time, in worker processes when more than
one (SB3's ``SubprocVecEnv``, each worker on one BLAS and one torch thread). A vector env wrapper, in this
process, logs each step into the run's history and its store in the order of the envs, so an interrupted
training run resumes like the other optimisers: the stored steps are replayed (the env is reset but not
stepped, the stored reward is returned) and the learner, seeded, takes the same actions again.
The env owns its simulations and reward convention, so RL runs neither use nor feed the other optimisers'
design cache; among themselves they share it: a step another RL run made on the same env (the same
:class:`EnvSpec`), the same design at the same speed, is served from the store (charged, not simulated).

A trained policy is saved by :func:`save_policy` as one file: stable-baselines3's zip archive with, inside
it, ``catenary_env_policy.json`` (the problem, its model fingerprint, the env with its speed or speed
range, the observation scaling, the run); :func:`load_policy` reads it back and ``catenary propose POLICY
--speed KMH`` proposes (and simulates) the policy's design at a speed. Loading a policy unpickles parts of
the archive, as stable-baselines3 does: load only files you trust.

Examples
--------
>>> spec = EnvSpec("Catenary-B1-v0", speed_kmh=None, speed_range=(200.0, 320.0), fidelity="study")
>>> policy, result = train_design_policy(spec, catenary_problem("B1"), budget=2000, seed=0)  # doctest: +SKIP
>>> design_for_speed(policy, catenary_problem("B1"), 280.0)  # doctest: +SKIP
array([...])
>>> save_policy(policy, "b1-policy.zip", catenary_problem("B1"), result)  # doctest: +SKIP
>>> policy, record = load_policy("b1-policy.zip")  # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import math
import os
import tempfile
import zipfile
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from catenary_env.cli.progress import ProgressDisplay
from catenary_env.errors import CatenaryError, MissingDependency

from .base import EvaluationRecord, OptimizationResult
from .problem import GridProblem, GridSpace
from .recorder import RunRecorder, open_run, package_version
from .store import RunConfig, RunStore

__all__ = [
    "BOX_WIDE_SPREAD",
    "POLICY_SPREAD",
    "DesignPolicy",
    "EnvSpec",
    "ObservationScaling",
    "LEARNERS",
    "PPOOptions",
    "PolicyRecord",
    "SACOptions",
    "design_for_speed",
    "import_stable_baselines3",
    "load_policy",
    "policy_run_config",
    "save_policy",
    "train_design_policy",
]


def import_stable_baselines3() -> Any:
    """The stable_baselines3 module, or a :class:`~catenary_env.errors.MissingDependency` (an ImportError)
    that says how to install it."""
    try:
        import stable_baselines3
    except ImportError as error:
        raise MissingDependency(
            "the RL design policies need stable-baselines3: pip install catenary-env[rl]"
        ) from error
    return stable_baselines3


@dataclass(frozen=True)
class EnvSpec:
    """How to make the design env (picklable; recorded with the run).

    Attributes
    ----------
    env_id : str
        Registered Gymnasium id, e.g. ``"Catenary-B1-v0"``.
    speed_kmh : float or None
        Train speed, km/h; None with ``speed_range``.
    speed_range : (float, float) or None
        Lowest and highest speed, km/h, drawn at each reset: a speed-conditioned policy.
    fidelity : str
        ``"study"`` or ``"test"``.
    excluded_speeds : tuple of (float, float)
        With ``speed_range``: bands of speeds, km/h, never drawn in training (held out, to evaluate the
        policy where it has not been trained; the env's ``excluded_speeds``).
    contact_wire_tension_range : (float, float) or None
        Lowest and highest contact-wire tension, N, drawn at each reset: a policy conditioned on the
        tension as well (the env's ``contact_wire_tension_range``); None: the preset's tension.
    excluded_tensions : tuple of (float, float)
        With ``contact_wire_tension_range``: bands of tensions, N, never drawn in training.
    """

    env_id: str
    speed_kmh: float | None = 300.0
    speed_range: tuple[float, float] | None = None
    fidelity: str = "study"
    excluded_speeds: tuple[tuple[float, float], ...] = ()
    contact_wire_tension_range: tuple[float, float] | None = None
    excluded_tensions: tuple[tuple[float, float], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """The spec as JSON values, part of a run's identity and of its steps' key in the store; without
        the held-out bands and the tension range where there are none, as before they existed, so that a
        store's earlier runs and steps still match."""
        data = dataclasses.asdict(self)
        for name in ("excluded_speeds", "contact_wire_tension_range", "excluded_tensions"):
            if not data[name]:
                del data[name]
        return data

    def make(self) -> Any:
        """Build the env with ``gymnasium.make``."""
        import gymnasium

        kwargs: dict[str, Any] = {"fidelity": self.fidelity}
        if self.speed_range is not None:
            kwargs["speed_range"] = tuple(self.speed_range)
            if self.excluded_speeds:
                kwargs["excluded_speeds"] = tuple(map(tuple, self.excluded_speeds))
        else:
            kwargs["speed_kmh"] = self.speed_kmh
        if self.contact_wire_tension_range is not None:
            kwargs["contact_wire_tension_range"] = tuple(self.contact_wire_tension_range)
            if self.excluded_tensions:
                kwargs["excluded_tensions"] = tuple(map(tuple, self.excluded_tensions))
        return gymnasium.make(self.env_id, **kwargs)

    @property
    def conditions(self) -> str:
        """The speeds (and tensions) trained on, in words."""
        if self.speed_range is None:
            text = f"{self.speed_kmh:g} km/h"
        else:
            text = f"{self.speed_range[0]:g}-{self.speed_range[1]:g} km/h{_except(self.excluded_speeds, 1.0)}"
        if self.contact_wire_tension_range is not None:
            lo, hi = self.contact_wire_tension_range
            held_out = _except(self.excluded_tensions, 1000.0)
            text += f", contact wire at {lo / 1000:g}-{hi / 1000:g} kN{held_out}"
        return text


def _except(bands: Any, unit: float) -> str:
    """ " except a-b and c-d" of held-out bands, in ``unit`` (empty without bands)."""
    if not bands:
        return ""
    return " except " + " and ".join(f"{a / unit:g}-{b / unit:g}" for a, b in bands)


POLICY_SPREAD = 0.2
"""Standard deviation of the untrained policy's actions by default, action units (the range being 2): 0.2 is
4 mm of height on B1 and SW1, where most proposals around the reference design are feasible."""

BOX_WIDE_SPREAD = 1.0
"""stable-baselines3's own initial spread, action units: proposals over the whole box (±20 mm of height on
B1), mostly infeasible (slack droppers, contact loss). ``PPOOptions(log_std_init=math.log(BOX_WIDE_SPREAD))``
keeps it."""


@dataclass(frozen=True)
class PPOOptions:
    """PPO hyper-parameters (stable-baselines3 names).

    Where the policy starts: stable-baselines3 initialises the layer that gives the Gaussian policy's mean
    with an orthogonal matrix of gain 0.01 and a zero bias, so the untrained policy proposes action 0, the
    centre of the bounds, give or take a fraction of a millimetre. On B1 and SW1 (every Δh in [-20, +20] mm)
    that is the reference design, the level wire. Its spread is ``exp(log_std_init)``: by default
    :data:`POLICY_SPREAD`, the start of the RL study (docs/problems.md, 'Experiments'), at which
    most first proposals are feasible; :data:`BOX_WIDE_SPREAD` keeps stable-baselines3's box-wide start.

    Attributes
    ----------
    learning_rate : float
        Adam step size.
    n_steps : int
        Env steps (designs) per rollout, between policy updates.
    batch_size : int
        Minibatch size of an update.
    n_epochs : int
        Passes over a rollout per update.
    ent_coef : float
        Entropy bonus.
    net_arch : tuple of int
        Hidden layer widths of the policy and value networks.
    log_std_init : float
        Initial log standard deviation of the Gaussian actions (in action units, the range being 2);
        default ln :data:`POLICY_SPREAD`.
    normalize_observation : bool
        Standardise observations with running statistics (SB3's ``VecNormalize``). The speed enters the
        observation as a fraction of the wave speed, a narrow band (0.43 to 0.70 for 200 to 320 km/h on
        the benchmark catenary): standardised, it spans a few units, which a policy conditions on far
        more easily. The statistics are kept with the policy for :func:`design_for_speed`.
    normalize_reward : bool
        Scale rewards by their running standard deviation (SB3's ``VecNormalize``); the history and
        the store keep the env's own rewards.
    n_envs : int
        Envs stepped at once (:func:`train_design_policy`): a rollout is ``n_steps * n_envs`` steps.
    device : str
        Torch device; ``"cpu"`` suits these small networks.
    """

    learning_rate: float = 3e-4
    n_steps: int = 64
    batch_size: int = 64
    n_epochs: int = 10
    ent_coef: float = 0.0
    net_arch: tuple[int, ...] = (64, 64)
    log_std_init: float = math.log(POLICY_SPREAD)
    normalize_observation: bool = True
    normalize_reward: bool = True
    n_envs: int = 1
    device: str = "cpu"


@dataclass(frozen=True)
class SACOptions:
    """SAC hyper-parameters (stable-baselines3 names), chosen once for one-step design episodes.

    Where the policy starts: as PPO's (:class:`PPOOptions`), at the reference design with a spread of
    :data:`POLICY_SPREAD`. The first ``learning_starts`` steps are a warm-up whose actions are drawn
    around action 0 with the standard deviation ``start_spread`` (stable-baselines3 would draw them
    uniformly over the box: mostly infeasible designs); the actor's mean layer starts at zero and its
    log-std layer at ln ``start_spread``, so its first proposals after the warm-up have the same spread
    about the reference design (through SAC's tanh, which is nearly linear there).

    An episode is one step, so ``gamma = 0``: the critic learns the expected reward of a design at a speed,
    Q(s, a) = E[-σ], and the actor the design that maximises it (with an entropy bonus, tuned to a
    target entropy, that keeps exploring). One gradient step per env step.

    Tuning, once, on one seed of the synthetic problem whose optimum moves with the speed
    (``optimizers/synthetic_env.py``; no catenary simulation spent): five settings of 2000 steps each,
    judged by the mean σ of the last 256 steps and the gap of the policy's designs to the grid optimum at
    210, 230 (held out), 260, 290 (held out) and 320 km/h. stable-baselines3's entropy coefficient
    starting at 1 (``"auto"``) widened the spread far beyond the start (24.5 N, gaps 7-13 %);
    ``"auto_0.01"`` (starting at 0.01, then tuned) gave 20.6 N and gaps of 1.5-2.7 %, PPO's defaults 22.2 N
    and 2-6 %; a fixed 0.001, a learning rate of 3e-4 and batches of 64 did no better (gaps up to 7.5 %,
    11 % and 3.1 %).

    Attributes
    ----------
    learning_rate : float
        Adam step size of the actor, the critics and the entropy coefficient.
    buffer_size : int
        Replay buffer, env steps (larger than any study's budget: nothing is forgotten).
    learning_starts : int
        Warm-up steps around the reference design before the first update.
    batch_size : int
        Replayed steps per update.
    tau : float
        Soft update of the target critics.
    ent_coef : str or float
        Entropy coefficient; ``"auto_0.01"`` starts it at 0.01 and tunes it to SB3's target entropy
        (``-n_variables``).
    net_arch : tuple of int
        Hidden layer widths of the actor and the critics.
    start_spread : float
        Standard deviation of the first proposals, action units (the range being 2).
    normalize_observation, normalize_reward : bool
        As :class:`PPOOptions` (the replay buffer keeps the env's rewards; SB3 scales them when sampled).
    n_envs : int
        Envs stepped at once.
    device : str
        Torch device.
    """

    learning_rate: float = 1e-3
    buffer_size: int = 100_000
    learning_starts: int = 256
    batch_size: int = 256
    tau: float = 0.005
    ent_coef: str | float = "auto_0.01"
    net_arch: tuple[int, ...] = (64, 64)
    start_spread: float = POLICY_SPREAD
    normalize_observation: bool = True
    normalize_reward: bool = True
    n_envs: int = 1
    device: str = "cpu"


LearnerOptions = PPOOptions | SACOptions
LEARNERS = {"ppo": PPOOptions, "sac": SACOptions}
"""The RL learners by name (``catenary optimize --optimizer NAME``) and their hyper-parameters."""


def learner_name(options: LearnerOptions) -> str:
    """The registry name of the learner of ``options``."""
    return next(name for name, kind in LEARNERS.items() if isinstance(options, kind))


class ObservationScaling(NamedTuple):
    """SB3 ``VecNormalize``'s observation standardisation, frozen at the end of training.

    Attributes
    ----------
    mean, var : ndarray
        Running mean and variance of the observations.
    epsilon : float
        Added to the variance.
    clip : float
        Standardised observations are clipped to ``[-clip, clip]``.
    """

    mean: NDArray[np.float64]
    var: NDArray[np.float64]
    epsilon: float
    clip: float

    def apply(self, observation: NDArray[np.float32]) -> NDArray[np.float32]:
        """The observation as the policy saw it in training."""
        scaled = (np.asarray(observation) - self.mean) / np.sqrt(self.var + self.epsilon)
        return np.clip(scaled, -self.clip, self.clip).astype(np.float32)


@dataclass(frozen=True)
class DesignPolicy:
    """A trained design policy: the learner's model and the env it was trained on.

    Attributes
    ----------
    model : stable_baselines3.PPO or stable_baselines3.SAC
        The trained model.
    env_spec : EnvSpec
        The env (its observations are what the policy reads).
    observation_scaling : ObservationScaling or None
        How observations were standardised in training (None: not at all).
    """

    model: Any
    env_spec: EnvSpec
    observation_scaling: ObservationScaling | None = None


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


def _recording_vec_env_class() -> type:
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


def train_design_policy(
    env_spec: EnvSpec,
    problem: GridProblem,
    budget: int,
    seed: int = 0,
    *,
    options: LearnerOptions | None = None,
    store: RunStore | str | os.PathLike[str] | None = None,
    resume: bool = False,
    start_if_none: bool = True,
    quiet: bool = True,
    archive: str | os.PathLike[str] | None = None,
) -> tuple[DesignPolicy, OptimizationResult]:
    """Train a design policy (PPO or SAC, as ``options`` say) for exactly ``budget`` env steps (simulations).

    Parameters
    ----------
    env_spec : EnvSpec
        The env to train on (with a speed range: a speed-conditioned policy).
    problem : GridProblem
        The problem of the env: its bounds and grid map actions to designs, its name goes in the store.
    budget : int
        Env steps = simulations = the learner's ``total_timesteps``; a multiple of ``options.n_envs``.
    seed : int
        Seeds the learner (torch, numpy) and the envs (env i: ``seed + i``).
    options : PPOOptions or SACOptions, optional
        The learner and its hyper-parameters; default ``PPOOptions()``.
    store : RunStore or path, optional
        Run store; default in memory.
    resume : bool
        Continue the latest stored run of the same configuration (replaying its steps).
    start_if_none : bool
        With ``resume``, start a new run when the store holds none of this configuration (else
        :class:`~optimizers.store.StoreError` lists the runs it holds).
    quiet : bool
        No progress display.
    archive : path, optional
        A run archive (:mod:`optimizers.archive`): the run goes into it when it finishes, and a snapshot of
        it while it trains (:class:`~optimizers.recorder.RunRecorder`).

    Returns
    -------
    (DesignPolicy, OptimizationResult)
        The policy, and the run's record (``best_x``: the best design met in training, at its speed).
    """
    sb3 = import_stable_baselines3()
    settings = PPOOptions() if options is None else options
    name = learner_name(settings)
    if settings.n_envs < 1:
        raise ValueError(f"n_envs = {settings.n_envs}: must be at least 1 env")
    if budget < 1 or budget % settings.n_envs:
        raise ValueError(
            f"budget = {budget}: must be at least 1 simulation and a multiple of the {settings.n_envs} envs "
            "stepped at once"
        )
    space = GridSpace.from_problem(problem)
    config = policy_run_config(env_spec, space, budget, seed, settings)
    with ExitStack() as stack:
        run_store = (
            store if isinstance(store, RunStore) else stack.enter_context(RunStore(store or ":memory:"))
        )
        run_id, resumed = stack.enter_context(open_run(run_store, config, resume, start_if_none))
        progress = ProgressDisplay(f"{name} on {space.name}", int(budget), "simulations", quiet=quiet)
        recorder = RunRecorder(run_store, run_id, config, space, "env", progress, resumed, archive)
        vec_env = _vector_env(env_spec, recorder, space, settings, _problem_keys(env_spec, problem))
        stack.callback(vec_env.close)
        # One torch thread: these small networks gain nothing from more, and a fixed thread count keeps
        # torch's sums in one order whatever the core count, so that a resumed run replays its steps.
        import torch

        stack.callback(torch.set_num_threads, torch.get_num_threads())
        torch.set_num_threads(1)
        if isinstance(settings, SACOptions):
            model = _sac(sb3, vec_env, settings, seed)
            model.learn(total_timesteps=int(budget))
        else:
            model = sb3.PPO(
                "MlpPolicy", vec_env, learning_rate=settings.learning_rate, n_steps=settings.n_steps,
                batch_size=settings.batch_size, n_epochs=settings.n_epochs, ent_coef=settings.ent_coef,
                policy_kwargs={"net_arch": list(settings.net_arch), "log_std_init": settings.log_std_init},
                seed=int(seed), device=settings.device, verbose=0,
            )  # fmt: skip
            model.learn(total_timesteps=int(budget), callback=_budget_callback(recorder, int(budget)))
        result = recorder.result("budget")
        scaling = _observation_scaling(vec_env) if settings.normalize_observation else None
    return DesignPolicy(model, env_spec, scaling), result


def policy_run_config(
    env_spec: EnvSpec, space: GridSpace, budget: int, seed: int, options: LearnerOptions
) -> RunConfig:
    """The identity in the store of the run :func:`train_design_policy` makes with these arguments, so that
    a reader finds the run without training."""
    learner_options = dataclasses.asdict(options)
    if options.n_envs == 1:  # a run on one env keeps the identity it had before vector envs
        del learner_options["n_envs"]
    run_options = {"env": env_spec.as_dict(), learner_name(options): learner_options}
    speed = None if env_spec.speed_range is not None else env_spec.speed_kmh
    return RunConfig(
        learner_name(options), space.store_key, int(budget), int(seed), speed, env_spec.fidelity,
        json.dumps(run_options, sort_keys=True), package_version(),
    )  # fmt: skip


def _sac(sb3: Any, vec_env: Any, settings: SACOptions, seed: int) -> Any:
    """A SAC model that starts at action 0 with the spread ``settings.start_spread`` (:class:`SACOptions`)."""
    import torch

    spread = float(settings.start_spread)

    class CentredSAC(sb3.SAC):  # type: ignore[misc,name-defined]
        """SAC whose warm-up actions are drawn around action 0 (the reference design), not over the box."""

        def _sample_action(self, learning_starts: int, action_noise: Any = None, n_envs: int = 1) -> Any:
            if self.num_timesteps >= learning_starts:
                return super()._sample_action(learning_starts, action_noise, n_envs)
            shape = (n_envs, *self.action_space.shape)
            action = np.clip(self.action_space.np_random.normal(0.0, spread, shape), -1.0, 1.0)
            return action.astype(np.float32), action.astype(np.float32)

    model = CentredSAC(
        "MlpPolicy", vec_env, learning_rate=settings.learning_rate, buffer_size=settings.buffer_size,
        learning_starts=settings.learning_starts, batch_size=settings.batch_size, tau=settings.tau,
        gamma=0.0, train_freq=1, gradient_steps=-1, ent_coef=settings.ent_coef,
        policy_kwargs={"net_arch": list(settings.net_arch)}, seed=int(seed), device=settings.device,
        verbose=0,
    )  # fmt: skip
    with torch.no_grad():
        for layer in (model.actor.mu, model.actor.log_std):
            layer.weight.zero_()
        model.actor.mu.bias.zero_()
        model.actor.log_std.bias.fill_(math.log(spread))
    return model


def _worker_env(env_spec: EnvSpec) -> Any:
    """The env of one worker process of a vector env: one BLAS thread and one torch thread, so that the
    workers share the cores without oversubscribing them (docs/performance.md, 'Threads')."""
    import torch

    from catenary_env.blas_threads import limit_process

    limit_process()
    torch.set_num_threads(1)
    return env_spec.make()


def _problem_keys(env_spec: EnvSpec, problem: GridProblem) -> Callable[[float], str] | None:
    """The store key of the problem at a contact-wire tension (N), for an env that draws the tension (its
    own model, so that its steps key as a run on that tension would); None for one that does not."""
    if env_spec.contact_wire_tension_range is None:
        return None
    variant = getattr(problem, "with_contact_wire_tension", None)
    if variant is None:
        raise ValueError(
            f"contact_wire_tension_range: the problem {problem.name!r} has no contact-wire tension to set"
        )

    @functools.lru_cache(maxsize=None)
    def key(tension: float) -> str:
        return GridSpace.from_problem(variant(tension)).store_key

    return key


def _vector_env(
    env_spec: EnvSpec,
    recorder: RunRecorder,
    space: GridSpace,
    settings: LearnerOptions,
    problem_key: Callable[[float], str] | None = None,
) -> Any:
    """The recorded envs in SB3's vector interface (one in this process, or ``n_envs`` worker processes),
    standardised as the options ask."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize

    env_key = json.dumps(env_spec.as_dict(), sort_keys=True)
    if settings.n_envs == 1:
        inner = DummyVecEnv([env_spec.make])
    else:
        inner = SubprocVecEnv([functools.partial(_worker_env, env_spec)] * settings.n_envs)
    vec_env = _recording_vec_env_class()(inner, recorder, space, env_key, problem_key)
    if not (settings.normalize_observation or settings.normalize_reward):
        return vec_env
    # gamma = 0: an episode is one step, its return is its reward.
    return VecNormalize(
        vec_env, norm_obs=settings.normalize_observation, norm_reward=settings.normalize_reward, gamma=0.0
    )


def _budget_callback(recorder: RunRecorder, budget: int) -> Any:
    """An SB3 callback that stops training right after the budget-th simulation."""
    from stable_baselines3.common.callbacks import BaseCallback

    class BudgetCallback(BaseCallback):
        """Stop after the budget-th step, unless that step completes a rollout (PPO then learns from it
        and stops by itself, since ``total_timesteps`` is the budget)."""

        def _on_step(self) -> bool:
            if recorder.n_charged < budget:
                return True
            return bool(self.locals["n_steps"] + 1 >= self.locals["n_rollout_steps"])

    return BudgetCallback()


def _observation_scaling(vec_env: Any) -> ObservationScaling:
    """The observation statistics of a ``VecNormalize`` at the end of training."""
    rms = vec_env.obs_rms
    return ObservationScaling(
        np.array(rms.mean), np.array(rms.var), float(vec_env.epsilon), float(vec_env.clip_obs)
    )


def design_for_speed(
    policy: DesignPolicy, problem: GridProblem, speed_kmh: float, contact_wire_tension: float | None = None
) -> NDArray[np.float64]:
    """The design the policy gives for a speed (and a contact-wire tension): its deterministic action,
    mapped onto the grid.

    Parameters
    ----------
    policy : DesignPolicy
        A trained policy.
    problem : GridProblem
        Its problem (bounds and grid).
    speed_kmh : float
        Train speed, km/h (within the training range for a meaningful answer).
    contact_wire_tension : float, optional
        The contact wire's tension, N, for a policy trained over a tension range (required there, refused
        otherwise).

    Returns
    -------
    ndarray, shape (n_variables,)
        The design's variables, m, on the grid.
    """
    trained = policy.env_spec.conditions
    if policy.env_spec.contact_wire_tension_range is not None and contact_wire_tension is None:
        raise ValueError(f"contact_wire_tension: give the tension, N: the policy was trained on {trained}")
    if policy.env_spec.contact_wire_tension_range is None and contact_wire_tension is not None:
        raise ValueError(
            f"contact_wire_tension = {contact_wire_tension!r}: the policy knows none ({trained})"
        )
    options = {"speed_kmh": float(speed_kmh)}
    if contact_wire_tension is not None:
        options["contact_wire_tension"] = float(contact_wire_tension)
    env = policy.env_spec.make()
    try:
        observation, _ = env.reset(seed=0, options=options)
    finally:
        env.close()
    if policy.observation_scaling is not None:
        observation = policy.observation_scaling.apply(observation)
    action, _ = policy.model.predict(observation, deterministic=True)
    return GridSpace.from_problem(problem).from_action(np.asarray(action).reshape(-1))


POLICY_MEMBER = "catenary_env_policy.json"
"""The member of a saved policy's zip archive that describes it (stable-baselines3 ignores it)."""
POLICY_FORMAT = 2
"""Format of the record; format 1 (PPO only: no ``learner``, no ``excluded_speeds``) is read too."""

MODEL_MEMBERS = frozenset(
    {"data", "policy.pth", "policy.optimizer.pth", "pytorch_variables.pth", "_stable_baselines3_version",
     "system_info.txt", "actor.optimizer.pth", "critic.optimizer.pth", "ent_coef_optimizer.pth"}
)  # fmt: skip
"""The members of a PPO or SAC model saved by stable-baselines3 (``BaseAlgorithm.save``; SAC's optimisers are
saved one per network); ``data`` (JSON, whose ``:serialized:`` entries are pickled) and ``policy.pth`` (the
weights) are always there."""


class PolicyFileError(CatenaryError, ValueError):
    """A file given as a saved policy that is not one (missing, a folder, not a zip archive, no record or a
    damaged one, other members than a saved model's); the message names the file and what is wrong."""


@dataclass(frozen=True)
class PolicyRecord:
    """What a saved policy file says about its policy, beside the network.

    Attributes
    ----------
    problem : str
        The problem's name (``"B1"``).
    learner : str
        ``"ppo"`` or ``"sac"`` (:data:`LEARNERS`).
    variable_names : tuple of str
        The variables of the designs it proposes.
    model_fingerprint : str
        The fingerprint of the problem's model when trained (an edited preset or a new simulator revision
        changes it).
    env_spec : EnvSpec
        The env trained on: its speed, or its speed range and held-out speed bands, and fidelity.
    budget, seed : int
        The training run's simulations and seed.
    run_id : int or None
        The training run in its store.
    best_x : tuple of float or None
        The best design met in training, m.
    best_sigma : float or None
        Its σ, N, at ``best_speed_kmh``.
    best_speed_kmh : float or None
        The speed ``best_x`` was simulated at, km/h.
    package_version : str
        The version of the package that trained it.
    command : str
        The command that reproduces the training run ("" when not given).
    """

    problem: str
    learner: str
    variable_names: tuple[str, ...]
    model_fingerprint: str
    env_spec: EnvSpec
    budget: int
    seed: int
    run_id: int | None
    best_x: tuple[float, ...] | None
    best_sigma: float | None
    best_speed_kmh: float | None
    package_version: str
    command: str = ""

    @property
    def speeds(self) -> str:
        """The speeds (and contact-wire tensions) trained on, in words."""
        return self.env_spec.conditions


def learner_name_of_model(model: Any) -> str:
    """The :data:`LEARNERS` name of a stable-baselines3 model (of its class or the class it derives from)."""
    for kind in type(model).__mro__:
        if kind.__name__.lower() in LEARNERS:
            return kind.__name__.lower()
    raise ValueError(f"a {type(model).__name__} model is none of the learners {', '.join(LEARNERS)}")


def save_policy(
    policy: DesignPolicy,
    path: str | os.PathLike[str],
    problem: GridProblem,
    result: OptimizationResult | None = None,
    command: str = "",
) -> Path:
    """Save a trained policy as one file: stable-baselines3's zip with :data:`POLICY_MEMBER` inside.

    The file is written beside ``path`` and renamed onto it, so an interrupted save leaves no half file.

    Parameters
    ----------
    policy : DesignPolicy
        The trained policy.
    path : path-like
        The file to write (any name; ``.zip`` is the custom).
    problem : GridProblem
        Its problem (name, variables, model fingerprint).
    result : OptimizationResult, optional
        The training run's record (budget, seed, run, best design met).
    command : str
        The command that reproduces the training run, kept in the record.

    Returns
    -------
    Path
        ``path``.
    """
    target = Path(path)
    record = {
        "format": POLICY_FORMAT,
        "problem": problem.name,
        "learner": learner_name_of_model(policy.model),
        "variable_names": list(problem.variable_names),
        "model_fingerprint": str(getattr(problem, "model_fingerprint", "")),
        "env_spec": policy.env_spec.as_dict(),
        "observation_scaling": None
        if policy.observation_scaling is None
        else {
            "mean": np.asarray(policy.observation_scaling.mean).tolist(),
            "var": np.asarray(policy.observation_scaling.var).tolist(),
            "epsilon": policy.observation_scaling.epsilon,
            "clip": policy.observation_scaling.clip,
        },
        "budget": None if result is None else result.budget,
        "seed": None if result is None else result.seed,
        "run_id": None if result is None else result.run_id,
        "best_x": None if result is None else result.best_x,
        "best_sigma": None if result is None else result.best_sigma,
        "best_speed_kmh": None if result is None else result.best_speed_kmh,
        "package_version": package_version(),
        "command": command,
        "units": {"best_x": "m", "best_sigma": "N", "best_speed_kmh": "km/h", "env_spec.speed_kmh": "km/h"},
    }
    handle, temporary = tempfile.mkstemp(suffix=".zip", prefix=f".{target.name}-", dir=target.parent)
    os.close(handle)
    try:
        policy.model.save(temporary)
        with zipfile.ZipFile(temporary, "a") as archive:
            archive.writestr(POLICY_MEMBER, json.dumps(record, indent=1))
        os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise
    return target


def load_policy(path: str | os.PathLike[str]) -> tuple[DesignPolicy, PolicyRecord]:
    """Read a policy saved by :func:`save_policy`.

    Loading the model unpickles parts of it (stable-baselines3 does: the ``:serialized:`` entries of its
    ``data`` member): a policy file from someone else can run code. Load only files you made or trust. What
    is not a policy file is refused before stable-baselines3 reads it (:func:`check_policy_file`).

    Raises
    ------
    PolicyFileError
        Not a policy file (missing, a folder, not a zip, no :data:`POLICY_MEMBER`, other members than a saved
        PPO or SAC model's), or a damaged one: the message names the file and what is wrong.
    """
    source = Path(path)
    record, scaling = check_policy_file(source)
    sb3 = import_stable_baselines3()
    try:
        model = getattr(sb3, record.learner.upper()).load(source, device="cpu")
    except Exception as error:  # whatever torch or pickle raise on a damaged archive
        raise PolicyFileError(
            f"{source}: the {record.learner} model inside cannot be loaded ({type(error).__name__}: {error})"
        ) from error
    return DesignPolicy(model, record.env_spec, scaling), record


def check_policy_file(source: Path) -> tuple[PolicyRecord, ObservationScaling | None]:
    """The record of a policy file and its observation scaling, after checking that the file has a saved
    policy's layout: a zip archive of :data:`MODEL_MEMBERS` and :data:`POLICY_MEMBER`, whose ``data`` is
    JSON. Nothing is unpickled.

    Raises
    ------
    PolicyFileError
        The file is missing, a folder, or not a policy file.
    """
    if source.is_dir():
        raise PolicyFileError(f"{source}: is a folder; give a policy file")
    try:
        with zipfile.ZipFile(source) as archive:
            members = {name: archive.read(name) for name in {"data", POLICY_MEMBER} & set(archive.namelist())}
            names = set(archive.namelist())
    except FileNotFoundError:
        raise PolicyFileError(f"{source}: no such policy file; {_SAVE_HINT}") from None
    except OSError as error:
        raise PolicyFileError(f"{source}: cannot be read ({error.strerror or error})") from None
    except zipfile.BadZipFile:
        raise PolicyFileError(f"{source}: not a design policy (not a zip archive); {_SAVE_HINT}") from None
    if POLICY_MEMBER not in names:
        raise PolicyFileError(
            f"{source}: a zip archive without {POLICY_MEMBER}, not a design policy; {_SAVE_HINT}"
        )
    record = _policy_record(source, members[POLICY_MEMBER])
    missing, foreign = {"data", "policy.pth"} - names, names - MODEL_MEMBERS - {POLICY_MEMBER}
    if missing or foreign:
        lacks, extra = ", ".join(sorted(missing)) or "none", ", ".join(sorted(foreign)) or "none"
        raise PolicyFileError(
            f"{source}: not the layout of a saved design policy (missing: {lacks}; other members: {extra}); "
            f"{_SAVE_HINT}"
        )
    try:
        json.loads(members["data"])
    except ValueError as error:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        raise PolicyFileError(f"{source}: the model's data member is not JSON ({error})") from None
    return record


_SAVE_HINT = "save one with: catenary optimize PROBLEM --optimizer ppo --budget N --save-policy FILE"


def _policy_record(source: Path, text: bytes) -> tuple[PolicyRecord, ObservationScaling | None]:
    """The record of a policy file and its observation scaling; ValueError naming the field that is wrong."""
    try:
        data = json.loads(text)
        if not isinstance(data, dict) or data.get("format") not in (1, POLICY_FORMAT):
            found = data.get("format") if isinstance(data, dict) else data
            raise ValueError(f"format: {found!r} is not 1 or {POLICY_FORMAT}")
        learner = str(data.get("learner", "ppo"))
        if learner not in LEARNERS:
            raise ValueError(f"learner: {learner!r} is not one of {', '.join(LEARNERS)}")
        spec = data["env_spec"]
        env_spec = EnvSpec(
            str(spec["env_id"]),
            None if spec["speed_kmh"] is None else float(spec["speed_kmh"]),
            None if spec["speed_range"] is None else tuple(float(v) for v in spec["speed_range"]),
            str(spec["fidelity"]),
            tuple((float(a), float(b)) for a, b in spec.get("excluded_speeds", ())),
            None
            if spec.get("contact_wire_tension_range") is None
            else tuple(float(v) for v in spec["contact_wire_tension_range"]),
            tuple((float(a), float(b)) for a, b in spec.get("excluded_tensions", ())),
        )
        raw = data["observation_scaling"]
        scaling = None if raw is None else ObservationScaling(
            np.asarray(raw["mean"], dtype=np.float64), np.asarray(raw["var"], dtype=np.float64),
            float(raw["epsilon"]), float(raw["clip"]),
        )  # fmt: skip
        best_x = data.get("best_x")
        record = PolicyRecord(
            problem=str(data["problem"]),
            learner=learner,
            variable_names=tuple(str(v) for v in data["variable_names"]),
            model_fingerprint=str(data["model_fingerprint"]),
            env_spec=env_spec,
            budget=int(data["budget"] or 0),
            seed=int(data["seed"] or 0),
            run_id=data.get("run_id"),
            best_x=None if best_x is None else tuple(float(v) for v in best_x),
            best_sigma=data.get("best_sigma"),
            best_speed_kmh=data.get("best_speed_kmh"),
            package_version=str(data.get("package_version", "")),
            command=str(data.get("command", "")),
        )
    except (ValueError, KeyError, TypeError) as error:
        raise PolicyFileError(
            f"{source}: {POLICY_MEMBER} is damaged ({type(error).__name__}: {error})"
        ) from None
    return record, scaling
