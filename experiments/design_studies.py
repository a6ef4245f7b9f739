"""Studies 3–5: the six GA design studies, the static analysis of their optima and their speed robustness
(docs/problems.md, 'Experiments').

For each problem B1, B2, B3, SW1, SW2, SW3:

1. *Design study*: the published study's genetic algorithm (``optimizers.ga``, MATLAB's integer ``ga`` with
   that study's population sizes, stall rule and generation limit) at 300 km/h; its best design is confirmed
   on the exact model (fidelity ``"reference"``), together with the reference design, and both σ are reported.
2. *Static analysis*: contact-wire stiffness along the central span at 100 N and 200 N, its variability
   α = (k_max − k_min) / (k_max + k_min) and static dropper forces, for the reference design and the optimum.
3. *Speed robustness*: σ of the reference design and the optimum from 200 to 320 km/h.

Every simulation is resumable: the GA's evaluations live in the run store the studies share
(``runs.sqlite`` in the output folder; an interrupted GA replays its stored evaluations and goes on), and
every other result is appended to ``log.jsonl`` as it completes, keyed by the model's fingerprint, so
that nothing is simulated twice. Each problem writes its data under ``design/<problem>/`` as soon as it
is done; :func:`report` makes the tables and figures from those files alone.

Quick: the ``"test"`` fidelity (a short, coarse section), a GA of 10 individuals over 2 generations,
7 stiffness points, 3 speeds. Full: 20 spans on the study fidelity, the published study's GA, 23 stiffness
points, 200–320 km/h in 20 km/h steps.

    python -m experiments.design_studies [--full] [--problems B1 SW1] [--workers 2] [--out results]
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from catenary_env.analysis.static_analysis import stiffness_profile
from catenary_env.fem.layout import CONTACT
from catenary_env.pipeline import solve_static
from catenary_env.problems import get_problem
from catenary_env.problems.design_problem import DesignProblem, resolve_fidelity
from optimizers.ga import POPULATION_SIZES, GAOptions
from optimizers.runner import optimize

from .common import (
    DEFAULT_OUT,
    STORE,
    ResultLog,
    add_full_option,
    add_out_option,
    add_workers_option,
    markdown_table,
    read_csv,
    run_cli,
    run_study,
    seed_value,
    study_dir,
    write_csv,
)
from .model_stamp import catenaries_of, stamp_study

NAME = "design"
PROBLEMS = ("B1", "B2", "B3", "SW1", "SW2", "SW3")
DESIGN_SPEED = 300.0
"""km/h: the problems' design speed (docs/problems.md)."""
STATIC_FORCES = (100.0, 200.0)
"""N: the upward forces of the stiffness profiles (docs/model.md, 'Static analysis')."""
FULL_BUDGET = 20_000
"""Simulations a full GA run may charge: a cap only, the GA stops by its stall rule or generation limit
well before it (the budget is part of a run's identity in the store, so it never changes)."""


@dataclass(frozen=True)
class Config:
    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 2
    problems: tuple[str, ...] = PROBLEMS
    seed: int = 0

    @property
    def fidelity(self) -> str:
        """The GA's and the sweeps' model."""
        return "study" if self.full else "test"

    @property
    def confirm_fidelity(self) -> str:
        """The model that confirms the optimum: the exact one (the quick setting's is already exact)."""
        return "reference" if self.full else "test"

    @property
    def ga_options(self) -> GAOptions:
        return GAOptions() if self.full else GAOptions(population_size=10, max_generations=2)

    @property
    def budget(self) -> int:
        return FULL_BUDGET if self.full else 40

    @property
    def speeds_kmh(self) -> tuple[float, ...]:
        return tuple(np.arange(200.0, 321.0, 20.0)) if self.full else (200.0, 260.0, 320.0)

    @property
    def stiffness_points(self) -> int:
        return 23 if self.full else 7


Task = tuple[str, "tuple[float, ...] | None"]
"""A design to evaluate: its label (``"reference"`` or ``"optimum"``) and its variables (None: the reference
design, which B3 and SW3 cannot express in their variables)."""


