"""Study 4: which optimiser finds the smoothest design with the fewest simulations (docs/problems.md,
'Experiments').

The published study's GA, nevergrad's CMA-ES, DE, PSO, random search and NGOpt, Optuna's TPE and Gaussian
process, and the PPO design policy (and any optimiser an installed package plugs in), at 300 km/h, each with
the same budget of simulations and several seeds. Every run goes to one
run store (the studies' shared ``runs.sqlite`` in the output folder, or ``Config.store``) and is resumed
from it: a study run again, or interrupted and restarted, replays what is stored and simulates only what
is missing, and a design simulated by one run is served to the others from the store's cache (it is still
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

    python -m experiments.optimizer_comparison [--full] [--workers 2] [--out results]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from catenary_env.problems import PROBLEMS as DESIGN_PROBLEMS
from optimizers.base import OptimizationResult
from optimizers.ga import GAOptions
from optimizers.nevergrad_adapters import ngopt_fault
from optimizers.plugins import get_optimizer
from optimizers.problem import GridSpace
from optimizers.problem_registry import resolve_problem
from optimizers.runner import optimize
from optimizers.store import RunStore
from optimizers.synthetic import SYNTHETIC_PROBLEMS

from . import benchmark_views as bv
from .common import (
    DEFAULT_OUT,
    STORE,
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
from .design_evaluations import evaluate_designs, study_problem
from .iohprofiler import runs_from_rows, write_algorithm
from .model_stamp import catenaries_of, stamp_study
from .rl_studies import check_starts_at_reference, policy_options, train_policy

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
    """

    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 1
    store: Path | None = None
    problems: tuple[str, ...] = None  # type: ignore[assignment]  (set in __post_init__)
    optimizers: tuple[str, ...] = OPTIMIZERS

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
    with RunStore(store_path) as store:
        for problem in config.problems:
            reference = study_problem(problem).reference_x()
            (outcome,) = evaluate_designs(
                store, problem, [(reference, SPEED_KMH)], config.fidelity, config.workers
            )
            reference_rows.append(
                {
                    "problem": problem,
                    "speed_kmh": SPEED_KMH,
                    "fidelity": config.fidelity,
                    "sigma_N": outcome.sigma,
                }
            )
            for optimizer in config.optimizers:
                for seed in config.seeds_for(problem):
                    result, note = _run(store, config, optimizer, problem, seed)
                    if result is None:
                        run_rows.append(_not_run_row(config, optimizer, problem, seed, note))
                        continue
                    rows = _evaluation_rows(store, result, problem)
                    evaluation_rows.extend(rows)
                    run_rows.append(_run_row(config, result, problem, rows, note))
                    print(_run_line(run_rows[-1]), file=sys.stderr, flush=True)
    write_csv(folder / "evaluations.csv", evaluation_rows)
    write_csv(folder / "runs.csv", run_rows)
    write_csv(folder / "reference.csv", reference_rows)
    stamp_study(folder, catenaries_of(config.problems))
    report(folder)
    return folder


def _run(
    store: RunStore, config: Config, optimizer: str, problem: str, seed: int
) -> tuple[OptimizationResult | None, str]:
    """One run (resumed from the store), or None and why it cannot run here."""
    options = config.options(optimizer)
    if optimizer == "ppo":
        try:  # the policy starts at the reference design only where the bounds are centred on it
            check_starts_at_reference(problem)
        except ValueError as error:
            return None, str(error)
        _, result = train_policy(
            store, problem, config.budget, seed, options, config.fidelity, speed_kmh=SPEED_KMH,
            quiet=not config.full,
        )  # fmt: skip
        return result, "PPO, spread 4 mm around the reference design"
    space = GridSpace.from_problem(resolve_problem(problem))
    spec = get_optimizer(optimizer)
    try:  # built once before the run, so that an optimiser that cannot run leaves no run in the store
        engine = spec.optimizer_class(space, config.budget, seed, options)  # type: ignore[call-arg]
    except (ImportError, RuntimeError) as error:
        return None, str(error)
    note = f"NGOpt selected {engine.selected_optimizer}" if optimizer == "ngopt" else ""
    try:
        result = optimize(
            problem, optimizer, config.budget, seed, speed_kmh=SPEED_KMH, fidelity=config.fidelity,
            options=options, store=store, resume=True, start_if_none=True, n_workers=config.workers,
            quiet=not config.full,
        )  # fmt: skip
    except TypeError as error:
        fault = ngopt_fault()
        if optimizer != "ngopt" or fault is None:
            raise
        return None, f"failed part-way ({error}): {fault}"
    return result, note


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
        "status": "done",
        "stop_reason": result.stop_reason,
        "n_simulations": result.n_simulations,
        "n_evaluations": len(rows),
        "best_sigma_N": result.best_sigma if result.best_sigma is not None else float("nan"),
        "infeasible_share": infeasible / len(rows) if rows else float("nan"),
        "simulation_time_s": sum(r["simulation_time_s"] for r in rows),
        "note": note,
    }


