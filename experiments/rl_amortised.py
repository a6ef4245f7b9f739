"""Study 5b: speed-conditioned design policies as amortised optimisers (docs/problems.md, 'Experiments').

A policy conditioned on the speed is an amortised optimiser: trained once, it gives a design for any speed
with no further simulation, where an optimiser pays its whole budget again for each speed. The study
measures what that costs and what it gives, on B1 and SW1 (quick: B1):

1. *Learning curves*: speed-conditioned policies trained on speeds drawn from 200–320 km/h outside the
   held-out bands (:data:`HELD_OUT`, 225–235 and 285–295 km/h), with PPO and SAC
   (:mod:`optimizers.rl`), 3 seeds: the mean reward (−σ, or −Fm for an infeasible design) and the
   feasible share over a window of steps, against env steps (one step, one simulation).
2. *The table*: at held-out speeds (:data:`HELD_OUT_SPEEDS`) and training speeds
   (:data:`TRAINING_SPEEDS`), σ of the reference design, of the GA optimum at that speed (a GA run of
   :attr:`Config.ga_budget` simulations per speed) and of each policy's design, and the gap policy / GA.
3. *The amortisation ledger* (:mod:`experiments.rl_analysis`): for N speeds, the simulations one policy
   cost (its training, plus one simulation per speed to know the σ of its design) against those of N GA
   runs, and the σ each gets; the break-even N at which the policy is the cheaper, for the gap to the GA
   optimum one accepts.
4. *Where the designs went*: how far each policy's designs moved from the reference towards the GA optima
   during training, how their spread narrowed, and how much of σ's variance the speed explains: what a
   policy that stays far from the GA has been doing.

Where the policies start: at the reference design (action 0) with the spread
:data:`optimizers.rl.POLICY_SPREAD`, as in study 5 (:mod:`experiments.rl_studies`); SAC's warm-up draws
its actions around action 0 with the same spread (:class:`optimizers.rl.SACOptions`). Hyper-parameters:
the learners' defaults (:class:`optimizers.rl.PPOOptions`, :class:`optimizers.rl.SACOptions`), chosen once,
with ``n_envs`` = ``--envs``; so each full run is also the ``catenary optimize`` command written beside its
saved policy.

Every run goes to the run store (``out/runs.sqlite`` by default, shared by the studies) and is resumed from
it: a killed study started again replays what it stored (a policy is re-trained by replaying its stored
steps, which gives the same policy) and simulates only the rest.

Lanes (``--lane``): on a machine of many cores, several processes of the study over one store each make the
runs that no other has made or is making (:meth:`~optimizers.store.RunStore.claim`), in the study's order,
and write no tables; the study run again without ``--lane`` once they have all ended replays every run and
writes them (``experiments/full_rl_lanes.sh``).

Outputs (``out/rl/amortised/``): ``steps.csv`` (every training step), ``ga_runs.csv``, ``ga_curves.csv``
(the GA's best σ after each simulation), ``designs.csv`` (every design simulated at each speed),
``ledger.csv``; ``amortised.md`` (tables), ``learning_curves.png``, ``ledger.png``; with ``--archive``,
``cost.md`` (the simulations and hours of the archive's finished runs); ``policies/`` (each
policy, loadable with ``catenary propose``, and beside it ``<policy>.txt``, the command that reproduces
its run).

Settings. Full: the study fidelity, B1 and SW1, PPO and SAC, 3 seeds of 10,000 steps on 2 envs, GA runs of
1000 simulations (the published study's populations) at 210, 230, 260, 290 and 320 km/h. Quick: the "test"
fidelity, B1, one seed of 8 steps, GA runs of 12 simulations at 230 and 260 km/h (a smoke test, not a
result). ``--problems synthetic-speed-quadratic`` runs the whole study in seconds on a synthetic problem
(``optimizers/synthetic.py``) whose optimum moves with the speed.

    python -m experiments.rl_amortised [--full] [--envs 2] [--workers 2] [--out results]
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import math
import shlex
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from optimizers.archive import finished_runs, restore_runs
from optimizers.base import EvaluationRecord, OptimizationResult
from optimizers.ga import POPULATION_SIZES, GAOptions
from optimizers.problem import GridProblem, GridSpace, Outcome
from optimizers.problem_registry import resolve_problem
from optimizers.rl import (
    LEARNERS,
    DesignPolicy,
    EnvSpec,
    LearnerOptions,
    design_for_speed,
    policy_run_config,
    save_policy,
    train_design_policy,
)
from optimizers.runner import optimize, run_config
from optimizers.store import RunConfig, RunStore
from optimizers.synthetic import SYNTHETIC_PROBLEMS

from . import protocol_cost
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
    seed_value,
    study_dir,
    worker_count,
    write_csv,
)
from .design_evaluations import evaluate_designs, study_problem
from .model_stamp import catenaries_of, stamp_study
from .rl_analysis import (
    DRIFT_COLUMNS,
    LEARNING_COLUMNS,
    LEDGER_COLUMNS,
    LEDGER_SPEEDS,
    TABLE_COLUMNS,
    amortisation_ledger,
    design_drift,
    ga_budgets,
    learning_figure,
    learning_summary,
    ledger_figure,
    speed_table,
    window_of,
)

NAME = "rl/amortised"
SPEED_RANGE = (200.0, 320.0)
HELD_OUT = ((225.0, 235.0), (285.0, 295.0))
"""Speed bands never drawn in training, km/h."""
HELD_OUT_SPEEDS = (230.0, 290.0)
TRAINING_SPEEDS = (210.0, 260.0, 320.0)
CHOICES = sorted({*POPULATION_SIZES, "synthetic-speed-quadratic"})


@dataclass(frozen=True)
class Config:
    """The study's settings (quick unless ``full``).

    Attributes
    ----------
    full : bool
        The study fidelity and the issue's budgets (hours); else quick.
    out : Path
        The results folder; the study writes into ``out/rl/amortised``.
    workers : int
        Local worker processes for the GA's and the given designs' simulations.
    envs : int
        Envs a policy trains on at once, each in its worker process (1: in this process).
    store : Path or None
        The run store; default ``out/runs.sqlite``, shared by the studies.
    problems : tuple of str
        The design problems; default B1 and SW1 (quick: B1).
    learners : tuple of str
        Of :data:`optimizers.rl.LEARNERS`.
    seeds : tuple of int
        Seeds of each learner; default 0, 1, 2 (quick: 0).
    archive : Path or None
        A run archive (:mod:`optimizers.archive`): its runs are restored into the store first, and each GA
        run and policy goes into it as it finishes, with a snapshot every ten minutes while it runs, so that
        a study of many hours is resumed on a fresh checkout from its last snapshot.
    lane : bool
        Make only the runs that no process has finished or is making now, and no tables (:func:`lane`).
    """

    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 2
    envs: int = 2
    store: Path | None = None
    problems: tuple[str, ...] = ()
    learners: tuple[str, ...] = tuple(LEARNERS)
    seeds: tuple[int, ...] = ()
    archive: Path | None = None
    lane: bool = False

    def __post_init__(self) -> None:
        if not self.problems:
            object.__setattr__(self, "problems", ("B1", "SW1") if self.full else ("B1",))
        if not self.seeds:
            object.__setattr__(self, "seeds", (0, 1, 2) if self.full else (0,))
        if any(not 0 <= seed < 2**32 for seed in self.seeds):
            raise ValueError(f"seeds = {self.seeds!r}: each must lie in [0, 2**32 - 1]")

    @property
    def fidelity(self) -> str:
        return "study" if self.full else "test"

    @property
    def policy_budget(self) -> int:
        """Env steps (simulations) of each policy: a multiple of the envs."""
        steps = 10_000 if self.full else 8
        return int(math.ceil(steps / self.envs) * self.envs)

    def learner_options(self, learner: str) -> LearnerOptions:
        """The learner's defaults on :attr:`envs` envs (quick: updates after a few steps)."""
        options = dataclasses.replace(LEARNERS[learner](), n_envs=self.envs)
        if self.full:
            return options
        if learner == "ppo":
            return dataclasses.replace(options, n_steps=2, batch_size=2 * self.envs)
        return dataclasses.replace(options, learning_starts=4, batch_size=4)

    @property
    def ga_budget(self) -> int:
        """Simulations of each single-speed GA run."""
        return 1000 if self.full else 12

    def ga_options(self, problem: str) -> GAOptions:
        return GAOptions(population_size=POPULATION_SIZES.get(problem, 20) if self.full else 6)

    @property
    def speeds(self) -> tuple[tuple[float, bool], ...]:
        """(speed in km/h, held out) of the table, in order of speed."""
        training, held_out = (TRAINING_SPEEDS, HELD_OUT_SPEEDS) if self.full else ((260.0,), (230.0,))
        return tuple(sorted([(v, False) for v in training] + [(v, True) for v in held_out]))


