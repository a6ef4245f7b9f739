"""The analysis of the amortised RL studies (:mod:`experiments.rl_amortised`, :mod:`experiments.rl_tension`),
from their data files alone: the learning summary, the policies against a GA run per condition, where the
policies' designs went, the amortisation ledger and their figures (docs/problems.md, 'Experiments')."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

LEDGER_SPEEDS = (1, 2, 5, 10, 20, 50, 100)
"""The numbers of speeds of the amortisation ledger's rows."""


# -- the ledger --------------------------------------------------------------------------------------------


def ga_simulations_to(curves: list[dict[str, Any]], problem: str, speed: float, sigma: float) -> float:
    """Simulations the GA run at a speed needed before its best σ was at most ``sigma`` (N); inf if never."""
    for row in sorted((r for r in curves if r["problem"] == problem and r["speed_kmh"] == speed),
                      key=lambda r: r["simulations"]):  # fmt: skip
        if row["best_sigma_N"] <= sigma * (1.0 + 1e-12):
            return float(row["simulations"])
    return math.inf


def break_even(training: float, ga_per_speed: float) -> float:
    """The number of speeds from which one policy costs fewer simulations than a GA run per speed.

    The policy costs ``training`` simulations once, plus one per speed (the σ of its design); the GA
    ``ga_per_speed`` per speed. Break-even: the smallest whole N with N ga_per_speed >= training + N, inf
    when a GA run costs no more than the policy's one simulation per speed.
    """
    if ga_per_speed <= 1.0:
        return math.inf
    return float(math.ceil(training / (ga_per_speed - 1.0)))


def break_even_by_gap(
    curves: list[dict[str, Any]],
    ga_runs: list[dict[str, Any]],
    problem: str,
    training: float,
    gaps_percent: tuple[float, ...] = (0.0, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0),
) -> list[tuple[float, float, float]]:
    """For each accepted gap g to the GA optimum (%): the simulations a GA run needed to come within g of
    its own optimum (mean over the table's speeds), and the break-even number of speeds of a policy of
    ``training`` simulations that reaches that gap: (g, GA simulations, break-even N)."""
    runs = [r for r in ga_runs if r["problem"] == problem and math.isfinite(r["best_sigma_N"])]
    out = []
    for gap in gaps_percent:
        needed = [
            ga_simulations_to(curves, problem, r["speed_kmh"], r["best_sigma_N"] * (1.0 + gap / 100.0))
            for r in runs
        ]
        mean = float(np.mean(needed)) if needed else math.nan
        out.append((gap, mean, break_even(training, mean)))
    return out


