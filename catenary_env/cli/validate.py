"""``catenary validate``: the EN 50318:2002 validation table (value, accepted range, pass or fail)."""

from __future__ import annotations

import argparse
import json

from .progress import ProgressDisplay


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``validate`` to the sub-commands of ``catenary``."""
    p = sub.add_parser("validate", help="EN 50318:2002 validation table (value, accepted range, pass/fail)")
    p.add_argument(
        "--speeds",
        type=float,
        nargs="+",
        default=[250.0, 300.0],
        metavar="KMH",
        help="speeds, km/h: those the standard gives ranges at, 250 and 300 (default: both)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object (for scripts; SI units)")


def run(args: argparse.Namespace) -> int:
    """Simulate the standard's model and print the table; 0 when every quantity is in its range, else 1."""
    from ..validation import ROW_UNITS, validate

    progress = ProgressDisplay("validate", 1.0, quiet=args.json)
    report = validate(tuple(args.speeds), progress=progress.fraction)
    progress.finish()
    if args.json:
        units = {"uplift_force": "N", **{f"rows.{key}": unit for key, unit in ROW_UNITS.items()}}
        rows = [row.as_dict() for row in report.rows]
        print(json.dumps({"passed": report.passed, "uplift_force": report.uplift_force, "units": units,
                          "rows": rows}, indent=2))  # fmt: skip
    else:
        print(report.table())
    return 0 if report.passed else 1
