"""How optimiser benchmarks are read (docs/problems.md, 'Reading the comparison'): fixed-budget and
fixed-target views, ranks with a significance test, computed from the comparison's data files alone.

- *Fixed budget*: per problem and optimiser, the median and inter-quartile range of the best σ after
  50, 100 and 300 simulations (:data:`BUDGETS`, those within the runs' budget).
- *Fixed target*: for targets 1, 2, 5 and 10 % above the problem's best-known σ
  (:mod:`catenary_env.problems.best_known`), the expected running time as COCO defines it,
  ``ERT = (simulations of every run until it reached the target, or all its simulations if it never did)
  / (runs that reached it)`` (infinite when none did), and the empirical cumulative distribution of the
  runtimes over all (problem, target, run) triples of an optimiser: the share reached within ``t``
  simulations (one figure, aggregated over the problems).
- *Ranks*: the optimisers ranked by their final best σ within each block (a problem and a seed: runs
  with the same seed are not paired by anything else, so a block is a replicate, not a matched pair),
  Friedman's test that all mean ranks are equal, and pairwise Wilcoxon signed-rank tests over the blocks
  with Holm's correction (``scipy.stats``). A run with no feasible design ranks last. The blocks are those
  where every optimiser compared has a run (:func:`common_blocks`): a partial set of runs (a protocol still
  running) is ranked on what all optimisers have done, and not at all below :data:`MIN_BLOCKS`.
- The share of infeasible proposals and the simulation time per run are in the comparison's own table
  (:func:`experiments.benchmark_report.summarise`).

Examples
--------
>>> expected_running_time([(10, True), (300, False), (40, True)])
175.0
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "BUDGETS",
    "MIN_BLOCKS",
    "TARGETS",
    "common_blocks",
    "ecdf",
    "expected_running_time",
    "fixed_budget_rows",
    "fixed_target_rows",
    "holm",
    "rank_tests",
    "runtimes",
]

BUDGETS = (50, 100, 300)
"""Simulations at which the fixed-budget view reads the best σ."""

TARGETS = (0.01, 0.02, 0.05, 0.10)
"""Targets of the fixed-target view: σ at most (1 + target) × the best-known σ."""

ALPHA = 0.05
"""Significance level of the tests."""

MIN_BLOCKS = 2
"""The fewest blocks (problem, seed) the rank tests are made on (one block ranks, it tests nothing)."""


def runtimes(curves: np.ndarray, lengths: Sequence[int], target: float) -> list[tuple[int, bool]]:
    """Per run, ``(simulations, reached)``: the first simulation after which the best σ was at most
    ``target`` N, or the run's whole length when it never was."""
    out = []
    for curve, length in zip(curves, lengths, strict=True):
        hits = np.flatnonzero(curve[:length] <= target)
        out.append((int(hits[0]) + 1, True) if len(hits) else (int(length), False))
    return out


def expected_running_time(times: Sequence[tuple[int, bool]]) -> float:
    """COCO's ERT of ``(simulations, reached)`` pairs: all simulations spent over the successes (inf if
    none)."""
    successes = sum(reached for _, reached in times)
    return sum(t for t, _ in times) / successes if successes else float("inf")


def fixed_budget_rows(curves: dict[str, dict[str, np.ndarray]]) -> list[dict[str, Any]]:
    """Median and IQR of the best σ at each of :data:`BUDGETS` within the runs' budget (NaN where a
    quantile falls on a run without a feasible design)."""
    rows = []
    for problem, by_optimizer in curves.items():
        for optimizer, stack in by_optimizer.items():
            row: dict[str, Any] = {"problem": problem, "optimizer": optimizer, "runs": len(stack)}
            for budget in [b for b in BUDGETS if b <= stack.shape[1]] or [stack.shape[1]]:
                capped = np.where(np.isfinite(stack[:, budget - 1]), stack[:, budget - 1], 1e300)
                quantiles = np.quantile(capped, (0.25, 0.5, 0.75))
                q25, median, q75 = (float(v) if v < 1e299 else np.inf for v in quantiles)
                row[f"at_{budget}"] = _cell(median, q25, q75)
                row[f"median_at_{budget}_N"] = median
            rows.append(row)
    return rows


