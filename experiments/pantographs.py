"""Study: two pantographs (docs/model.md, 'Several pantographs'; docs/problems.md, 'Experiments').

1. *Optima behind a leader*: the six design studies' optima (``results/design/<problem>/summary.json``) and
   their level reference designs at 300 km/h with a trailing pantograph :data:`SPACING` m behind, the same
   pantograph with the same uplift force (the problem's, set once on the reference design): σ of each
   pantograph, and whether each optimum still beats the level wire for the trailing one.
2. *Design for the worse pantograph*: the published study's GA on B1 and SW1 with the ``worst`` objective
   (the larger σ of the two pantographs); its optimum against the single-pantograph optimum, σ of both
   pantographs from 200 to 320 km/h.

Quick: the "test" fidelity on 10 spans (so that a 200 m train fits on the section), a GA of 10 individuals
over 2 generations on the 5-span "test" section (the run store knows fidelities by name), whose train is as
long as that section takes (one span), 3 speeds. Full: the study fidelity (20 spans), the published study's
GA, 200-320 km/h in 20 km/h steps. The GA's evaluations live in the run store the studies share
(resumable).

    python -m experiments.pantographs [--full] [--workers 2] [--out results] [--designs results]
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

from catenary_env.pipeline import CONSTRAINTS, Evaluation, Fidelity, analysis_window, evaluate
from catenary_env.problems import get_problem, resolve_fidelity
from catenary_env.train import Train
from optimizers.base import OptimizationResult
from optimizers.catenary_adapter import catenary_problem
from optimizers.ga import GAOptions
from optimizers.runner import optimize

from .common import (
    DEFAULT_OUT,
    STORE,
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
    write_json,
)
from .model_stamp import catenaries_of, stamp_study

NAME = "pantographs"
DESIGN_PROBLEMS = ("B1", "B2", "B3", "SW1", "SW2", "SW3")
GA_PROBLEMS = ("B1", "SW1")
SPACING = 200.0
"""m between the two pantographs (the common spacing above 250 km/h)."""
DESIGN_SPEED = 300.0
"""km/h."""
FULL_BUDGET = 20_000
"""Simulations a full GA run may charge (a cap: it stops by its stall rule), as the design studies'."""


@dataclass(frozen=True)
class Config:
    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 2
    designs: Path = DEFAULT_OUT
    problems: tuple[str, ...] = DESIGN_PROBLEMS
    ga_problems: tuple[str, ...] = GA_PROBLEMS
    seed: int = 0
    optima_only: bool = False

    @property
    def fidelity(self) -> Fidelity:
        """The study fidelity (20 spans), or the test one on 10 spans: room for a 200 m train."""
        return resolve_fidelity("study") if self.full else resolve_fidelity("test", 10)

    @property
    def ga_fidelity(self) -> str:
        """The GA's fidelity, by name (the run store's key)."""
        return "study" if self.full else "test"

    def ga_spacing(self, problem: str) -> float:
        """The GA's train: :data:`SPACING`, or the longest the quick GA's section takes, m."""
        if self.full:
            return SPACING
        catenary, fidelity = get_problem(problem).catenary_definition, resolve_fidelity("test")
        return Train().spacing_range(catenary, fidelity.n_spans, analysis_window(catenary, fidelity)[1])[1]

    @property
    def ga_options(self) -> GAOptions:
        return GAOptions() if self.full else GAOptions(population_size=10, max_generations=2)

    @property
    def budget(self) -> int:
        return FULL_BUDGET if self.full else 40

    @property
    def speeds_kmh(self) -> tuple[float, ...]:
        return tuple(np.arange(200.0, 321.0, 20.0)) if self.full else (200.0, 260.0, 320.0)


def train_of(problem: str, objective: str = "leading", spacing: float = SPACING) -> Train:
    """The problem's pantograph and a second one ``spacing`` m behind it."""
    return Train.behind([get_problem(problem).pantograph_definition], spacing, objective)


def evaluate_design(
    problem: str, x: tuple[float, ...] | None, speed_kmh: float, fidelity: Fidelity
) -> Evaluation:
    """A design of the problem (``x`` None: its reference design) at a speed, with the trailing pantograph
    and the problem's uplift force (picklable, for the workers)."""
    p, train = get_problem(problem), train_of(problem)
    force = p.uplift_force(speed_kmh, fidelity)
    if x is None:  # B3 and SW3 cannot express it in their variables
        catenary, pantograph = p.catenary_definition, p.pantograph_definition
        return evaluate(
            catenary, pantograph, p.reference_design(), speed_kmh / 3.6, fidelity, force, train=train
        )
    return p.evaluate(x, speed_kmh, fidelity, uplift_force=force, train=train)


