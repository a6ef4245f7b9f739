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
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

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

from .benchmark_report import DONE, NOT_RUN, NOT_RUN_YET, SPEED_KMH, report
from .common import (
    DEFAULT_OUT,
    STORE,
    add_archive_option,
    add_full_option,
    add_out_option,
    add_store_option,
    add_workers_option,
    run_cli,
    run_study,
    study_dir,
    write_csv,
)
from .design_evaluations import evaluate_designs, stored_outcome, study_problem
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


def _optimizer_name(name: str) -> str:
    """``--optimizers`` entries: ppo or a registered (or plugged-in) optimiser; argparse's one line else."""
    if name != "ppo":
        try:
            get_optimizer(name)
        except KeyError as error:
            raise argparse.ArgumentTypeError(f"{error.args[0]}; or ppo") from None
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
