"""Optimisers from other installed packages: the ``catenary_env.optimizers`` entry-point group.

A package that declares, in its ``pyproject.toml``::

    [project.entry-points."catenary_env.optimizers"]
    mine = "my_package.my_module:MyOptimizer"

has its optimiser registered under ``mine`` the first time an optimiser is looked up by a name the
registry does not hold (:func:`get_optimizer`), so it runs with ``catenary optimize
--optimizer mine``, in :func:`optimizers.optimize` and in the comparison harness
(``catenary experiment optimizers --optimizers mine``). The object named may be

- an :class:`~optimizers.base.OptimizerSpec`;
- an :class:`~optimizers.base.Optimizer` subclass with a ``name`` (the entry point's name must be it); its
  hyper-parameters are its ``options_class`` attribute (a frozen dataclass whose fields all have defaults),
  or none, and its one-line summary the first line of its docstring.

The recipe, with a complete example: docs/problems.md, 'Your own optimiser'. The group is read at run
time with :func:`importlib.metadata.entry_points`; an entry point that fails to load is reported by a
warning naming it and skipped, so that one broken package does not stop the others.
"""

from __future__ import annotations

import importlib.metadata
import warnings
from dataclasses import dataclass
from typing import Any

from catenary_env.errors import UnknownNameError

from .base import OPTIMIZERS, Optimizer, OptimizerSpec

__all__ = ["ENTRY_POINT_GROUP", "NoOptions", "get_optimizer", "load_plugins", "plugin_spec"]

ENTRY_POINT_GROUP = "catenary_env.optimizers"
"""The entry-point group an installed package declares its optimisers in."""


@dataclass(frozen=True)
class NoOptions:
    """The hyper-parameters of an optimiser that has none."""


def plugin_spec(name: str, target: Any) -> OptimizerSpec:
    """The registry entry of an entry point's object (see the module's docstring).

    Raises
    ------
    TypeError
        The object is neither an OptimizerSpec nor an Optimizer subclass, or its name is not ``name``.
    """
    if isinstance(target, OptimizerSpec):
        spec = target
    elif isinstance(target, type) and issubclass(target, Optimizer):
        options = getattr(target, "options_class", NoOptions)
        summary = (target.__doc__ or target.__name__).strip().splitlines()[0]
        spec = OptimizerSpec(getattr(target, "name", name), target, options, summary)
    else:
        raise TypeError(f"{target!r} is neither an OptimizerSpec nor an Optimizer subclass")
    if spec.name != name:
        raise TypeError(f"the entry point is called {name!r}, its optimiser {spec.name!r}")
    return spec


def load_plugins() -> tuple[str, ...]:
    """Register the optimisers of the installed packages' entry points not registered yet; their names."""
    added = []
    for entry in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        if entry.name in OPTIMIZERS:
            continue
        try:
            spec = plugin_spec(entry.name, entry.load())
        except Exception as error:  # noqa: BLE001 (a third party's package: report it, go on)
            warnings.warn(
                f"optimizer entry point {entry.name} = {entry.value!r} ({ENTRY_POINT_GROUP}) is skipped: "
                f"{type(error).__name__}: {error}",
                stacklevel=2,
            )
            continue
        OPTIMIZERS.register(spec)
        added.append(spec.name)
    return tuple(added)


def get_optimizer(name: str) -> OptimizerSpec:
    """The registry entry ``name``, looked for also among the installed packages' optimisers
    (:func:`load_plugins`); UnknownNameError (a KeyError) lists the names available."""
    if name not in OPTIMIZERS:
        load_plugins()
    if name not in OPTIMIZERS:
        raise UnknownNameError(f"unknown optimizer {name!r}; available: {', '.join(sorted(OPTIMIZERS))}")
    return OPTIMIZERS[name]
