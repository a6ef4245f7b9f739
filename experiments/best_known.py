"""The best-known design of each problem, from the committed results (docs/problems.md, 'Best-known
designs'): writes ``catenary_env/problems/best_known.json`` (read by ``problem.best_known``) and
``results/best_known.md``.

Per problem with variables, the lowest feasible σ of every evaluation recorded at the study fidelity and
300 km/h, in the design studies' GA histories (``results/design/PROBLEM/history.csv``) and the runs of the
optimiser comparisons (:data:`COMPARISONS`: the five-seed one and the full protocol, finished runs only,
``evaluations.csv``), whose model stamps must be today's model (:mod:`experiments.model_stamp`); the design
is then simulated on the exact model (the ``reference`` fidelity, about 3 s a problem) to confirm it.

    python -m experiments.best_known [--results results]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path
from typing import Any

from catenary_env.errors import UsageError
from catenary_env.fingerprint import simulator_fingerprint
from catenary_env.problems import get_problem
from catenary_env.problems.best_known import TABLE, BestKnown, best_known_table

from .common import DEFAULT_OUT, markdown_table, read_csv, run_cli
from .model_stamp import ModelStamp

PROBLEMS = ("B1", "B2", "B3", "SW1", "SW2", "SW3")
SPEED_KMH = 300.0
FIDELITY = "study"
COMPARISONS = ("optimizers", "full-protocol/optimizers")
"""The optimiser comparisons' folders under the results folder: the five-seed comparison and the full
protocol (docs/problems.md, 'Reading the comparison')."""


def candidates(results: Path, problem: str) -> list[tuple[float, tuple[float, ...], str]]:
    """Every feasible (σ, design, which run) of a problem in the committed results."""
    found = []
    history = results / "design" / problem / "history.csv"
    if history.exists():
        names = get_problem(problem).variables
        for row in read_csv(history):
            if int(row["feasible"]):
                x = tuple(float(row[name]) for name in names)
                where = (
                    f"design study GA ({history.relative_to(results.parent)}, evaluation {int(row['index'])})"
                )
                found.append((float(row["sigma_N"]), x, where))
    for folder in COMPARISONS:
        comparison = results / folder / "evaluations.csv"
        if not comparison.exists():
            continue
        for row in read_csv(comparison):
            if row["problem"] == problem and int(row["feasible"]):
                x = tuple(float(v) for v in str(row["x_m"]).split())
                where = (
                    f"optimiser comparison {row['optimizer']} seed {int(row['seed'])} "
                    f"({results.name}/{folder}, run {int(row['run'])}, evaluation {int(row['index'])})"
                )
                found.append((float(row["sigma_N"]), x, where))
    return found


def best_known(results: Path, problem: str) -> BestKnown | None:
    """The best-known design of ``problem`` from the results, confirmed on the exact model."""
    found = candidates(results, problem)
    if not found:
        return None
    sigma, x, where = min(found, key=lambda c: c[0])
    design_problem = get_problem(problem)
    key = (x, design_problem.store_fingerprint(), simulator_fingerprint())
    recorded = best_known_table().get(problem)
    if recorded is not None and (recorded.x, recorded.model_fingerprint, recorded.simulator) == key:
        # Confirmed before: not again (another processor's rounding would rewrite the table).
        return dataclasses.replace(recorded, sigma_N=sigma, found_by=where)
    confirmed = design_problem.evaluate(x, SPEED_KMH, "reference")
    if not confirmed.feasible or confirmed.statistics is None:
        raise RuntimeError(f"{problem}: the best-known design {x} is infeasible on the exact model")
    return BestKnown(
        problem, sigma, x, SPEED_KMH, FIDELITY, key[1], key[2], where, float(confirmed.statistics.std),
        "reference",
    )  # fmt: skip


def check_stamps(results: Path) -> None:
    """Refuse results made by another model than today's."""
    for study in ("design", *COMPARISONS):
        stamp = ModelStamp.read(results / study)
        if stamp is not None and not stamp.is_current():
            raise UsageError(f"{results / study}: made by another model (model.json); rerun the study first")


def main(results: Path) -> Path:
    check_stamps(results)
    table = [best for best in (best_known(results, p) for p in PROBLEMS) if best is not None]
    TABLE.write_text(json.dumps([dataclasses.asdict(b) for b in table], indent=1) + "\n", encoding="utf-8")
    best_known_table.cache_clear()
    (results / "best_known.md").write_text(report(table) + "\n", encoding="utf-8")
    return TABLE


def report(table: list[BestKnown]) -> str:
    """The Markdown table of the best-known designs."""
    rows: list[dict[str, Any]] = [
        {
            **dataclasses.asdict(b),
            "design": ", ".join(
                f"{n} = {v:g}" for n, v in zip(get_problem(b.problem).variables, b.x, strict=True)
            ),
        }
        for b in table
    ]
    return markdown_table(
        rows,
        [
            ("problem", "problem", "s"),
            ("sigma_N", "best-known σ (N, study model)", ".3f"),
            ("confirmed_sigma_N", "σ on the exact model (N)", ".3f"),
            ("design", "design (m)", "s"),
            ("found_by", "found by", "s"),
            ("model_fingerprint", "model", "s"),
        ],
    )


def cli(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m experiments.best_known", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "--results", type=Path, default=DEFAULT_OUT, help="the results folder (default: results)"
    )
    args = parser.parse_args(argv)
    print(main(args.results))
    return 0


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.best_known"))
