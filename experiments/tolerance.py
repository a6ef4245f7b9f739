"""Study 7: designs an engineer would build (docs/acceptance.md): installation tolerances, buildability
limits and robust design, at the design speed, 300 km/h.

1. *Spread* (``spread``): the level wire and the six design studies' optima under three tolerance levels
   (±2, ±5 and ±10 mm of contact-wire height at every dropper, ±5 cm of dropper position; all tagged A), on
   the same seeded draws for every design of the same droppers (common random numbers): σ's median, 10th
   and 90th percentiles, the infeasible share, the EN 50367 pass rate, and the tolerance at which each
   optimum's median σ meets the level wire's.
2. *Buildable* (``buildable``): the six GA design studies re-run under the buildability defaults (dropper
   force >= 30 N, dropper length >= 0.5 m, dropper spacing <= 11 m): the new optima beside the recorded
   ones (σ, reduction, smallest dropper force).
3. *Robust* (``robust``): a GA on B1 and SW1 with the robust objective (mean σ over K draws of the
   practice tolerances): the robust optimum against the nominal one, nominal σ and σ under draws, both
   confirmed on the exact model for a few draws.

The recorded optima are read from ``results/design/<problem>/summary.json`` (the design studies' data).
Quick: the "test" fidelity (5 spans, coarse, exact model), a few draws and a tiny GA; full: the study
fidelity, 100 draws a level, the design studies' GA, confirmation on the "reference" fidelity (hours).

    python -m experiments.tolerance [--full] [--draws N] [--parts spread buildable robust] [--out results]
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import math
import sys
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from catenary_env.errors import UsageError
from catenary_env.model.buildability import DEFAULT_BUILDABILITY, NO_LIMITS, BuildabilityLimits
from catenary_env.model.tolerances import PRACTICE, Tolerances, draw_deviations
from catenary_env.pipeline import CONSTRAINTS, Evaluation
from catenary_env.problems import get_problem, resolve_fidelity
from catenary_env.problems.tolerance import RobustObjective
from optimizers import optimize
from optimizers.ga import GAOptions
from optimizers.problem import Outcome

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
    study_dir,
    write_csv,
    write_json,
)
from .model_stamp import catenaries_of, stamp_study

NAME = "tolerance"
PROBLEMS = ("B1", "B2", "B3", "SW1", "SW2", "SW3")
ROBUST_PROBLEMS = ("B1", "SW1")
PARTS = ("spread", "buildable", "robust")
DESIGN_SPEED = 300.0
"""km/h: the problems' design speed (docs/problems.md)."""
SPREAD_ROW = "spread-2"
"""The spread's row format in the log's keys: rows of another format are simulated again."""
ROBUST_ROW = "robust-1"
"""The robust part's row format in the log's keys."""
LEVELS_MM = (2.0, 5.0, 10.0)
"""Contact-wire height tolerances of the spread, ± mm (with :data:`PRACTICE`'s dropper-position error)."""
RECORDED = Path(__file__).resolve().parents[1] / "results" / "design"
"""The design studies' recorded data: the optima of the spread and the 'before' of the buildable part."""


