"""Study 5: RL design policies, and designs for a range of speeds (docs/problems.md, 'Experiments').

Three parts, on B1 and SW1 (quick: B1):

1. *Learning curves*: PPO (:func:`optimizers.rl.train_design_policy`) at 300 km/h, several seeds: the
   reward (−σ, or −Fm for an infeasible design) against environment steps (one step, one simulation).
2. *Speed-conditioned policy*: PPO trained with speeds drawn from 200–320 km/h at each episode, so that
   design = policy(speed), against separate GA optima at 200, 260 and 320 km/h, each design simulated at
   its own speed.
3. *A design for the whole speed range*: the GA on the mean σ over 200–320 km/h (the environments'
   objective ``"mean_sigma_over_speeds"``, :class:`experiments.design_evaluations.MeanSigmaProblem`)
   against the GA's 300 km/h optimum and the reference design, each simulated across the speeds.

Where the policy starts. A design env's action in [-1, 1] maps affinely onto the bounds, and the bounds of
B1 and SW1 (every Δh in [-20, +20] mm) are centred on the reference design (the level wire): action 0 *is*
the reference design. stable-baselines3 initialises the layer that gives the Gaussian policy's mean with
an orthogonal matrix of gain 0.01 and a zero bias, so the untrained policy proposes the reference design
give or take a fraction of a millimetre; the spread of its proposals is set by ``log_std_init`` =
ln 0.2 (:data:`optimizers.rl.POLICY_SPREAD`, PPO's default): a standard deviation of 0.2 action units, 4 mm
of height. A spread of 1 (stable-baselines3's default, ±20 mm) proposes mostly infeasible designs (slack
droppers, contact loss) and a policy learns nothing from a few hundred −Fm rewards; at 4 mm, most
proposals are feasible (on the test fidelity, 14 of 16 on B1 and 15 of 16 on SW1 in a check before the
study; ``rl.md`` gives the share each run met). :func:`check_starts_at_reference` refuses a problem whose
bounds are not centred on its reference design (B2, B3, SW2, SW3), where this start would not hold.

Every run goes to a run store (the studies' shared ``runs.sqlite`` in the output folder, or
``Config.store``) and is resumed from it; the designs no run asked for (the reference, the policy's
designs, an optimum at other speeds) are simulated through the same store
(:func:`experiments.design_evaluations.evaluate_designs`). A policy is re-trained on a resumed run by
replaying its stored steps (no simulation), which gives the same policy.

Outputs (``results/rl/``): ``steps.csv`` (every training step), ``ga_runs.csv``, ``speed_policy.csv``,
``robust.csv``, ``reference.csv``; ``rl.md`` (tables) and ``learning_curves.png``, ``speed_policy.png``,
``robust_design.png``.

Settings. Full: the study fidelity, B1 and SW1, 1000 steps × 3 seeds for the learning curves, 2000 steps
for the speed-conditioned policy (rollouts of 32 steps), 1000 simulations per GA run (the published study's
population) at 200, 260, 300 and 320 km/h, 300 evaluations for the mean-σ GA (a population of 30, so
ten generations), each at the 7 speeds 200–320 km/h every 20 km/h. Quick: the "test" fidelity, B1 only,
about ten simulations per run, rollouts of 4 steps, a GA population of 6 (a smoke test, not a result).

    python -m experiments.rl_studies [--full] [--workers 2] [--out results]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from catenary_env.problems import get_problem
from optimizers.base import OptimizationResult
from optimizers.catenary_adapter import catenary_problem
from optimizers.ga import POPULATION_SIZES, GAOptions
from optimizers.rl import DesignPolicy, EnvSpec, PPOOptions, design_for_speed, train_design_policy
from optimizers.runner import optimize
from optimizers.store import RunStore

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
from .design_evaluations import evaluate_designs, mean_sigma_problem
from .model_stamp import catenaries_of, stamp_study

NAME = "rl"
SPEED_KMH = 300.0
SPEED_RANGE = (200.0, 320.0)
GA_SPEEDS = (200.0, 260.0, 320.0)
MEAN_POPULATION = 30
"""Population of the mean-σ GA: its 300 evaluations (2100 simulations) then make ten generations, where
the published study's population of 80 or 100 would make two or three."""


def policy_options(n_steps: int) -> PPOOptions:
    """PPO settings of the studies: rollouts (and minibatches) of ``n_steps`` steps, the policy starting at
    the reference design with PPO's default spread, :data:`optimizers.rl.POLICY_SPREAD` (see the module's
    docstring)."""
    return PPOOptions(n_steps=n_steps, batch_size=n_steps)