def env_id(problem: str) -> str:
    """The design env of a problem: the catenary envs', or the synthetic one's."""
    if problem in SYNTHETIC_PROBLEMS:
        from optimizers.synthetic_env import ENV_ID

        return ENV_ID
    return f"Catenary-{problem}-v0"


def check_starts_at_reference(problem: str) -> None:
    """Refuse a problem whose reference design is not action 0, the untrained policies' mean."""
    grid = resolve_problem(problem)
    reference = study_problem(problem).reference_x()
    action = None if reference is None else 2.0 * (reference - grid.lower) / (grid.upper - grid.lower) - 1.0
    if action is None or not np.allclose(action, 0.0, atol=1e-9):
        raise ValueError(
            f"problem = {problem!r}: its bounds are not centred on its reference design, so a policy "
            "starting at action 0 would not start at the reference; use B1 or SW1"
        )


def policy_env(config: Config, problem: str) -> EnvSpec:
    """The env a speed-conditioned policy of the problem trains on."""
    return EnvSpec(env_id(problem), None, SPEED_RANGE, config.fidelity, HELD_OUT)


@dataclass(frozen=True)
class StudyRun:
    """One run of a study, for its lanes: its identity in the store, its name in words, and what makes (or
    resumes) it in a store."""

    identity: RunConfig
    name: str
    make: Callable[[RunStore], object]