@dataclass(frozen=True)
class Config:
    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 2
    draws: int | None = None
    seed: int = 0
    parts: tuple[str, ...] = PARTS
    problems: tuple[str, ...] = PROBLEMS
    levels_mm: tuple[float, ...] = LEVELS_MM

    def __post_init__(self) -> None:
        unknown = [p for p in self.parts if p not in PARTS]
        if unknown:
            raise UsageError(f"--parts {' '.join(unknown)}: must be among {', '.join(PARTS)}")
        if self.draws is not None and not 1 <= self.draws <= 10000:
            raise UsageError(f"--draws {self.draws}: must be an integer in [1, 10000]")
        if self.seed < 0:
            raise UsageError(f"--seed {self.seed}: must be an integer >= 0")

    @property
    def fidelity(self) -> str:
        return "study" if self.full else "test"

    @property
    def confirm_fidelity(self) -> str:
        """The exact model (the quick setting's test fidelity is exact already)."""
        return "reference" if self.full else "test"

    @property
    def n_draws(self) -> int:
        return self.draws if self.draws is not None else (100 if self.full else 3)

    @property
    def robust(self) -> RobustObjective:
        """The robust objective of part 3: the practice tolerances, K draws."""
        return RobustObjective(PRACTICE, draws=8 if self.full else 2, seed=self.seed)

    @property
    def confirm_draws(self) -> int:
        return 5 if self.full else 2

    @property
    def ga_options(self) -> GAOptions:
        return GAOptions() if self.full else GAOptions(population_size=6, max_generations=2)

    @property
    def budget(self) -> int:
        return 20_000 if self.full else 12

    def levels(self) -> tuple[Tolerances, ...]:
        return tuple(
            Tolerances(mm / 1000.0, PRACTICE.position, PRACTICE.distribution, PRACTICE.provenance)
            for mm in self.levels_mm
        )


# -- designs ----------------------------------------------------------------------------------------------


def recorded_optimum(problem: str, folder: Path = RECORDED) -> tuple[float, ...] | None:
    """The design study's recorded optimum of a problem (variables, m), or None where none is recorded."""
    path = folder / problem / "summary.json"
    if not path.is_file():
        return None
    x = json.loads(path.read_text(encoding="utf-8")).get("optimum_x")
    return None if x is None else tuple(float(v) for v in x)


def spread_designs(config: Config) -> list[tuple[str, str, tuple[float, ...]]]:
    """(label, problem, x) of the spread: each catenary's level wire, then each recorded optimum."""
    designs = []
    for catenary, problem in (("benchmark", "B1"), ("stitched", "SW1")):
        if any(get_problem(p).catenary == catenary for p in config.problems):
            designs.append((f"level {catenary}", problem, tuple(get_problem(problem).reference_x().tolist())))
    for name in config.problems:
        x = recorded_optimum(name)
        if x is not None:
            designs.append((f"{name} optimum", name, x))
    return designs


# -- one simulation, for worker processes ------------------------------------------------------------------


def evaluate_draw(
    problem: str,
    x: tuple[float, ...],
    tolerances: Tolerances | None,
    seed: int,
    draw: int,
    fidelity: str,
    uplift: float,
) -> Evaluation:
    """A design of a registered problem on draw ``draw`` of ``seed`` (``tolerances`` None: as drawn)."""
    p = get_problem(problem)
    deviations = None
    if tolerances is not None:
        n_spans = resolve_fidelity(fidelity).n_spans
        deviations = draw_deviations(tolerances, n_spans, p.n_droppers, seed, draw)
    return p.evaluate(x, DESIGN_SPEED, fidelity, uplift, deviations)


def simulate_variant(
    problem: str,
    buildability: BuildabilityLimits,
    robust: RobustObjective | None,
    x: tuple[float, ...],
    speed_kmh: float,
    fidelity: str,
) -> Outcome:
    """An optimiser's simulation of a problem with buildability limits and (or) the robust objective."""
    variant = get_problem(problem).with_options(buildability, robust)
    evaluation = variant.evaluate(tuple(x), float(speed_kmh), fidelity)
    sigma = None if evaluation.statistics is None else float(evaluation.statistics.std)
    constraints = tuple(float(v) for v in evaluation.constraints)  # the GA's penalty while none is feasible
    return Outcome(
        bool(evaluation.feasible), sigma, evaluation.reason, float(evaluation.wall_time), constraints
    )


@dataclass(frozen=True, eq=False)
class VariantProblem:
    """A registered problem with options, as an optimiser's problem (its name and fingerprint say which)."""

    name: str
    variable_names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    step: NDArray[np.float64]
    base: str
    buildability: BuildabilityLimits = NO_LIMITS
    robust: RobustObjective | None = None
    model_fingerprint: str = ""
    constraint_names: tuple[str, ...] = CONSTRAINTS

    @property
    def simulate(self) -> Any:
        return functools.partial(simulate_variant, self.base, self.buildability, self.robust)