def _evaluate_group(
    problem_name: str, designs: list[tuple[float, ...] | None], speed: float, fidelity: str
) -> list[dict]:
    """σ and feasibility of designs at one speed and fidelity, in a worker process: one group per speed,
    so that the worker calibrates the pantograph's uplift once for all of them."""
    problem = get_problem(problem_name)
    rows = []
    for x in designs:
        ev = (
            problem.reference_evaluation(speed, fidelity)
            if x is None
            else problem.evaluate(np.asarray(x), speed, fidelity)
        )
        stats = ev.statistics
        rows.append(
            {
                "feasible": int(ev.feasible),
                "sigma_N": float("nan") if stats is None else float(stats.std),
                "mean_N": float("nan") if stats is None else float(stats.mean),
                "uplift_N": float(ev.uplift_force),
                "wall_time_s": float(ev.wall_time),
                "reason": ev.reason,
            }
        )
    return rows


def _static_data(problem_name: str, x: tuple[float, ...] | None, fidelity: str, n_points: int) -> dict:
    """The central span's contact-wire profile, dropper forces and stiffness profiles, in a worker."""
    problem = get_problem(problem_name)
    design = problem.reference_design() if x is None else problem.design(np.asarray(x))
    static = solve_static(problem.catenary_definition, design, resolve_fidelity(fidelity))
    lay = static.layout
    span = lay.n_spans // 2
    x0 = span * lay.span_length
    base = lay.catenary.contact_wire_height
    nodes = np.flatnonzero(
        (lay.node_kind == CONTACT) & (lay.node_x >= x0 - 1e-9) & (lay.node_x <= x0 + lay.span_length + 1e-9)
    )
    central = lay.dropper_span == span
    bottoms = lay.bar_nodes[lay.dropper_bars[central], 1]
    profiles = [stiffness_profile(static, force, n_points) for force in STATIC_FORCES]
    return {
        "wire_x_m": (lay.node_x[nodes] - x0).tolist(),
        "wire_height_m": (static.positions[lay.node_dof[nodes] + 1] - base).tolist(),
        "dropper_x_m": (lay.node_x[bottoms] - x0).tolist(),
        "dropper_height_m": (static.positions[lay.node_dof[bottoms] + 1] - base).tolist(),
        "dropper_force_N": static.dropper_forces[central].tolist(),
        "stiffness": [
            {"force_N": p.force, "x_m": p.positions.tolist(), "k_N_per_m": p.stiffness.tolist()}
            for p in profiles
        ],
        "feasible": not static.infeasibility(),
    }


class _Runner:
    """Runs the tasks of one problem in worker processes, skipping those the log holds."""

    def __init__(self, problem: DesignProblem, log: ResultLog, workers: int) -> None:
        self.problem = problem
        self.log = log
        self.workers = workers
        self.prefix = f"{problem.name}|{problem.store_fingerprint()}"

    def _key(self, kind: str, x: tuple[float, ...] | None, *rest: object) -> str:
        return "|".join([kind, self.prefix, "reference" if x is None else repr(x), *map(str, rest)])

    def evaluations(self, tasks: list[Task], speeds: tuple[float, ...], fidelity: str) -> list[dict]:
        """Rows (design, speed_kmh, fidelity, feasible, sigma_N, ...) of every task at every speed."""
        groups = {
            speed: [
                (label, x)
                for label, x in tasks
                if self.log.get(self._key("eval", x, speed, fidelity)) is None
            ]
            for speed in speeds
        }
        with self._pool(sum(1 for g in groups.values() if g)) as pool:
            futures = {
                speed: pool.submit(_evaluate_group, self.problem.name, [x for _, x in group], speed, fidelity)
                for speed, group in groups.items()
                if group
            }
            for speed, future in futures.items():
                for (_, x), row in zip(groups[speed], future.result(), strict=True):
                    self.log.put(self._key("eval", x, speed, fidelity), row)
        return [
            {
                "design": label,
                "speed_kmh": speed,
                "fidelity": fidelity,
                **self.log.get(self._key("eval", x, speed, fidelity)),
            }
            for speed in speeds
            for label, x in tasks
        ]

    def statics(self, tasks: list[Task], fidelity: str, n_points: int) -> dict[str, dict]:
        """Static data of every task's design, by label."""
        keys = {label: self._key("static", x, fidelity, n_points) for label, x in tasks}
        todo = [(label, x) for label, x in tasks if self.log.get(keys[label]) is None]
        with self._pool(len(todo)) as pool:
            futures = {
                label: pool.submit(_static_data, self.problem.name, x, fidelity, n_points)
                for label, x in todo
            }
            for label, future in futures.items():
                self.log.put(keys[label], future.result())
        return {label: self.log.get(keys[label]) for label, _ in tasks}

    def _pool(self, n_tasks: int) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(max_workers=max(1, min(self.workers, n_tasks)))


