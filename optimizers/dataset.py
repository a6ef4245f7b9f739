"""A run store as a dataset of evaluated designs: one Parquet file per problem and model, and a datasheet
(``catenary export STORE OUT``; ``pip install catenary-env[dataset]`` for pyarrow).

Parquet, because it is the columnar format the tools of surrogate modelling read directly (pandas,
polars, pyarrow, DuckDB, Spark, R's arrow) with the column types kept, and pyarrow is an optional
extra: the export is the only thing that needs it. Each row is one evaluation of a run, in the order
the run asked for it; ``cached = false`` rows are the simulations themselves (one per design, speed and
fidelity in a store), ``cached = true`` rows repeat a design another run (or the same run) simulated.

Columns: ``run_id``, ``optimizer``, ``seed``, ``index`` (in the run), ``problem``, ``model`` (the fingerprint
of the model: definitions, fidelities and simulator, :mod:`catenary_env.fingerprint`), one column per
design variable (m), ``speed_kmh``, ``fidelity``, ``feasible``, ``reason``, ``sigma_N`` (σ of the 20 Hz
filtered contact force; null where no passage was simulated), one column per constraint value
(feasible when all are <= 0; null where not computed or not stored), one column per statistic of the
contact force (``mean_stat``, ``std_stat`` (σ again), ``statistical_max_stat``, ... in N,
``contact_loss_percent_stat`` in %, ``max_support_uplift_stat`` in m; null where not simulated, or stored
before the run store kept them), ``wall_time_s``, ``cached``,
``charged``, ``source`` (``simulation``; ``env`` for an RL run's env steps; ``export`` for a row rebuilt
from a results export, :data:`optimizers.store.EXPORT_SOURCE`), ``reward`` (RL runs),
``package_version``, ``created_at``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from catenary_env.errors import MissingDependency, UnknownNameError

from .problem import constraint_names, statistic_names
from .problem_registry import resolve_problem
from .store import RunStore

__all__ = ["DATASHEET", "export_store"]

DATASHEET = "DATASHEET.md"
"""The datasheet's file name in the output folder."""


def _names(problem: str, sizes: Sequence[int]) -> list[list[str]]:
    """The variables', constraints' and statistics' column names of a problem (generic ones where the
    problem is unknown here or gives another number of values)."""
    try:
        grid_problem = resolve_problem(problem)
        known = [list(grid_problem.variable_names), list(constraint_names(grid_problem))]
        known.append([f"{name}_stat" for name in statistic_names(grid_problem)])
    except UnknownNameError:
        known = [[], [], []]
    prefixes = ("x", "constraint", "statistic")
    return [
        names if len(names) == size else [f"{prefix}_{i}" for i in range(size)]
        for names, size, prefix in zip(known, sizes, prefixes, strict=True)
    ]


def _optional(names: list[str], stored: Sequence[float]) -> dict[str, float | None]:
    """Values by name, None where not stored or not computed (NaN)."""
    values = list(stored) or [None] * len(names)
    return {n: None if v is None or math.isnan(v) else float(v) for n, v in zip(names, values, strict=True)}


def _table(rows: Sequence[dict[str, Any]], problem: str, model: str) -> dict[str, list[Any]]:
    sizes = [max(len(r[key]) for r in rows) for key in ("x", "constraints", "statistics")]
    variables, constraints, statistics = _names(problem, sizes)
    names = ["run_id", "optimizer", "seed", "index", "problem", "model", *variables, "speed_kmh", "fidelity",
             "feasible", "reason", "sigma_N", *constraints, *statistics, "wall_time_s", "cached", "charged",
             "source", "reward", "package_version", "created_at"]  # fmt: skip
    columns: dict[str, list[Any]] = {name: [] for name in names}
    for r in rows:
        values = {"run_id": r["run_id"], "optimizer": r["optimizer"], "seed": r["seed"], "index": r["idx"],
                  "problem": problem, "model": model, "speed_kmh": r["speed_kmh"], "fidelity": r["fidelity"],
                  "feasible": bool(r["feasible"]), "reason": r["reason"], "sigma_N": r["sigma"],
                  "wall_time_s": r["wall_time"], "cached": bool(r["cached"]), "charged": bool(r["charged"]),
                  "source": r["source"], "reward": r["reward"], "package_version": r["package_version"],
                  "created_at": r["created_at"]}  # fmt: skip
        values.update(zip(variables, r["x"], strict=True))
        values.update(_optional(constraints, r["constraints"]))
        values.update(_optional(statistics, r["statistics"]))
        for name, column in columns.items():
            column.append(values[name])
    return columns