def _not_run_row(config: Config, optimizer: str, problem: str, seed: int, reason: str) -> dict[str, Any]:
    return {
        "run": "",
        "optimizer": optimizer,
        "problem": problem,
        "seed": seed,
        "budget": config.budget,
        "fidelity": config.fidelity,
        "status": "not run",
        "stop_reason": "",
        "n_simulations": 0,
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
    done = [r for r in runs if r["status"] == "done"]
    summary, curves_by = [], {}
    for problem in dict.fromkeys(r["problem"] for r in runs):
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
    done = [r for r in runs if r["status"] == "done"]
    notes += sorted({f"- {r['optimizer']}: {r['note']}" for r in done if r["note"]})
    notes += sorted(
        {f"- {r['optimizer']} on {r['problem']}: not run: {r['note']}" for r in runs if r not in done}
    )
    notes += identical_histories(evaluations, runs)
    text = table + "\n\n" + "\n".join(notes) + "\n\n" + views(folder, curves, runs)
    (folder / "optimizers.md").write_text(text + "\n", encoding="utf-8")
    _figure(curves, reference, folder / "convergence.png")
    _write_ioh(folder / "ioh", evaluations, runs)
    return text


def identical_histories(evaluations: list[dict[str, Any]], runs: list[dict[str, Any]]) -> list[str]:
    """Notes on pairs of optimisers whose runs proposed the same designs on every problem and seed, and why
    (DE's first population is a random sample drawn from the same seed as random search's)."""
    designs: dict[tuple[str, str, int], list[str]] = {}
    for row in evaluations:
        designs.setdefault((row["optimizer"], row["problem"], int(row["seed"])), []).append(str(row["x_m"]))
    names = list(dict.fromkeys(r["optimizer"] for r in runs if r["status"] == "done"))
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


def views(folder: Path, curves: dict[str, dict[str, np.ndarray]], runs: list[dict[str, Any]]) -> str:
    """The fixed-budget, fixed-target and rank views (:mod:`experiments.benchmark_views`); writes
    ``fixed_budget.csv``, ``fixed_target.csv``, ``ranks.csv`` and ``ecdf.png``; returns their Markdown."""
    done = [r for r in runs if r["status"] == "done"]
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
    parts = ["### Fixed budget: best σ (N), median [IQR] of the runs", markdown_table(
        budget_rows, [("problem", "problem", "s"), ("optimizer", "optimiser", "s"), ("runs", "runs", "d")]
        + [(k, f"after {k[3:]} simulations", "s") for k in budget_rows[0] if k.startswith("at_")],
    )] if budget_rows else []  # fmt: skip
    if target_rows:
        write_csv(folder / "fixed_target.csv", target_rows)
        columns = [("problem", "problem", "s"), ("optimizer", "optimiser", "s")]
        columns += [(f"cell_{100 * t:g}", f"ERT to {100 * t:g} % (runs reached)", "s") for t in bv.TARGETS]
        targets = ", ".join(f"{p} {s:.2f} N" for p, s in best.items())
        parts += [f"### Fixed target: simulations to come within x % of the best-known σ ({targets})",
                  markdown_table(target_rows, columns)]  # fmt: skip
        budget = int(max(int(r["budget"]) for r in done))
        bv.ecdf_figure(bv.ecdf(curves, lengths, best, budget), list(best), folder / "ecdf.png")
    if len(finals) >= 3:
        parts.append(_rank_section(folder, finals))
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


def _rank_section(folder: Path, finals: dict[str, dict[tuple[str, int], float]]) -> str:
    friedman, pairs = bv.rank_tests(finals)
    write_csv(folder / "ranks.csv", pairs)
    ranks = sorted(friedman["mean_ranks"].items(), key=lambda item: item[1])
    significant = [f"{p['better']} better than {p['b'] if p['better'] == p['a'] else p['a']} "
                   f"(p = {p['p_holm']:.3f})" for p in pairs if p["significant"]]  # fmt: skip
    return "\n".join([
        f"### Ranks over {friedman['blocks']} blocks (problem, seed) by final best σ",
        "",
        "mean rank (1 = best): " + ", ".join(f"{name} {rank:.2f}" for name, rank in ranks),
        "",
        f"Friedman χ² = {friedman['statistic']:.2f}, p = {friedman['p_value']:.2g}; pairwise Wilcoxon "
        f"signed-rank tests with Holm's correction at {bv.ALPHA:g}: "
        + ("; ".join(significant) if significant else "no pair differs significantly"),
    ])  # fmt: skip


def _figure(curves: dict[str, dict[str, np.ndarray]], reference: dict[str, float], path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    fig, axes = plt.subplots(1, len(curves), figsize=(5.5 * len(curves), 4.2), squeeze=False)
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
    done = [r for r in runs if r["status"] == "done"]
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


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.optimizer_comparison``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.optimizer_comparison")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.optimizer_comparison"))
