"""The commands of this package on the ``catenary`` command line, one module each: ``catenary optimize``
(:mod:`.optimize`), ``catenary propose`` (:mod:`.propose`), ``catenary runs`` (:mod:`.runs`) and
``catenary export`` (:mod:`.export`).

:func:`add_commands` is the ``catenary_env.commands`` entry point (pyproject.toml) that plugs them in.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from . import export, optimize, propose, runs

__all__ = ["add_commands"]


def add_commands(subparsers: Any) -> dict[str, Callable[[argparse.Namespace], int]]:
    """Add ``catenary optimize``, ``propose``, ``runs`` and ``export``; their handlers by name."""
    commands = {"optimize": optimize, "propose": propose, "runs": runs, "export": export}
    for module in commands.values():
        module.add_parser(subparsers)
    return {name: module.run for name, module in commands.items()}
