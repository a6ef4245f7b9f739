"""``catenary report``: every study's tables and figures in one Markdown file, re-made from its data."""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from ..common import DEFAULT_OUT
from ..model_stamp import model_section
from .experiment import STUDIES

REPORT = "report.md"
"""The report's file name in the studies' folder."""
FULL_PROTOCOL = "full-protocol"
"""The folder, in the studies' folder, of the studies' full protocols (`experiments/full_protocol.sh`): a
study with results there gets a second section, the full protocol's, beside its own."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``report`` to the sub-commands of ``catenary``."""
    p = sub.add_parser(
        "report",
        help="write results/report.md: every study's tables and figures, re-made from its data alone",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=DEFAULT_OUT,
        metavar="FOLDER",
        help=f"the studies' folder, with a folder per study (default: {DEFAULT_OUT})",
    )


def build_report(out: Path) -> Path | None:
    """Write ``out/report.md``: which model made each study's data (:mod:`experiments.model_stamp`), every
    study's tables, re-made from its data without simulating, and its figures; None when no study has data
    under ``out``."""
    sections, missing, made = [], [], {}
    homes = {name: study.folder or name for name, study in STUDIES.items()}
    for name, study in STUDIES.items():
        # Another study's folder may lie inside this one's (rl/amortised in rl): its files are not this one's.
        nested = [
            Path(h).relative_to(homes[name])
            for other, h in homes.items()
            if other != name and Path(h).is_relative_to(homes[name])
        ]
        folders = {
            name: Path(out) / homes[name],
            f"{name} ({FULL_PROTOCOL})": Path(out) / FULL_PROTOCOL / homes[name],
        }
        found = {title: f for title, f in folders.items() if f.is_dir() and _own(f, "*.csv", nested)}
        if name not in found:
            missing.append(name)
        for title, folder in found.items():
            module = importlib.import_module(f"experiments.{study.module}")
            figures = [f"![{p.stem}]({p.relative_to(out).as_posix()})" for p in _own(folder, "*.png", nested)]
            sections.append("\n\n".join([f"## {title}: {study.summary}", module.report(folder), *figures]))
        made.update(found)
    if not sections:
        return None
    sections.insert(0, model_section(made))
    if missing:
        sections.append(
            "Not run yet: " + ", ".join(f"`catenary experiment {name}`" for name in missing) + "."
        )
    path = Path(out) / REPORT
    path.write_text("# catenary-env: study results\n\n" + "\n\n".join(sections) + "\n", encoding="utf-8")
    return path


def _own(folder: Path, pattern: str, nested: list[Path]) -> list[Path]:
    """The files matching ``pattern`` in ``folder`` and below, but for those in the ``nested`` folders
    (relative to ``folder``) of other studies."""
    return sorted(
        path
        for path in folder.rglob(pattern)
        if not any(path.relative_to(folder).is_relative_to(n) for n in nested)
    )


def run(args: argparse.Namespace) -> int:
    """Write the report; 0, or 1 when no study has data under ``--out``."""
    path = build_report(args.out)
    if path is None:
        print(f"no study data under {args.out}: run 'catenary experiment NAME' first")
        return 1
    print(f"wrote {path}")
    return 0