def _cell(median: float, q25: float, q75: float) -> str:
    values = [f"{v:.2f}" if np.isfinite(v) else "none" for v in (median, q25, q75)]
    return f"{values[0]} [{values[1]}, {values[2]}]"


def fixed_target_rows(
    curves: dict[str, dict[str, np.ndarray]],
    lengths: dict[str, dict[str, list[int]]],
    best_known: dict[str, float],
) -> list[dict[str, Any]]:
    """ERT and successes per problem, optimiser and target (problems without a best-known σ skipped)."""
    rows = []
    for problem, by_optimizer in curves.items():
        if problem not in best_known:
            continue
        for optimizer, stack in by_optimizer.items():
            row: dict[str, Any] = {"problem": problem, "optimizer": optimizer}
            for target in TARGETS:
                times = runtimes(stack, lengths[problem][optimizer], (1.0 + target) * best_known[problem])
                ert = expected_running_time(times)
                label = f"{100 * target:g}"
                row[f"ert_{label}"] = ert
                row[f"reached_{label}"] = f"{sum(r for _, r in times)}/{len(times)}"
                row[f"cell_{label}"] = f"{ert:.0f} ({row[f'reached_{label}']})".replace("inf", "∞")
            rows.append(row)
    return rows


def ecdf(
    curves: dict[str, dict[str, np.ndarray]],
    lengths: dict[str, dict[str, list[int]]],
    best_known: dict[str, float],
    budget: int,
) -> dict[str, np.ndarray]:
    """Per optimiser, the share of its (problem, target, run) triples reached within 1..``budget``
    simulations, aggregated over the problems with a best-known σ and :data:`TARGETS`."""
    reached: dict[str, list[int]] = {}
    for problem, by_optimizer in curves.items():
        if problem not in best_known:
            continue
        for optimizer, stack in by_optimizer.items():
            for target in TARGETS:
                times = runtimes(stack, lengths[problem][optimizer], (1.0 + target) * best_known[problem])
                reached.setdefault(optimizer, []).extend(t if ok else budget + 1 for t, ok in times)
    steps = np.arange(1, budget + 1)
    return {name: np.mean(np.array(t)[:, None] <= steps[None, :], axis=0) for name, t in reached.items()}


def holm(p_values: Sequence[float]) -> list[float]:
    """Holm's step-down adjusted p-values, in the order given."""
    order = np.argsort(p_values)
    adjusted = np.empty(len(p_values))
    running = 0.0
    for rank, index in enumerate(order):
        running = max(running, min(1.0, (len(p_values) - rank) * float(p_values[index])))
        adjusted[index] = running
    return adjusted.tolist()


