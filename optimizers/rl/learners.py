"""The RL learners, PPO and SAC from stable-baselines3: their hyper-parameters, chosen once, and where an
untrained policy starts (docs/problems.md, 'Experiments')."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from catenary_env.errors import MissingDependency


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


def learner_name_of_model(model: Any) -> str:
    """The :data:`LEARNERS` name of a stable-baselines3 model (of its class or the class it derives from)."""
    for kind in type(model).__mro__:
        if kind.__name__.lower() in LEARNERS:
            return kind.__name__.lower()
    raise ValueError(f"a {type(model).__name__} model is none of the learners {', '.join(LEARNERS)}")


def make_sac(sb3: Any, vec_env: Any, settings: SACOptions, seed: int) -> Any:
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