def single_optimum(designs: Path, problem: str) -> tuple[float, ...] | None:
    """The design study's optimum of ``problem`` (``designs/design/<problem>/summary.json``), or None."""
    path = Path(designs) / "design" / problem / "summary.json"
    if not path.exists():
        return None
    x = json.loads(path.read_text(encoding="utf-8")).get("optimum_x")
    return None if x is None else tuple(float(v) for v in x)


def _row(problem: str, design: str, speed: float, ev: Evaluation) -> dict[str, Any]:
    blocks = ev.pantograph_statistics or (None, None)
    row: dict[str, Any] = {
        "problem": problem,
        "design": design,
        "speed_kmh": speed,
        "feasible": int(ev.feasible),
    }
    for which, stats in zip(("leading", "trailing"), blocks, strict=True):
        row[f"sigma_{which}_N"] = float("nan") if stats is None else stats.std
        row[f"mean_{which}_N"] = float("nan") if stats is None else stats.mean
        row[f"loss_{which}_percent"] = float("nan") if stats is None else stats.contact_loss_percent
    row["reason"] = ev.reason
    return row


def _evaluate_all(
    tasks: list[tuple[str, str, tuple[float, ...] | None, float]], config: Config
) -> list[dict]:
    """Rows of (problem, design label, x, speed) tasks; the uplift is calibrated here, once per problem and
    speed."""
    for problem, speed in dict.fromkeys((t[0], t[3]) for t in tasks):
        get_problem(problem).uplift_force(speed, config.fidelity)  # calibrated once, cached for the workers
    args = [(p, x, speed, config.fidelity) for p, _, x, speed in tasks]
    with ProcessPoolExecutor(max_workers=config.workers) as pool:
        evaluations = list(pool.map(evaluate_design, *zip(*args, strict=True)))
    return [_row(p, label, speed, ev) for (p, label, _, speed), ev in zip(tasks, evaluations, strict=True)]


def optima_table(config: Config) -> list[dict]:
    """Part 1: each design study's optimum and level design at 300 km/h, with a trailing pantograph."""
    tasks = []
    for problem in config.problems:
        tasks.append((problem, "level", None, DESIGN_SPEED))
        x = single_optimum(config.designs, problem)
        if x is not None:
            tasks.append((problem, "optimum", x, DESIGN_SPEED))
    return _evaluate_all(tasks, config)


def beats_level(rows: list[dict]) -> list[dict]:
    """The rows with ``beats_level_trailing``: 1 where the design gives the trailing pantograph a lower σ than
    its problem's level wire, losing contact no more often (both may lose it: ``feasible`` says)."""
    out = []
    for row in rows:
        level = next(r for r in rows if r["problem"] == row["problem"] and r["design"] == "level")
        better = row["sigma_trailing_N"] < level["sigma_trailing_N"]
        kept = row["loss_trailing_percent"] <= level["loss_trailing_percent"]
        out.append(row | {"beats_level_trailing": int(row["design"] != "level" and better and kept)})
    return out


def worst_design(problem: str, config: Config) -> tuple[tuple[float, ...] | None, dict[str, Any]]:
    """Part 2's GA: the problem with a trailing pantograph and the ``worst`` objective; its best design (None
    if it met no feasible one) and a summary of the search (:func:`search_summary`)."""
    result = optimize(
        catenary_problem(problem, train_of(problem, "worst", config.ga_spacing(problem))),
        "ga",
        config.budget,
        config.seed,
        speed_kmh=DESIGN_SPEED,
        fidelity=config.ga_fidelity,
        options=config.ga_options,
        store=Path(config.out) / STORE,
        resume=True,
        n_workers=config.workers,
        quiet=False,
    )
    best = None if result.best_x is None else tuple(float(v) for v in result.best_x)
    return best, search_summary(result)


def search_summary(result: OptimizationResult) -> dict[str, Any]:
    """What a GA run met: simulations, stop reason, best σ (None when no design was feasible), and the
    design with the least contact loss of any pantograph (the constraint a trailing pantograph breaks)."""
    index = CONSTRAINTS.index("contact_loss_percent")
    known = [r for r in result.history if len(r.constraints) > index and np.isfinite(r.constraints[index])]
    closest = min(known, key=lambda r: r.constraints[index], default=None)
    return {
        "simulations": result.n_simulations,
        "stop_reason": result.stop_reason,
        "best_sigma_N": result.best_sigma,
        "least_contact_loss_percent": None if closest is None else float(closest.constraints[index]),
        "least_contact_loss_x": None if closest is None else [float(v) for v in closest.x],
    }


