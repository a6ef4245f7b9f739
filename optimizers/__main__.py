"""``python -m optimizers PROBLEM --optimizer NAME --budget N ...``: the ``catenary optimize`` command."""

from __future__ import annotations

import argparse
import sys

from catenary_env.cli_errors import raise_on_sigterm

from .cli import DESCRIPTION, add_arguments, run


def main() -> int:
    """Parse the command line and run the optimisation."""
    parser = argparse.ArgumentParser(prog="python -m optimizers", description=DESCRIPTION)
    add_arguments(parser)
    args = parser.parse_args()
    raise_on_sigterm()
    return run(args)


if __name__ == "__main__":  # guarded: worker processes are spawned and re-import this module
    sys.exit(main())
