"""``catenary experiment NAME [--full]`` and ``catenary report``: the studies from the command line."""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

from .common import DEFAULT_OUT
from .model_stamp import model_section

REPORT = "report.md"
"""The report's file name in the studies' folder."""


class Study(NamedTuple):
    """A study of ``catenary experiment``: its module in ``experiments`` and one line for ``--help``."""

    module: str
    summary: str


STUDIES = {
    "validation": Study("validation", "EN 50318:2002 table and figure at 250 and 300 km/h"),
    "ablation": Study("ablation", "one modelling choice at a time: EN 50318:2002 quantities, benchmark σ"),
    "convergence": Study("convergence", "mesh and time-step convergence of σ (benchmark preset, 300 km/h)"),
    "presag": Study("presag", "σ against pre-sag on both catenaries, and the best pre-sag against speed"),
    "design": Study(
        "design_studies", "the six GA design studies, static analysis of the optima, σ against speed"
    ),
    "optimizers": Study(
        "optimizer_comparison", "seven optimisers on B1 and SW1 at equal budgets, with IOHprofiler output"
    ),
    "rl": Study("rl_studies", "PPO learning curves, a speed-conditioned policy, a design for 200-320 km/h"),
}


def add_parsers(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "experiment", help="run a study (docs/problems.md, 'Experiments'); writes data (CSV) and figures"
    )
    p.add_argument(
        "name", choices=sorted(STUDIES), help="; ".join(f"{k}: {v.summary}" for k, v in STUDIES.items())
    )
    p.add_argument(
        "--full",
        action="store_true",
        help="the full setting (20 spans, fine grids: minutes to hours); "
        "default: the quick setting (minutes)",
    )
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder (default: results)")
    p = sub.add_parser(
        "report",
        help="write results/report.md: every study's tables and figures, re-made from its data alone",
    )
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the studies' folder (default: results)")


def run_experiment(args: argparse.Namespace) -> int:
    module = importlib.import_module(f"experiments.{STUDIES[args.name].module}")
    folder = module.main(module.Config(full=args.full, out=args.out))
    print(module.report(folder))
    return 0


def build_report(out: Path) -> Path | None:
    """Write ``out/report.md``: which model made each study's data (:mod:`experiments.model_stamp`), every
    study's tables, re-made from its data without simulating, and its figures; None when no study has data
    under ``out``."""
    sections, missing = [], []
    for name, study in STUDIES.items():
        folder = Path(out) / name
        if not (folder.is_dir() and any(folder.rglob("*.csv"))):
            missing.append(name)
            continue
        module = importlib.import_module(f"experiments.{study.module}")
        text = module.report(folder)
        figures = [f"![{p.stem}]({p.relative_to(out).as_posix()})" for p in sorted(folder.rglob("*.png"))]
        sections.append("\n\n".join([f"## {name}: {study.summary}", text, *figures]))
    if not sections:
        return None
    sections.insert(0, model_section({name: Path(out) / name for name in STUDIES if name not in missing}))
    if missing:
        sections.append(
            "Not run yet: " + ", ".join(f"`catenary experiment {name}`" for name in missing) + "."
        )
    path = Path(out) / REPORT
    path.write_text("# catenary-env: study results\n\n" + "\n\n".join(sections) + "\n", encoding="utf-8")
    return path


def run_report(args: argparse.Namespace) -> int:
    path = build_report(args.out)
    if path is None:
        print(f"no study data under {args.out}: run 'catenary experiment NAME' first")
        return 1
    print(f"wrote {path}")
    return 0


HANDLERS: dict[str, Callable[[argparse.Namespace], int]] = {
    "experiment": run_experiment,
    "report": run_report,
}


def add_commands(sub: argparse._SubParsersAction) -> dict[str, Callable[[argparse.Namespace], int]]:
    """Add ``catenary experiment`` and ``catenary report``: the ``catenary_env.commands`` entry point."""
    add_parsers(sub)
    return dict(HANDLERS)
