"""Study: ablation of the modelling choices (docs/model.md, 'Modelling choices').

One choice of :class:`~catenary_env.model.options.ModellingOptions` is switched at a time from the defaults,
and each model is run on the EN 50318:2002 reference model at 250 and 300 km/h (the validation's sixteen
quantities, as :func:`catenary_env.validation.validate` computes them) and on the benchmark catenary's level
design at 300 km/h (σ). The benchmark's pantograph is set once, on the default model, to the EN 50367 mean
contact force (157.3 N), and held for every row, as a design study holds it for every design: a choice that
moves the mean shows it.

Quick: the "test" fidelity (5 spans, 1 analysed, coarse mesh, 2 ms), minutes. Full: the validation's own
setting (10 spans, 2 analysed, 0.5 m contact-wire elements, 1 ms) and the "reference" fidelity for the
benchmark (20 spans, 10 analysed). All runs use the exact model; the two damping choices that the fast loops
do not integrate run the straightforward loop, which is slow (tens of minutes a passage at the full setting).

    python -m experiments.ablation [--full] [--workers 1] [--out results]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from catenary_env.model.design import level_design
from catenary_env.model.options import CHOICES, FORMER_DEFAULTS, ModellingOptions
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.pipeline import FIDELITIES, Fidelity, calibrate_uplift, en50367_mean_force, simulate
from catenary_env.validation import validate

from .common import (
    DEFAULT_OUT,
    add_full_option,
    add_out_option,
    add_workers_option,
    read_csv,
    run_cli,
    run_study,
    study_dir,
    write_csv,
    write_json,
)
from .model_stamp import stamp_study

NAME = "ablation"
EN_SPEEDS = (250.0, 300.0)  # km/h
BENCHMARK_SPEED = 300.0  # km/h
HEADERS = {
    "mean": "Fm",
    "std": "σ",
    "statistical_max": "Fm+3σ",
    "statistical_min": "Fm−3σ",
    "actual_max": "max",
    "actual_min": "min",
    "max_support_uplift": "uplift (mm)",
    "contact_loss_percent": "loss (%)",
}
"""Column headers of the EN 50318 quantities (forces in N)."""

COLOUR_LIMIT = 8.0
"""% at which the figure's colours saturate."""

Row = tuple[str, str]
"""(choice, setting): a field of ModellingOptions and its value, or ("baseline", "defaults")."""


@dataclass(frozen=True)
class Case:
    """One model and speed of the ablation."""

    catenary: str
    speed_kmh: float

    @property
    def label(self) -> str:
        name = "EN 50318:2002" if self.catenary == "en50318-2002" else self.catenary
        return f"{name}, {self.speed_kmh:g} km/h"


CASES = (*(Case("en50318-2002", s) for s in EN_SPEEDS), Case("benchmark", BENCHMARK_SPEED))
EN_LABELS = tuple(c.label for c in CASES[:-1])
BENCHMARK = CASES[-1].label


@dataclass(frozen=True)
class Config:
    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 1

    @property
    def en_fidelity(self) -> Fidelity | None:
        """None: the validation's own setting."""
        return None if self.full else FIDELITIES["test"]

    @property
    def benchmark_fidelity(self) -> Fidelity:
        return FIDELITIES["reference" if self.full else "test"]


FORMER = ("former defaults", "revision 2")
"""The row of the model before the defaults changed (physics revision 2)."""


def ablation_rows() -> list[Row]:
    """The defaults, every other setting of every choice one at a time, and the former defaults."""
    default = ModellingOptions()
    rows = [("baseline", "defaults")]
    for choice, settings in CHOICES.items():
        rows += [(choice, s) for s in settings if s != getattr(default, choice)]
    return [*rows, FORMER]


def options_of(row: Row) -> ModellingOptions:
    choice, setting = row
    if choice == "baseline":
        return ModellingOptions()
    if row == FORMER:
        return ModellingOptions(**FORMER_DEFAULTS)
    return dataclasses.replace(ModellingOptions(), **{choice: setting})