def check_starts_at_reference(problem: str) -> None:
    """Refuse a problem whose reference design is not action 0 (the untrained policy's mean)."""
    design_problem = get_problem(problem)
    reference = design_problem.reference_x()
    if reference is None or not np.allclose(design_problem.grid.to_action(reference), 0.0, atol=1e-9):
        raise ValueError(
            f"problem = {problem!r}: its bounds are not centred on its reference design, so a policy "
            "starting at action 0 would not start at the reference; use B1 or SW1"
        )


def train_policy(
    store: RunStore,
    problem: str,
    budget: int,
    seed: int,
    options: PPOOptions,
    fidelity: str,
    speed_kmh: float | None = SPEED_KMH,
    speed_range: tuple[float, float] | None = None,
    quiet: bool = True,
    archive: Path | None = None,
) -> tuple[DesignPolicy, OptimizationResult]:
    """Train (or resume) a PPO design policy on ``Catenary-{problem}-v0`` in the store (and ``archive``,
    :mod:`optimizers.archive`)."""
    from catenary_env.envs import register_envs

    check_starts_at_reference(problem)
    register_envs()
    return train_design_policy(
        policy_env(problem, fidelity, speed_kmh, speed_range), catenary_problem(problem), budget, seed,
        options=options, store=store, resume=True, start_if_none=True, quiet=quiet, archive=archive,
    )  # fmt: skip


def policy_env(
    problem: str,
    fidelity: str,
    speed_kmh: float | None = SPEED_KMH,
    speed_range: tuple[float, float] | None = None,
) -> EnvSpec:
    """The env :func:`train_policy` trains on: ``Catenary-{problem}-v0`` at a speed (km/h) or over a
    range of speeds."""
    return EnvSpec(f"Catenary-{problem}-v0", None if speed_range else speed_kmh, speed_range, fidelity)


@dataclass(frozen=True)
class Config:
    """The study's settings (quick unless ``full``).

    Attributes
    ----------
    full : bool
        The study fidelity and budgets of hundreds to thousands of simulations; else quick.
    out : Path
        The results folder; the study writes into ``out/rl``.
    workers : int
        Local worker processes for the GA's and the given designs' simulations (PPO steps in this process).
    store : Path or None
        The run store; default ``out/runs.sqlite``, shared by the studies.
    problems : tuple of str
        The design problems studied; default B1 and SW1 (quick: B1).
    """

    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 1
    store: Path | None = None
    problems: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not self.problems:
            object.__setattr__(self, "problems", ("B1", "SW1") if self.full else ("B1",))

    @property
    def fidelity(self) -> str:
        return "study" if self.full else "test"

    @property
    def seeds(self) -> tuple[int, ...]:
        """Seeds of the learning curves."""
        return (0, 1, 2) if self.full else (0, 1)

    @property
    def learning_budget(self) -> int:
        return 1000 if self.full else 12

    @property
    def policy_budget(self) -> int:
        """Steps of the speed-conditioned policy."""
        return 2000 if self.full else 12

    @property
    def ppo(self) -> PPOOptions:
        return policy_options(32 if self.full else 4)

    @property
    def ga_budget(self) -> int:
        """Simulations of each single-speed GA run."""
        return 1000 if self.full else 12

    @property
    def mean_budget(self) -> int:
        """Evaluations of the mean-σ GA run (each simulates every speed of :attr:`speeds_kmh`)."""
        return 300 if self.full else 8

    def ga_options(self, problem: str) -> GAOptions:
        return GAOptions(population_size=POPULATION_SIZES[problem] if self.full else 6)

    @property
    def mean_ga_options(self) -> GAOptions:
        """The mean-σ GA's: a population of :data:`MEAN_POPULATION` (quick: 6)."""
        return GAOptions(population_size=MEAN_POPULATION if self.full else 6)

    @property
    def speeds_kmh(self) -> tuple[float, ...]:
        """The speeds of the mean σ, km/h."""
        return tuple(float(v) for v in range(200, 321, 20)) if self.full else GA_SPEEDS

    @property
    def sweep_kmh(self) -> tuple[float, ...]:
        """The speeds each design is simulated at across the range, km/h (with 300 km/h)."""
        return tuple(sorted({*self.speeds_kmh, *GA_SPEEDS, SPEED_KMH}))


