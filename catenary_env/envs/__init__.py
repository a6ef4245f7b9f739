"""Gymnasium environments ``Catenary-<problem>-v0``, one per design problem (docs/problems.md, 'Environments';
needs gymnasium).

Since Gymnasium 1.0 a third-party package registers its environments on import; :func:`register_envs`
does it and may be called any number of times.

Examples
--------
>>> import gymnasium as gym
>>> from catenary_env.envs import register_envs
>>> register_envs()
>>> gym.spec("Catenary-SW2-v0").kwargs
{'problem': 'SW2'}
"""

from __future__ import annotations

try:
    import gymnasium
except ImportError as error:  # pragma: no cover - depends on the installation
    raise ImportError("the environments need gymnasium: pip install catenary-env[gym]") from error

from ..problems import PROBLEMS
from .design_env import CatenaryDesignEnv

__all__ = ["CatenaryDesignEnv", "env_ids", "register_envs"]

ENTRY_POINT = "catenary_env.envs.design_env:CatenaryDesignEnv"


def env_ids() -> list[str]:
    """The environment IDs, one per registered design problem, in the problems' order."""
    return [f"Catenary-{name}-v0" for name in PROBLEMS]


def register_envs() -> None:
    """Register ``Catenary-<problem>-v0`` for every design problem; IDs already registered are left alone."""
    for name, env_id in zip(PROBLEMS, env_ids(), strict=True):
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=ENTRY_POINT, kwargs={"problem": name})
