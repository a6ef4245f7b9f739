"""Gymnasium environments ``Catenary-<problem>-v0``, one per design problem (docs/problems.md, 'Environments';
needs gymnasium).

Since Gymnasium 1.0 a third-party package registers its environments on import; :func:`register_envs`
does it and may be called any number of times. ``import catenary_env`` registers the eight problems' envs
without importing the simulator (the entry points are strings).

Every episode is one step, so a vector env should reset a finished env within the same step; Gymnasium's
own default, next-step autoreset, would spend every second step on a reset. Each env is registered with
:data:`VECTOR_KWARGS` among its keyword arguments, which ``gymnasium.make_vec`` takes as its vector
options in every mode: ``gymnasium.make_vec("Catenary-B1-v0", 4)`` gives a
:class:`~gymnasium.vector.SyncVectorEnv` and ``vectorization_mode="async"`` an
:class:`~gymnasium.vector.AsyncVectorEnv` (one process per env), both with ``autoreset_mode=SAME_STEP``.
Gymnasium lets the registered options replace ``vector_kwargs`` given to ``make_vec``: other vector
options go to :func:`make_vector_env`.

Examples
--------
>>> import gymnasium as gym
>>> from catenary_env.envs import register_envs
>>> register_envs()
>>> gym.spec("Catenary-SW2-v0").kwargs
{'problem': 'SW2', 'vector_kwargs': {'autoreset_mode': 'SameStep'}}
>>> envs = gym.make_vec("Catenary-B1-v0", 2, vectorization_mode="async", fidelity="test")
>>> envs.metadata["autoreset_mode"]
<AutoresetMode.SAME_STEP: 'SameStep'>
>>> envs.close()
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

try:
    import gymnasium
except ImportError as error:  # pragma: no cover - depends on the installation
    raise ImportError("the environments need gymnasium: pip install catenary-env[gym]") from error

from .vector_options import VECTOR_KWARGS

if TYPE_CHECKING:
    from .design_env import CatenaryDesignEnv

__all__ = [
    "BUILTIN_PROBLEMS",
    "VECTOR_KWARGS",
    "CatenaryDesignEnv",
    "env_ids",
    "make_vector_env",
    "register_envs",
]

ENTRY_POINT = "catenary_env.envs.design_env:CatenaryDesignEnv"

BUILTIN_PROBLEMS = ("BPresag", "B1", "B2", "B3", "SWPresag", "SW1", "SW2", "SW3")
"""The eight problems of ``catenary_env.problems.PROBLEMS``, by name, so that registering their envs on
``import catenary_env`` needs no simulator (tests/test_envs.py checks that the two agree)."""


def __getattr__(name: str) -> Any:
    if name == "CatenaryDesignEnv":  # imported on first use: it imports the simulator
        from .design_env import CatenaryDesignEnv

        return CatenaryDesignEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def env_ids() -> list[str]:
    """The environment IDs, one per registered design problem, in the problems' order."""
    from ..problems import PROBLEMS

    return [f"Catenary-{name}-v0" for name in PROBLEMS]


def register_envs(builtin_only: bool = False) -> None:
    """Register ``Catenary-<problem>-v0`` for every design problem; IDs already registered are left alone.

    Parameters
    ----------
    builtin_only : bool
        Register the eight built-in problems' envs only, without importing the problem registry (what
        ``import catenary_env`` does); by default every problem registered now gets its env.
    """
    if builtin_only:
        names = list(BUILTIN_PROBLEMS)
    else:
        from ..problems import PROBLEMS

        names = list(PROBLEMS)
    for name in names:
        env_id = f"Catenary-{name}-v0"
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id, entry_point=ENTRY_POINT, kwargs={"problem": name, "vector_kwargs": VECTOR_KWARGS}
            )


def make_vector_env(
    num_envs: int = 1,
    *,
    problem: str,
    asynchronous: bool = False,
    vector_kwargs: dict[str, Any] | None = None,
    **kwargs: Any,
) -> gymnasium.vector.VectorEnv:
    """A vector env of ``num_envs`` envs ``Catenary-<problem>-v0`` with same-step autoreset, as
    ``gymnasium.make_vec`` makes (with ``vectorization_mode="async"`` for ``asynchronous=True``).

    Parameters
    ----------
    num_envs : int
        Envs in the vector, >= 1.
    problem : str
        The design problem (set by the registered ID).
    asynchronous : bool
        One process per env (:class:`~gymnasium.vector.AsyncVectorEnv`): the simulations of a step run in
        parallel. Default: all in this process (:class:`~gymnasium.vector.SyncVectorEnv`).
    vector_kwargs : dict, optional
        More options of the vector env's class (``context``, ``shared_memory``, ...), over
        :data:`VECTOR_KWARGS`: what ``gymnasium.make_vec`` cannot take for these envs.
    **kwargs
        The env's arguments (``speed_kmh``, ``speed_range``, ``fidelity``, ...), the same for every env.

    Returns
    -------
    gymnasium.vector.VectorEnv
        With ``autoreset_mode=AutoresetMode.SAME_STEP``: a finished episode (every step finishes one) is
        reset within its step, and ``info["final_obs"]`` holds its last observation.
    """
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ValueError(f"num_envs = {num_envs!r}: must be an integer >= 1")
    env_id = f"Catenary-{problem}-v0"

    def make_env() -> gymnasium.Env:
        return gymnasium.make(env_id, **kwargs)

    vector = gymnasium.vector.AsyncVectorEnv if asynchronous else gymnasium.vector.SyncVectorEnv
    return vector([make_env] * num_envs, **{**VECTOR_KWARGS, **(vector_kwargs or {})})


register_envs(builtin_only=True)  # on import, as Gymnasium 1.x expects of a third-party package
