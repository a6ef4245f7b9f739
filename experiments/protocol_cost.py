"""What a long study cost, measured from its run archive: the optimiser benchmark's full protocol
(docs/performance.md, 'The full protocol of the optimiser benchmark'), the amortised RL study ('The full
studies').

Every evaluation in the archive carries its time stamp (to the second) and the wall time of its simulation, so
the archive alone, on any checkout, says what the runs cost:

- *simulations*: the evaluations each run was charged for (its budget), and those simulated (a design another
  run had simulated comes from the run store and costs nothing);
- *simulation time*: the wall time of the simulated ones, in core-hours (each lane one process on one core);
- *run time*: a run's time from its start to its last evaluation, its optimiser's own work included (the `gp`
  sampler's model fits), leaving out the gaps longer than :data:`INTERRUPTION` (a session's end: the run was
  resumed later from its snapshot). Runs rebuilt from an export kept no time stamps: their simulation time
  counts, their run time cannot.

    python -m experiments.protocol_cost    # writes results/full-protocol/optimizers/cost.md
    python -m experiments.protocol_cost --archive results/rl/amortised/archive --cores 2 \
        --title "The amortised RL study's cost" --out results/rl/amortised/cost.md
"""

from __future__ import annotations

import argparse
import statistics
from collections import defaultdict
from datetime import datetime
from pathlib import Path
from typing import Any

from optimizers.archive import finished_runs

from .model_stamp import ModelStamp

ROOT = Path(__file__).resolve().parents[1]
ARCHIVE = ROOT / "results" / "full-protocol" / "archive"
INTERRUPTION = 600.0
"""s: a gap between a run's evaluations longer than this is an interruption, not work (a `gp` ask takes some
3 s, a PPO update under a second)."""
CATENARY = {"B": "benchmark", "SW": "stitched"}
"""The catenary of a problem, by the letters its name starts with (docs/problems.md); another problem (a
synthetic one) stands for itself."""


def _seconds(stamp: str) -> float:
    return datetime.fromisoformat(stamp).timestamp()


def run_cost(run: dict[str, Any], rows: list[dict[str, Any]]) -> dict[str, Any]:
    """One run's cost: simulations charged and made, simulation time (s), and its run time (s; None for a run
    rebuilt from an export, which kept no time stamps)."""
    simulated = [r for r in rows if r["charged"] and not r["cached"]]
    timed = any(r["source"] != "export" for r in rows)
    run_time = None
    if timed:
        # In time order: a generation's designs are stamped as its workers finish them, and a generation
        # interrupted and resumed holds designs of both sessions, so the order of the rows is not the clock's.
        stamps = sorted([_seconds(run["created_at"])] + [_seconds(r["created_at"]) for r in rows])
        gaps = [b - a for a, b in zip(stamps[:-1], stamps[1:], strict=True)]
        run_time = sum(gap for gap in gaps if gap <= INTERRUPTION)
    problem = str(run["problem"]).split("@")[0]
    return {
        "optimizer": run["optimizer"],
        "problem": problem,
        "catenary": next((name for prefix, name in CATENARY.items() if problem.startswith(prefix)), problem),
        "charged": sum(int(r["charged"]) for r in rows),
        "simulated": len(simulated),
        "simulation_time_s": sum(float(r["wall_time"]) for r in simulated),
        "run_time_s": run_time,
    }


def _minutes(values: list[float]) -> str:
    if not values:
        return "–"
    return f"{statistics.median(values) / 60:.1f} ({min(values) / 60:.1f}–{max(values) / 60:.1f})"


def _hours(run_time_s: float, cores: int) -> str:
    """Run time in core-hours, and in hours on the cores where a run held more than one."""
    core_hours = run_time_s * cores / 3600
    if cores == 1:
        return f"{core_hours:.1f} core-hours"
    return f"{run_time_s / 3600:.1f} h on {cores} cores ({core_hours:.1f} core-hours)"