# -- one problem ------------------------------------------------------------------------------------------


def generation_of(index: int, population: int, elite: int) -> int:
    """The GA generation of the evaluation at ``index`` of a run's history: the initial population is
    generation 0, each later generation evaluates ``population − elite`` children (the elite is not
    evaluated again, optimizers/ga.py)."""
    return 0 if index < population else 1 + (index - population) // (population - elite)


def convergence_rows(history: list[dict], population: int, elite: int) -> list[dict]:
    """Best and mean σ of the GA's population per generation, from the history's rows.

    The population of generation g is the elite of generation g − 1 (its ``elite`` lowest losses) and the
    children evaluated in g; the mean is over its feasible individuals.
    """
    rows = []
    losses: np.ndarray = np.empty(0)
    simulations = 0
    for generation in sorted({int(r["generation"]) for r in history}):
        batch = [r for r in history if int(r["generation"]) == generation]
        children = np.array([r["sigma_N"] if r["feasible"] else np.inf for r in batch], dtype=float)
        losses = np.concatenate([np.sort(losses)[:elite], children]) if generation else children
        simulations += sum(int(r["charged"]) for r in batch)
        finite = losses[np.isfinite(losses)]
        rows.append(
            {
                "generation": generation,
                "best_sigma_N": float(finite.min()) if finite.size else float("nan"),
                "mean_sigma_N": float(finite.mean()) if finite.size else float("nan"),
                "feasible_share": finite.size / losses.size,
                "simulations": simulations,
            }
        )
    return rows


def run_problem(name: str, config: Config, folder: Path, log: ResultLog) -> Path:
    """The design study, static analysis and speed sweep of one problem; returns its data folder."""
    problem = get_problem(name)
    options = config.ga_options
    ga_result = optimize(
        name,
        "ga",
        config.budget,
        config.seed,
        speed_kmh=DESIGN_SPEED,
        fidelity=config.fidelity,
        options=options,
        store=Path(config.out) / STORE,
        resume=True,
        n_workers=config.workers,
        quiet=False,
    )
    population = options.population_size or POPULATION_SIZES[name]
    history = [
        {
            "index": r.index,
            "generation": generation_of(r.index, population, options.elite_count),
            **{v: x for v, x in zip(problem.variables, r.x, strict=True)},
            "feasible": int(r.feasible),
            "sigma_N": float("nan") if r.sigma is None else r.sigma,
            "charged": int(r.charged),
            "cached": int(r.cached),
            "wall_time_s": r.wall_time,
            "reason": r.reason,
        }
        for r in ga_result.history
    ]
    out = study_dir(folder, name)
    write_csv(out / "history.csv", history)
    convergence = convergence_rows(history, population, options.elite_count)
    write_csv(out / "convergence.csv", convergence)
    summary: dict[str, Any] = {
        "problem": name,
        "catenary": problem.catenary,
        "variables": list(problem.variables),
        "reference_x": None if problem.reference_x() is None else problem.reference_x().tolist(),
        "optimum_x": None if ga_result.best_x is None else list(ga_result.best_x),
        "sigma_optimum_N": ga_result.best_sigma,
        "generations": convergence[-1]["generation"],
        "simulations": ga_result.n_simulations,
        "evaluations": len(ga_result.history),
        "stop_reason": ga_result.stop_reason,
        "population": population,
        "fidelity": config.fidelity,
        "confirm_fidelity": config.confirm_fidelity,
        "ga_wall_time_s": float(sum(r.wall_time for r in ga_result.history)),
    }
    tasks: list[Task] = [("reference", None)]
    if ga_result.best_x is not None:
        tasks.append(("optimum", tuple(ga_result.best_x)))
    runner = _Runner(problem, log, config.workers)
    design_rows = runner.evaluations(tasks[:1], (DESIGN_SPEED,), config.fidelity)
    confirm_rows = runner.evaluations(tasks, (DESIGN_SPEED,), config.confirm_fidelity)
    summary["sigma_reference_N"] = design_rows[0]["sigma_N"]
    summary["sigma_reference_confirmed_N"] = confirm_rows[0]["sigma_N"]
    summary["sigma_optimum_confirmed_N"] = confirm_rows[-1]["sigma_N"] if len(tasks) > 1 else None
    summary["optimum_confirmed_feasible"] = bool(confirm_rows[-1]["feasible"]) if len(tasks) > 1 else None
    write_csv(out / "speed.csv", runner.evaluations(tasks, config.speeds_kmh, config.fidelity))
    statics = runner.statics(tasks, config.fidelity, config.stiffness_points)
    _write_statics(out, statics)
    (out / "summary.json").write_text(json.dumps(summary, indent=2), encoding="utf-8")
    return out