def study_runs(config: Config) -> list[StudyRun]:
    """The study's runs in the order :func:`main` makes them: per problem, the GA runs, then the policies."""
    runs = []
    for problem in config.problems:
        for speed, _ in config.speeds:
            runs.append(ga_study_run(config, problem, speed, problem, f"ga on {problem} at {speed:g} km/h"))
        for learner in config.learners:
            for seed in config.seeds:
                name = f"{learner} on {problem} seed {seed}"
                runs.append(
                    policy_study_run(config, policy_env(config, problem), problem, learner, seed, name)
                )
    return runs


def ga_study_run(
    config: Config, problem: str | GridProblem, speed: float, population_of: str, name: str
) -> StudyRun:
    """The GA run of a study (:func:`ga_run`) as a run of its lanes."""
    space = GridSpace.from_problem(resolve_problem(problem))
    options = config.ga_options(population_of)
    identity = run_config("ga", space, config.ga_budget, 0, speed, config.fidelity, options)
    make = functools.partial(ga_run, config=config, problem=problem, speed=speed, population_of=population_of)
    return StudyRun(identity, name, make)


def policy_study_run(
    config: Config, env: EnvSpec, problem: str | GridProblem, learner: str, seed: int, name: str
) -> StudyRun:
    """A policy of a study (:func:`train_policy`) as a run of its lanes."""
    space = GridSpace.from_problem(resolve_problem(problem))
    options = config.learner_options(learner)
    identity = policy_run_config(env, space, config.policy_budget, seed, options)
    make = functools.partial(
        train_policy, config=config, env=env, problem=problem, learner=learner, seed=seed
    )
    return StudyRun(identity, name, make)


