"""The optimiser benchmark's report (:mod:`experiments.optimizer_comparison`), from its data files alone: per
problem and optimiser the final σ and the runs that reached the target, the fixed-target and fixed-budget
views, the rank tests, the convergence figure and the IOHprofiler files (docs/problems.md, 'Reading the
comparison')."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from catenary_env.problems import PROBLEMS as DESIGN_PROBLEMS
from optimizers.synthetic import SYNTHETIC_PROBLEMS

from . import benchmark_views as bv
from .common import markdown_table, read_csv, write_csv
from .design_evaluations import study_problem
from .iohprofiler import runs_from_rows, write_algorithm

SPEED_KMH = 300.0
"""The train speed of every run of the benchmark, km/h."""
TARGET = 0.02
"""Within 2 % of the best σ any run found on the problem."""
DE_POPULATION = 30
"""The size of nevergrad's DE first population in the benchmark (its default, the "standard" population)."""
DONE, NOT_RUN, NOT_RUN_YET = "done", "not run", "not run yet"
"""The status of a run in ``runs.csv``: finished; cannot run here (the note says why); not finished in the
store when the results were written from it (``--from-store``: the note and ``n_simulations`` say what the
store holds of it)."""


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
    """The runs that finished in the IOHprofiler format, one folder per optimiser."""
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