def main(config: Config) -> Path:
    folder = study_dir(config.out, NAME)
    tables: dict[str, list[dict[str, Any]]] = {k: [] for k in ("steps", "ga", "speed", "robust", "reference")}
    with RunStore(config.store or Path(config.out) / STORE) as store:
        for problem in config.problems:
            _reference(store, config, problem, tables["reference"])
            _learning_curves(store, config, problem, tables["steps"])
            optima = _ga_optima(store, config, problem, tables["ga"])
            _speed_policy(store, config, problem, optima, tables)
            _robust_design(store, config, problem, optima, tables)
    write_csv(folder / "steps.csv", tables["steps"])
    write_csv(folder / "ga_runs.csv", tables["ga"])
    write_csv(folder / "speed_policy.csv", tables["speed"])
    write_csv(folder / "robust.csv", tables["robust"])
    write_csv(folder / "reference.csv", tables["reference"])
    stamp_study(folder, catenaries_of(config.problems))
    report(folder)
    return folder


def _x_text(x: Any) -> str:
    return " ".join(f"{v:.6g}" for v in x)


def _reference(store: RunStore, config: Config, problem: str, rows: list[dict[str, Any]]) -> None:
    reference = get_problem(problem).reference_x()
    speeds = config.sweep_kmh
    requests = [(reference, v) for v in speeds]
    outcomes = evaluate_designs(store, problem, requests, config.fidelity, config.workers)
    for speed, outcome in zip(speeds, outcomes, strict=True):
        sigma = _sigma(outcome.sigma, outcome.feasible)
        rows.append(
            {"problem": problem, "speed_kmh": speed, "feasible": int(outcome.feasible), "sigma_N": sigma}
        )


def _sigma(sigma: float | None, feasible: bool) -> float:
    return float(sigma) if feasible and sigma is not None else float("nan")


def _step_rows(
    store: RunStore, part: str, problem: str, result: OptimizationResult, options: PPOOptions
) -> list[dict[str, Any]]:
    """One row per env step of a training run, with the env's reward read back from the store."""
    stored = store.evaluations(int(result.run_id or 0))
    return [
        {
            "part": part,
            "problem": problem,
            "seed": result.seed,
            "rollout_steps": options.n_steps,
            "step": record.index + 1,
            "speed_kmh": record.speed_kmh,
            "feasible": int(record.feasible),
            "sigma_N": _sigma(record.sigma, record.feasible),
            "reward": stored[record.index].reward if record.index in stored else float("nan"),
            "x_m": _x_text(record.x),
        }
        for record in result.history
    ]


def _learning_curves(store: RunStore, config: Config, problem: str, rows: list[dict[str, Any]]) -> None:
    for seed in config.seeds:
        _, result = train_policy(store, problem, config.learning_budget, seed, config.ppo, config.fidelity)
        rows.extend(_step_rows(store, "learning", problem, result, config.ppo))
        best = "no feasible design" if result.best_sigma is None else f"best σ {result.best_sigma:.3f} N"
        print(f"ppo on {problem} seed {seed}: {best}", file=sys.stderr, flush=True)


def _ga_optima(
    store: RunStore, config: Config, problem: str, rows: list[dict[str, Any]]
) -> dict[float, tuple[float, ...] | None]:
    """The GA's best design at each speed of :data:`GA_SPEEDS` and at 300 km/h (None: none feasible)."""
    optima: dict[float, tuple[float, ...] | None] = {}
    for speed in sorted({*GA_SPEEDS, SPEED_KMH}):
        result = optimize(
            problem, "ga", config.ga_budget, 0, speed_kmh=speed, fidelity=config.fidelity,
            options=config.ga_options(problem), store=store, resume=True, start_if_none=True,
            n_workers=config.workers, quiet=not config.full,
        )  # fmt: skip
        optima[speed] = result.best_x
        rows.append(_ga_row(problem, result, f"sigma at {speed:g} km/h", speed))
    return optima


def _ga_row(problem: str, result: OptimizationResult, objective: str, speed: float | None) -> dict[str, Any]:
    return {
        "problem": problem,
        "objective": objective,
        "speed_kmh": speed if speed is not None else float("nan"),
        "budget": result.budget,
        "n_simulations": result.n_simulations,
        "stop_reason": result.stop_reason,
        "best_sigma_N": result.best_sigma if result.best_sigma is not None else float("nan"),
        "x_m": _x_text(result.best_x) if result.best_x is not None else "",
    }