def make_free_runs(config: Config, runs: Sequence[StudyRun]) -> str:
    """A lane of a study: make, in order, the runs that no process has finished or is making now; what it
    made and left to the others, in words. Each run is held while it is made
    (:meth:`~optimizers.store.RunStore.claim`), so the lanes over one store never make a run twice."""
    store_path = config.store or Path(config.out) / STORE
    store_path.parent.mkdir(parents=True, exist_ok=True)  # a fresh --out, as main's study folder makes it
    made, left = [], []
    with RunStore(store_path) as store:
        restore_archive(config, store, store_path)
        for run in runs:
            with store.claim(run.identity) as mine:
                run_id = store.find_run(run.identity)
                if mine and (run_id is None or store.stop_reason(run_id) is None):
                    run.make(store)
                    made.append(run.name)
                else:
                    left.append(run.name)
    return (
        f"This lane made {len(made)} run(s): {'; '.join(made) or 'none'}. {len(left)} were made, or are "
        f"being made, by other processes: {'; '.join(left) or 'none'}. Once every lane has ended, run the "
        "study again without --lane for its tables (it replays every run)."
    )


def lane(config: Config) -> str:
    """``--lane``: :func:`make_free_runs` over the study's runs."""
    return make_free_runs(config, study_runs(config))


def main(config: Config) -> Path:
    folder = study_dir(config.out, NAME)
    (folder / "policies").mkdir(exist_ok=True)
    tables: dict[str, list[dict[str, Any]]] = {k: [] for k in ("steps", "ga", "curves", "designs")}
    store_path = config.store or Path(config.out) / STORE
    with RunStore(store_path) as store:
        restore_archive(config, store, store_path)
        for problem in config.problems:
            check_starts_at_reference(problem)
            _reference_designs(store, config, problem, tables["designs"])
            _ga_runs(store, config, problem, tables)
            for learner in config.learners:
                for seed in config.seeds:
                    _policy(store, store_path, config, problem, learner, seed, folder, tables)
    write_tables(config, folder, tables)
    report(folder)
    if config.archive is not None:
        write_cost(Path(config.archive), folder, config.envs)
    return folder


def restore_archive(config: Config, store: RunStore, store_path: Path) -> None:
    """With ``config.archive``: restore its runs into the store (a fresh checkout resumes from it) and stamp
    it with the model of its problems."""
    if config.archive is None:
        return
    Path(config.archive).mkdir(parents=True, exist_ok=True)
    restored = restore_runs(store, config.archive)
    print(f"{restored} run(s) restored from {config.archive} into {store_path}", file=sys.stderr)
    stamp_study(config.archive, catenaries_of(config.problems))


def write_tables(config: Config, folder: Path, tables: dict[str, list[dict[str, Any]]]) -> None:
    """The study's data files (``steps.csv``, ``ga_runs.csv``, ``ga_curves.csv``, ``designs.csv``) and the
    stamp of the model that made them."""
    for name, key in (("steps", "steps"), ("ga_runs", "ga"), ("ga_curves", "curves"), ("designs", "designs")):
        if tables[key]:  # no GA curve when no GA run met a feasible design
            write_csv(folder / f"{name}.csv", tables[key])
    stamp_study(folder, catenaries_of(config.problems))


def write_cost(archive: Path, folder: Path, cores: int, title: str = "The amortised RL study's cost") -> None:
    """``cost.md``: what the archive's finished runs cost (:mod:`experiments.protocol_cost`); each run
    held ``cores`` cores (its envs, or as many GA workers)."""
    if finished_runs(archive):
        text = protocol_cost.report(archive, title, cores=cores)
        (folder / "cost.md").write_text(text, encoding="utf-8")


def x_text(x: Any) -> str:
    return " ".join(f"{v:.6g}" for v in x)