def _run(task: tuple[Row, Case, Config, float]) -> tuple[list[dict], float]:
    """The quantities of one row and case, and the wall time (s)."""
    row, case, config, uplift = task
    start = time.perf_counter()
    if case.catenary == "en50318-2002":
        report = validate((case.speed_kmh,), config.en_fidelity, options_of(row))
        values = [
            {"quantity": r.quantity, "value": r.value, "low": r.low, "high": r.high, "passed": int(r.passed)}
            for r in report.rows
        ]
    else:
        catenary = dataclasses.replace(load_catenary(case.catenary), modelling=options_of(row))
        pantograph = load_pantograph(catenary.pantograph)
        design = level_design(catenary)
        stats = simulate(
            catenary, pantograph, design, case.speed_kmh / 3.6, config.benchmark_fidelity, uplift
        ).statistics
        values = [
            {"quantity": q, "value": getattr(stats, q), "low": math.nan, "high": math.nan, "passed": ""}
            for q in ("std", "mean")
        ]
    return values, time.perf_counter() - start


def main(config: Config) -> Path:
    catenary = load_catenary("benchmark")
    speed = BENCHMARK_SPEED / 3.6
    uplift = calibrate_uplift(
        catenary,
        load_pantograph(catenary.pantograph),
        level_design(catenary),
        speed,
        config.benchmark_fidelity,
        en50367_mean_force(speed),
    )
    tasks = [(row, case, config, uplift) for row in ablation_rows() for case in CASES]
    # The straightforward loop's rows first, the longest (benchmark) case first: the workers finish together.
    order = sorted(
        range(len(tasks)),
        key=lambda i: (options_of(tasks[i][0]).rayleigh_only, tasks[i][1].catenary != "benchmark"),
    )
    if config.workers > 1:
        with ProcessPoolExecutor(max_workers=config.workers) as pool:
            done = list(pool.map(_run, [tasks[i] for i in order]))
    else:
        done = [_run(tasks[i]) for i in order]
    results = [done[order.index(i)] for i in range(len(tasks))]
    rows, timing = [], []
    for (row, case, _, _), (values, seconds) in zip(tasks, results, strict=True):
        rows += [{"choice": row[0], "setting": row[1], "case": case.label, **v} for v in values]
        timing.append(
            {"choice": row[0], "setting": row[1], "case": case.label, "wall_time_s": round(seconds, 1)}
        )
    folder = study_dir(config.out, NAME)
    write_csv(folder / "ablation.csv", rows)
    write_json(
        folder / "ablation.json",
        {
            "full": config.full,
            "defaults": dataclasses.asdict(ModellingOptions()),
            "en50318_fidelity": dataclasses.asdict(config.en_fidelity)
            if config.en_fidelity
            else "validation",
            "benchmark_fidelity": dataclasses.asdict(config.benchmark_fidelity),
            "benchmark_uplift_N": uplift,
            "timing": timing,
            "rows": rows,
        },
    )
    stamp_study(folder, ("en50318-2002", "benchmark"))
    report(folder)
    return folder


# -- report: tables and figure from the CSV ---------------------------------------------------------------


def _scale(quantity: str) -> float:
    return 1e3 if quantity == "max_support_uplift" else 1.0


def _indexed(rows: list[dict]) -> tuple[list[Row], dict[tuple[str, str, str, str], dict]]:
    order = list(dict.fromkeys((r["choice"], r["setting"]) for r in rows))
    return order, {(r["choice"], r["setting"], r["case"], r["quantity"]): r for r in rows}


