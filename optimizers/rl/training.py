"""Training a design policy for exactly a budget of simulations, on one env or several worker processes,
resumable from the run store."""

from __future__ import annotations

import dataclasses
import functools
import json
import os
from collections.abc import Callable
from contextlib import ExitStack
from typing import Any

import numpy as np

from catenary_env.cli.progress import ProgressDisplay

from ..base import OptimizationResult
from ..problem import GridProblem, GridSpace
from ..recorder import RunRecorder, open_run, package_version
from ..store import RunConfig, RunStore
from .learners import LearnerOptions, PPOOptions, SACOptions, import_stable_baselines3, learner_name, make_sac
from .policy import DesignPolicy, EnvSpec, ObservationScaling
from .recording import recording_vec_env_class


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
        stack.callback(recorder.keep_unfinished)  # interrupted: the archive keeps what it made
        vec_env = _vector_env(env_spec, recorder, space, settings, _problem_keys(env_spec, problem))
        stack.callback(vec_env.close)
        # One torch thread: these small networks gain nothing from more, and a fixed thread count keeps
        # torch's sums in one order whatever the core count, so that a resumed run replays its steps.
        import torch

        stack.callback(torch.set_num_threads, torch.get_num_threads())
        torch.set_num_threads(1)
        if isinstance(settings, SACOptions):
            model = make_sac(sb3, vec_env, settings, seed)
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
    vec_env = recording_vec_env_class()(inner, recorder, space, env_key, problem_key)
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