def sigma_or_nan(outcome: Outcome | EvaluationRecord) -> float:
    """σ of a feasible outcome, N; NaN for an infeasible one (the tables' "–")."""
    return float(outcome.sigma) if outcome.feasible and outcome.sigma is not None else float("nan")


def _simulate(
    store: RunStore,
    config: Config,
    problem: str,
    designs: list[tuple[str, int, float, tuple[float, ...]]],
    rows: list[dict[str, Any]],
) -> None:
    """Simulate (or find in the store) each (design, seed, speed, x) and add its row."""
    outcomes = evaluate_designs(
        store, problem, [(x, v) for *_, v, x in designs], config.fidelity, config.workers
    )
    held_out = dict(config.speeds)
    for (design, seed, speed, x), outcome in zip(designs, outcomes, strict=True):
        rows.append(
            {
                "problem": problem, "design": design, "seed": seed, "speed_kmh": speed,
                "held_out": int(held_out.get(speed, False)), "feasible": int(outcome.feasible),
                "sigma_N": sigma_or_nan(outcome), "x_m": x_text(x),
            }
        )  # fmt: skip


def _reference_designs(store: RunStore, config: Config, problem: str, rows: list[dict[str, Any]]) -> None:
    reference = tuple(float(v) for v in study_problem(problem).reference_x())  # type: ignore[union-attr]
    _simulate(store, config, problem, [("reference", -1, v, reference) for v, _ in config.speeds], rows)


def _ga_runs(store: RunStore, config: Config, problem: str, tables: dict[str, list[dict[str, Any]]]) -> None:
    """A GA run at each speed of the table: its result, its best σ after each simulation, its optimum."""
    optima = []
    for speed, _ in config.speeds:
        result = ga_run(store, config=config, problem=problem, speed=speed, population_of=problem)
        tables["ga"].append(ga_row(problem, speed, config, result, problem))
        tables["curves"].extend(best_so_far(problem, speed, result))
        if result.best_x is not None:
            optima.append(("ga", 0, speed, tuple(result.best_x)))
    _simulate(store, config, problem, optima, tables["designs"])


def ga_run(
    store: RunStore, *, config: Config, problem: str | GridProblem, speed: float, population_of: str
) -> OptimizationResult:
    """Make (or resume) the GA run of the problem (a name, or a problem) at a speed, km/h, with the
    population of the problem named ``population_of``."""
    return optimize(
        problem, "ga", config.ga_budget, 0, speed_kmh=speed, fidelity=config.fidelity,
        options=config.ga_options(population_of), store=store, resume=True, start_if_none=True,
        n_workers=config.workers, quiet=not config.full, archive=config.archive,
    )  # fmt: skip


def ga_row(
    name: str, speed: float, config: Config, result: OptimizationResult, problem: str
) -> dict[str, Any]:
    """The row of ``ga_runs.csv`` of a GA run at a speed on the problem the table calls ``name``."""
    return {
        "problem": name, "speed_kmh": speed, "budget": result.budget,
        "population": config.ga_options(problem).population_size,
        "n_simulations": result.n_simulations, "stop_reason": result.stop_reason,
        "best_sigma_N": result.best_sigma if result.best_sigma is not None else float("nan"),
        "x_m": x_text(result.best_x) if result.best_x is not None else "",
    }  # fmt: skip


def best_so_far(problem: str, speed: float, result: OptimizationResult) -> list[dict[str, Any]]:
    """The GA's best σ after each simulation that improved it (the curve is a staircase)."""
    rows, best, simulations = [], math.inf, 0
    for record in result.history:
        simulations += int(record.charged)
        if record.feasible and record.sigma is not None and record.sigma < best:
            best = record.sigma
            rows.append(
                {"problem": problem, "speed_kmh": speed, "simulations": simulations, "best_sigma_N": best}
            )
    return rows


