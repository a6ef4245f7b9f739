"""The command line of catenary-env, ``catenary`` (README.md, 'Command line'): one module per command.

    catenary static PRESET [--presag S | --offsets ...] [--json] [--plot FILE]
    catenary simulate PRESET --speed KMH [...] [--json] [--plot FILE]
    catenary validate [--json]
    catenary evaluate PROBLEM --x V1 V2 ... [--speed KMH] [--json]
    catenary tolerance PROBLEM [--x V1 V2 ...] [--height M] [--position M] [--draws N] [--seed S] [--json]
    catenary optimize PROBLEM --optimizer NAME --budget N --seed S [...]
    catenary propose POLICY --speed KMH [--no-evaluate]
    catenary runs [--store PATH]
    catenary experiment NAME [the study's options]
    catenary report
    catenary presets [--copy NAME DEST]

The command line is the edge of the package: nothing in the simulator imports it, and it imports optional
packages only where a command needs them. Errors follow one policy (:mod:`.exits`): bad input exits with
status 2 and one line naming the field and its range, before any solve; anything else is a bug and keeps its
traceback.

The simulator's own commands import the simulator only when they run, and the commands of the packages
above (optimize, propose, runs, experiment, report; :mod:`.plugins`) are loaded only when one of them is
asked for, so that ``catenary presets`` starts at once.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

from .exits import EXIT_USAGE, raise_on_sigterm, run_command
from .options import FIDELITY_NAMES
from .plugins import COMMANDS_GROUP, Handler, Unavailable, plugin_commands

__all__ = ["COMMANDS_GROUP", "FIDELITY_NAMES", "CommandParser", "build_parser", "main"]

CORE_COMMANDS = ("static", "simulate", "validate", "presets")
"""The simulator's own commands, each a module of this package with ``add_parser(subparsers)`` and
``run(args)``."""

EDGE_COMMANDS = ("evaluate", "tolerance")
"""Commands of this package on the design problems, built with the plug-ins' (they import the simulator)."""


class CommandParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, like the commands' own (:mod:`.exits`)."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see: {self.prog} --help)\n")


def build_parser(command: str | None = None) -> tuple[argparse.ArgumentParser, dict[str, Handler]]:
    """The ``catenary`` parser and the handler of each command.

    Parameters
    ----------
    command : str, optional
        The command about to run. One of the simulator's own (:data:`CORE_COMMANDS`) builds that command
        alone and loads no plug-in, for a quick start; otherwise every command is built.
    """
    parser = CommandParser(
        prog="catenary",
        description="The command line of catenary-env (README.md, 'Command line'): a railway overhead-line "
        "(catenary) simulator, its design problems and optimisers.",
        epilog="Exit status: 0 done; 1 a validation out of its ranges, or no study data for a report; 2 the "
        "input was refused (one line says why); 70 an internal error (a bug: its traceback, please report "
        "it); 130 or 143 interrupted (Ctrl-C, SIGTERM).",
    )
    parser.add_argument(
        "--debug", action="store_true", help="show the traceback of an error instead of its one-line message"
    )
    sub = parser.add_subparsers(dest="command", required=True)
    handlers: dict[str, Handler] = {}
    built = (command,) if command in CORE_COMMANDS else CORE_COMMANDS + EDGE_COMMANDS
    for name in built:
        module: Any = importlib.import_module(f"{__name__}.{name}")
        module.add_parser(sub)
        handlers[name] = module.run
    if command not in CORE_COMMANDS:
        handlers.update(plugin_commands(sub))
    return parser, handlers


def _command_of(argv: Sequence[str]) -> str | None:
    """The command named in ``argv`` (its first word that is not an option), or None."""
    return next((word for word in argv if not word.startswith("-")), None)


def _warning_printer(command: str) -> Callable[..., None]:
    """Show a warning (an unreadable cache, say) on one line, like the commands' own warnings."""

    def show(message: Warning | str, *args: Any, **kwargs: Any) -> None:
        print(f"catenary {command}: warning: {message}", file=sys.stderr)

    return show


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``catenary`` on ``argv`` (default: the process's arguments); the exit status (:mod:`.exits`)."""
    words = list(sys.argv[1:] if argv is None else argv)
    parser, handlers = build_parser(_command_of(words))
    args, unknown = parser.parse_known_args(words)
    handler = handlers[args.command]
    if unknown and not isinstance(handler, Unavailable):  # the command's, so its help is the one to see
        prog = f"catenary {args.command}"
        parser.exit(
            EXIT_USAGE, f"{prog}: error: unrecognized arguments: {' '.join(unknown)} (see: {prog} --help)\n"
        )
    raise_on_sigterm()
    with warnings.catch_warnings():
        warnings.showwarning = _warning_printer(args.command)
        return run_command(f"catenary {args.command}", handler, args)
