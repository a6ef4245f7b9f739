"""``python -m optimizers PROBLEM --optimizer NAME --budget N ...``: the ``catenary optimize`` command."""

from __future__ import annotations

import sys

from catenary_env.cli import CommandParser
from catenary_env.cli.exits import raise_on_sigterm, run_command

from .cli.optimize import DESCRIPTION, add_arguments, run


def main() -> int:
    """Parse the command line and run the optimisation (under the command line's error policy)."""
    parser = CommandParser(prog="python -m optimizers", description=DESCRIPTION)
    add_arguments(parser)
    args = parser.parse_args()
    raise_on_sigterm()
    return run_command("python -m optimizers", run, args)


if __name__ == "__main__":  # guarded: worker processes are spawned and re-import this module
    sys.exit(main())
