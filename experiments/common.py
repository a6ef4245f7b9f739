"""What the studies share: the output folder, tidy CSV/JSON writing and reading."""

from __future__ import annotations

import argparse
import csv
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from catenary_env.cli_errors import interruption, raise_on_sigterm

DEFAULT_OUT = Path("results")
STORE = "runs.sqlite"
"""The run store the studies share, in their output folder: one store lets a study reuse what another has
simulated (the same design at the same speed and fidelity is simulated once, optimizers/store.py), e.g. the
GA runs of the optimiser comparison and the design studies that start from the same seed."""


def worker_count(text: str) -> int:
    """``--workers`` of the studies' command lines: a whole number of processes, at least 1 (refused before
    anything is simulated)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of processes") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value}: must be at least 1 process")
    return value


def study_dir(out: Path, name: str) -> Path:
    path = Path(out) / name
    path.mkdir(parents=True, exist_ok=True)
    return path


def write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    """Write rows (dicts with the same keys) as CSV; written to a temporary file first, so an
    interrupted run never leaves a half-written table."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    tmp.replace(path)


def read_csv(path: Path) -> list[dict[str, Any]]:
    with open(path, newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        for key, value in row.items():
            try:
                row[key] = float(value)
            except (TypeError, ValueError):
                pass
    return rows


def write_json(path: Path, data: Any) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=2), encoding="utf-8")
    tmp.replace(path)


def markdown_table(rows: list[dict[str, Any]], columns: list[tuple[str, str, str]]) -> str:
    """A Markdown table: ``columns`` are (key, header, format)."""
    lines = ["| " + " | ".join(h for _, h, _ in columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        lines.append("| " + " | ".join(format(row[k], f) for k, _, f in columns) + " |")
    return "\n".join(lines)


def run_cli(cli: Callable[[], int], name: str) -> int:
    """Run a study's ``python -m`` entry point as ``catenary experiment`` does: Ctrl-C or SIGTERM end it with
    one line, not a traceback (what was simulated is in the run store; run it again to resume)."""
    raise_on_sigterm()
    try:
        return cli()
    except KeyboardInterrupt as error:
        what, status = interruption(error)
        print(f"{name}: {what}; run it again to resume", file=sys.stderr)
        return status