def variant_problem(name: str, suffix: str, buildability: BuildabilityLimits, robust: RobustObjective | None):
    p = get_problem(name).with_options(buildability, robust)
    return VariantProblem(
        f"{name}+{suffix}", p.variables, p.lower, p.upper, p.step, name, buildability, robust,
        p.store_fingerprint(),
    )  # fmt: skip


# -- the three parts ---------------------------------------------------------------------------------------


def _completed(
    config: Config, function: Callable[..., Any], jobs: list[tuple[Any, ...]]
) -> Iterator[tuple[tuple[Any, ...], Any]]:
    """(job, result) of each job as it completes: in this process with one worker, else in a pool."""
    if config.workers == 1 or len(jobs) < 2:
        for job in jobs:
            yield job, function(*job)
        return
    with ProcessPoolExecutor(max_workers=config.workers) as pool:
        futures = {pool.submit(function, *job): job for job in jobs}
        for future in as_completed(futures):
            yield futures[future], future.result()


def _logged(
    config: Config,
    folder: Path,
    function: Callable[..., Any],
    jobs: list[tuple[Any, ...]],
    key: Callable[[tuple[Any, ...]], str],
    order: Callable[[tuple[Any, ...]], Any] | None = None,
) -> list[Any]:
    """``function(*job)`` of every job, in the jobs' order: from the study's log (``log.jsonl``) where it
    holds the job's key, else computed (in ``order``) and logged as it completes."""
    log = ResultLog(folder / "log.jsonl")
    todo = [job for job in jobs if log.get(key(job)) is None]
    for job, row in _completed(config, function, todo if order is None else sorted(todo, key=order)):
        log.put(key(job), row)
    return [log.get(key(job)) for job in jobs]


def _row(label: str, problem: str, level_mm: float, draw: int, ev: Evaluation) -> dict[str, Any]:
    stats = ev.statistics
    return {
        "design": label,
        "problem": problem,
        "level_mm": level_mm,
        "draw": draw,
        "feasible": int(ev.feasible),
        "sigma_N": stats.std if stats else math.nan,
        "mean_N": stats.mean if stats else math.nan,
        "accepted": int(ev.feasible and ev.acceptance is not None and ev.acceptance.passed),
        # The verdict the catenary decides: the mean-force window aside, which the uplift force sets.
        "accepted_by_catenary": int(
            ev.feasible and ev.acceptance is not None and ev.acceptance.passed_by_the_catenary
        ),
        "failed_criteria": "; ".join(ev.acceptance.failed) if ev.feasible and ev.acceptance else "",
        "min_dropper_force_N": min(ev.dropper_forces) if ev.dropper_forces else math.nan,
        "reason": ev.reason,
    }


def spread_row(
    label: str,
    problem: str,
    level_mm: float,
    draw: int,
    x: tuple[float, ...],
    tolerances: Tolerances | None,
    seed: int,
    fidelity: str,
    uplift: float,
) -> dict[str, Any]:
    """One row of the spread, in a worker: the design as designed (``draw`` -1) or on one draw."""
    evaluation = evaluate_draw(problem, x, tolerances, seed, draw, fidelity, uplift)
    return _row(label, problem, level_mm, draw, evaluation)


def run_spread(config: Config, folder: Path) -> None:
    """Part 1: every design, nominal (level 0, draw -1) and on the draws of each level. Each row is logged
    as it completes (``log.jsonl``, keyed by the problem's store fingerprint), so that an interrupted spread
    resumes where it stopped; the draws run in order of their number (every design's and level's draw k
    before any draw k + 1), so that a spread cut short holds the first draws of all, and ``--draws K``
    writes the spread of those K from the log without simulating."""
    designs = spread_designs(config)
    uplift = {p: get_problem(p).uplift_force(DESIGN_SPEED, config.fidelity) for _, p, _ in designs}
    prefix = {p: get_problem(p).store_fingerprint() for _, p, _ in designs}
    jobs = []
    for label, problem, x in designs:
        common = (config.seed, config.fidelity, uplift[problem])
        jobs.append((label, problem, 0.0, -1, x, None, *common))
        for mm, tolerances in zip(config.levels_mm, config.levels(), strict=True):
            jobs.extend((label, problem, mm, k, x, tolerances, *common) for k in range(config.n_draws))

    def key(job: tuple[Any, ...]) -> str:
        label, problem, mm, k, x, _, seed, fidelity, force = job
        return json.dumps([SPREAD_ROW, prefix[problem], label, mm, k, list(x), seed, fidelity, force])

    rows = _logged(config, folder, spread_row, jobs, key, order=lambda job: job[3])  # by draw
    write_csv(folder / "spread.csv", rows)


