"""``catenary export``: a run store as a dataset of evaluated designs (Parquet and a datasheet).

    catenary export STORE OUT

Writes ``OUT/PROBLEM_MODEL.parquet`` per problem and model, and ``OUT/DATASHEET.md``
(:mod:`optimizers.dataset`; needs ``pip install catenary-env[dataset]``). It only reads the store.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from catenary_env.errors import UsageError

from ..dataset import DATASHEET, export_store

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``export`` to the sub-commands of the ``catenary`` command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "export",
        help="write every evaluation of a run store as Parquet files with a datasheet (a dataset of designs)",
        description="Write every evaluation of an SQLite run store (variables in m, sigma in N, constraint "
        "values, feasibility and reason, speed in km/h, fidelity, the model's fingerprint) as one Parquet "
        "file per problem and model, with a datasheet. Needs pyarrow: pip install catenary-env[dataset].",
    )
    parser.add_argument("store", metavar="STORE", help="the run store (e.g. results/runs.sqlite)")
    parser.add_argument("out", metavar="OUT", type=Path, help="the folder to write into (created if absent)")
    return parser


def run(args: argparse.Namespace) -> int:
    """Execute ``export``; return the exit status (0)."""
    if not Path(args.store).is_file():
        raise UsageError(f"STORE {args.store}: no such file (a run store is made by catenary optimize)")
    if args.out.exists() and not args.out.is_dir():
        raise UsageError(f"OUT {args.out}: exists and is not a folder")
    paths = export_store(args.store, args.out)
    for path in paths:
        print(path)
    print(args.out / DATASHEET)
    return 0
