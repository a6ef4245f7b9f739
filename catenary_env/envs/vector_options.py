"""The vector options registered with every design env (docs/problems.md, 'Environments')."""

from __future__ import annotations

import gymnasium

__all__ = ["VECTOR_KWARGS"]

VECTOR_KWARGS = {"autoreset_mode": gymnasium.vector.AutoresetMode.SAME_STEP.value}
"""Same-step autoreset: every episode is one step, so a finished env is reset within its step.

``gymnasium.make_vec`` reads a registered ``vector_kwargs`` in its sync and async modes (its default mode is
sync when no ``vector_entry_point`` is registered, and none is); ``gymnasium.make`` hands it to the env,
which accepts only this value."""
