"""Benchmark: one evaluation as the studies run it, this checkout against another commit (docs/performance.md,
'Speed').

The speed targets compare this code's study evaluation (``evaluate``: a preset's level design at 300 km/h,
study fidelity, a fixed uplift force) with an earlier commit's, measured in the same run. This script checks
the earlier commit out into a temporary git worktree, then times the evaluation in alternate processes, one
of this checkout and one of that commit, ``--rounds`` times each, ``--evaluations`` evaluations in each
(after one untimed, which also compiles the commit's numba cache the first time). It prints each process's
median (wall clock and CPU time), the ratio of the medians round by round, and σ of both, which must agree
to rounding (else the two commits are different models, and the ratio compares unlike things).

    python benchmarks/bench_against.py e91dc2e^                   # the second speed step's baseline
    python benchmarks/bench_against.py HEAD~3 --presets benchmark --rounds 5
    python benchmarks/bench_against.py e91dc2e^ --one-blas-thread # both with OPENBLAS_NUM_THREADS=1
    python benchmarks/bench_against.py e91dc2e^ --design optimum  # the design studies' optima

``--design optimum`` evaluates, instead of each preset's level design, the best-known design of its design
problem (B1 on the benchmark catenary, SW1 on the stitched one, found by the design studies): the kind of
design an optimiser evaluates late in a run, whose droppers are often slack (B1's optimum some 13 slack
droppers a step, the level design 1.4), which the level design does not show.

Both run in the caller's environment: an old commit that let numpy's BLAS start a thread per core runs so
here too, as it did for its users; ``--one-blas-thread`` gives both one BLAS thread. The CPU time counts
every thread's, so the wall clock's ratio is the one to quote. Quote medians and ratios: the machines are
shared and noisy, and their speed drifts from hour to hour.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ONE_THREAD = {name: "1" for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}


OPTIMUM_PROBLEMS = {"benchmark": "B1", "stitched": "SW1"}
"""The design problem whose best-known design ``--design optimum`` evaluates on each preset."""


def optimum(preset: str) -> list[list[float]]:
    """The dropper positions and contact-wire offsets (m) of the best-known design of ``preset``'s problem,
    as this checkout has it."""
    from catenary_env.problems import get_problem

    problem = get_problem(OPTIMUM_PROBLEMS[preset])
    design = problem.design(problem.best_known.x)
    return [list(design.dropper_positions), list(design.contact_wire_offsets)]


def child(preset: str, evaluations: int, design_json: str) -> None:
    """In a timed process: the study evaluation of ``preset``'s level design (``design_json`` "level") or of
    the design given (its dropper positions and offsets, m), once untimed, then ``evaluations`` times; prints
    one JSON line. Uses only what every commit since the span-mode model has."""
    import catenary_env
    from catenary_env.model.design import Design, level_design
    from catenary_env.model.presets import load_catenary, load_pantograph
    from catenary_env.pipeline import Fidelity, evaluate

    catenary = load_catenary(preset)
    pantograph = load_pantograph(catenary.pantograph)
    given = json.loads(design_json)

    def one() -> float:
        design = level_design(catenary) if given == "level" else Design(*map(tuple, given))
        return evaluate(catenary, pantograph, design, 300 / 3.6, Fidelity(), 170.0).statistics.std

    one()
    wall, cpu = [], []
    for _ in range(evaluations):
        start = time.perf_counter(), time.process_time()
        sigma = one()
        wall.append(time.perf_counter() - start[0])
        cpu.append(time.process_time() - start[1])
    package = str(Path(catenary_env.__file__).resolve().parent.parent)
    out = {"wall": statistics.median(wall), "cpu": statistics.median(cpu), "sigma": sigma, "package": package}
    print(json.dumps(out))


def timed(tree: Path, preset: str, args: argparse.Namespace) -> dict[str, float | str]:
    """One process of ``tree``'s code: its medians and σ."""
    env = dict(os.environ, PYTHONPATH=str(tree), **(ONE_THREAD if args.one_blas_thread else {}))
    design = json.dumps("level" if args.design == "level" else optimum(preset))
    command = [sys.executable, __file__, "--child", preset, str(args.evaluations), design]
    done = subprocess.run(command, env=env, cwd=tree, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"the evaluation in {tree} failed:\n{done.stderr[-2000:]}")
    result = json.loads(done.stdout.splitlines()[-1])
    if Path(result["package"]) != tree.resolve():  # an installed copy shadowed the tree
        raise RuntimeError(f"the process imported catenary_env from {result['package']}, not from {tree}")
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("baseline", nargs="?", help="the commit to compare with (any git revision)")
    parser.add_argument(
        "--presets", nargs="+", default=["benchmark", "stitched"], help="catenary presets (default: both)"
    )
    parser.add_argument("--rounds", type=int, default=3, help="processes of each commit (default 3)")
    parser.add_argument("--evaluations", type=int, default=5, help="timed evaluations a process (default 5)")
    parser.add_argument("--one-blas-thread", action="store_true", help="both with one BLAS thread")
    parser.add_argument(
        "--design",
        choices=["level", "optimum"],
        default="level",
        help="each preset's level design (default) or its design problem's best-known one",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON summary")
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child[0], int(args.child[1]), args.child[2])
        return 0
    if args.baseline is None:
        parser.error("baseline: give the commit to compare with, e.g. e91dc2e^")
    if args.rounds < 1 or args.evaluations < 1:
        parser.error("--rounds and --evaluations: must be at least 1")
    git = ["git", "-C", str(ROOT)]
    found = subprocess.run([*git, "rev-parse", "--verify", "--quiet", f"{args.baseline}^{{commit}}"],
                           capture_output=True, text=True)  # fmt: skip
    if found.returncode != 0:
        parser.error(f"baseline: {args.baseline!r} is not a commit of {ROOT}")
    commit = found.stdout.strip()
    with tempfile.TemporaryDirectory() as folder:
        baseline = Path(folder) / "baseline"
        subprocess.run([*git, "worktree", "add", "--detach", "--quiet", str(baseline), commit], check=True)
        try:
            trees = {"this checkout": ROOT, f"baseline {commit[:10]}": baseline}
            runs: dict[tuple[str, str], list[dict]] = {}
            for _ in range(args.rounds):
                for preset in args.presets:
                    for name, tree in trees.items():
                        runs.setdefault((preset, name), []).append(timed(tree, preset, args))
        finally:
            subprocess.run([*git, "worktree", "remove", "--force", str(baseline)], check=False)
    summary = {}
    for preset in args.presets:
        this, base = (runs[preset, name] for name in trees)
        summary[preset] = {
            "this_wall": [r["wall"] for r in this],
            "baseline_wall": [r["wall"] for r in base],
            "ratio_wall": [a["wall"] / b["wall"] for a, b in zip(this, base, strict=True)],
            "ratio_cpu": [a["cpu"] / b["cpu"] for a, b in zip(this, base, strict=True)],
            "sigma": [this[0]["sigma"], base[0]["sigma"]],
        }
    if args.json:
        print(json.dumps({"baseline": commit, "one_blas_thread": args.one_blas_thread, "design": args.design,
                          "presets": summary}))  # fmt: skip
        return 0
    threads = "one BLAS thread each" if args.one_blas_thread else "the caller's environment"
    which = "level design" if args.design == "level" else "best-known design of B1 / SW1"
    print(f"evaluate ({which}, 300 km/h, study fidelity, 170 N): this checkout against {commit[:10]}, "
          f"{args.rounds} alternate processes of each, median of {args.evaluations} evaluations in each, "
          f"{threads}")  # fmt: skip
    for preset, row in summary.items():
        ratios = sorted(row["ratio_wall"])
        this, base = (" ".join(f"{t:.3f}" for t in row[key]) for key in ("this_wall", "baseline_wall"))
        print(f"  {preset}: {this} s against {base} s; ratio {ratios[0]:.2f}-{ratios[-1]:.2f}, median "
              f"{statistics.median(ratios):.2f} (CPU {statistics.median(row['ratio_cpu']):.2f}); "
              f"σ {row['sigma'][0]:.6f} and {row['sigma'][1]:.6f} N")  # fmt: skip
    return 0


if __name__ == "__main__":
    try:
        raise SystemExit(main())
    except KeyboardInterrupt:
        print("bench_against: interrupted", file=sys.stderr)
        raise SystemExit(130) from None