def _write_statics(out: Path, statics: dict[str, dict]) -> None:
    geometry, droppers, stiffness = [], [], []
    for label, data in statics.items():
        geometry += [
            {"design": label, "x_m": x, "height_m": z}
            for x, z in zip(data["wire_x_m"], data["wire_height_m"], strict=True)
        ]
        droppers += [
            {"design": label, "x_m": x, "height_m": z, "force_N": f}
            for x, z, f in zip(
                data["dropper_x_m"], data["dropper_height_m"], data["dropper_force_N"], strict=True
            )
        ]
        stiffness += [
            {"design": label, "force_N": p["force_N"], "x_m": x, "k_N_per_m": k}
            for p in data["stiffness"]
            for x, k in zip(p["x_m"], p["k_N_per_m"], strict=True)
        ]
    write_csv(out / "geometry.csv", geometry)
    write_csv(out / "droppers.csv", droppers)
    write_csv(out / "stiffness.csv", stiffness)


def main(config: Config) -> Path:
    folder = study_dir(config.out, NAME)
    log = ResultLog(folder / "log.jsonl")
    for name in config.problems:
        get_problem(name)  # an unknown name fails here, before any simulation
    for name in config.problems:
        run_problem(name, config, folder, log)
    stamp_study(folder, catenaries_of(config.problems))
    report(folder)
    return folder


# -- report: tables and figures from the data files alone ------------------------------------------------


def _reduction(reference: float | None, value: float | None) -> float:
    """Reduction of ``value`` against ``reference``, %, NaN where either is missing."""
    if reference is None or value is None or not np.isfinite(reference) or not np.isfinite(value):
        return float("nan")
    return 100.0 * (1.0 - value / reference)


def _alpha(rows: list[dict], design: str, force: float) -> float:
    k = np.array([r["k_N_per_m"] for r in rows if r["design"] == design and r["force_N"] == force])
    return float((k.max() - k.min()) / (k.max() + k.min())) if k.size else float("nan")


def _load(folder: Path) -> list[tuple[dict, Path]]:
    done = []
    for name in PROBLEMS:
        path = folder / name / "summary.json"
        if path.exists():
            done.append((json.loads(path.read_text(encoding="utf-8")), folder / name))
    return done


def _format_x(names: list[str], x: list[float] | None) -> str:
    if x is None:
        return "–"
    return ", ".join(
        f"{n} = {1e3 * v:+.0f} mm" if n.startswith("dh") or n == "s" else f"{n} = {v:.2f} m"
        for n, v in zip(names, x, strict=True)
    )