def run_buildable(config: Config, folder: Path) -> None:
    """Part 2: the GA under the buildability defaults; the recorded optimum and the new one, on this model."""
    rows = []
    for name in config.problems:
        problem = variant_problem(name, "buildable", DEFAULT_BUILDABILITY, None)
        result = optimize(
            problem, "ga", config.budget, config.seed, speed_kmh=DESIGN_SPEED, fidelity=config.fidelity,
            options=config.ga_options, store=Path(config.out) / STORE, resume=True,
            n_workers=config.workers, quiet=False,
        )  # fmt: skip
        base = get_problem(name)
        uplift = base.uplift_force(DESIGN_SPEED, config.fidelity)
        reference = base.reference_evaluation(DESIGN_SPEED, config.fidelity)
        old = recorded_optimum(name)
        for label, x in (("recorded optimum", old), ("buildable optimum", result.best_x)):
            if x is None:
                continue
            ev = evaluate_draw(name, tuple(x), None, config.seed, -1, config.fidelity, uplift)
            row = _row(label, name, 0.0, -1, ev)
            row["x"] = " ".join(f"{v:g}" for v in x)
            row["reference_sigma_N"] = reference.statistics.std if reference.statistics else math.nan
            row["buildable"] = int(_buildable(name, tuple(x), config.fidelity, uplift))
            rows.append(row)
    write_csv(folder / "buildable.csv", rows)


def _buildable(name: str, x: tuple[float, ...], fidelity: str, uplift: float) -> bool:
    """Statically feasible and within the buildability defaults (contact loss aside)."""
    variant = get_problem(name).with_options(buildability=DEFAULT_BUILDABILITY)
    ev = variant.evaluate(x, DESIGN_SPEED, fidelity, uplift)
    return not ev.reason.startswith(("design", "static", "buildability"))


def robust_row(
    label: str, problem: str, x: tuple[float, ...], draw: int, seed: int, fidelity: str, uplift: float
) -> dict[str, Any]:
    """One row of the robust part, in a worker: an optimum as designed (``draw`` -1) or on one draw of
    the practice tolerances."""
    tolerances = None if draw < 0 else PRACTICE
    evaluation = evaluate_draw(problem, x, tolerances, seed, draw, fidelity, uplift)
    row = _row(label, problem, 0.0 if draw < 0 else 1000 * PRACTICE.height, draw, evaluation)
    return {**row, "fidelity": fidelity, "x": " ".join(f"{v:g}" for v in x)}