def policy_gaps(designs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per problem, learner, seed and speed: σ of the policy's design, of the GA optimum, of the reference,
    and the gap policy / GA optimum (%; NaN where the policy's design is infeasible)."""
    by = {(r["problem"], r["design"], r["seed"], r["speed_kmh"]): r for r in designs}
    rows = []
    for (problem, design, seed, speed), row in by.items():
        if design in ("reference", "ga"):
            continue
        ga = by.get((problem, "ga", 0, speed), {}).get("sigma_N", math.nan)
        reference = by.get((problem, "reference", -1, speed), {}).get("sigma_N", math.nan)
        rows.append(
            {
                "problem": problem, "learner": design, "seed": seed, "speed_kmh": speed,
                "held_out": row["held_out"], "reference_N": reference, "ga_N": ga, "policy_N": row["sigma_N"],
                "gap_percent": 100.0 * (row["sigma_N"] / ga - 1.0),
            }
        )  # fmt: skip
    return rows


def amortisation_ledger(
    designs: list[dict[str, Any]],
    curves: list[dict[str, Any]],
    ga_runs: list[dict[str, Any]],
    steps: list[dict[str, Any]],
    n_speeds: tuple[int, ...] = LEDGER_SPEEDS,
    trained_on: Callable[[str], str] = str,
) -> list[dict[str, Any]]:
    """The amortisation ledger: for each problem, learner and number of speeds N, the simulations of one
    policy (its training, the mean over seeds, plus one per speed) against those of N GA runs, both at
    their full budget and stopped as soon as the GA's best σ reaches the policy's (the GA's cost of the
    policy's quality, mean over the table's speeds), with the mean σ each gets over the table's speeds and
    the break-even N of both.

    Parameters
    ----------
    designs, curves, ga_runs, steps : list of dict
        The rows of ``designs.csv``, ``ga_curves.csv``, ``ga_runs.csv`` and ``steps.csv``.
    n_speeds : tuple of int
        The numbers of speeds of the rows.
    trained_on : callable
        The problem a policy was trained on (``steps.csv``'s) of a table's problem (default: itself; the
        tension study's table names a problem at a tension, :mod:`experiments.rl_tension`).
    """
    gaps = [{**r, "trained_on": trained_on(r["problem"])} for r in policy_gaps(designs)]
    out = []
    for (problem, learner), rows in groups(gaps, "trained_on", "learner").items():
        runs = [r for r in ga_runs if trained_on(r["problem"]) == problem]
        ga_full = float(np.mean([r["n_simulations"] for r in runs]))
        matched = [ga_simulations_to(curves, r["problem"], r["speed_kmh"], r["policy_N"]) for r in rows]
        ga_match = float(np.mean([m if math.isfinite(m) else ga_full for m in matched]))
        per_seed = groups([s for s in steps if s["problem"] == problem and s["learner"] == learner], "seed")
        training = float(np.mean([len(v) for v in per_seed.values()]))
        summary = {
            "problem": problem, "learner": learner, "training_simulations": training,
            "policy_sigma_N": float(np.nanmean([r["policy_N"] for r in rows])),
            "ga_sigma_N": float(np.nanmean([r["ga_N"] for r in rows])),
            "gap_percent": float(np.nanmean([r["gap_percent"] for r in rows])),
            "feasible_share": float(np.mean([math.isfinite(r["policy_N"]) for r in rows])),
            "ga_per_speed": ga_full, "ga_per_speed_to_policy_sigma": ga_match,
            "break_even_full": break_even(training, ga_full),
            "break_even_same_sigma": break_even(training, ga_match),
        }  # fmt: skip
        for n in n_speeds:
            out.append(
                {
                    **summary, "n_speeds": n, "policy_simulations": training + n,
                    "ga_simulations": n * ga_full, "ga_simulations_to_policy_sigma": n * ga_match,
                }
            )  # fmt: skip
    return out


# -- the tables and figures -----------------------------------------------------------------------------

LEARNING_COLUMNS = [
    ("problem", "problem", "s"),
    ("learner", "learner", "s"),
    ("seed", "seed", ".0f"),
    ("steps", "steps", ".0f"),
    ("first_reward", "mean reward, first window", ".2f"),
    ("last_reward", "mean reward, last window", ".2f"),
    ("first_feasible_percent", "feasible, first window (%)", ".0f"),
    ("last_feasible_percent", "feasible, last window (%)", ".0f"),
]
TABLE_COLUMNS = [
    ("problem", "problem", "s"),
    ("speed_kmh", "speed (km/h)", "g"),
    ("held", "held out", "s"),
    ("learner", "learner", "s"),
    ("reference_N", "σ reference (N)", ".2f"),
    ("ga_N", "σ GA optimum (N)", ".2f"),
    ("policy_N", "σ policy, mean over seeds (N)", ".2f"),
    ("gap_percent", "gap to GA (%)", "+.1f"),
    ("feasible", "feasible seeds", "s"),
]
DRIFT_COLUMNS = [
    ("problem", "problem", "s"),
    ("learner", "learner", "s"),
    ("seed", "seed", ".0f"),
    ("to_ga_first_mm", "to the GA optima, first window (mm)", ".1f"),
    ("to_ga_last_mm", "to the GA optima, last window (mm)", ".1f"),
    ("covered_percent", "way covered (%)", ".0f"),
    ("spread_first_mm", "spread, first window (mm)", ".1f"),
    ("spread_last_mm", "spread, last window (mm)", ".1f"),
    ("speed_share_percent", "σ's variance the speed explains, last window (%)", ".0f"),
]
LEDGER_COLUMNS = [
    ("problem", "problem", "s"),
    ("learner", "learner", "s"),
    ("training_simulations", "training (simulations)", ".0f"),
    ("gap_percent", "mean gap to GA (%)", "+.1f"),
    ("ga_per_speed", "GA run (simulations)", ".0f"),
    ("ga_per_speed_to_policy_sigma", "GA to the policy's σ (simulations)", ".0f"),
    ("break_even_full", "break-even N, GA in full", ".0f"),
    ("break_even_same_sigma", "break-even N, same σ", ".0f"),
]


def ga_budgets(ga_runs: list[dict[str, Any]]) -> str:
    """The GA runs' budgets and populations, in words."""
    budgets = sorted({(int(r["budget"]), int(r["population"])) for r in ga_runs})
    return "; ".join(f"GA: {b} simulations, population {p}" for b, p in budgets)


def groups(rows: list[dict[str, Any]], *keys: str) -> dict[tuple[Any, ...], list[dict[str, Any]]]:
    out: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for row in rows:
        out.setdefault(tuple(row[k] for k in keys), []).append(row)
    return out


def window_of(steps: list[dict[str, Any]]) -> int:
    """Steps per point of the curves: a fortieth of the shortest run, at least 4."""
    lengths = [len(v) for v in groups(steps, "problem", "learner", "seed").values()]
    return max(4, min(lengths) // 40) if lengths else 4


def learning_summary(steps: list[dict[str, Any]], window: int) -> list[dict[str, Any]]:
    out = []
    for (problem, learner, seed), rows in groups(steps, "problem", "learner", "seed").items():
        rows.sort(key=lambda r: r["step"])
        first, last = rows[:window], rows[-window:]
        out.append(
            {
                "problem": problem, "learner": learner, "seed": seed, "steps": len(rows),
                "first_reward": float(np.mean([r["reward"] for r in first])),
                "last_reward": float(np.mean([r["reward"] for r in last])),
                "first_feasible_percent": 100.0 * float(np.mean([r["feasible"] for r in first])),
                "last_feasible_percent": 100.0 * float(np.mean([r["feasible"] for r in last])),
            }
        )  # fmt: skip
    return out


def _x(row: dict[str, Any]) -> np.ndarray:
    """A row's design vector, m (``x_m``: the values apart; one value reads back as a float)."""
    return np.array(str(row["x_m"]).split(), dtype=float)


def speed_share(rows: list[dict[str, Any]]) -> float:
    """The share of the variance of σ over ``rows`` (steps) that their speeds explain: 1 − the variance left
    by a least-squares cubic in the speed over the variance of σ, over the feasible steps; NaN with fewer
    than eight, or when σ does not vary."""
    feasible = [r for r in rows if r["feasible"]]
    sigma = np.array([r["sigma_N"] for r in feasible], dtype=float)
    if sigma.size < 8 or np.ptp(sigma) == 0.0:
        return math.nan
    speed = np.array([r["speed_kmh"] for r in feasible], dtype=float)
    basis = np.vander((speed - speed.mean()) / max(speed.std(), 1e-12), 4)
    residual = sigma - basis @ np.linalg.lstsq(basis, sigma, rcond=None)[0]
    return float(1.0 - residual.var() / sigma.var())


def design_drift(
    steps: list[dict[str, Any]], designs: list[dict[str, Any]], window: int
) -> list[dict[str, Any]]:
    """Where each policy's designs went during training: per problem, learner and seed, the mean design of
    the first and the last ``window`` steps, its distance (Euclidean, over the design variables) to the mean
    of the GA optima over the table's speeds, the share of that distance covered (the step from the first
    mean to the last, projected on the direction to the GA optima), the spread (the RMS over the variables
    of the designs' standard deviation) and the share of σ's variance the speed explains
    (:func:`speed_share`) in the last window. Lengths in mm."""
    optima = {
        problem: np.mean([_x(r) for r in rows], axis=0)
        for (problem,), rows in groups([d for d in designs if d["design"] == "ga"], "problem").items()
    }
    out = []
    for (problem, learner, seed), rows in groups(steps, "problem", "learner", "seed").items():
        rows.sort(key=lambda r: r["step"])
        first, last = rows[:window], rows[-window:]
        x_first, x_last = (np.array([_x(r) for r in part]) for part in (first, last))
        start, end = x_first.mean(axis=0), x_last.mean(axis=0)
        target = optima.get(problem, np.full(start.shape, math.nan))  # NaN: no GA optimum
        to_go = target - start
        covered = float((end - start) @ to_go / (to_go @ to_go)) if to_go.any() else math.nan
        out.append(
            {
                "problem": problem, "learner": learner, "seed": seed,
                "to_ga_first_mm": 1e3 * float(np.linalg.norm(to_go)),
                "to_ga_last_mm": 1e3 * float(np.linalg.norm(target - end)),
                "covered_percent": 100.0 * covered,
                "spread_first_mm": 1e3 * float(np.sqrt(np.mean(x_first.var(axis=0)))),
                "spread_last_mm": 1e3 * float(np.sqrt(np.mean(x_last.var(axis=0)))),
                "speed_share_percent": 100.0 * speed_share(last),
            }
        )  # fmt: skip
    return out


def speed_table(designs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The table: per problem, speed and learner, σ of the reference, the GA optimum and the policies (mean
    over the seeds whose design is feasible), and the gap."""
    out = []
    for (problem, learner, speed), rows in sorted(
        groups(policy_gaps(designs), "problem", "learner", "speed_kmh").items()
    ):
        sigmas = [r["policy_N"] for r in rows if math.isfinite(r["policy_N"])]
        policy = float(np.mean(sigmas)) if sigmas else math.nan
        out.append(
            {
                "problem": problem, "speed_kmh": speed, "held": "yes" if rows[0]["held_out"] else "no",
                "learner": learner, "reference_N": rows[0]["reference_N"], "ga_N": rows[0]["ga_N"],
                "policy_N": policy, "gap_percent": 100.0 * (policy / rows[0]["ga_N"] - 1.0),
                "feasible": f"{len(sigmas)}/{len(rows)}",
            }
        )  # fmt: skip
    return out


def _curve(values: list[float], window: int) -> tuple[Any, Any]:
    smooth = np.convolve(values, np.ones(window) / window, mode="valid")
    return np.arange(window, len(values) + 1), smooth


def learning_figure(steps: list[dict[str, Any]], window: int, path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    problems = list(dict.fromkeys(s["problem"] for s in steps))
    fig, axes = plt.subplots(2, len(problems), figsize=(5.5 * len(problems), 7.0), squeeze=False)
    colours = {"ppo": "tab:blue", "sac": "tab:orange"}
    for column, problem in enumerate(problems):
        for (learner, seed), rows in groups(
            [s for s in steps if s["problem"] == problem], "learner", "seed"
        ).items():
            rows.sort(key=lambda r: r["step"])
            label = f"{learner}" if seed == min(r["seed"] for r in steps if r["learner"] == learner) else None
            for row, key in ((0, "reward"), (1, "feasible")):
                x, y = _curve(
                    [r[key] * (100.0 if key == "feasible" else 1.0) for r in rows], min(window, len(rows))
                )
                axes[row][column].plot(
                    x, y, color=colours.get(learner), linewidth=0.8, alpha=0.8, label=label
                )
        seeds = len({s["seed"] for s in steps if s["problem"] == problem})
        axes[0][column].set_title(f"{problem}: speed-conditioned policies, {seeds} seed(s) each")
        axes[0][column].set_ylabel(f"reward, mean over {window} steps (−N)")
        axes[1][column].set_ylabel(f"feasible designs over {window} steps (%)")
        axes[1][column].set_xlabel("environment steps (simulations)")
        axes[0][column].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def ledger_figure(
    ledger: list[dict[str, Any]], curves: list[dict[str, Any]], ga_runs: list[dict[str, Any]], path: Path
) -> None:
    """Left: simulations against the number of speeds, one policy against a GA run per speed. Right: the
    break-even number of speeds against the gap to the GA optimum one accepts, with each policy's gap."""
    from catenary_env.plots import pyplot

    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(12.0, 4.8))
    colours: dict[str, str] = {}  # a problem's GA line in the colour of its first policy
    for (problem, learner), rows in groups(ledger, "problem", "learner").items():
        n = [r["n_speeds"] for r in rows]
        label = f"{problem} {learner} policy (gap {rows[0]['gap_percent']:+.0f} %)"
        colour = left.plot(n, [r["policy_simulations"] for r in rows], "-o", markersize=3, label=label)[
            0
        ].get_color()
        if problem not in colours:
            colours[problem] = colour
            left.plot(
                n, [r["ga_simulations"] for r in rows], "--", color=colour, label=f"{problem}: GA per speed"
            )
        label = f"{problem}: GA stopped at the {learner} policy's σ"
        left.plot(n, [r["ga_simulations_to_policy_sigma"] for r in rows], ":", color=colour, label=label)
        first = rows[0]
        label = f"{problem} {learner} policy"
        right.plot([first["gap_percent"]], [first["break_even_same_sigma"]], "o", color=colour, label=label)
    for problem, colour in colours.items():
        training = next(r["training_simulations"] for r in ledger if r["problem"] == problem)
        points = [
            (g, n) for g, _, n in break_even_by_gap(curves, ga_runs, problem, training) if math.isfinite(n)
        ]
        if points:
            right.plot(
                *zip(*points, strict=True), "-", color=colour, label=f"{problem}: a policy of {training:.0f}"
            )
    left.set(xscale="log", yscale="log", xlabel="number of speeds N", ylabel="simulations")
    left.set_title("One policy against a GA run per speed")
    right.set(yscale="log", xlabel="gap to the GA optimum accepted (%)", ylabel="break-even number of speeds")
    right.set_title("Speeds from which the policy is cheaper")
    left.legend(fontsize=7)
    right.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