def report(archive: Path = ARCHIVE, title: str = "The full protocol's cost", cores: int = 1) -> str:
    """The cost of the archive's finished runs, as markdown; ``cores``: the cores each run held (1: one
    lane per core; 2: a run stepping two envs or two GA workers)."""
    if cores < 1:
        raise ValueError(f"cores = {cores}: must be at least 1")
    costs = [run_cost(run, rows) for run, rows in finished_runs(archive)]
    if not costs:
        raise SystemExit(f"{archive}: no finished run")
    stamp = ModelStamp.read(archive)
    by_group: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    for cost in costs:
        by_group[cost["optimizer"], cost["catenary"]].append(cost)
    timed = [c for c in costs if c["run_time_s"] is not None]
    lines = [
        f"# {title}",
        "",
        f"Written by `python -m experiments.protocol_cost` from the run archive ({len(costs)} finished runs"
        + (f"; model `{stamp.simulator}`" if stamp else "")
        + "). "
        + (
            "Times are wall times of one process on one core of the 2-core machine, each lane beside the "
            "other."
            if cores == 1
            else f"Each run held {cores} cores (its simulations in {cores} processes at once): a simulation "
            f"time is the sum of its simulations' wall times (core time), a run time its wall time on the "
            f"{cores} cores."
        ),
        "",
        "| | runs | simulations charged | simulated | simulation time (core-h) |",
        "|---|---|---|---|---|",
    ]
    present = [c["catenary"] for c in costs]
    others = sorted(set(present) - set(CATENARY.values()))  # a synthetic problem, by its name
    for name in (*(n for n in CATENARY.values() if n in present), *others, "all"):
        group = [c for c in costs if name in (c["catenary"], "all")]
        hours = sum(c["simulation_time_s"] for c in group) / 3600
        lines.append(
            f"| {name} | {len(group)} | {sum(c['charged'] for c in group):,} | "
            f"{sum(c['simulated'] for c in group):,} | {hours:.1f} |"
        )
    lines += [
        "",
        f"Run time of the {len(timed)} runs with time stamps"
        + (" (the others were rebuilt from an export)" if len(timed) < len(costs) else "")
        + ": "
        + _hours(sum(c["run_time_s"] for c in timed), cores)
        + f", against {sum(c['simulation_time_s'] for c in timed) / 3600:.1f} core-hours of simulation. Per "
        "run, in minutes, median (least–most):",
        "",
        "| optimiser | catenary | runs | simulation time (min) | runs timed | run time (min) |",
        "|---|---|---|---|---|---|",
    ]
    for (optimizer, catenary), group in sorted(by_group.items()):
        with_time = [c for c in group if c["run_time_s"] is not None]
        simulation = _minutes([c["simulation_time_s"] for c in group])
        run_time = _minutes([c["run_time_s"] for c in with_time])
        cells = (optimizer, catenary, len(group), simulation, len(with_time), run_time)
        lines.append("| " + " | ".join(str(cell) for cell in cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--archive", type=Path, default=ARCHIVE, help="the run archive (default: %(default)s)"
    )
    parser.add_argument(
        "--out", type=Path, default=None, help="where to write (default: the archive's ../optimizers/cost.md)"
    )
    parser.add_argument("--title", default="The full protocol's cost", help="the report's title")
    parser.add_argument(
        "--cores", type=int, default=1, help="cores each run held: 1 (a lane per core, default) or more"
    )
    args = parser.parse_args(argv)
    if args.cores < 1:
        parser.error(f"--cores {args.cores}: must be at least 1")
    out = args.out or args.archive.parent / "optimizers" / "cost.md"
    if not out.parent.is_dir():  # before the archive is read
        parser.error(
            f"--out {out}: no folder {out.parent} to write it in; give --out FILE in a folder that exists"
        )
    out.write_text(report(args.archive, args.title, args.cores), encoding="utf-8")
    print(out.read_text(encoding="utf-8"))


if __name__ == "__main__":
    main()
