"""Study 1: validation against EN 50318:2002 at 250 and 300 km/h (table and figure).

    python -m experiments.validation [--out results]

The reference model is simulated as given (the presets' data); there is no quick setting because
the standard's model is itself small (10 spans).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

from catenary_env.validation import DISPLAY_UNITS, ValidationRow, markdown_table, validate

from .common import (
    DEFAULT_OUT,
    add_full_option,
    add_out_option,
    read_csv,
    run_cli,
    run_study,
    study_dir,
    write_csv,
)
from .model_stamp import stamp_study

NAME = "validation"


@dataclass(frozen=True)
class Config:
    out: Path = DEFAULT_OUT
    full: bool = False  # the same model either way


def main(config: Config) -> Path:
    result = validate((250.0, 300.0))
    rows = [{**r.as_dict(), "passed": int(r.passed)} for r in result.rows]
    folder = study_dir(config.out, NAME)
    write_csv(folder / "en50318.csv", rows)
    stamp_study(folder, ("en50318-2002",))
    report(folder)
    return folder


def report(folder: Path) -> str:
    """Markdown table and a figure from the CSV (no simulation)."""
    rows = [
        ValidationRow(r["speed_kmh"], r["quantity"], r["value"], r["low"], r["high"])
        for r in read_csv(folder / "en50318.csv")
    ]
    table = markdown_table(rows)
    (folder / "en50318.md").write_text(table + "\n", encoding="utf-8")
    _figure(rows, folder / "en50318.png")
    return table


def _figure(rows: list[ValidationRow], path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    quantities = [q for q in dict.fromkeys(r.quantity for r in rows) if q != "contact_loss_percent"]
    fig, axes = plt.subplots(1, len(quantities), figsize=(2.0 * len(quantities), 3.2))
    for ax, quantity in zip(axes, quantities, strict=True):
        for i, r in enumerate(r for r in rows if r.quantity == quantity):
            scale = DISPLAY_UNITS.get(quantity, (1.0, "N"))[0]
            ax.plot([i, i], [scale * r.low, scale * r.high], color="0.7", lw=8, solid_capstyle="butt")
            ax.plot(i, scale * r.value, "o", color="C2" if r.passed else "C3")
        ax.set_xticks([0, 1], ["250", "300"])
        ax.set_xlim(-0.6, 1.6)
        ax.set_title(
            quantity.replace("_", " ") + (" (mm)" if quantity == "max_support_uplift" else " (N)"), fontsize=8
        )
        ax.tick_params(labelsize=7)
    fig.suptitle(
        "EN 50318:2002: simulated value (dot) and accepted range (bar) at 250 and 300 km/h", fontsize=9
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment validation`` and ``python -m experiments.validation``)."""
    add_full_option(parser, "the same model as the quick one (the standard's model is small: minutes)")
    add_out_option(parser)


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.validation``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.validation")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.validation"))
