"""Study 4: which optimiser finds the smoothest design with the fewest simulations (docs/problems.md,
'Experiments').

The published study's GA, nevergrad's CMA-ES, DE, PSO, random search and NGOpt, Optuna's TPE and Gaussian
process, and the PPO design policy (and any optimiser an installed package plugs in), at 300 km/h, each with
the same budget of simulations and several seeds. Every run goes to one
run store (the studies' shared ``runs.sqlite`` in the output folder, or ``Config.store``) and is resumed
from it: a study run again, or interrupted and restarted, reads back the runs that finished (without
replaying their optimiser), resumes the others (their stored evaluations replayed, only what is missing
simulated), and a design simulated by one run is served to the others from the store's cache (it is still
charged to each run's budget, so that a run's result does not depend on what else the store holds).

Outputs (``results/optimizers/``):

- ``evaluations.csv``: every evaluation of every run (run, optimizer, problem, seed, index, the number of
  the simulation it belongs to, σ, feasible, charged, cached, the seconds the run spent on it and the
  seconds its simulation took wherever it was made, the design);
- ``runs.csv``: one line per run, and a line "not run" with the reason for an optimiser that cannot run
  here; ``reference.csv``: σ of each problem's reference design;
- ``optimizers.md`` and ``summary.csv``: per problem and optimiser, the final σ (median, inter-quartile
  range, best), the runs that came within 2 % of the best σ any run found and the simulations they
  needed, the share of infeasible proposals and the simulation time per run;
- ``convergence.png``: best σ so far against simulations, median and inter-quartile band per optimiser,
  one panel per problem;
- ``ioh/``: the runs in the IOHprofiler format, for IOHanalyzer (:mod:`experiments.iohprofiler`).

Settings. Full (the protocol of docs/problems.md, 'Reading the comparison'): the six problems with variables,
the study fidelity, 300 simulations a run, 15 seeds on B1 and SW1 and 10 on the others, the GA's population of
docs/problems.md ('Optimisers'), nevergrad's batches of 8, PPO as in :mod:`experiments.rl_studies`
(rollouts of 32 steps, the policy starting at the reference design with a spread of 4 mm). Quick: the
"test" fidelity, 12 simulations a run, 2 seeds, a GA population of 6 and PPO rollouts of 8 steps (a smoke
test of the machinery, not a comparison).

NGOpt: with nevergrad 1.0.12 and numpy >= 2.3 NGOpt fails where it selects a MetaModel optimiser
(:func:`optimizers.nevergrad_adapters.ngopt_fault`); on these integer grids it selects
DoubleFastGADiscreteOnePlusOne and runs. Where it cannot run, the study records it as "not run" with the
reason instead of failing.

With ``--from-store`` the study simulates nothing: it writes these files from the runs that finished in the
run store (read only, so the lanes of a protocol may be running into it), every other run of the protocol a
line "not run yet" of ``runs.csv`` with the simulations the store holds of it, and ``optimizers.md`` says
"Partial: N of M runs".

    python -m experiments.optimizer_comparison [--full] [--workers 2] [--out results] [--from-store]
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from catenary_env.problems import PROBLEMS as DESIGN_PROBLEMS
from optimizers.archive import archive_run, restore_runs, snapshot_run
from optimizers.base import OptimizationResult
from optimizers.ga import GAOptions
from optimizers.nevergrad_adapters import ngopt_fault
from optimizers.plugins import get_optimizer
from optimizers.problem import GridSpace
from optimizers.problem_registry import resolve_problem
from optimizers.recorder import finished_result
from optimizers.rl import policy_run_config
from optimizers.runner import optimize, run_config
from optimizers.store import EXPORT_SOURCE, RunConfig, RunStore, StoreError
from optimizers.synthetic import SYNTHETIC_PROBLEMS

from . import benchmark_views as bv
from .common import (
    DEFAULT_OUT,
    STORE,
    add_archive_option,
    add_full_option,
    add_out_option,
    add_store_option,
    add_workers_option,
    markdown_table,
    read_csv,
    run_cli,
    run_study,
    study_dir,
    write_csv,
)
from .design_evaluations import evaluate_designs, stored_outcome, study_problem
from .iohprofiler import runs_from_rows, write_algorithm
from .model_stamp import catenaries_of, stamp_study
from .rl_studies import check_starts_at_reference, policy_env, policy_options, train_policy

NAME = "optimizers"
PROBLEMS = ("B1", "SW1")
"""The problems of the quick setting."""
FULL_PROBLEMS = ("B1", "B2", "B3", "SW1", "SW2", "SW3")
"""The problems of the full protocol: every problem with variables (docs/problems.md, 'Reading the
comparison')."""
FULL_SEEDS = {"B1": 15, "SW1": 15}
"""Seeds per problem in the full protocol (:data:`FULL_OTHER_SEEDS` for the others)."""
FULL_OTHER_SEEDS = 10
OPTIMIZERS = ("ga", "cma", "de", "pso", "random", "ngopt", "tpe", "gp", "ppo")
SPEED_KMH = 300.0
TARGET = 0.02
"""Within 2 % of the best σ any run found on the problem."""
DE_POPULATION = 30
"""The size of nevergrad's DE first population here (its default, the "standard" population)."""
DONE, NOT_RUN, NOT_RUN_YET = "done", "not run", "not run yet"
"""The status of a run in ``runs.csv``: finished; cannot run here (the note says why); not finished in the
store when the results were written from it (``--from-store``: the note and ``n_simulations`` say what the
store holds of it)."""
ANOTHER_PROCESS = "being made by another process (another lane of the study)"
"""The note of a run that another process holds (:meth:`~optimizers.store.RunStore.claim`)."""


@dataclass(frozen=True)
class Config:
    """The study's settings (quick unless ``full``).

    Attributes
    ----------
    full : bool
        The full protocol: the study fidelity, 300 simulations a run, 15 seeds on B1 and SW1 and 10 on the
        other problems; else quick (2 seeds).
    out : Path
        The results folder; the study writes into ``out/optimizers``.
    workers : int
        Local worker processes for the simulations of a batch (PPO steps its env in this process).
    store : Path or None
        The run store; default ``out/runs.sqlite``, shared by the studies.
    problems : tuple of str or None
        The design problems compared (None: :data:`FULL_PROBLEMS` in full, :data:`PROBLEMS` quick); a
        synthetic problem (``optimizers/synthetic.py``) runs the study's
        machinery in microseconds an evaluation, with every optimiser but PPO (which needs a design env).
    optimizers : tuple of str
        The optimisers run (default all of :data:`OPTIMIZERS`). Two processes given disjoint sets share
        the work of one problem on two cores; the combined results come from one more run over all of
        them, which replays every run from the store.
    from_store : bool
        Write the results from the runs that finished in the run store, simulating nothing and starting or
        resuming no run (the store is only read: lanes may be running into it); every other run of the
        protocol is a line "not run yet" with the simulations the store holds of it.
    archive : Path or None
        A run archive (:mod:`optimizers.archive`): the runs it holds and the store does not are restored
        into the store first, and every run of the protocol that finished is written into it (if not there
        yet), so that a protocol lasting days can be committed as it goes and resumed on a fresh checkout;
        with ``from_store``, each run of the protocol still going is kept there as a snapshot.
    """

    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 1
    store: Path | None = None
    problems: tuple[str, ...] = None  # type: ignore[assignment]  (set in __post_init__)
    optimizers: tuple[str, ...] = OPTIMIZERS
    from_store: bool = False
    archive: Path | None = None

    def __post_init__(self) -> None:
        if self.problems is None:
            object.__setattr__(self, "problems", FULL_PROBLEMS if self.full else PROBLEMS)

    @property
    def fidelity(self) -> str:
        return "study" if self.full else "test"

    @property
    def budget(self) -> int:
        return 300 if self.full else 12

    @property
    def seeds(self) -> tuple[int, ...]:
        """The seeds of B1 and SW1 (the most of any problem)."""
        return self.seeds_for("B1")

    def seeds_for(self, problem: str) -> tuple[int, ...]:
        """The seeds of a problem's runs."""
        if not self.full:
            return (0, 1)
        return tuple(range(FULL_SEEDS.get(problem, FULL_OTHER_SEEDS)))

    def options(self, optimizer: str) -> Any:
        """The hyper-parameters of an optimiser in this setting."""
        if optimizer == "ga":
            return GAOptions() if self.full else GAOptions(population_size=6)
        if optimizer == "ppo":
            return policy_options(32 if self.full else 8)
        return get_optimizer(optimizer).options_class()  # its documented defaults, a plug-in's too


def main(config: Config) -> Path:
    folder = study_dir(config.out, NAME)
    store_path = config.store or Path(config.out) / STORE
    evaluation_rows: list[dict[str, Any]] = []
    run_rows: list[dict[str, Any]] = []
    reference_rows: list[dict[str, Any]] = []
    with _open_store(store_path, config.from_store) as store:
        if config.archive is not None:
            Path(config.archive).mkdir(parents=True, exist_ok=True)
            stamp_study(config.archive, catenaries_of(config.problems))  # the runs it will hold (its files)
        if config.archive is not None and not config.from_store:
            restored = restore_runs(store, config.archive)
            print(f"{restored} run(s) restored from {config.archive} into {store_path}", file=sys.stderr)
        for problem in config.problems:
            reference_rows += _reference_rows(store, config, problem)
            for optimizer in config.optimizers:
                for seed in config.seeds_for(problem):
                    run_row, rows = _protocol_run(store, config, optimizer, problem, seed)
                    run_rows.append(run_row)
                    evaluation_rows.extend(rows)
                    if rows and not config.from_store:
                        print(_run_line(run_row), file=sys.stderr, flush=True)
    write_csv(folder / "evaluations.csv", evaluation_rows)
    write_csv(folder / "runs.csv", run_rows)
    write_csv(folder / "reference.csv", reference_rows)
    stamp_study(folder, catenaries_of(config.problems))
    report(folder)
    return folder


def _open_store(path: Path, read_only: bool) -> RunStore:
    """The run store; read only with ``--from-store`` (runs may be writing into it), which needs one."""
    if read_only and not Path(path).is_file():
        raise StoreError(
            f"{path}: no run store here; --from-store writes the results of the runs a store holds"
        )
    return RunStore(path, read_only=read_only)


def _reference_rows(store: RunStore, config: Config, problem: str) -> list[dict[str, Any]]:
    """σ of the problem's reference design (simulated unless stored; with ``from_store``, none if not
    stored); none where the problem cannot express the reference design (B3, SW3)."""
    reference = study_problem(problem).reference_x()
    if reference is None:
        return []
    if config.from_store:
        outcome = stored_outcome(store, problem, reference, SPEED_KMH, config.fidelity)
        if outcome is None:
            return []
    else:
        (outcome,) = evaluate_designs(
            store, problem, [(reference, SPEED_KMH)], config.fidelity, config.workers
        )
    return [
        {"problem": problem, "speed_kmh": SPEED_KMH, "fidelity": config.fidelity, "sigma_N": outcome.sigma}
    ]


class _Prepared(NamedTuple):
    """A run of the protocol before it is made: its identity in the store (None: it cannot run here),
    the note of its line (why it cannot run), and its problem's grid."""

    identity: RunConfig | None
    note: str
    space: GridSpace


def _prepare(config: Config, optimizer: str, problem: str, seed: int) -> _Prepared:
    """The run's identity and note, or why it cannot run here; nothing is simulated."""
    space = GridSpace.from_problem(resolve_problem(problem))
    options = config.options(optimizer)
    if optimizer == "ppo":
        try:  # the policy starts at the reference design only where the bounds are centred on it
            check_starts_at_reference(problem)
        except ValueError as error:
            return _Prepared(None, str(error), space)
        identity = policy_run_config(
            policy_env(problem, config.fidelity, SPEED_KMH), space, config.budget, seed, options
        )
        return _Prepared(identity, "PPO, spread 4 mm around the reference design", space)
    spec = get_optimizer(optimizer)
    try:  # built once before the run, so that an optimiser that cannot run leaves no run in the store
        engine = spec.optimizer_class(space, config.budget, seed, options)  # type: ignore[call-arg]
    except (ImportError, RuntimeError) as error:
        return _Prepared(None, str(error), space)
    note = f"NGOpt selected {engine.selected_optimizer}" if optimizer == "ngopt" else ""
    identity = run_config(optimizer, space, config.budget, seed, SPEED_KMH, config.fidelity, options)
    return _Prepared(identity, note, space)


def _protocol_run(
    store: RunStore, config: Config, optimizer: str, problem: str, seed: int
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The line of runs.csv of one run of the protocol and its evaluations' rows: read from the store where it
    finished there (not replayed: a finished `gp` run would spend its model fits again), else made (or
    resumed), or with ``from_store`` a line "not run yet". A run that another process is making (another
    lane: :meth:`~optimizers.store.RunStore.claim`) is a line "not run yet" and left to it."""
    prepared = _prepare(config, optimizer, problem, seed)
    if prepared.identity is None:
        return _not_run_row(config, optimizer, problem, seed, prepared.note), []
    claim = contextlib.nullcontext(True) if config.from_store else store.claim(prepared.identity)
    with claim as mine:  # --from-store only reads
        if not mine:
            return _not_run_row(config, optimizer, problem, seed, ANOTHER_PROCESS, NOT_RUN_YET), []
        note = prepared.note
        result, held, pending = _stored_run(store, prepared.identity, prepared.space)
        if config.archive is not None and (result is not None or (held and config.from_store)):
            keep = archive_run if result is not None else snapshot_run  # a run going on: what it has so far
            keep(store, int(store.find_run(prepared.identity)), config.archive)  # type: ignore[arg-type]
        if result is None and config.from_store:
            return _not_run_row(config, optimizer, problem, seed, pending, NOT_RUN_YET, held), []
        if result is None:
            result, note = _run(store, config, optimizer, problem, seed, note)
            if result is None:
                return _not_run_row(config, optimizer, problem, seed, note), []
    rows = _evaluation_rows(store, result, problem)
    return _run_row(config, result, problem, rows, note), rows


def _run(
    store: RunStore, config: Config, optimizer: str, problem: str, seed: int, note: str
) -> tuple[OptimizationResult | None, str]:
    """One run (resumed from the store) and its note, or None and why it failed."""
    options = config.options(optimizer)
    if optimizer == "ppo":
        _, result = train_policy(
            store, problem, config.budget, seed, options, config.fidelity, speed_kmh=SPEED_KMH,
            quiet=not config.full, archive=config.archive,
        )  # fmt: skip
        return result, note
    try:
        result = optimize(
            problem, optimizer, config.budget, seed, speed_kmh=SPEED_KMH, fidelity=config.fidelity,
            options=options, store=store, resume=True, start_if_none=True, n_workers=config.workers,
            quiet=not config.full, archive=config.archive,
        )  # fmt: skip
    except TypeError as error:
        fault = ngopt_fault()
        if optimizer != "ngopt" or fault is None:
            raise
        return None, f"failed part-way ({error}): {fault}"
    return result, note


def _stored_run(
    store: RunStore, identity: RunConfig, space: GridSpace
) -> tuple[OptimizationResult | None, int, str]:
    """A run read from the store: its result where it finished there (nothing replayed by its optimiser,
    nothing simulated); else None, the simulations the store holds of it, and a note saying so."""
    try:
        run_id = store.find_run(identity)
    except StoreError as error:  # a run of another package version: a resumption would refuse it too
        return None, 0, str(error)
    if run_id is None:
        return None, 0, "no simulation in the store"
    if store.stop_reason(run_id) is None:
        held = sum(int(s.record.charged) for s in store.evaluations(run_id).values())
        return (
            None,
            held,
            f"run {run_id} unfinished: {held} of its {identity.budget} simulations in the store",
        )
    return finished_result(store, run_id, identity, space), 0, ""


def _evaluation_rows(store: RunStore, result: OptimizationResult, problem: str) -> list[dict[str, Any]]:
    """The tidy rows of a run's evaluations (``result.problem`` is the store's key: the name and the
    model's fingerprint)."""
    space = GridSpace.from_problem(resolve_problem(problem))
    rows = []
    simulation = 0
    for record in result.history:
        simulation += int(record.charged)
        if record.cached and record.charged:  # simulated by another run (or step): its own time
            key = space.design_key(record.x)
            source = "env" if result.optimizer == "ppo" else "simulation"
            found = store.lookup(space.store_key, key, record.speed_kmh, result.fidelity, source)
            if found is None:  # a run rebuilt from an export: its simulation's row is one too
                found = store.lookup(space.store_key, key, record.speed_kmh, result.fidelity, EXPORT_SOURCE)
            simulation_time = found.wall_time if found is not None else 0.0
        else:
            simulation_time = record.wall_time
        rows.append(
            {
                "run": result.run_id,
                "optimizer": result.optimizer,
                "problem": problem,
                "seed": result.seed,
                "index": record.index,
                "simulation": simulation,
                "sigma_N": record.sigma if record.feasible and record.sigma is not None else float("nan"),
                "feasible": int(record.feasible),
                "charged": int(record.charged),
                "cached": int(record.cached),
                "wall_time_s": record.wall_time,
                "simulation_time_s": simulation_time if record.charged else 0.0,
                "x_m": " ".join(f"{v:.6g}" for v in record.x),
            }
        )
    return rows


def _run_row(
    config: Config, result: OptimizationResult, problem: str, rows: list[dict[str, Any]], note: str
) -> dict[str, Any]:
    infeasible = sum(1 for r in rows if not r["feasible"])
    return {
        "run": result.run_id,
        "optimizer": result.optimizer,
        "problem": problem,
        "seed": result.seed,
        "budget": result.budget,
        "fidelity": config.fidelity,
        "status": DONE,
        "stop_reason": result.stop_reason,
        "n_simulations": result.n_simulations,
        "n_evaluations": len(rows),
        "best_sigma_N": result.best_sigma if result.best_sigma is not None else float("nan"),
        "infeasible_share": infeasible / len(rows) if rows else float("nan"),
        "simulation_time_s": sum(r["simulation_time_s"] for r in rows),
        "note": note,
    }


def _not_run_row(
    config: Config, optimizer: str, problem: str, seed: int, reason: str, status: str = NOT_RUN,
    held: int = 0,
) -> dict[str, Any]:  # fmt: skip
    """The line of a run that cannot run here (``NOT_RUN``), or has not finished in the store
    (``NOT_RUN_YET``, with the ``held`` simulations the store holds of it)."""
    return {
        "run": "",
        "optimizer": optimizer,
        "problem": problem,
        "seed": seed,
        "budget": config.budget,
        "fidelity": config.fidelity,
        "status": status,
        "stop_reason": "",
        "n_simulations": held,
        "n_evaluations": 0,
        "best_sigma_N": float("nan"),
        "infeasible_share": float("nan"),
        "simulation_time_s": 0.0,
        "note": reason,
    }


def _run_line(row: dict[str, Any]) -> str:
    return (
        f"{row['optimizer']} on {row['problem']} seed {row['seed']}: best σ {row['best_sigma_N']:.3f} N "
        f"after {row['n_simulations']} simulations ({row['stop_reason']})"
    )


# -- analysis (from the data files alone) ----------------------------------------------------------------


def best_so_far(rows: list[dict[str, Any]], budget: int) -> np.ndarray:
    """Best σ so far after each simulation 1..budget of one run (+inf before its first feasible design;
    the last value carried on where the run stopped early)."""
    curve = np.full(budget, np.inf)
    best = np.inf
    for row in sorted(rows, key=lambda r: r["index"]):
        if row["feasible"] and row["sigma_N"] < best:
            best = row["sigma_N"]
        if row["simulation"] >= 1:
            curve[int(row["simulation"]) - 1 :] = best
    return curve


def quantiles(curves: np.ndarray, q: tuple[float, ...] = (0.25, 0.5, 0.75)) -> np.ndarray:
    """Quantiles over runs (axis 0) of curves that may hold +inf; NaN where a quantile is infinite."""
    finite = np.where(np.isfinite(curves), curves, 1e300)
    out = np.quantile(finite, q, axis=0)
    return np.where(out >= 1e299, np.nan, out)


def simulations_to_target(curve: np.ndarray, target: float) -> int | None:
    """The first simulation after which the best σ is at most ``target``, or None."""
    hits = np.flatnonzero(curve <= target)
    return int(hits[0]) + 1 if len(hits) else None


def summarise(
    evaluations: list[dict[str, Any]], runs: list[dict[str, Any]], reference: dict[str, float]
) -> tuple[list[dict[str, Any]], dict[str, dict[str, np.ndarray]]]:
    """The summary rows per problem and optimiser, and the best-so-far curves per problem and optimiser."""
    by_run: dict[Any, list[dict[str, Any]]] = {}
    for row in evaluations:
        by_run.setdefault(int(row["run"]), []).append(row)
    done = [r for r in runs if r["status"] == DONE]
    summary, curves_by = [], {}
    for problem in dict.fromkeys(r["problem"] for r in done):  # problems without a finished run: no rows
        pruns = [r for r in done if r["problem"] == problem]
        budget = int(max((r["budget"] for r in pruns), default=1))
        curves = {int(r["run"]): best_so_far(by_run.get(int(r["run"]), []), budget) for r in pruns}
        finals = [c[-1] for c in curves.values() if np.isfinite(c[-1])]
        target = (1.0 + TARGET) * min(finals) if finals else float("nan")
        curves_by[problem] = {}
        for optimizer in dict.fromkeys(r["optimizer"] for r in runs if r["problem"] == problem):
            oruns = [r for r in pruns if r["optimizer"] == optimizer]
            if not oruns:
                continue
            stack = np.array([curves[int(r["run"])] for r in oruns])
            curves_by[problem][optimizer] = stack
            summary.append(_summary_row(problem, optimizer, oruns, stack, target, reference.get(problem)))
    return summary, curves_by


def _summary_row(
    problem: str,
    optimizer: str,
    runs: list[dict[str, Any]],
    stack: np.ndarray,
    target: float,
    reference: float | None,
) -> dict[str, Any]:
    q25, median, q75 = quantiles(stack[:, -1:])[:, 0]
    hits = [s for s in (simulations_to_target(c, target) for c in stack) if s is not None]
    return {
        "problem": problem,
        "optimizer": optimizer,
        "runs": len(runs),
        "median_sigma_N": median,
        "q25_sigma_N": q25,
        "q75_sigma_N": q75,
        "best_sigma_N": float(np.min(stack[:, -1])),
        "reduction_percent": 100.0 * (1.0 - median / reference) if reference else float("nan"),
        "target_sigma_N": target,
        "runs_within_2_percent": len(hits),
        "median_simulations_to_2_percent": float(np.median(hits)) if hits else float("nan"),
        "infeasible_percent": 100.0 * float(np.median([r["infeasible_share"] for r in runs])),
        "median_simulation_time_s": float(np.median([r["simulation_time_s"] for r in runs])),
    }


def report(folder: Path) -> str:
    """Tables, figure and IOHprofiler files from the CSV files (no simulation)."""
    evaluations = read_csv(folder / "evaluations.csv")
    runs = read_csv(folder / "runs.csv")
    reference = {r["problem"]: r["sigma_N"] for r in read_csv(folder / "reference.csv")}
    summary, curves = summarise(evaluations, runs, reference)
    partial = partial_share(runs)
    write_csv(folder / "summary.csv", summary)
    for row in summary:
        row["final"] = f"{row['median_sigma_N']:.2f} [{row['q25_sigma_N']:.2f}, {row['q75_sigma_N']:.2f}]"
        row["hits"] = f"{row['runs_within_2_percent']}/{row['runs']}"
    table = markdown_table(
        summary,
        [
            ("problem", "problem", "s"),
            ("optimizer", "optimiser", "s"),
            ("final", "final σ (N): median [IQR]", "s"),
            ("best_sigma_N", "best σ (N)", ".2f"),
            ("reduction_percent", "median vs reference (%)", ".1f"),
            ("hits", "runs within 2 %", "s"),
            ("median_simulations_to_2_percent", "simulations to 2 % (median)", ".0f"),
            ("infeasible_percent", "infeasible proposals (%)", ".1f"),
            ("median_simulation_time_s", "simulation time per run (s)", ".1f"),
        ],
    )
    notes = [f"- reference design: σ = {s:.2f} N on {p}" for p, s in reference.items()]
    if any(not np.isfinite(r["q75_sigma_N"]) for r in summary):
        notes.append("- nan: the quantile falls on a run that found no feasible design")
    done = [r for r in runs if r["status"] == DONE]
    notes += sorted({f"- {r['optimizer']}: {r['note']}" for r in done if r["note"]})
    notes += sorted(
        {
            f"- {r['optimizer']} on {r['problem']}: not run: {r['note']}"
            for r in runs
            if r["status"] == NOT_RUN
        }
    )
    notes += identical_histories(evaluations, runs) + not_run_yet(runs)
    heading = (
        f"Partial: {partial} of the protocol finished (written from the run store while it runs); every "
        "table, figure and test here is of those runs only."
        if partial
        else ""
    )
    parts = [heading, table, "\n".join(notes), views(folder, curves, runs, partial)]
    text = "\n\n".join(part for part in parts if part)
    (folder / "optimizers.md").write_text(text + "\n", encoding="utf-8")
    _figure(curves, reference, folder / "convergence.png", partial)
    _write_ioh(folder / "ioh", evaluations, runs)
    return text


def partial_share(runs: list[dict[str, Any]]) -> str:
    """The share of the protocol in ``runs.csv``, "N of M runs", where some runs are not run yet (results
    written from the store while the protocol runs, ``--from-store``), else ""; M leaves out the runs that
    cannot run here."""
    pending = sum(r["status"] == NOT_RUN_YET for r in runs)
    done = sum(r["status"] == DONE for r in runs)
    return f"{done} of {done + pending} runs" if pending else ""


def not_run_yet(runs: list[dict[str, Any]]) -> list[str]:
    """Notes on the runs not run yet, per problem: how many of each optimiser, and the simulations the store
    holds of them (``runs.csv`` has them seed by seed)."""
    pending: dict[str, dict[str, list[int]]] = {}
    for r in runs:
        if r["status"] == NOT_RUN_YET:
            pending.setdefault(r["problem"], {}).setdefault(r["optimizer"], []).append(
                int(r["n_simulations"])
            )
    notes = []
    for problem, by_optimizer in pending.items():
        parts = [
            f"{optimizer} {len(held)}" + (f" ({sum(held)} simulations in the store)" if sum(held) else "")
            for optimizer, held in by_optimizer.items()
        ]
        notes.append(f"- not run yet on {problem} (runs of each optimiser): " + ", ".join(parts))
    return notes


def identical_histories(evaluations: list[dict[str, Any]], runs: list[dict[str, Any]]) -> list[str]:
    """Notes on pairs of optimisers whose runs proposed the same designs on every problem and seed, and why
    (DE's first population is a random sample drawn from the same seed as random search's)."""
    designs: dict[tuple[str, str, int], list[str]] = {}
    for row in evaluations:
        designs.setdefault((row["optimizer"], row["problem"], int(row["seed"])), []).append(str(row["x_m"]))
    names = list(dict.fromkeys(r["optimizer"] for r in runs if r["status"] == DONE))
    notes = []
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            keys = [(p, s) for (o, p, s) in designs if o == a]
            if keys and all(designs.get((b, p, s)) == designs[(a, p, s)] for p, s in keys):
                why = (
                    f" (nevergrad's DE starts from a random population of {DE_POPULATION}, drawn from the "
                    "seed as random search draws its designs: a budget within it cannot tell them apart)"
                    if {a, b} == {"de", "random"}
                    else ""
                )
                notes.append(f"- {a} and {b}: identical histories on every problem and seed{why}")
    return notes


def views(
    folder: Path, curves: dict[str, dict[str, np.ndarray]], runs: list[dict[str, Any]], partial: str = ""
) -> str:
    """The fixed-budget, fixed-target and rank views (:mod:`experiments.benchmark_views`); writes
    ``fixed_budget.csv``, ``fixed_target.csv``, ``ranks.csv``, ``ranks_every_problem.csv`` (where an optimiser
    is not run on some problem) and ``ecdf.png`` (removing those an earlier write left where the runs give
    none); returns their Markdown, each heading with ``partial`` (:func:`partial_share`) where it is not
    empty."""
    for name in ("fixed_target.csv", "ranks.csv", "ranks_every_problem.csv", "ecdf.png"):
        (folder / name).unlink(missing_ok=True)
    suffix = f" (partial: {partial})" if partial else ""
    done = [r for r in runs if r["status"] == DONE]
    lengths: dict[str, dict[str, list[int]]] = {}
    finals: dict[str, dict[tuple[str, int], float]] = {}
    for r in done:  # in the order of summarise's curves
        lengths.setdefault(r["problem"], {}).setdefault(r["optimizer"], []).append(int(r["n_simulations"]))
    for problem, by_optimizer in curves.items():
        seeds = {
            o: [int(r["seed"]) for r in done if r["problem"] == problem and r["optimizer"] == o]
            for o in by_optimizer
        }
        for optimizer, stack in by_optimizer.items():
            for seed, curve in zip(seeds[optimizer], stack, strict=True):
                finals.setdefault(optimizer, {})[(problem, seed)] = float(curve[-1])
    best = _best_known(curves, done)
    budget_rows = bv.fixed_budget_rows(curves)
    target_rows = bv.fixed_target_rows(curves, lengths, best)
    write_csv(folder / "fixed_budget.csv", budget_rows)
    parts = [f"### Fixed budget: best σ (N), median [IQR] of the runs{suffix}", markdown_table(
        budget_rows, [("problem", "problem", "s"), ("optimizer", "optimiser", "s"), ("runs", "runs", "d")]
        + [(k, f"after {k[3:]} simulations", "s") for k in budget_rows[0] if k.startswith("at_")],
    )] if budget_rows else []  # fmt: skip
    if target_rows:
        write_csv(folder / "fixed_target.csv", target_rows)
        columns = [("problem", "problem", "s"), ("optimizer", "optimiser", "s")]
        columns += [(f"cell_{100 * t:g}", f"ERT to {100 * t:g} % (runs reached)", "s") for t in bv.TARGETS]
        targets = ", ".join(f"{p} {s:.2f} N" for p, s in best.items())
        parts += [f"### Fixed target: simulations to come within x % of the best-known σ ({targets}){suffix}",
                  markdown_table(target_rows, columns)]  # fmt: skip
        budget = int(max(int(r["budget"]) for r in done))
        runs_in = {o: sum(len(lengths[p].get(o, [])) for p in best) for o in finals}
        labels = {o: f"{o} ({n} runs)" for o, n in runs_in.items()}
        bv.ecdf_figure(
            bv.ecdf(curves, lengths, best, budget), list(best), folder / "ecdf.png", labels, partial
        )
    if partial:  # an optimiser just started would leave the ranks only the few blocks it has finished
        fewest = min(Counter((r["problem"], r["optimizer"]) for r in runs).values())
        started = {o: len(by_block) for o, by_block in finals.items() if len(by_block) < fewest}
        finals = {o: by_block for o, by_block in finals.items() if o not in started}
        if started:
            left_out = ", ".join(f"{o} ({n} finished)" for o, n in sorted(started.items()))
            suffix += f"; left out until they have finished {fewest} runs (one problem's seeds): {left_out}"
    if len(finals) >= 3:
        parts.append(_rank_section(folder / "ranks.csv", finals, suffix))
        # PPO runs on B1 and SW1 only: with it, the blocks are theirs; without it, every problem's.
        narrow = sorted({r["optimizer"] for r in runs if r["status"] == NOT_RUN} & set(finals))
        everywhere = {o: by_block for o, by_block in finals.items() if o not in narrow}
        if partial:  # the broad view: an optimiser with runs on few problems yet would narrow it to those
            everywhere, behind = bv.broadest(everywhere)
            if behind:
                left_out = ", ".join(f"{o} ({n} finished)" for o, n in sorted(behind.items()))
                suffix += f"; left out until more of their runs have finished: {left_out}"
        if narrow and len(everywhere) >= 3:
            without = f", without {', '.join(narrow)} (not run on every problem)"
            parts.append(_rank_section(folder / "ranks_every_problem.csv", everywhere, without + suffix))
    return "\n\n".join(parts)


def _best_known(curves: dict[str, Any], done: list[dict[str, Any]]) -> dict[str, float]:
    """The best-known σ of the problems whose runs are on its fidelity (not the quick setting's test
    model)."""
    best = {}
    for problem in curves:
        known = DESIGN_PROBLEMS[problem].best_known if problem in DESIGN_PROBLEMS else None
        if known and all(r["fidelity"] == known.fidelity for r in done if r["problem"] == problem):
            best[problem] = known.sigma_N
    return best


def _rank_section(path: Path, finals: dict[str, dict[tuple[str, int], float]], suffix: str) -> str:
    """The rank tests over the blocks (problem, seed) where every optimiser of ``finals`` has a finished
    run, their pairs written to ``path``; none where fewer than
    :data:`~experiments.benchmark_views.MIN_BLOCKS` are (a partial set)."""
    blocks = bv.common_blocks(finals)
    if len(blocks) < bv.MIN_BLOCKS:
        return (
            f"### Ranks{suffix}\n\nnot computed: the {len(finals)} optimisers have finished runs in common "
            f"on {len(blocks)} block(s) (problem, seed), fewer than {bv.MIN_BLOCKS}"
        )
    friedman, pairs = bv.rank_tests(finals)
    write_csv(path, pairs)
    ranks = sorted(friedman["mean_ranks"].items(), key=lambda item: item[1])
    significant = [f"{p['better']} better than {p['b'] if p['better'] == p['a'] else p['a']} "
                   f"(p = {p['p_holm']:.3f})" for p in pairs if p["significant"]]  # fmt: skip
    return "\n".join([
        f"### Ranks over {friedman['blocks']} blocks (problem, seed) by final best σ{suffix}",
        "",
        "mean rank (1 = best): " + ", ".join(f"{name} {rank:.2f}" for name, rank in ranks),
        "",
        f"Friedman χ² = {friedman['statistic']:.2f}, p = {friedman['p_value']:.2g}; pairwise Wilcoxon "
        f"signed-rank tests with Holm's correction at {bv.ALPHA:g}: "
        + ("; ".join(significant) if significant else "no pair differs significantly"),
    ])  # fmt: skip


def _figure(
    curves: dict[str, dict[str, np.ndarray]], reference: dict[str, float], path: Path, partial: str = ""
) -> None:
    """Best σ so far against simulations, one panel per problem with finished runs (``partial``: "N of M
    runs" of a partial set, in the title); none (an earlier one removed) before the first run finished."""
    from catenary_env.plots import pyplot

    path.unlink(missing_ok=True)
    if not curves:
        return
    plt = pyplot()
    fig, axes = plt.subplots(1, len(curves), figsize=(5.5 * len(curves), 4.2), squeeze=False)
    if partial:
        fig.suptitle(f"partial: {partial} of the protocol", fontsize=10)
    for ax, (problem, by_optimizer) in zip(axes[0], curves.items(), strict=True):
        for i, (optimizer, stack) in enumerate(by_optimizer.items()):
            q25, median, q75 = quantiles(stack)
            x = np.arange(1, stack.shape[1] + 1)
            ax.plot(x, median, color=f"C{i}", label=f"{optimizer} ({len(stack)} runs)")
            ax.fill_between(x, q25, q75, color=f"C{i}", alpha=0.2, linewidth=0)
        if problem in reference:
            ax.axhline(reference[problem], color="k", linestyle=":", label="reference design")
        ax.set_xlabel("simulations")
        ax.set_ylabel("best σ so far (N)")
        ax.set_title(f"{problem}: median and inter-quartile band")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _write_ioh(root: Path, evaluations: list[dict[str, Any]], runs: list[dict[str, Any]]) -> None:
    # IOHprofiler's function id: the problem's place in the catalogue, the synthetic problems after it
    function_ids = {name: number for number, name in enumerate([*DESIGN_PROBLEMS, *SYNTHETIC_PROBLEMS], 1)}
    done = [r for r in runs if r["status"] == DONE]
    for problem in dict.fromkeys(r["problem"] for r in done):
        dimension = study_problem(problem).n_variables
        for optimizer in dict.fromkeys(r["optimizer"] for r in done if r["problem"] == problem):
            chosen = [r for r in done if r["problem"] == problem and r["optimizer"] == optimizer]
            ids = {int(r["run"]) for r in chosen}
            rows = [e for e in evaluations if int(e["run"]) in ids]
            first = chosen[0]
            attributes = {
                "fidelity": str(first["fidelity"]),
                "speed_kmh": f"{SPEED_KMH:g}",
                "budget": f"{int(first['budget'])}",
            }
            info = f"catenary-env {optimizer}" + (f"; {first['note']}" if first["note"] else "")
            write_algorithm(
                root, optimizer, info, function_ids[problem], problem, dimension,
                list(runs_from_rows(rows).values()), attributes,
            )  # fmt: skip


def _optimizer_name(name: str) -> str:
    """``--optimizers`` entries: ppo or a registered (or plugged-in) optimiser; argparse's one line else."""
    if name != "ppo":
        try:
            get_optimizer(name)
        except KeyError as error:
            raise argparse.ArgumentTypeError(str(error.args[0])) from None
    return name


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment optimizers`` and its ``python -m`` entry point)."""
    add_full_option(
        parser,
        "the study fidelity, 300 simulations a run, 15 seeds on B1 and SW1, 10 on the others "
        "(about 27 h on two cores for the six problems, docs/performance.md)",
    )
    parser.add_argument(
        "--problems", nargs="+", default=None, choices=list(DESIGN_PROBLEMS), metavar="NAME",
        help=f"the design problems, of {' '.join(DESIGN_PROBLEMS)} (default: {' '.join(FULL_PROBLEMS)} with "
        f"--full, else {' '.join(PROBLEMS)})",
    )  # fmt: skip
    parser.add_argument(
        "--optimizers", nargs="+", default=list(OPTIMIZERS), type=_optimizer_name, metavar="NAME",
        help=f"the optimisers, of {' '.join(OPTIMIZERS)} or an installed package's (docs/problems.md, "
        "'Your own optimiser'; default: all); disjoint sets in two processes share a problem's runs",
    )  # fmt: skip
    add_workers_option(parser, 1, "the simulations of a batch (PPO steps its env in this process)")
    add_out_option(parser)
    add_store_option(parser)
    parser.add_argument(
        "--from-store", action="store_true",
        help="simulate nothing: write the tables, figures and IOHprofiler files from the runs of the "
        "protocol that finished in the store (read only, so lanes may be running into it), and list every "
        "other run as 'not run yet' with the simulations the store holds of it",
    )  # fmt: skip
    add_archive_option(parser, "; with --from-store, also a snapshot of each run still going")


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.optimizer_comparison``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.optimizer_comparison")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.optimizer_comparison"))
