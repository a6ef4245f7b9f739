"""Benchmark: the simulations a second a user's optimisation delivers (docs/performance.md, 'Threads').

Runs the command a user runs, ``catenary optimize B1 --optimizer cma --budget 300 --workers 2`` (the target:
6 simulations/s or more on the 2-core machine), as a whole process with a fresh run store, and the same
command on one worker as the baseline, alternately, ``--runs`` times each. Prints for each the median rate
(simulations over the command's wall time, start-up included: what the user waits for), the median time of
a feasible design inside a worker, and the ratio of the two rates. On two cores that ratio is about 2 when
nothing oversubscribes them; with numpy's default of one BLAS thread per core in every worker it was
about 1.1.

    python benchmarks/bench_throughput.py                       # B1, cma, 300 simulations, 3 runs each
    python benchmarks/bench_throughput.py --budget 100 --runs 1 --problem SW1

The problem's uplift calibration is made once before the clock starts (it is kept on disk, as a user's
second run finds it). Quote medians and ratios: the machines are shared and noisy.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def optimize(args: argparse.Namespace, workers: int, store: Path) -> dict[str, float]:
    """Run ``catenary optimize`` once; its rate (simulations/s of wall time) and median design time, s."""
    command = [
        sys.executable, "-m", "catenary_env.cli", "optimize", args.problem,
        "--optimizer", args.optimizer, "--budget", str(args.budget), "--seed", str(args.seed),
        "--workers", str(workers), "--store", str(store), "--json", "--quiet",
    ]  # fmt: skip
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    history = json.loads(done.stdout)["history"]
    simulated = [entry for entry in history if entry["charged"] and not entry["cached"]]
    feasible = [entry["wall_time"] for entry in simulated if entry["feasible"]]
    return {
        "wall": wall,
        "simulations": len(simulated),
        "rate": len(simulated) / wall,
        "design_time": statistics.median(feasible) if feasible else float("nan"),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problem", default="B1", help="design problem (default: B1)")
    parser.add_argument("--optimizer", default="cma", help="optimiser (default: cma)")
    parser.add_argument("--budget", type=int, default=300, help="simulations a run (default: 300)")
    parser.add_argument("--seed", type=int, default=0, help="the runs' seed (default: 0)")
    parser.add_argument("--workers", type=int, default=2, help="workers of the timed command (default: 2)")
    parser.add_argument("--runs", type=int, default=3, help="runs of each command (default: 3)")
    parser.add_argument("--json", action="store_true", help="print one JSON summary")
    args = parser.parse_args()

    from catenary_env.problems import PROBLEMS

    PROBLEMS[args.problem].uplift_force()  # the calibration, kept on disk: not timed
    results: dict[int, list[dict[str, float]]] = {args.workers: [], 1: []}
    with tempfile.TemporaryDirectory() as folder:
        for run in range(args.runs):
            for workers in results:
                store = Path(folder) / f"run-{workers}-{run}.sqlite"
                results[workers].append(optimize(args, workers, store))
    summary = {
        str(workers): {key: statistics.median(r[key] for r in runs) for key in runs[0]}
        for workers, runs in results.items()
    }
    ratio = summary[str(args.workers)]["rate"] / summary["1"]["rate"]
    if args.json:
        print(json.dumps({"medians": summary, "ratio": ratio, "runs": args.runs}, indent=1))
        return 0
    print(f"catenary optimize {args.problem} --optimizer {args.optimizer} --budget {args.budget}, medians of "
          f"{args.runs} runs:")  # fmt: skip
    for workers, row in summary.items():
        print(
            f"  --workers {workers}: {row['rate']:.2f} simulations/s ({row['simulations']:.0f} in "
            f"{row['wall']:.1f} s), a feasible design {row['design_time']:.3f} s inside a worker"
        )
    print(f"  ratio of the rates, {args.workers} workers to 1: {ratio:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