def main(config: Config) -> Path:
    folder = study_dir(config.out, NAME)
    write_csv(folder / "optima.csv", optima_table(config))
    designs, searches, tasks = {}, {}, []
    for problem in () if config.optima_only else config.ga_problems:
        worst, searches[problem] = worst_design(problem, config)
        designs[problem] = {"single": single_optimum(config.designs, problem), "worst": worst}
        for label, x in designs[problem].items():
            if x is not None:
                tasks.extend((problem, label, x, speed) for speed in config.speeds_kmh)
    if tasks:
        write_csv(folder / "speed.csv", _evaluate_all(tasks, config))
        (folder / "designs.json").write_text(json.dumps(designs, indent=1) + "\n", encoding="utf-8")
    if searches:
        write_json(folder / "searches.json", searches)
    stamp_study(folder, catenaries_of(config.problems + config.ga_problems))
    report(folder)
    return folder


def report(folder: Path) -> str:
    """Tables and the figure from the data files (no simulation)."""
    optima = beats_level(read_csv(folder / "optima.csv"))
    table = markdown_table(
        optima,
        [
            ("problem", "problem", "s"),
            ("design", "design", "s"),
            ("sigma_leading_N", "σ leading (N)", ".2f"),
            ("sigma_trailing_N", "σ trailing (N)", ".2f"),
            ("loss_trailing_percent", "trailing contact loss (%)", ".2f"),
            ("feasible", "feasible", ".0f"),
            ("beats_level_trailing", "beats level (trailing)", ".0f"),
        ],
    )
    if (folder / "searches.json").exists():
        table += "\n\n" + _searches_table(json.loads((folder / "searches.json").read_text(encoding="utf-8")))
    (folder / "pantographs.md").write_text(table + "\n", encoding="utf-8")
    if (folder / "speed.csv").exists():
        _figure(read_csv(folder / "speed.csv"), folder / "pantographs.png")
    return table


def _searches_table(searches: dict[str, dict[str, Any]]) -> str:
    """The GA runs for the worse pantograph: what each met (a run may meet no feasible design)."""
    rows = [
        {
            "problem": problem,
            "simulations": one["simulations"],
            "stop": one["stop_reason"],
            "best": "none feasible" if one["best_sigma_N"] is None else f"{one['best_sigma_N']:.2f} N",
            "least_loss": one["least_contact_loss_percent"],
        }
        for problem, one in searches.items()
    ]
    return markdown_table(
        rows,
        [
            ("problem", "GA, worse pantograph", "s"),
            ("simulations", "simulations", ".0f"),
            ("stop", "stop", "s"),
            ("best", "best worse-pantograph σ", "s"),
            ("least_loss", "least contact loss met (%)", ".3f"),
        ],
    )


def _figure(rows: list[dict], path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    problems = list(dict.fromkeys(r["problem"] for r in rows))
    fig, axes = plt.subplots(1, len(problems), figsize=(5.5 * len(problems), 4), squeeze=False)
    for ax, problem in zip(axes[0], problems, strict=True):
        for i, label in enumerate(("single", "worst")):
            pick = [r for r in rows if r["problem"] == problem and r["design"] == label]
            speeds = [r["speed_kmh"] for r in pick]
            name = "single-pantograph optimum" if label == "single" else "worst-σ optimum"
            for key, style, which in (
                ("sigma_leading_N", "o-", "leading"),
                ("sigma_trailing_N", "s--", "trailing"),
            ):
                # A speed at which a pantograph loses contact breaks the line and is marked x.
                sigma = [r[key] if r["feasible"] else float("nan") for r in pick]
                ax.plot(speeds, sigma, style, color=f"C{i}", label=f"{name}, {which}")
                lost = [(r["speed_kmh"], r[key]) for r in pick if not r["feasible"]]
                if lost:
                    ax.plot(*zip(*lost, strict=True), "x", color=f"C{i}", markersize=8)
        ax.set_xlabel("speed (km/h)")
        ax.set_ylabel("σ of the contact force (N)")
        ax.set_title(f"{problem}: two pantographs {SPACING:g} m apart (x: contact lost)")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment pantographs`` and ``python -m experiments.pantographs``)."""
    add_full_option(parser, "20 spans, the published study's GA on B1 and SW1, 7 speeds (hours)")
    parser.add_argument(
        "--designs",
        type=Path,
        default=DEFAULT_OUT,
        metavar="FOLDER",
        help="where the design studies' optima are (FOLDER/design/<problem>/summary.json; default results)",
    )
    parser.add_argument(
        "--optima-only", action="store_true", help="only the first table: the optima and level designs"
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
    """``python -m experiments.pantographs``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.pantographs")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.pantographs"))