def _speed_policy(
    store: RunStore,
    config: Config,
    problem: str,
    optima: dict[float, tuple[float, ...] | None],
    tables: dict[str, list[dict[str, Any]]],
) -> None:
    policy, result = train_policy(
        store, problem, config.policy_budget, 0, config.ppo, config.fidelity, speed_range=SPEED_RANGE
    )
    tables["steps"].extend(_step_rows(store, "speed_policy", problem, result, config.ppo))
    space = catenary_problem(problem)
    speeds = config.sweep_kmh
    designs = [("policy", v, tuple(design_for_speed(policy, space, v).tolist())) for v in speeds]
    designs += [("ga", v, optima[v]) for v in GA_SPEEDS if optima[v] is not None]
    _simulate_rows(store, config, problem, designs, tables["speed"])


def _robust_design(
    store: RunStore,
    config: Config,
    problem: str,
    optima: dict[float, tuple[float, ...] | None],
    tables: dict[str, list[dict[str, Any]]],
) -> None:
    mean_problem = mean_sigma_problem(problem, config.speeds_kmh)
    result = optimize(
        mean_problem, "ga", config.mean_budget, 0, speed_kmh=float(np.mean(config.speeds_kmh)),
        fidelity=config.fidelity, options=config.mean_ga_options, store=store, resume=True,
        start_if_none=True, n_workers=config.workers, quiet=not config.full,
    )  # fmt: skip
    speeds = config.speeds_kmh
    objective = f"mean sigma over {len(speeds)} speeds, {min(speeds):g}-{max(speeds):g} km/h"
    tables["ga"].append(_ga_row(problem, result, objective, None))
    candidates = [
        ("reference", tuple(get_problem(problem).reference_x().tolist())),  # type: ignore[union-attr]
        ("optimum_300", optima[SPEED_KMH]),
        ("mean_sigma", result.best_x),
    ]
    designs = [(name, v, x) for name, x in candidates if x is not None for v in config.sweep_kmh]
    _simulate_rows(store, config, problem, designs, tables["robust"])


def _simulate_rows(
    store: RunStore,
    config: Config,
    problem: str,
    designs: list[tuple[str, float, tuple[float, ...] | None]],
    rows: list[dict[str, Any]],
) -> None:
    """Simulate (or find in the store) each (name, speed, x) and add its row."""
    outcomes = evaluate_designs(
        store,
        problem,
        [(x, v) for _, v, x in designs],
        config.fidelity,
        config.workers,  # type: ignore[misc]
    )
    for (name, speed, x), outcome in zip(designs, outcomes, strict=True):
        rows.append(
            {
                "problem": problem,
                "design": name,
                "speed_kmh": speed,
                "feasible": int(outcome.feasible),
                "sigma_N": _sigma(outcome.sigma, outcome.feasible),
                "x_m": _x_text(x),
            }
        )


# -- report (from the data files alone) -------------------------------------------------------------------

LEARNING_COLUMNS = [
    ("problem", "problem", "s"),
    ("seed", "seed", ".0f"),
    ("steps", "steps", ".0f"),
    ("first_reward", "mean reward, first rollout", ".2f"),
    ("last_reward", "mean reward, last rollout", ".2f"),
    ("first_feasible_percent", "feasible, first rollout (%)", ".0f"),
    ("feasible_percent", "feasible, all steps (%)", ".0f"),
    ("best_sigma_N", "best σ (N)", ".2f"),
]
SPEED_COLUMNS = [
    ("problem", "problem", "s"),
    ("speed_kmh", "speed (km/h)", "g"),
    ("reference_N", "σ reference (N)", ".2f"),
    ("ga_N", "σ GA optimum (N)", ".2f"),
    ("policy_N", "σ policy (N)", ".2f"),
    ("policy_vs_ga_percent", "policy vs GA (%)", "+.1f"),
]
ROBUST_COLUMNS = [
    ("problem", "problem", "s"),
    ("design", "design", "s"),
    ("sigma_300_N", "σ at 300 km/h (N)", ".2f"),
    ("mean_N", "mean σ (N)", ".2f"),
    ("worst_N", "worst σ (N)", ".2f"),
    ("feasible_speeds", "feasible speeds", "s"),
]
GA_COLUMNS = [
    ("problem", "problem", "s"),
    ("objective", "objective", "s"),
    ("n_simulations", "simulations", ".0f"),
    ("stop_reason", "stopped by", "s"),
    ("best_sigma_N", "best σ (N)", ".2f"),
    ("x_m", "design (m)", "s"),
]


