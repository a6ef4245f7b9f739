"""Optimisation runs in the IOHprofiler format, for IOHanalyzer (docs/problems.md, 'Experiments').

The layout is that of the ``ioh`` package's ``logger.Analyzer`` (IOHexperimenter 0.3, its JSON "v2"
format), written here without ``ioh``, which the project does not depend on. Per algorithm, a folder::

    ALGORITHM/IOHprofiler_f{FID}_{PROBLEM}.json
    ALGORITHM/data_f{FID}_{PROBLEM}/IOHprofiler_f{FID}_DIM{N}.dat

The JSON holds the problem, the algorithm and one entry per run: ``instance``, ``evals`` (the run's
length), ``best`` (``evals``, ``y``, ``x`` of its best point) and the run attribute ``seed``. The ``.dat``
file holds one block per run, in the JSON's order: a header line ``evaluations raw_y``, then a line
``E Y`` for every evaluation ``E`` = 1, 2, ... of the run (``Y`` its σ, ten decimals), as the Analyzer
logger writes with the trigger ``ALWAYS``. IOH's readers (IOHanalyzer, ``iohinspector``) find the runs of a
file by their first evaluation being 1, so every run's block starts at evaluation 1.

What is mapped how:

- *evaluation* = a simulation charged to the run (docs/problems.md, 'Optimisers': the first evaluation of
  each distinct design); a free repeat of a design is not an evaluation;
- *raw_y* = σ of the contact force, N, minimised (``"maximization": false``);
- an infeasible design (statically infeasible: no σ; or contact lost) is logged with
  ``raw_y`` = :data:`INFEASIBLE_Y` = 10⁶ N, the penalty the nevergrad optimisers are told, above any σ:
  the best-so-far curve IOHanalyzer computes is then the run's best feasible σ, and "no feasible design
  yet" reads as 10⁶ N; a run that found no feasible design is logged too (its best is 10⁶ N), so that
  every run is in the files;
- *function id* = the problem's place in ``catenary_env.problems.PROBLEMS`` from 1 (B1 is 2, SW1 is 6; the
  synthetic problems of ``optimizers/synthetic.py`` follow them);
  *instance* = 1 for every run (the problem has no random instances); the seed is a run attribute.

Examples
--------
>>> run = IOHRun(seed=0, evaluations=((1, None, ()), (2, 41.5, (0.0,)), (3, 40.0, (0.001,))))
>>> evaluation_lines(run)
[(1, 1000000.0), (2, 41.5), (3, 40.0)]
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "FORMAT_VERSION",
    "INFEASIBLE_Y",
    "IOHRun",
    "evaluation_lines",
    "read_dat",
    "write_algorithm",
]

FORMAT_VERSION = "0.3.22"
"""The ``ioh`` release whose Analyzer output this layout was checked against (its ``version`` field)."""

SUITE = "catenary-env"

INFEASIBLE_Y = 1.0e6
"""``raw_y`` of an infeasible evaluation, N (optimizers.nevergrad_adapters.INFEASIBLE_LOSS)."""


@dataclass(frozen=True)
class IOHRun:
    """One run, as IOHprofiler sees it.

    Attributes
    ----------
    seed : int
        The run's seed (a run attribute).
    evaluations : tuple of (int, float or None, tuple of float)
        Per simulation charged, in order: its number from 1, its σ (N; None when infeasible) and the design
        variables (m).
    """

    seed: int
    evaluations: tuple[tuple[int, float | None, tuple[float, ...]], ...]


def evaluation_lines(run: IOHRun) -> list[tuple[int, float]]:
    """The ``(evaluations, raw_y)`` lines of a run: every evaluation, an infeasible one at
    :data:`INFEASIBLE_Y`."""
    return [(number, INFEASIBLE_Y if sigma is None else sigma) for number, sigma, _ in run.evaluations]


def _best(run: IOHRun) -> tuple[int, float, tuple[float, ...]]:
    number, y, x = min(((n, s if s is not None else INFEASIBLE_Y, x) for n, s, x in run.evaluations),
                       key=lambda e: (e[1], e[0]))  # fmt: skip
    return number, float(y), x


def write_algorithm(
    root: Path,
    algorithm: str,
    info: str,
    function_id: int,
    problem: str,
    dimension: int,
    runs: Sequence[IOHRun],
    attributes: dict[str, str] | None = None,
) -> Path | None:
    """Write one algorithm's runs on one problem under ``root/algorithm``; return the JSON's path (None,
    and nothing written, without a run that has an evaluation)."""
    kept = [run for run in runs if run.evaluations]
    if not kept:
        return None
    folder = Path(root) / algorithm
    data_dir = f"data_f{function_id}_{problem}"
    data_name = f"IOHprofiler_f{function_id}_DIM{dimension}.dat"
    (folder / data_dir).mkdir(parents=True, exist_ok=True)
    blocks = []
    entries = []
    for run in kept:
        blocks.append("evaluations raw_y\n" + "".join(f"{e} {y:.10f}\n" for e, y in evaluation_lines(run)))
        number, sigma, x = _best(run)
        entries.append(
            {
                "instance": 1,
                "evals": int(run.evaluations[-1][0]),
                "best": {"evals": int(number), "y": sigma, "x": [float(v) for v in x]},
                "seed": int(run.seed),
            }
        )
    (folder / data_dir / data_name).write_text("".join(blocks), encoding="utf-8")
    meta: dict[str, object] = {
        "version": FORMAT_VERSION,
        "suite": SUITE,
        "function_id": int(function_id),
        "function_name": problem,
        "maximization": False,
        "algorithm": {"name": algorithm, "info": info},
    }
    if attributes:
        meta["experiment_attributes"] = [{key: str(value)} for key, value in attributes.items()]
    meta["run_attributes"] = ["seed"]
    meta["attributes"] = ["evaluations", "raw_y"]
    meta["scenarios"] = [{"dimension": int(dimension), "path": f"{data_dir}/{data_name}", "runs": entries}]
    path = folder / f"IOHprofiler_f{function_id}_{problem}.json"
    path.write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    return path


def read_dat(path: Path) -> list[list[tuple[int, float]]]:
    """The runs of a ``.dat`` file: per block, its ``(evaluations, raw_y)`` lines.

    Raises
    ------
    ValueError
        A line before the first header, a header other than ``evaluations raw_y``, or a line that is not
        an integer and a number.
    """
    runs: list[list[tuple[int, float]]] = []
    for number, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), start=1):
        fields = line.split()
        if not fields:
            continue
        if not fields[0][0].isdigit():
            if fields != ["evaluations", "raw_y"]:
                raise ValueError(f"{path}:{number}: header {line!r}, expected 'evaluations raw_y'")
            runs.append([])
            continue
        if not runs or len(fields) != 2:
            raise ValueError(f"{path}:{number}: {line!r} is not a line 'evaluations raw_y' of a run")
        runs[-1].append((int(fields[0]), float(fields[1])))
    return runs


def runs_from_rows(rows: Iterable[dict[str, object]]) -> dict[int, IOHRun]:
    """IOH runs by seed from tidy evaluation rows (``seed``, ``simulation``, ``charged``, ``feasible``,
    ``sigma_N``, ``x_m``): only the charged evaluations count."""
    per_seed: dict[int, list[tuple[int, float | None, tuple[float, ...]]]] = {}
    for row in rows:
        if not int(float(str(row["charged"]))):
            continue
        sigma = float(str(row["sigma_N"])) if int(float(str(row["feasible"]))) else None
        x = tuple(float(v) for v in str(row["x_m"]).split())
        per_seed.setdefault(int(float(str(row["seed"]))), []).append(
            (int(float(str(row["simulation"]))), sigma, x)
        )
    return {seed: IOHRun(seed, tuple(sorted(evals))) for seed, evals in sorted(per_seed.items())}
