"""``python -m optimizers PROBLEM --optimizer NAME --budget N ...``: the ``catenary optimize`` command."""

from __future__ import annotations

import argparse
import sys

from .cli import DESCRIPTION, add_arguments, run


def main() -> int:
    """Parse the command line and run the optimisation."""
    parser = argparse.ArgumentParser(prog="python -m optimizers", description=DESCRIPTION)
    add_arguments(parser)
    try:
        return run(parser.parse_args())
    except KeyboardInterrupt:
        print(
            "\noptimize: interrupted (the evaluations done are in the store: re-run with --resume)",
            file=sys.stderr,
        )
        return 130


if __name__ == "__main__":  # guarded: worker processes are spawned and re-import this module
    sys.exit(main())
