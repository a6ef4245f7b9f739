"""``catenary experiment NAME [--full]`` and ``catenary report``: the studies from the command line."""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable
from pathlib import Path

from .common import DEFAULT_OUT

STUDIES = {
    "validation": "EN 50318:2002 table and figure at 250 and 300 km/h",
    "convergence": "mesh and time-step convergence of σ (benchmark preset, 300 km/h)",
    "presag": "σ against pre-sag on both catenaries, and the best pre-sag against speed",
    "design": "the six GA design studies, static analysis of the optima, σ against speed",
}


def add_parsers(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "experiment", help="run a study (docs/problems.md, 'Experiments'); writes data (CSV) and figures"
    )
    p.add_argument("name", choices=sorted(STUDIES), help="; ".join(f"{k}: {v}" for k, v in STUDIES.items()))
    p.add_argument(
        "--full",
        action="store_true",
        help="the full setting (20 spans, fine grids: minutes to hours); "
        "default: the quick setting (minutes)",
    )
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder (default: results)")
    p = sub.add_parser(
        "report", help="re-make every study's tables and figures from its data, without simulating"
    )
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the studies' folder (default: results)")


def run_experiment(args: argparse.Namespace) -> int:
    module = importlib.import_module(f"experiments.{args.name}")
    folder = module.main(module.Config(full=args.full, out=args.out))
    print(module.report(folder))
    return 0


def run_report(args: argparse.Namespace) -> int:
    found = False
    for name in STUDIES:
        folder = Path(args.out) / name
        if folder.is_dir() and any(folder.glob("*.csv")):
            module = importlib.import_module(f"experiments.{name}")
            print(f"## {name}\n\n{module.report(folder)}\n")
            found = True
    if not found:
        print(f"no study data under {args.out}: run 'catenary experiment NAME' first")
        return 1
    return 0


HANDLERS: dict[str, Callable[[argparse.Namespace], int]] = {
    "experiment": run_experiment,
    "report": run_report,
}


def add_commands(sub: argparse._SubParsersAction) -> dict[str, Callable[[argparse.Namespace], int]]:
    """Add ``catenary experiment`` and ``catenary report``: the ``catenary_env.commands`` entry point."""
    add_parsers(sub)
    return dict(HANDLERS)
