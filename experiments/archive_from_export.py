"""Rebuild the run archive of the optimiser comparison from a results export, where the run store that made
the runs was lost (docs/problems.md, 'Experiments').

The export's ``evaluations.csv`` keeps, for each evaluation of a finished run, its design, σ, feasibility,
charge, cache flag and times; its ``runs.csv`` keeps each run's stop reason. The run's identity in the store
(:class:`~optimizers.store.RunConfig`: options, model fingerprint and version) is the one the comparison
gives the run today, so the rebuilt run is found by a resumed protocol as finished. What the export does not
keep (an infeasible design's reason, the constraint values, the statistics, PPO's rewards) is not invented:
the rows carry ``source = "export"`` (:data:`~optimizers.store.EXPORT_SOURCE`) and are never served as cache.

    python -m experiments.archive_from_export EXPORT_FOLDER ARCHIVE_FOLDER --date 2026-12-02T09:40:00+00:00
"""

from __future__ import annotations

import argparse
import json
import math
from collections import defaultdict
from pathlib import Path
from typing import Any

from optimizers.archive import write_run_file
from optimizers.store import EXPORT_SOURCE

from .benchmark_report import DONE
from .common import read_csv
from .optimizer_comparison import SPEED_KMH, Config, _prepare

REASON = "infeasible (its reason was not kept by the export this run was rebuilt from)"
"""The reason of an infeasible evaluation rebuilt from an export."""


def archive_from_export(export: Path, archive: Path, date: str, config: Config | None = None) -> list[Path]:
    """Write every finished run of the export (``runs.csv``, ``evaluations.csv`` of the comparison made with
    ``config``, default the full protocol) into the archive folder as a run file (a run already there is
    kept); ``date`` (ISO 8601) stands for the times the export does not keep. Return the files."""
    config = config or Config(full=True)
    evaluations: dict[int, list[dict[str, Any]]] = defaultdict(list)
    for row in read_csv(export / "evaluations.csv"):
        evaluations[int(row["run"])].append(row)
    paths = []
    for line in read_csv(export / "runs.csv"):
        if line["status"] != DONE:
            continue
        prepared = _prepare(config, line["optimizer"], line["problem"], int(line["seed"]))
        if prepared.identity is None:
            raise ValueError(f"{line['optimizer']} on {line['problem']} cannot run here: {prepared.note}")
        space = prepared.space
        run = {
            "run_id": int(line["run"]), **prepared.identity._asdict(), "created_at": date,
            "finished_at": date, "stop_reason": line["stop_reason"],
        }  # fmt: skip
        rows = []
        for row in sorted(evaluations[int(line["run"])], key=lambda r: int(r["index"])):
            x = [float(v) for v in row["x_m"].split()]
            sigma = None if math.isnan(float(row["sigma_N"])) else float(row["sigma_N"])
            feasible = bool(int(row["feasible"]))
            rows.append(
                {
                    "idx": int(row["index"]), "problem": space.store_key,
                    "design_key": ",".join(str(int(k)) for k in space.design_key(x)),
                    "speed_kmh": SPEED_KMH, "fidelity": config.fidelity, "source": EXPORT_SOURCE,
                    "x": json.dumps(x), "feasible": int(feasible), "sigma": sigma,
                    "reason": "" if feasible else REASON, "wall_time": float(row["wall_time_s"]),
                    "cached": int(row["cached"]), "charged": int(row["charged"]), "reward": None,
                    "created_at": date, "constraints": None, "statistics": None,
                }
            )  # fmt: skip
        if [r["idx"] for r in rows] != list(range(len(rows))):
            raise ValueError(f"{export}: run {line['run']} has gaps in its evaluations")
        paths.append(write_run_file(archive, run, rows))
    return paths


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.archive_from_export", description=__doc__)
    parser.add_argument("export", type=Path, help="the export's folder (runs.csv, evaluations.csv)")
    parser.add_argument("archive", type=Path, help="the run archive's folder")
    parser.add_argument("--date", required=True, help="ISO 8601 time standing for the runs' own times")
    args = parser.parse_args(argv)
    paths = archive_from_export(args.export, args.archive, args.date)
    print(f"{len(paths)} finished run(s) of {args.export} in {args.archive}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