def rank_tests(
    finals: dict[str, dict[tuple[str, int], float]],
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Friedman's test and the pairwise Wilcoxon-Holm tests of the final best σ.

    Parameters
    ----------
    finals : dict
        Per optimiser, its final best σ (N; inf without a feasible design) by block ``(problem, seed)``.

    Returns
    -------
    friedman : dict
        ``blocks``, ``statistic``, ``p_value`` and ``mean_ranks`` (by optimiser; 1 = best).
    pairs : list of dict
        Per pair: the Wilcoxon p-value, Holm's adjusted one, which is better, and whether it is
        significant at :data:`ALPHA`.
    """
    from scipy import stats

    names = sorted(finals)
    blocks = common_blocks(finals)
    if len(blocks) < MIN_BLOCKS:
        raise ValueError(
            f"{len(blocks)} block(s) where every optimiser has a run: the tests need {MIN_BLOCKS}"
        )
    table = np.array([[finals[n][b] for n in names] for b in blocks])  # blocks x optimisers
    ranks = stats.rankdata(np.where(np.isfinite(table), table, 1e300), axis=1)
    statistic, p_value = stats.friedmanchisquare(*table.T) if len(names) >= 3 else (np.nan, np.nan)
    friedman = {
        "blocks": len(blocks),
        "statistic": float(statistic),
        "p_value": float(p_value),
        "mean_ranks": dict(zip(names, ranks.mean(axis=0).tolist(), strict=True)),
    }
    pairs = []
    for (i, a), (j, b) in itertools.combinations(enumerate(names), 2):
        difference = np.where(np.isfinite(table[:, i]), table[:, i], 1e6) - np.where(
            np.isfinite(table[:, j]), table[:, j], 1e6
        )
        p = 1.0 if np.all(difference == 0) else float(stats.wilcoxon(difference).pvalue)
        pairs.append({"a": a, "b": b, "p_value": p, "better": a if np.median(difference) < 0 else b})
    for pair, adjusted in zip(pairs, holm([p["p_value"] for p in pairs]), strict=True):
        pair["p_holm"] = adjusted
        pair["significant"] = adjusted < ALPHA
    return friedman, pairs


def common_blocks(finals: dict[str, dict[tuple[str, int], float]]) -> list[tuple[str, int]]:
    """The blocks ``(problem, seed)`` where every optimiser of ``finals`` (:func:`rank_tests`) has a run."""
    return sorted(set.intersection(*(set(by_block) for by_block in finals.values()))) if finals else []


def broadest(
    finals: dict[str, dict[tuple[str, int], float]],
) -> tuple[dict[str, dict[tuple[str, int], float]], dict[str, int]]:
    """The optimisers to rank together over many blocks while runs are missing: in order of their finished
    blocks (most first), each joins unless it would leave fewer than half the blocks those before it share.
    Returns them, and those left out with their finished blocks.

    >>> a = {("B1", s): 1.0 for s in range(10)} | {("B2", s): 1.0 for s in range(10)}
    >>> kept, left = broadest({"a": a, "b": dict(a), "c": {("B1", 0): 2.0}})
    >>> sorted(kept), left
    (['a', 'b'], {'c': 1})
    """
    kept: dict[str, dict[tuple[str, int], float]] = {}
    left: dict[str, int] = {}
    for name in sorted(finals, key=lambda n: (-len(finals[n]), n)):
        joined = {**kept, name: finals[name]}
        if len(kept) < 2 or 2 * len(common_blocks(joined)) >= len(common_blocks(kept)):
            kept = joined
        else:
            left[name] = len(finals[name])
    return kept, left


def ecdf_figure(
    curves: dict[str, np.ndarray],
    problems: Sequence[str],
    path: Path,
    labels: dict[str, str] | None = None,
    partial: str = "",
) -> None:
    """The aggregated ECDF of runtimes, one line per optimiser (``labels``: its legend entry by name, e.g.
    with its runs, which differ between optimisers in a partial set; ``partial``: "N of M runs" of such a
    set, in the title)."""
    from catenary_env.plots import pyplot

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for i, (optimizer, share) in enumerate(sorted(curves.items(), key=lambda item: -item[1][-1])):
        label = (labels or {}).get(optimizer, optimizer)
        ax.step(np.arange(1, len(share) + 1), share, where="post", color=f"C{i}", label=label)
    ax.set_xlabel("simulations")
    ax.set_ylabel("share of (problem, target, run) reached")
    ax.set_ylim(0.0, 1.0)
    targets = ", ".join(f"{100 * t:g}" for t in TARGETS)
    scope = ", ".join(problems) + (f"; partial: {partial} of the protocol" if partial else "")
    ax.set_title(f"ECDF of runtimes to {targets} % above the best-known σ\n({scope})", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