def run_robust(config: Config, folder: Path) -> None:
    """Part 3: the GA on the robust objective; nominal and robust optima, nominal σ and σ under draws, on
    the study's model and on the exact one. The GA resumes from the run store and each row of the
    comparison is logged as it completes (``log.jsonl``), so that an interrupted part, or the problems run
    in separate processes, lose nothing."""
    jobs = []
    for name in (p for p in ROBUST_PROBLEMS if p in config.problems):
        optima = {"nominal optimum": recorded_optimum(name)}
        problem = variant_problem(name, "robust", NO_LIMITS, config.robust)
        result = optimize(
            problem, "ga", config.budget, config.seed, speed_kmh=DESIGN_SPEED, fidelity=config.fidelity,
            options=config.ga_options, store=Path(config.out) / STORE, resume=True,
            n_workers=config.workers, quiet=False,
        )  # fmt: skip
        optima["robust optimum"] = None if result.best_x is None else tuple(result.best_x)
        for fidelity, n_draws in (
            (config.fidelity, config.n_draws),
            (config.confirm_fidelity, config.confirm_draws),
        ):
            uplift = get_problem(name).uplift_force(DESIGN_SPEED, fidelity)
            for label, x in optima.items():
                if x is not None:
                    draws = [(-1, config.seed), *((k, config.seed + 1) for k in range(n_draws))]
                    jobs += [(label, name, x, k, seed, fidelity, uplift) for k, seed in draws]

    prefix = {name: get_problem(name).store_fingerprint() for name in {job[1] for job in jobs}}

    def key(job: tuple[Any, ...]) -> str:
        label, problem, x, k, seed, fidelity, force = job
        return json.dumps([ROBUST_ROW, prefix[problem], label, list(x), k, seed, fidelity, force])

    write_csv(folder / "robust.csv", _logged(config, folder, robust_row, jobs, key))


def main(config: Config) -> Path:
    folder = study_dir(config.out, NAME)
    write_json(
        folder / "settings.json",
        {
            "fidelity": config.fidelity,
            "draws": config.n_draws,
            "seed": config.seed,
            "levels_mm": list(config.levels_mm),
            "position_tolerance_m": PRACTICE.position,
            "distribution": PRACTICE.distribution,
            "tolerance_tags": PRACTICE.provenance,
            "buildability": dataclasses.asdict(DEFAULT_BUILDABILITY),
            "robust": config.robust.describe(),
        },
    )
    if "spread" in config.parts:
        run_spread(config, folder)
    if "buildable" in config.parts:
        run_buildable(config, folder)
    if "robust" in config.parts:
        run_robust(config, folder)
    stamp_study(folder, catenaries_of(config.problems))
    return folder


# -- report -------------------------------------------------------------------------------------------------


def spread_summary(rows: list[dict]) -> list[dict[str, Any]]:
    """Per design and level: nominal σ, median, p10, p90, infeasible share and pass rate."""
    out = []
    for design in dict.fromkeys(r["design"] for r in rows):
        mine = [r for r in rows if r["design"] == design]
        nominal = next(r for r in mine if r["draw"] == -1)
        for level in sorted({r["level_mm"] for r in mine if r["draw"] >= 0}):
            draws = [r for r in mine if r["level_mm"] == level and r["draw"] >= 0]
            sigmas = np.array([r["sigma_N"] for r in draws if r["feasible"]])
            p10, p50, p90 = np.percentile(sigmas, [10, 50, 90]) if sigmas.size else (math.nan,) * 3
            out.append(
                {
                    "design": design,
                    "problem": nominal["problem"],
                    "level_mm": level,
                    "nominal_N": nominal["sigma_N"],
                    "median_N": p50,
                    "p10_N": p10,
                    "p90_N": p90,
                    "infeasible_percent": 100.0 * np.mean([not r["feasible"] for r in draws]),
                    "accepted_percent": 100.0 * np.mean([r["accepted"] for r in draws]),
                    "catenary_accepted_percent": 100.0 * np.mean([r["accepted_by_catenary"] for r in draws]),
                }
            )
    return out


def robust_summary(rows: list[dict]) -> list[dict[str, Any]]:
    """Per problem, optimum and model (the study's, the exact one): the spread's summary of its draws,
    with its variables."""
    keyed = [{**r, "design": (r["problem"], r["design"], r["fidelity"])} for r in rows]
    out = []
    for s in spread_summary(keyed):
        problem, optimum, fidelity = s["design"]
        mine = [r for r in keyed if r["design"] == s["design"]]
        nominal = next(r for r in mine if r["draw"] == -1)
        out.append({
            **s, "optimum": optimum, "fidelity": fidelity, "x": str(nominal["x"]),
            "draws": sum(1 for r in mine if r["draw"] >= 0),
            "nominal_dropper_N": nominal["min_dropper_force_N"],
        })  # fmt: skip
    return out