def _policy(
    store: RunStore,
    store_path: Path,
    config: Config,
    problem: str,
    learner: str,
    seed: int,
    folder: Path,
    tables: dict[str, list[dict[str, Any]]],
) -> None:
    """Train (or resume) one policy, save it with the command that reproduces it, and simulate its designs."""
    env = policy_env(config, problem)
    policy, result = train_policy(store, config=config, env=env, problem=problem, learner=learner, seed=seed)
    design_problem = resolve_problem(problem)
    tables["steps"].extend(step_rows(store, problem, learner, seed, result))
    path = folder / "policies" / f"{learner}-{problem}-seed{seed}.zip"
    command = reproduce_command(config, store_path, problem, learner, seed, path)
    save_policy(policy, path, design_problem, result, command)
    path.with_suffix(".txt").write_text(command + "\n", encoding="utf-8")
    designs = [
        (learner, seed, v, tuple(design_for_speed(policy, design_problem, v).tolist()))
        for v, _ in config.speeds
    ]
    _simulate(store, config, problem, designs, tables["designs"])
    best = "no feasible design" if result.best_sigma is None else f"best σ met {result.best_sigma:.3f} N"
    print(f"{learner} on {problem} seed {seed}: {best}", file=sys.stderr, flush=True)


def train_policy(
    store: RunStore, *, config: Config, env: EnvSpec, problem: str | GridProblem, learner: str, seed: int
) -> tuple[DesignPolicy, OptimizationResult]:
    """Train (or resume) the policy of a learner and seed on an env of the problem (a name, or a problem)."""
    from catenary_env.envs import register_envs

    register_envs()
    return train_design_policy(
        env, resolve_problem(problem), config.policy_budget, seed, options=config.learner_options(learner),
        store=store, resume=True, start_if_none=True, quiet=not config.full, archive=config.archive,
    )  # fmt: skip


def step_rows(
    store: RunStore, problem: str, learner: str, seed: int, result: OptimizationResult
) -> list[dict[str, Any]]:
    """The rows of ``steps.csv`` of a policy's training run: every step, its speed, σ, reward and design."""
    stored = store.evaluations(int(result.run_id or 0))
    return [
        {
            "learner": learner, "problem": problem, "seed": seed, "step": record.index + 1,
            "speed_kmh": record.speed_kmh, "feasible": int(record.feasible), "sigma_N": sigma_or_nan(record),
            "reward": stored[record.index].reward if record.index in stored else float("nan"),
            "x_m": x_text(record.x),
        }
        for record in result.history
    ]  # fmt: skip


def trains_with_defaults(config: Config, learner: str) -> bool:
    """Whether the study trains the learner with its defaults (the full setting), as ``catenary optimize``
    does: its runs are then reproduced by that command."""
    return config.learner_options(learner) == dataclasses.replace(LEARNERS[learner](), n_envs=config.envs)


def optimize_command(
    config: Config,
    store: Path,
    problem: str,
    learner: str,
    seed: int,
    policy: Path,
    env_words: Sequence[str] = (),
) -> str:
    """The ``catenary optimize`` command that reproduces (resumes from the store) one policy's run of the full
    setting and saves it again; ``env_words``: options of the env beyond the speeds."""
    bands = [f"{v:g}" for band in HELD_OUT for v in band]
    return shlex.join(
        [
            "catenary", "optimize", problem, "--optimizer", learner, "--budget", str(config.policy_budget),
            "--seed", str(seed), "--fidelity", config.fidelity, "--workers", str(config.envs),
            "--speed-range", *(f"{v:g}" for v in SPEED_RANGE), "--held-out-speeds", *bands, *env_words,
            "--store", str(store), "--resume-or-start", "--save-policy", str(policy),
        ]
    )  # fmt: skip


def reproduce_command(
    config: Config, store: Path, problem: str, learner: str, seed: int, policy: Path
) -> str:
    """The command that reproduces (resumes from the store) one policy's run and saves it again: ``catenary
    optimize`` when the study trains with the learner's defaults (the full setting), else the study's own
    command restricted to that run."""
    if trains_with_defaults(config, learner):
        return optimize_command(config, store, problem, learner, seed, policy)
    words = [
        "catenary", "experiment", "rl-amortised", *(["--full"] if config.full else []),
        "--problems", problem, "--learners", learner, "--seeds", str(seed), "--envs", str(config.envs),
        "--store", str(store), "--out", str(config.out),
    ]  # fmt: skip
    return shlex.join(words)