def report(folder: Path) -> str:
    """Markdown tables (written to ``design.md``) and figures of every problem done so far, no simulation."""
    done = _load(folder)
    if not done:
        return f"no design study data under {folder}"
    headline, optima, alphas, speed_rows, dropper_rows = [], [], [], [], []
    for s, sub in done:
        headline.append(
            {
                **s,
                "reduction": _reduction(s["sigma_reference_N"], s["sigma_optimum_N"]),
                "sigma_optimum_confirmed_N": s["sigma_optimum_confirmed_N"] or float("nan"),
                "reduction_confirmed": _reduction(
                    s["sigma_reference_confirmed_N"], s["sigma_optimum_confirmed_N"]
                ),
                "sigma_optimum_N": s["sigma_optimum_N"] or float("nan"),
            }
        )
        optima.append({"problem": s["problem"], "optimum": _format_x(s["variables"], s["optimum_x"])})
        stiffness = read_csv(sub / "stiffness.csv")
        row: dict[str, Any] = {"problem": s["problem"]}
        for force in STATIC_FORCES:
            ref, opt = _alpha(stiffness, "reference", force), _alpha(stiffness, "optimum", force)
            row |= {f"ref{force:.0f}": ref, f"opt{force:.0f}": opt, f"red{force:.0f}": _reduction(ref, opt)}
        alphas.append(row)
        speed_rows += [{"problem": s["problem"], **r} for r in read_csv(sub / "speed.csv")]
        dropper_rows += _dropper_force_rows(s["problem"], read_csv(sub / "droppers.csv"))
        _problem_figure(s, sub)
    fidelity = done[0][0]["fidelity"]
    confirm = done[0][0]["confirm_fidelity"]
    text = "\n\n".join(
        [
            f"σ at 300 km/h on the {fidelity!r} model, confirmed on the {confirm!r} model:",
            markdown_table(
                headline,
                [
                    ("problem", "problem", "s"),
                    ("sigma_reference_N", "σ reference (N)", ".2f"),
                    ("sigma_optimum_N", "σ optimum (N)", ".2f"),
                    ("reduction", "reduction (%)", ".1f"),
                    ("sigma_reference_confirmed_N", f"σ ref. {confirm} (N)", ".2f"),
                    ("sigma_optimum_confirmed_N", f"σ opt. {confirm} (N)", ".2f"),
                    ("reduction_confirmed", f"reduction {confirm} (%)", ".1f"),
                    ("generations", "generations", "d"),
                    ("simulations", "simulations", "d"),
                    ("stop_reason", "stop", "s"),
                ],
            ),
            markdown_table(optima, [("problem", "problem", "s"), ("optimum", "optimal variables", "s")]),
            "Variability α = (k_max − k_min) / (k_max + k_min) of the static stiffness along the span:",
            markdown_table(
                alphas,
                [("problem", "problem", "s")]
                + [
                    (f"{kind}{f:.0f}", f"{label} {f:.0f} N", fmt)
                    for f in STATIC_FORCES
                    for kind, label, fmt in (
                        ("ref", "α ref.", ".3f"),
                        ("opt", "α opt.", ".3f"),
                        ("red", "reduction (%)", ".1f"),
                    )
                ],
            ),
            "Static dropper forces of the central span (N), at the design's dropper positions:",
            markdown_table(
                dropper_rows,
                [
                    ("problem", "problem", "s"),
                    ("design", "design", "s"),
                    ("forces", "first to last dropper", "s"),
                    ("min", "smallest", ".1f"),
                    ("max", "largest", ".1f"),
                ],
            ),
            "σ (N) against speed:",
            _speed_table(speed_rows),
        ]
    )
    (folder / "design.md").write_text(text + "\n", encoding="utf-8")
    _speed_figure(speed_rows, folder / "speed.png")
    _convergence_figure(done, folder / "convergence.png")
    return text


def _dropper_force_rows(problem: str, droppers: list[dict]) -> list[dict[str, Any]]:
    """One row per design: its static dropper forces in order along the span, smallest and largest."""
    rows = []
    for design in ("reference", "optimum"):
        forces = [r["force_N"] for r in droppers if r["design"] == design]
        if forces:
            rows.append(
                {
                    "problem": problem,
                    "design": design,
                    "forces": ", ".join(f"{f:.1f}" for f in forces),
                    "min": min(forces),
                    "max": max(forces),
                }
            )
    return rows


