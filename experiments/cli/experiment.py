"""``catenary experiment NAME [options]``: run a study (docs/problems.md, 'Experiments').

The options after NAME are the study's own, declared once in its module (``add_arguments``): the same as
``python -m experiments.MODULE`` takes. ``catenary experiment NAME --help`` lists them.
"""

from __future__ import annotations

import argparse
import importlib
from typing import NamedTuple

from ..common import run_study

__all__ = ["STUDIES", "Study", "add_parser", "run"]


class Study(NamedTuple):
    """A study of ``catenary experiment``: its module in ``experiments``, one line for ``--help`` and its
    folder in the studies' output folder (default: its name)."""

    module: str
    summary: str
    folder: str = ""


STUDIES = {
    "validation": Study("validation", "EN 50318:2002 table and figure at 250 and 300 km/h"),
    "ablation": Study("ablation", "one modelling choice at a time: EN 50318:2002 quantities, benchmark σ"),
    "convergence": Study("convergence", "mesh and time-step convergence of σ (benchmark preset, 300 km/h)"),
    "time-step": Study(
        "time_step", "Newmark against every mode integrated exactly: can a passage take a longer step?"
    ),
    "presag": Study("presag", "σ against pre-sag on both catenaries, and the best pre-sag against speed"),
    "design": Study(
        "design_studies", "the six GA design studies, static analysis of the optima, σ against speed"
    ),
    "optimizers": Study(
        "optimizer_comparison", "nine optimisers, six problems, equal budgets, IOHprofiler output"
    ),
    "rl": Study("rl_studies", "PPO learning curves, a speed-conditioned policy, a design for 200-320 km/h"),
    "rl-amortised": Study(
        "rl_amortised",
        "speed-conditioned PPO and SAC policies at held-out speeds against a GA run per speed",
        "rl/amortised",
    ),
    "rl-tension": Study(
        "rl_tension",
        "SAC policies conditioned on speed and contact-wire tension, against a GA run each",
        "rl/tension",
    ),
    "tolerance": Study(
        "tolerance",
        "σ under installation tolerances, the design studies under buildability limits, robust GA",
    ),
    "pantographs": Study(
        "pantographs",
        "two pantographs 200 m apart: the design studies' optima, a GA for the worse pantograph",
    ),
}


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``experiment`` to the sub-commands of ``catenary``."""
    p = sub.add_parser(
        "experiment",
        help="run a study (docs/problems.md, 'Experiments'); writes data (CSV) and figures",
        description="Run a study: it writes tidy data (CSV) and figures under OUT/<study> and prints its "
        "report. The options after NAME are the study's own (catenary experiment NAME --help), the same as "
        "python -m experiments.MODULE takes; every study takes --full (the full setting: 20 spans, hours) "
        "and --out FOLDER.",
    )
    p.add_argument(
        "name",
        choices=sorted(STUDIES),
        metavar="NAME",
        help="; ".join(f"{k}: {v.summary}" for k, v in STUDIES.items()),
    )
    p.add_argument(
        "options",
        nargs=argparse.REMAINDER,
        metavar="...",
        help="the study's options, e.g. --full, --out FOLDER, --workers N (catenary experiment NAME --help)",
    )


def run(args: argparse.Namespace) -> int:
    """Run the study with its options; 0."""
    module = importlib.import_module(f"experiments.{STUDIES[args.name].module}")
    return run_study(module, args.options, f"catenary experiment {args.name}")
