"""What the studies share: their command-line options and entry point, the output folder, tidy CSV/JSON
writing and reading.

Each study module declares its options once, in ``add_arguments(parser)``, with a frozen ``Config`` whose
fields are named like them; :func:`run_study` builds the parser from it for both entry points,
``python -m experiments.NAME`` and ``catenary experiment NAME``, so the two take the same options.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

from catenary_env.cli import CommandParser
from catenary_env.cli.exits import raise_on_sigterm, run_command
from catenary_env.cli.paths import check_output_folder
from catenary_env.errors import UserFileError

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


def seed_value(text: str) -> int:
    """``--seeds`` of the studies' command lines: a whole number from 0 to 2³² − 1, what the learners' and
    numpy's generators take (refused before anything is simulated)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 0 <= value < 2**32:
        raise argparse.ArgumentTypeError(f"{value}: must lie in [0, 2**32 - 1]")
    return value


def study_dir(out: Path, name: str) -> Path:
    """The study's folder ``out/name``, created if absent (a folder that cannot be made is a user error,
    naming ``--out``)."""
    path = Path(out) / name
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UserFileError.from_os_error(error, "--out") from error
    return path


def write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    """Write rows (dicts with the same keys) as CSV (no rows: an empty file, which :func:`read_csv` reads
    back as none); written to a temporary file first, so an interrupted run never leaves a half-written
    table."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as handle:
        if rows:
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


def markdown_table(
    rows: list[dict[str, Any]], columns: list[tuple[str, str, str]], missing: str | None = None
) -> str:
    """A Markdown table: ``columns`` are (key, header, format); ``missing``, if given, stands for a NaN."""

    def cell(value: Any, spec: str) -> str:
        if missing is not None and isinstance(value, float) and math.isnan(value):
            return missing
        return format(value, spec)

    lines = ["| " + " | ".join(h for _, h, _ in columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        lines.append("| " + " | ".join(cell(row[k], f) for k, _, f in columns) + " |")
    return "\n".join(lines)


def add_full_option(parser: argparse.ArgumentParser, full: str) -> None:
    """``--full``: the study's full setting (``full`` says what it is and how long it takes)."""
    parser.add_argument(
        "--full", action="store_true", help=f"the full setting: {full}; default: the quick one"
    )


def add_out_option(parser: argparse.ArgumentParser) -> None:
    """``--out FOLDER``: where the study writes its folder."""
    parser.add_argument(
        "--out",
        type=Path,
        default=DEFAULT_OUT,
        metavar="FOLDER",
        help=f"output folder; the study writes into FOLDER/<study> (default: {DEFAULT_OUT})",
    )


def add_workers_option(parser: argparse.ArgumentParser, default: int, what: str = "the simulations") -> None:
    """``--workers N``: local worker processes (``what`` they run)."""
    parser.add_argument(
        "--workers",
        type=worker_count,
        default=default,
        metavar="N",
        help=f"local worker processes for {what}, at least 1 (default {default})",
    )


def add_store_option(parser: argparse.ArgumentParser) -> None:
    """``--store PATH``: the run store, shared by the studies by default."""
    parser.add_argument(
        "--store",
        type=Path,
        default=None,
        metavar="PATH",
        help=f"SQLite run store (default: OUT/{STORE}, shared by the studies: one reuses what another "
        "simulated)",
    )


def add_archive_option(parser: argparse.ArgumentParser, also: str = "") -> None:
    """``--archive FOLDER``: the study's run archive (optimizers/archive.py); ``also``: what else the study
    does with it."""
    parser.add_argument(
        "--archive", type=Path, default=None, metavar="FOLDER",
        help="a run archive: restore its runs into the store first, and write each run into it as it "
        "finishes, with a snapshot every ten minutes while it runs and when it is stopped (one file a run, "
        f"to commit as the study goes; docs/problems.md, 'Experiments'){also}",
    )  # fmt: skip


def config_from(config_class: Any, args: argparse.Namespace) -> Any:
    """The study's ``Config`` from its parsed options: each field from the option of its name (lists as
    tuples); a field without an option keeps its default."""
    values = {}
    for one in dataclasses.fields(config_class):
        if hasattr(args, one.name):
            value = getattr(args, one.name)
            values[one.name] = tuple(value) if isinstance(value, list) else value
    return config_class(**values)


def study_parser(study: ModuleType, prog: str) -> argparse.ArgumentParser:
    """The parser of a study's options (its ``add_arguments``), the same for both entry points."""
    parser = CommandParser(prog=prog, description=(study.__doc__ or "").split("\n\n")[0])
    study.add_arguments(parser)
    return parser


def run_study(study: ModuleType, argv: Sequence[str] | None, prog: str) -> int:
    """Parse a study's options, run it and print its report (a study run in lanes, ``--lane``: what its
    ``lane`` made); 0."""
    args = study_parser(study, prog).parse_args(argv)
    check_output_folder(args.out, "--out")
    config = config_from(study.Config, args)
    print(study.lane(config) if getattr(config, "lane", False) else study.report(study.main(config)))
    return 0


def run_cli(cli: Callable[[], int], name: str) -> int:
    """Run a study's ``python -m`` entry point as ``catenary experiment`` does: a user error ends in one line
    (exit status 2), a bug in its traceback; Ctrl-C or SIGTERM end it with one line, not a traceback (what was
    simulated is in the run store; run it again to resume)."""
    raise_on_sigterm()
    return run_command(name, lambda _: cli(), argparse.Namespace(), "; run it again to resume")


# -- resumable results -----------------------------------------------------------------------------------


@dataclass
class ResultLog:
    """Append-only JSON-lines file of finished computations: an interrupted study resumes from it.

    Each line is ``{"key": ..., "value": ...}``, written and flushed as soon as the computation ends;
    a line cut short by a kill is ignored on reading.
    """

    path: Path
    entries: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.path.exists():
            for line in self.path.read_text(encoding="utf-8").splitlines():
                try:
                    entry = json.loads(line)
                except json.JSONDecodeError:
                    continue
                self.entries[entry["key"]] = entry["value"]

    def get(self, key: str) -> Any:
        return self.entries.get(key)

    def put(self, key: str, value: Any) -> Any:
        with open(self.path, "a", encoding="utf-8") as handle:
            handle.write(json.dumps({"key": key, "value": value}) + "\n")
            handle.flush()
            os.fsync(handle.fileno())
        self.entries[key] = value
        return value