def _meets(mm: float) -> str:
    """:func:`meeting_tolerance` in words."""
    if math.isnan(mm):
        return "not comparable (no level with feasible draws of both)"
    if math.isinf(mm):
        return "never (below it at every level both have feasible draws)"
    return "not below it as designed" if mm == 0.0 else f"±{mm:.1f} mm"


def meeting_tolerance(summary: list[dict], design: str, level_design: str) -> float:
    """The height tolerance (mm) at which ``design``'s median σ meets the level wire's, by linear
    interpolation between the levels at which both have feasible draws; 0 where it is not below it as
    designed, inf where it stays below at every such level, NaN where there is no such level (or neither is
    feasible as designed)."""
    levels = [(0.0, _nominal(summary, design), _nominal(summary, level_design))]
    for s in summary:
        if s["design"] == design:
            other = next(
                (t for t in summary if t["design"] == level_design and t["level_mm"] == s["level_mm"]), None
            )
            levels.append((s["level_mm"], s["median_N"], other["median_N"] if other else math.nan))
    gaps = [(mm, opt - lev) for mm, opt, lev in levels if not math.isnan(opt - lev)]
    if not gaps or gaps[0][0] != 0.0:
        return math.nan
    if gaps[0][1] >= 0.0:
        return 0.0
    if len(gaps) == 1:  # no level at which both have feasible draws
        return math.nan
    for (a, ga), (b, gb) in zip(gaps, gaps[1:], strict=False):
        if gb >= 0.0:
            return a + (b - a) * (-ga) / (gb - ga)
    return math.inf


def _nominal(summary: list[dict], design: str) -> float:
    return next((s["nominal_N"] for s in summary if s["design"] == design), math.nan)


SPREAD_COLUMNS = [
    ("design", "design", "s"),
    ("level_mm", "± height (mm)", "g"),
    ("nominal_N", "σ nominal (N)", ".2f"),
    ("median_N", "σ median (N)", ".2f"),
    ("p10_N", "p10 (N)", ".2f"),
    ("p90_N", "p90 (N)", ".2f"),
    ("infeasible_percent", "infeasible (%)", ".0f"),
    ("catenary_accepted_percent", "EN 50367 pass, Fm window aside (%)", ".0f"),
    ("accepted_percent", "EN 50367 pass (%)", ".0f"),
    ("meets", "median meets the level wire's at", "s"),
]
BUILDABLE_COLUMNS = [
    ("problem", "problem", "s"),
    ("design", "design", "s"),
    ("x", "variables (m)", "s"),
    ("sigma_N", "σ (N)", ".2f"),
    ("reference_sigma_N", "σ level (N)", ".2f"),
    ("reduction_percent", "reduction (%)", ".1f"),
    ("min_dropper_force_N", "smallest dropper force (N)", ".1f"),
    ("buildable", "buildable", ".0f"),
]
ROBUST_COLUMNS = [
    ("problem", "problem", "s"),
    ("optimum", "optimum", "s"),
    ("fidelity", "model", "s"),
    ("x", "variables (m)", "s"),
    ("nominal_N", "σ as designed (N)", ".2f"),
    ("nominal_dropper_N", "smallest dropper force as designed (N)", ".1f"),
    ("draws", "draws", "d"),
    ("median_N", "σ median (N)", ".2f"),
    ("p10_N", "p10 (N)", ".2f"),
    ("p90_N", "p90 (N)", ".2f"),
    ("infeasible_percent", "infeasible (%)", ".0f"),
    ("catenary_accepted_percent", "EN 50367 pass, Fm window aside (%)", ".0f"),
]


