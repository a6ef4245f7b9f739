"""The commands that the packages built on the simulator plug into ``catenary`` (``optimize``, ``propose``,
``runs``, ``experiment``, ``report``), through the ``catenary_env.commands`` entry points, so that the
simulator never imports them."""

from __future__ import annotations

import argparse
import dataclasses
import importlib.metadata
import importlib.util
from collections.abc import Callable
from pathlib import Path

from ..errors import UsageError
from .exits import print_error

COMMANDS_GROUP = "catenary_env.commands"
"""Entry-point group of the packages that add sub-commands to ``catenary`` (``optimize``, ``experiment``).

An entry point names a function ``add_commands(subparsers) -> {command: handler}``."""

Handler = Callable[[argparse.Namespace], int]


def plugin_commands(sub: argparse._SubParsersAction) -> dict[str, Handler]:
    """The commands of the ``catenary_env.commands`` entry points.

    One that fails to load stays a command, whose run says why (the real error, and the module that shadows
    the package where one does), so that a broken or shadowed package never makes a command vanish.
    """
    handlers: dict[str, Handler] = {}
    for entry in sorted(importlib.metadata.entry_points(group=COMMANDS_GROUP), key=lambda e: e.name):
        try:
            add_commands = entry.load()
        except Exception as error:  # a broken plug-in must not take the simulator's commands down
            sub.add_parser(entry.name, help=f"unavailable: run it for the reason ({type(error).__name__})")
            handlers[entry.name] = Unavailable(entry.name, _load_failure(entry.value, error), error)
            continue
        handlers.update(add_commands(sub))
    return handlers


@dataclasses.dataclass(frozen=True)
class Unavailable:
    """The handler of a plug-in command that failed to load: it reports why (``--debug``: the traceback)."""

    name: str
    reason: str
    error: BaseException

    def __call__(self, args: argparse.Namespace) -> int:
        if getattr(args, "debug", False):
            raise self.error
        return print_error(
            f"catenary {self.name}",
            UsageError(f"the '{self.name}' command could not be loaded: {self.reason}"),
        )


def _load_failure(target: str, error: BaseException) -> str:
    """Why the entry point ``target`` (``module:function``) failed, and where its package came from."""
    reason = f"{target} raised {type(error).__name__}: {error}"
    package = target.partition(":")[0].partition(".")[0]
    try:
        spec = importlib.util.find_spec(package)
    except (ImportError, ValueError):
        spec = None
    if spec is None:
        return f"{reason}; no package '{package}' is installed (pip install catenary-env)"
    origin = spec.origin or next(iter(spec.submodule_search_locations or []), None)
    home = Path(__file__).resolve().parents[2]
    if origin is not None and home not in Path(origin).resolve().parents:
        return (
            f"{reason}; '{package}' is imported from {origin}, not from this project ({home}): a module of "
            "that name shadows it; rename that module or run from another folder"
        )
    return reason