def report(folder: Path) -> str:
    """Tables and figures from the CSV files (no simulation)."""
    steps = read_csv(folder / "steps.csv")
    reference = read_csv(folder / "reference.csv")
    speed = read_csv(folder / "speed_policy.csv")
    robust = read_csv(folder / "robust.csv")
    ga_runs = read_csv(folder / "ga_runs.csv")
    sections = [
        ("Learning curves (PPO at 300 km/h)", learning_summary(steps), LEARNING_COLUMNS),
        ("Speed-conditioned policy against GA optima", speed_policy_table(speed, reference), SPEED_COLUMNS),
        ("One design for 200–320 km/h", robust_table(robust), ROBUST_COLUMNS),
        ("GA runs", ga_runs, GA_COLUMNS),
    ]
    text = "\n\n".join(f"### {title}\n\n{markdown_table(rows, columns)}" for title, rows, columns in sections)
    (folder / "rl.md").write_text(text + "\n", encoding="utf-8")
    _learning_figure(steps, reference, folder / "learning_curves.png")
    _speed_figure(speed, reference, folder / "speed_policy.png")
    _robust_figure(robust, folder / "robust_design.png")
    return text


def _groups(rows: list[dict[str, Any]], *keys: str) -> dict[tuple[Any, ...], list[dict[str, Any]]]:
    out: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for row in rows:
        out.setdefault(tuple(row[k] for k in keys), []).append(row)
    return out


def _rollout(steps: list[dict[str, Any]]) -> int:
    """Steps per PPO rollout of a run (the window of the curves), at most its number of steps."""
    return int(min(steps[0]["rollout_steps"], len(steps)))


