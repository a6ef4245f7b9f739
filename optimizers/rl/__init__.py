"""RL design policies: stable-baselines3 PPO or SAC trained on a design env (``pip install
catenary-env[rl]``).

A design env (docs/problems.md, 'Environments') has one-step episodes: the observation carries the task
context (the normalised speed), the action in ``Box(-1, 1)`` is the whole design, the reward is −σ. Trained
with a speed range, the policy is speed-conditioned: ``design = policy(speed)``, something no single-speed
optimiser gives.

The env contract this package relies on, and nothing else, so it works on any Gymnasium env with it:

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

from .learners import (
    BOX_WIDE_SPREAD,
    LEARNERS,
    POLICY_SPREAD,
    LearnerOptions,
    PPOOptions,
    SACOptions,
    import_stable_baselines3,
    learner_name,
)
from .policy import DesignPolicy, EnvSpec, ObservationScaling, design_for_speed
from .policy_files import (
    POLICY_MEMBER,
    PolicyFileError,
    PolicyRecord,
    check_policy_file,
    load_policy,
    save_policy,
)
from .training import policy_run_config, train_design_policy

__all__ = [
    "BOX_WIDE_SPREAD",
    "LEARNERS",
    "POLICY_MEMBER",
    "POLICY_SPREAD",
    "DesignPolicy",
    "EnvSpec",
    "LearnerOptions",
    "ObservationScaling",
    "PPOOptions",
    "PolicyFileError",
    "PolicyRecord",
    "SACOptions",
    "check_policy_file",
    "design_for_speed",
    "import_stable_baselines3",
    "learner_name",
    "load_policy",
    "policy_run_config",
    "save_policy",
    "train_design_policy",
]