def _speed_table(rows: list[dict]) -> str:
    speeds = sorted({r["speed_kmh"] for r in rows})
    lines = ["| problem | design | " + " | ".join(f"{v:g} km/h" for v in speeds) + " |"]
    lines.append("|---|---|" + "---|" * len(speeds))
    for problem in dict.fromkeys(r["problem"] for r in rows):
        for design in ("reference", "optimum"):
            values = {r["speed_kmh"]: r for r in rows if r["problem"] == problem and r["design"] == design}
            if values:
                cells = [
                    f"{values[v]['sigma_N']:.2f}" if v in values and values[v]["feasible"] else "infeasible"
                    for v in speeds
                ]
                lines.append(f"| {problem} | {design} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _problem_figure(summary: dict, sub: Path) -> None:
    """The optimal span geometry against the reference, the GA's convergence and the stiffness profiles."""
    from catenary_env.plots import pyplot

    plt = pyplot()
    geometry, droppers = read_csv(sub / "geometry.csv"), read_csv(sub / "droppers.csv")
    convergence, stiffness = read_csv(sub / "convergence.csv"), read_csv(sub / "stiffness.csv")
    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(15, 4))
    for design, style in (("reference", "C7"), ("optimum", "C0")):
        wire = [r for r in geometry if r["design"] == design]
        drops = [r for r in droppers if r["design"] == design]
        left.plot(
            [r["x_m"] for r in wire], [1e3 * r["height_m"] for r in wire], "-", color=style, label=design
        )
        left.plot([r["x_m"] for r in drops], [1e3 * r["height_m"] for r in drops], "o", color=style, ms=5)
        for force, dash in zip(STATIC_FORCES, ("-", "--"), strict=True):
            pick = [r for r in stiffness if r["design"] == design and r["force_N"] == force]
            right.plot(
                [r["x_m"] for r in pick],
                [r["k_N_per_m"] / 1e3 for r in pick],
                dash,
                color=style,
                label=f"{design}, {force:.0f} N",
            )
    left.set_xlabel("position in span (m)")
    left.set_ylabel("contact-wire height (mm, 0 = level)")
    left.set_title(f"{summary['problem']}: span geometry (dots: droppers)")
    left.legend(fontsize=8)
    generations = [r["generation"] for r in convergence]
    middle.plot(generations, [r["best_sigma_N"] for r in convergence], "C0-", label="best")
    middle.plot(generations, [r["mean_sigma_N"] for r in convergence], "C1-", label="mean (feasible)")
    middle.axhline(summary["sigma_reference_N"], color="C7", ls="--", lw=0.8, label="reference design")
    middle.set_xlabel("generation")
    middle.set_ylabel("σ of the contact force (N)")
    middle.set_title(f"GA convergence ({summary['simulations']} simulations)")
    middle.legend(fontsize=8)
    right.set_xlabel("position in span (m)")
    right.set_ylabel("static stiffness (kN/m)")
    right.set_title("stiffness along the span")
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(sub / "design.png", dpi=110)
    plt.close(fig)


def _speed_figure(rows: list[dict], path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    problems = list(dict.fromkeys(r["problem"] for r in rows))
    fig, axes = plt.subplots(1, len(problems), figsize=(3.2 * len(problems), 3.2), sharey=True, squeeze=False)
    for ax, problem in zip(axes[0], problems, strict=True):
        for design, style in (("reference", "C7o-"), ("optimum", "C0o-")):
            pick = [r for r in rows if r["problem"] == problem and r["design"] == design and r["feasible"]]
            ax.plot([r["speed_kmh"] for r in pick], [r["sigma_N"] for r in pick], style, ms=3, label=design)
        ax.set_title(problem)
        ax.set_xlabel("speed (km/h)")
    axes[0][0].set_ylabel("σ of the contact force (N)")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _convergence_figure(done: list[tuple[dict, Path]], path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for i, (s, sub) in enumerate(done):
        rows = read_csv(sub / "convergence.csv")
        ax.plot(
            [r["simulations"] for r in rows],
            [r["best_sigma_N"] / s["sigma_reference_N"] for r in rows],
            "-",
            color=f"C{i}",
            label=s["problem"],
        )
    ax.set_xlabel("simulations")
    ax.set_ylabel("best σ / σ of the reference design")
    ax.set_title("GA design studies at 300 km/h")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment design`` and ``python -m experiments.design_studies``)."""
    add_full_option(
        parser, "20 spans and the study's GA (hours per problem), instead of 5 spans and a small GA"
    )
    parser.add_argument(
        "--problems",
        nargs="+",
        default=list(PROBLEMS),
        choices=PROBLEMS,
        metavar="NAME",
        help=f"the design problems studied, of {' '.join(PROBLEMS)} (default: all six)",
    )
    add_workers_option(parser, 2)
    parser.add_argument(
        "--seed",
        type=seed_value,
        default=0,
        metavar="S",
        help="the GA's random seed, an integer >= 0 (default 0)",
    )
    add_out_option(parser)


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.design_studies``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.design_studies")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.design_studies"))