def _table(rows: list[dict], case: str, extra: bool = False) -> str:
    """One Markdown table: a row per (choice, setting), a column per quantity, value and change (%)."""
    order, value = _indexed(rows)
    columns = [(case, q, h) for q, h in HEADERS.items()] + (
        [(BENCHMARK, "std", "benchmark σ")] if extra else []
    )
    lines = [
        "| choice | setting | " + " | ".join(h for _, _, h in columns) + " |",
        "|---|---|" + "---|" * len(columns),
    ]
    for choice, setting in order:
        cells = []
        for c, q, _ in columns:
            r = value[(choice, setting, c, q)]
            base = value[("baseline", "defaults", c, q)]["value"]
            text = f"{_scale(q) * r['value']:.2f}" + (" ✗" if r["passed"] == 0 else "")
            if choice != "baseline" and base != 0.0:
                text += f" ({100.0 * (r['value'] / base - 1.0):+.1f} %)"
            cells.append(text)
        lines.append(f"| {choice} | {setting} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def report(folder: Path) -> str:
    """Markdown tables (one per speed; ✗: outside the accepted range) and the figure, from the CSV."""
    rows = read_csv(folder / "ablation.csv")
    text = (
        f"{EN_LABELS[0]}\n\n{_table(rows, EN_LABELS[0])}\n\n"
        f"{EN_LABELS[1]}, and σ of the {BENCHMARK} (N)\n\n{_table(rows, EN_LABELS[1], extra=True)}"
    )
    (folder / "ablation.md").write_text(text + "\n", encoding="utf-8")
    _figure(rows, folder / "ablation.png")
    return text


def _figure(rows: list[dict], path: Path) -> None:
    """Change of every quantity (%) against the defaults, one row per switched choice."""
    import numpy as np

    from catenary_env.plots import pyplot

    plt = pyplot()
    order, value = _indexed(rows)
    switched = [k for k in order if k[0] != "baseline"]
    columns = [(c, q) for c in EN_LABELS for q in HEADERS if q != "contact_loss_percent"] + [
        (BENCHMARK, "std")
    ]
    labels = [f"{HEADERS[q]}\n{c.split(', ')[-1]}" for c, q in columns[:-1]] + ["σ bench-\nmark 300"]
    change = np.array(
        [
            [
                100.0 * (value[(*k, c, q)]["value"] / value[("baseline", "defaults", c, q)]["value"] - 1.0)
                for c, q in columns
            ]
            for k in switched
        ]
    )
    fig, ax = plt.subplots(figsize=(1.5 + 0.62 * len(columns), 1.2 + 0.42 * len(switched)))
    # Colours saturate at ±COLOUR_LIMIT %: Fm − 3σ, a small difference of large numbers, changes most.
    ax.imshow(change, cmap="RdBu_r", vmin=-COLOUR_LIMIT, vmax=COLOUR_LIMIT, aspect="auto")
    for j in (len(HEADERS) - 1.5, 2 * len(HEADERS) - 2.5):  # between the speeds, before the benchmark
        ax.axvline(j, color="black", lw=0.8)
    for i, k in enumerate(switched):
        for j, (c, q) in enumerate(columns):
            mark = "\n✗" if value[(*k, c, q)]["passed"] == 0 else ""
            dark = abs(change[i, j]) > 0.6 * COLOUR_LIMIT
            ax.text(
                j,
                i,
                f"{change[i, j]:+.1f}{mark}",
                ha="center",
                va="center",
                fontsize=6.5,
                color="w" if dark else "k",
            )
    ax.set_xticks(range(len(columns)), labels, fontsize=6.5)
    ax.set_yticks(range(len(switched)), [f"{c} = {s}" for c, s in switched], fontsize=7)
    ax.set_title(
        "Change (%) against the defaults, one modelling choice switched at a time "
        "(✗: outside the EN 50318:2002 range)",
        fontsize=8,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment ablation`` and ``python -m experiments.ablation``)."""
    add_full_option(
        parser,
        "the validation's own model and the 20-span benchmark (hours), instead of the coarse test model",
    )
    add_workers_option(parser, 1, "the modelling choices' simulations")
    add_out_option(parser)


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.ablation``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.ablation")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.ablation"))