# -- report (from the data files alone) -------------------------------------------------------------------


def report(folder: Path) -> str:
    """Tables and figures from the CSV files (no simulation)."""
    steps = read_csv(folder / "steps.csv")
    designs = read_csv(folder / "designs.csv")
    curves = read_csv(folder / "ga_curves.csv") if (folder / "ga_curves.csv").is_file() else []
    ga_runs = read_csv(folder / "ga_runs.csv")
    window = window_of(steps)
    ledger = amortisation_ledger(designs, curves, ga_runs, steps)
    write_csv(folder / "ledger.csv", ledger)
    sections = [
        (f"Learning curves (windows of {window} steps)", learning_summary(steps, window), LEARNING_COLUMNS),
        (
            f"Policies against a GA run per speed ({ga_budgets(ga_runs)}; –: no feasible design)",
            speed_table(designs),
            TABLE_COLUMNS,
        ),
        (
            f"Where the policies' designs went (mean design of the first and last {window} steps)",
            design_drift(steps, designs, window),
            DRIFT_COLUMNS,
        ),
        ("Amortisation ledger", [r for r in ledger if r["n_speeds"] == LEDGER_SPEEDS[0]], LEDGER_COLUMNS),
    ]
    text = "\n\n".join(
        f"### {title}\n\n{markdown_table(rows, columns, missing='–')}" for title, rows, columns in sections
    )
    (folder / "amortised.md").write_text(text + "\n", encoding="utf-8")
    learning_figure(steps, window, folder / "learning_curves.png")
    ledger_figure(ledger, curves, ga_runs, folder / "ledger.png")
    return text


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment rl-amortised``, ``python -m experiments.rl_amortised``)."""
    add_full_option(parser, "the study fidelity, B1 and SW1, PPO and SAC, 3 seeds of 10,000 steps (days)")
    parser.add_argument(
        "--problems", nargs="+", default=[], choices=CHOICES, metavar="NAME",
        help=f"the design problems, of {' '.join(CHOICES)} (default: B1 SW1; quick: B1)",
    )  # fmt: skip
    add_training_arguments(parser, tuple(LEARNERS))


def add_training_arguments(parser: argparse.ArgumentParser, learners: tuple[str, ...]) -> None:
    """The options of the policies' training and the study's files, shared with :mod:`experiments.rl_tension`:
    ``--learners`` (default ``learners``), ``--seeds``, ``--envs``, ``--workers``, ``--out``, ``--store``,
    ``--archive``, ``--lane``."""
    parser.add_argument(
        "--learners", nargs="+", default=list(learners), choices=list(LEARNERS), metavar="NAME",
        help=f"the RL learners, of {' '.join(LEARNERS)} (default: {' '.join(learners)})",
    )  # fmt: skip
    parser.add_argument(
        "--seeds", nargs="+", type=seed_value, default=[], metavar="S",
        help="the seeds of each learner (default: 0 1 2; quick: 0)",
    )  # fmt: skip
    parser.add_argument(
        "--envs", type=worker_count, default=2, metavar="N",
        help="envs a policy trains on at once, each in its worker process (default 2: both cores)",
    )  # fmt: skip
    add_workers_option(parser, 2, "the GA's and the given designs' simulations")
    add_out_option(parser)
    add_store_option(parser)
    add_archive_option(parser)
    parser.add_argument(
        "--lane", action="store_true",
        help="one lane of several processes over one store: make only the runs that no other has made or "
        "is making, and no tables (run the study again without --lane when every lane has ended)",
    )  # fmt: skip


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.rl_amortised``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.rl_amortised")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.rl_amortised"))
