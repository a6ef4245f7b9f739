"""``catenary runs``: the runs a run store holds and how far each has got.

    catenary runs [--store PATH] [--json]

For the long studies (docs/problems.md, 'Experiments'): which runs are done, which a process is making now
(:meth:`~optimizers.store.RunStore.being_made`), which stopped part-way (an interrupted run resumes with
``--resume``, or by running its study again), their simulations against the budget and the best σ so far.
It only reads the store, so it can watch runs that are writing into it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from catenary_env.errors import UsageError

from ..store import RunConfig, RunStore
from .optimize import DEFAULT_STORE

__all__ = ["add_parser", "run"]

COLUMNS = ("run", "optimizer", "problem", "seed", "speed", "fidelity", "simulations", "best σ (N)", "status")


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``runs`` to the sub-commands of the ``catenary`` command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "runs",
        help="the runs in a run store: simulations against the budget, best sigma, finished or not",
        description="List the runs of an SQLite run store (catenary optimize's, or the studies' "
        "results/runs.sqlite) with their simulations against the budget, the best feasible sigma so far (N) "
        "and whether each finished (and why it stopped) or not: a run not finished was interrupted, or is "
        "still running.",
    )
    parser.add_argument(
        "--store", default=DEFAULT_STORE, metavar="PATH", help=f"the run store (default: ./{DEFAULT_STORE})"
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print a JSON list, one object per run: its stored settings and progress (sigma in N, speed in "
        "km/h, null for a speed range)",
    )
    return parser


def run(args: argparse.Namespace) -> int:
    """Execute ``runs``; return the exit status (0; a store that is missing or not a run store is refused)."""
    if not Path(args.store).is_file():
        raise UsageError(f"--store {args.store}: no such file (a run store is made by catenary optimize)")
    with RunStore(args.store, read_only=True) as store:
        runs = store.run_progress()
        for r in runs:  # a run not finished is being made now by some process, or was interrupted
            config = RunConfig(*(r[name] for name in RunConfig._fields))
            r["running"] = r["finished_at"] is None and store.being_made(config)
    print(json.dumps(runs) if args.json else _table(runs, args.store))
    return 0


def _table(runs: list[dict[str, Any]], store: str) -> str:
    if not runs:
        return f"{store}: no run"
    rows = [COLUMNS] + [_row(r) for r in runs]
    widths = [max(len(row[i]) for row in rows) for i in range(len(COLUMNS))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip() for row in rows]
    running = sum(r["running"] for r in runs)
    interrupted = sum(r["finished_at"] is None and not r["running"] and not _given(r) for r in runs)
    lines.append(
        f"{len(runs)} run(s) in {store}: {running} running now, {interrupted} interrupted (they resume with "
        "--resume, or when their study runs again)"
    )
    return "\n".join(lines)


def _row(run: dict[str, Any]) -> tuple[str, ...]:
    speed = "range" if run["speed_kmh"] is None else f"{run['speed_kmh']:g} km/h"
    best = "–" if run["best_sigma"] is None else f"{run['best_sigma']:.3f}"
    last = run["last_evaluation_at"]
    if run["finished_at"] is not None:
        status = f"{run['stop_reason']}, {_time(run['finished_at'])}"
    elif _given(run):
        status = "designs a study gave, no budget" + (f", last evaluation {_time(last)}" if last else "")
    else:
        state = "running now" if run["running"] else "interrupted"
        status = f"{state}, last evaluation {_time(last)}" if last is not None else f"{state}, no evaluation"
    return (
        str(run["run_id"]), run["optimizer"], run["problem"], str(run["seed"]), speed, run["fidelity"],
        f"{run['simulations']}" + ("" if _given(run) else f"/{run['budget']}"), best, status,
    )  # fmt: skip


def _given(run: dict[str, Any]) -> bool:
    """Whether a run is a collection of designs a study asked to simulate (budget 0, never finished:
    ``experiments/design_evaluations.py``), not an optimisation run."""
    return run["budget"] == 0


def _time(stamp: str) -> str:
    """``2026-12-01T11:58:39.863+00:00`` as ``2026-12-01 11:58 UTC``."""
    return f"{stamp[:10]} {stamp[11:16]} UTC" if stamp.endswith("+00:00") else stamp
