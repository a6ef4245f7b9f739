"""The commands of the studies on the ``catenary`` command line, one module each: ``catenary experiment``
(:mod:`.experiment`) and ``catenary report`` (:mod:`.report`).

:func:`add_commands` is the ``catenary_env.commands`` entry point (pyproject.toml) that plugs them in.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from . import experiment, report
from .report import build_report

__all__ = ["add_commands", "build_report"]


def add_commands(sub: argparse._SubParsersAction) -> dict[str, Callable[[argparse.Namespace], int]]:
    """Add ``catenary experiment`` and ``catenary report``; their handlers by name."""
    experiment.add_parser(sub)
    report.add_parser(sub)
    return {"experiment": experiment.run, "report": report.run}