def report(folder: Path) -> str:
    """Tables and a figure from the CSVs (no simulation)."""
    parts = []
    if (folder / "spread.csv").is_file():
        rows = read_csv(folder / "spread.csv")
        summary = spread_summary(rows)
        for s in summary:
            level = f"level {get_problem(s['problem']).catenary}"
            s["meets"] = (
                _meets(meeting_tolerance(summary, s["design"], level)) if "optimum" in s["design"] else ""
            )
        parts.append(markdown_table(summary, SPREAD_COLUMNS))
        _figure(rows, folder / "spread.png")
    if (folder / "buildable.csv").is_file():
        rows = read_csv(folder / "buildable.csv")
        for r in rows:
            r["x"] = str(r.get("x", ""))
            r["reduction_percent"] = 100.0 * (1.0 - r["sigma_N"] / r["reference_sigma_N"])
        parts.append(markdown_table(rows, BUILDABLE_COLUMNS))
    if (folder / "robust.csv").is_file():
        rows = read_csv(folder / "robust.csv")
        parts.append(markdown_table(robust_summary(rows), ROBUST_COLUMNS))
        study = [
            {**r, "design": f"{r['problem']} {r['design']}"}
            for r in rows
            if r["fidelity"] == rows[0]["fidelity"]
        ]
        _figure(study, folder / "robust.png")
    text = "\n\n".join(parts)
    (folder / "tolerance.md").write_text(text + "\n", encoding="utf-8")
    return text


def _figure(rows: list[dict], path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    levels = sorted({r["level_mm"] for r in rows if r["draw"] >= 0})
    designs = list(dict.fromkeys(r["design"] for r in rows))
    width = max(4.5 * len(levels), 7.0)
    fig, axes = plt.subplots(1, len(levels), figsize=(width, 4.5), sharey=True, squeeze=False)
    for ax, level in zip(axes[0], levels, strict=True):
        data = [
            [r["sigma_N"] for r in rows if r["design"] == d and r["level_mm"] == level and r["feasible"]]
            or [math.nan]
            for d in designs
        ]
        ax.boxplot(data, whis=(10, 90), showfliers=False)
        nominal = [next(r["sigma_N"] for r in rows if r["design"] == d and r["draw"] == -1) for d in designs]
        ax.plot(range(1, len(designs) + 1), nominal, "k_", markersize=14, label="as designed")
        for i, d in enumerate(designs, start=1):  # the share of built sections that can be built at all
            draws = [r for r in rows if r["design"] == d and r["level_mm"] == level and r["draw"] >= 0]
            share = 100.0 * np.mean([r["feasible"] for r in draws]) if draws else math.nan
            ax.annotate(f"{share:.0f} %", (i, 1.0), xycoords=("data", "axes fraction"), ha="center",
                        va="bottom", fontsize=8)  # fmt: skip
        ax.set_xticks(range(1, len(designs) + 1), designs, rotation=60, ha="right")
        ax.set_title(f"±{level:g} mm height, ±{100 * PRACTICE.position:g} cm position", pad=16)
    axes[0][0].set_ylabel("σ of the feasible draws (N); whiskers p10-p90")
    fig.suptitle("σ under installation tolerances;\nabove each design: the share of draws that are feasible")
    axes[0][0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment tolerance`` and ``python -m experiments.tolerance``)."""
    add_full_option(parser, "20 spans, 100 draws a level, the design studies' GA, exact confirmation (hours)")
    parser.add_argument(
        "--draws",
        type=int,
        default=None,
        metavar="N",
        help="tolerance draws per design and level (default: 3 quick, 100 full)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the draws and of the GA (default 0)")
    parser.add_argument(
        "--parts", nargs="+", choices=PARTS, default=list(PARTS),
        help="which parts to run: spread (σ under tolerances), buildable (GA under the buildability "
        "defaults), robust (GA on the robust objective); default: all three",
    )  # fmt: skip
    parser.add_argument(
        "--problems", nargs="+", default=list(PROBLEMS), choices=PROBLEMS, metavar="NAME",
        help=f"the design problems, of {' '.join(PROBLEMS)} (default: all; the robust part runs "
        f"{' and '.join(ROBUST_PROBLEMS)} of them); separate problems in separate processes share the log",
    )  # fmt: skip
    add_workers_option(parser, 2)
    add_out_option(parser)


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.tolerance``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.tolerance")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.tolerance"))
