"""The README's block on the optimiser benchmark's full protocol, written from its committed results
(docs/problems.md, 'Reading the comparison'), so that the README says what the results say while the protocol
runs and when it is done: the fixed-budget table over the problems, the ECDF figure, the ranks with their
significance tests, and what the best-known designs say about the GA design studies.

    python -m experiments.benchmark_summary    # rewrites the block in README.md from results/
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from .common import read_csv

ROOT = Path(__file__).resolve().parents[1]
FOLDER = Path("results") / "full-protocol" / "optimizers"
"""The full protocol's results, relative to the repository (the README's links are)."""
START = (
    "<!-- full protocol: written by `python -m experiments.benchmark_summary` from "
    "results/full-protocol/optimizers and catenary_env/problems/best_known.json; do not edit -->"
)
END = "<!-- end of the full protocol's block -->"
KEPT = ("### Fixed budget", "### Ranks")
"""The sections of the results' ``optimizers.md`` the block quotes (the fixed-target tables stay there)."""


def block(root: Path = ROOT) -> str:
    """The README's block, from the results under ``root``."""
    text = (root / FOLDER / "optimizers.md").read_text(encoding="utf-8")
    first = text.split("\n", 1)[0]
    parts = [START]
    partial = first.startswith("Partial: ")
    if partial:
        parts.append(f"**{first}**")
    for section in text.split("\n### ")[1:]:
        heading, _, body = section.partition("\n")
        if f"### {heading}".startswith(KEPT):
            parts += [f"#### {heading}", body.strip()]
        if f"### {heading}".startswith(KEPT[0]) and (root / FOLDER / "ecdf.png").is_file():
            figure = (FOLDER / "ecdf.png").as_posix()
            parts.append(
                f"![share of (run, target) pairs reached against simulations, targets 1-10 % above]({figure})"
            )
    parts += [
        "#### What the best-known designs say about the GA design studies",
        _best_known(root, partial),
        END,
    ]
    return "\n\n".join(parts)


def _best_known(root: Path, partial: bool) -> str:
    """Per problem, whether the design study's optimum is still the best-known design, and how close the
    benchmark's best run came (``partial``: of the runs finished so far)."""
    table = json.loads((root / "catenary_env" / "problems" / "best_known.json").read_text(encoding="utf-8"))
    closest: dict[str, tuple[float, str]] = {}
    for row in read_csv(root / FOLDER / "summary.csv"):
        if row["problem"] not in closest or row["best_sigma_N"] < closest[row["problem"]][0]:
            closest[row["problem"]] = (row["best_sigma_N"], row["optimizer"])
    lines = []
    for known in table:
        problem, sigma = known["problem"], known["sigma_N"]
        exact = f"{sigma:.2f} N (exact model {known['confirmed_sigma_N']:.2f} N)"
        summary = root / "results" / "design" / problem / "summary.json"
        if known["found_by"].startswith("design study"):
            best = closest.get(problem)
            runs = "no run of the benchmark has finished"
            if best:
                above = 100 * (best[0] / sigma - 1)
                so_far = " so far" if partial else ""
                runs = f"the benchmark's best run{so_far}, {best[1]}'s, came to {best[0]:.3f} N "
                runs += f"({above:.2f} % above)"
            lines.append(f"- {problem}: the design study's optimum, {exact}, is the best known; {runs}.")
        elif summary.is_file():
            study = json.loads(summary.read_text(encoding="utf-8"))
            run = known["found_by"].split(" (")[0].removeprefix("optimiser comparison ")
            lines.append(
                f"- {problem}: a run of the benchmark ({run}) found {exact} in 300 simulations, below the "
                f"design study's optimum ({study['sigma_optimum_N']:.2f} N after {study['simulations']:,} "
                "simulations and its stall rule)."
            )
    return "\n".join(lines)


def rewrite(readme: Path, root: Path = ROOT) -> None:
    """Replace the block in the README (between its markers) by the one the results give."""
    text = readme.read_text(encoding="utf-8")
    start, end = text.index(START), text.index(END) + len(END)
    readme.write_text(text[:start] + block(root) + text[end:], encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.benchmark_summary", description=__doc__)
    parser.add_argument("--readme", type=Path, default=ROOT / "README.md", help="the README to rewrite")
    rewrite(parser.parse_args(argv).readme)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