def learning_summary(steps: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    learning = [s for s in steps if s["part"] == "learning"]
    for (problem, seed), rows in _groups(learning, "problem", "seed").items():
        rows.sort(key=lambda r: r["step"])
        window = _rollout(rows)
        feasible = [r["sigma_N"] for r in rows if r["feasible"]]
        out.append(
            {
                "problem": problem,
                "seed": seed,
                "steps": len(rows),
                "first_reward": float(np.mean([r["reward"] for r in rows[:window]])),
                "last_reward": float(np.mean([r["reward"] for r in rows[-window:]])),
                "first_feasible_percent": 100.0 * float(np.mean([r["feasible"] for r in rows[:window]])),
                "feasible_percent": 100.0 * float(np.mean([r["feasible"] for r in rows])),
                "best_sigma_N": min(feasible) if feasible else float("nan"),
            }
        )
    return out


def speed_policy_table(speed: list[dict[str, Any]], reference: list[dict[str, Any]]) -> list[dict[str, Any]]:
    ref = {(r["problem"], r["speed_kmh"]): r["sigma_N"] for r in reference}
    by = {(r["problem"], r["design"], r["speed_kmh"]): r["sigma_N"] for r in speed}
    out = []
    for problem, design, v in by:
        if design != "ga":
            continue
        policy = by.get((problem, "policy", v), float("nan"))
        ga = by[(problem, design, v)]
        out.append(
            {
                "problem": problem,
                "speed_kmh": v,
                "reference_N": ref.get((problem, v), float("nan")),
                "ga_N": ga,
                "policy_N": policy,
                "policy_vs_ga_percent": 100.0 * (policy / ga - 1.0),
            }
        )
    return out


def robust_table(robust: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    for (problem, design), rows in _groups(robust, "problem", "design").items():
        sigmas = [r["sigma_N"] for r in rows]
        at_300 = [r["sigma_N"] for r in rows if r["speed_kmh"] == SPEED_KMH]
        out.append(
            {
                "problem": problem,
                "design": design,
                "sigma_300_N": at_300[0] if at_300 else float("nan"),
                "mean_N": float(np.mean(sigmas)),  # NaN where infeasible at a speed
                "worst_N": float(np.max(sigmas)),
                "feasible_speeds": f"{sum(int(r['feasible']) for r in rows)}/{len(rows)}",
            }
        )
    return out


def _panels(n: int) -> tuple[Any, Any, Any]:
    from catenary_env.plots import pyplot

    plt = pyplot()
    fig, axes = plt.subplots(1, max(n, 1), figsize=(5.5 * max(n, 1), 4.2), squeeze=False)
    return plt, fig, axes[0]


def _save(plt: Any, fig: Any, path: Path) -> None:
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _learning_figure(steps: list[dict[str, Any]], reference: list[dict[str, Any]], path: Path) -> None:
    learning = [s for s in steps if s["part"] == "learning"]
    problems = list(dict.fromkeys(s["problem"] for s in learning))
    plt, fig, axes = _panels(len(problems))
    for ax, problem in zip(axes, problems, strict=False):
        curves = []
        for (seed,), rows in _groups([s for s in learning if s["problem"] == problem], "seed").items():
            rows.sort(key=lambda r: r["step"])
            window = _rollout(rows)
            reward = np.array([r["reward"] for r in rows])
            smooth = np.convolve(reward, np.ones(window) / window, mode="valid")
            x = np.arange(window, len(reward) + 1)  # the step that ends each window
            ax.plot(x, smooth, linewidth=0.8, alpha=0.6, label=f"seed {seed:.0f}")
            curves.append((x, smooth))
        if curves:
            n = min(len(c[1]) for c in curves)
            median = np.median([c[1][:n] for c in curves], axis=0)
            ax.plot(curves[0][0][:n], median, color="k", label="median over seeds")
        for r in reference:
            if r["problem"] == problem and r["speed_kmh"] == SPEED_KMH:
                ax.axhline(-r["sigma_N"], color="k", linestyle=":", label="reference design (−σ)")
        ax.set_xlabel("environment steps (simulations)")
        ax.set_ylabel("reward, mean over a rollout (−N)")
        ax.set_title(f"PPO on {problem}, 300 km/h")
        ax.legend(fontsize=8)
    _save(plt, fig, path)


def _speed_figure(speed: list[dict[str, Any]], reference: list[dict[str, Any]], path: Path) -> None:
    problems = list(dict.fromkeys(r["problem"] for r in speed))
    plt, fig, axes = _panels(len(problems))
    for ax, problem in zip(axes, problems, strict=False):
        ref = sorted((r["speed_kmh"], r["sigma_N"]) for r in reference if r["problem"] == problem)
        ax.plot(*zip(*ref, strict=True), "k:", marker=".", label="reference design")
        for design, style in (("policy", "o-"), ("ga", "s")):
            chosen = [r for r in speed if r["problem"] == problem and r["design"] == design]
            pts = sorted((r["speed_kmh"], r["sigma_N"]) for r in chosen)
            if pts:
                label = "policy(speed)" if design == "policy" else "GA optimum at the speed"
                ax.plot(*zip(*pts, strict=True), style, label=label)
        ax.set_xlabel("speed (km/h)")
        ax.set_ylabel("σ of the contact force (N)")
        ax.set_title(f"{problem}: speed-conditioned policy")
        ax.legend(fontsize=8)
    _save(plt, fig, path)


def _robust_figure(robust: list[dict[str, Any]], path: Path) -> None:
    problems = list(dict.fromkeys(r["problem"] for r in robust))
    labels = {"reference": "reference design", "optimum_300": "GA optimum at 300 km/h",
              "mean_sigma": "GA optimum of the mean σ"}  # fmt: skip
    plt, fig, axes = _panels(len(problems))
    for ax, problem in zip(axes, problems, strict=False):
        for (design,), rows in _groups([r for r in robust if r["problem"] == problem], "design").items():
            pts = sorted((r["speed_kmh"], r["sigma_N"]) for r in rows)
            ax.plot(*zip(*pts, strict=True), "o-", label=labels.get(design, design))
        ax.set_xlabel("speed (km/h)")
        ax.set_ylabel("σ of the contact force (N)")
        ax.set_title(f"{problem}: one design across speeds")
        ax.legend(fontsize=8)
    _save(plt, fig, path)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment rl`` and ``python -m experiments.rl_studies``)."""
    add_full_option(
        parser, "the study fidelity, B1 and SW1, budgets of hundreds to thousands of simulations (hours)"
    )
    parser.add_argument(
        "--problems", nargs="+", default=[], choices=list(POPULATION_SIZES), metavar="NAME",
        help=f"the design problems, of {' '.join(POPULATION_SIZES)} (default: B1 SW1; quick: B1)",
    )  # fmt: skip
    add_workers_option(parser, 1, "the GA's and the given designs' simulations (PPO steps in this process)")
    add_out_option(parser)
    add_store_option(parser)


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.rl_studies``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.rl_studies")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.rl_studies"))