def export_store(store: str | Path, out: str | Path) -> list[Path]:
    """Write every evaluation of a run store to ``out/PROBLEM@MODEL.parquet`` and ``out/DATASHEET.md``;
    return the Parquet files' paths.

    Raises
    ------
    MissingDependency
        pyarrow is not installed.
    StoreError
        ``store`` is not a run store.
    """
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError as error:
        raise MissingDependency(
            "catenary export writes Parquet: pip install catenary-env[dataset]"
        ) from error
    with RunStore(store, read_only=True) as opened:
        rows = opened.all_evaluations()
    by_problem: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        by_problem.setdefault(str(row["problem"]), []).append(row)
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for key, chosen in by_problem.items():
        problem, _, model = key.partition("@")
        path = folder / f"{key.replace('@', '_')}.parquet"
        pq.write_table(pa.table(_table(chosen, problem, model)), path)
        paths.append(path)
    (folder / DATASHEET).write_text(datasheet(store, by_problem), encoding="utf-8")
    return paths


def datasheet(store: str | Path, by_problem: dict[str, list[dict[str, Any]]]) -> str:
    """The datasheet of an export: what it holds, how it was made, how to cite the model."""
    lines = []
    for key, rows in by_problem.items():
        simulated = [r for r in rows if not r["cached"]]
        feasible = sum(bool(r["feasible"]) for r in simulated)
        problem, _, model = key.partition("@")
        lines.append(f"| {problem} | {model or '–'} | {len(rows)} | {len(simulated)} | {feasible} |")
    counts = "\n".join(lines)
    return f"""# Datasheet: evaluated catenary designs

## What
Every evaluation stored in the run store `{Path(store).name}`: designs of the catenary design problems of
catenary-env (docs/problems.md), each simulated by the finite element model of the pantograph-catenary
interaction (docs/model.md): its variables (m), σ of the 20 Hz filtered contact force (N), the feasibility
constraint values (feasible when all are <= 0: the largest dropper compression at equilibrium in N, the
largest dropper-length shortfall in m and the contact-loss share in %), feasibility and its reason, the
other statistics of the contact force, the speed (km/h), the model fidelity and the model's fingerprint.
Columns: see `optimizers/dataset.py`.

| problem | model | rows | simulations (`cached = false`) | feasible simulations |
|---|---|---|---|---|
{counts}

## How it was made
By optimisation runs (`catenary optimize`, the studies of `catenary experiment`): the designs are what the
optimisers asked for, so they cluster around good designs and are not a uniform sample of the design
space; `optimizer` and `seed` say which run asked. A row with `cached = true` repeats an earlier
simulation of the same design (same σ). Rows of two models (another `model` fingerprint) are never
comparable: the files are split by model. Written by `catenary export`.

## Uses and limits
Surrogate models of σ and of feasibility, benchmarks of optimisers on recorded data. σ comes from the
fidelity named in each row (`study`: the span-mode model of 20 spans; `test`: a coarse model for unit
tests, not for design conclusions; docs/performance.md, 'Model fidelities'). The other statistics of the
contact force (the columns ending `_stat`) are empty in rows stored before the run store kept them.

## How to cite
Cite catenary-env (the repository and its version, the `package_version` column) and the model it
implements (docs/model.md, 'References'), and give the `model` fingerprint of the rows you used.
"""
