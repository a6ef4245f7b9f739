"""Study 2: σ against pre-sag on both catenaries at the design speed, 300 km/h (the quick setting's nearest
speed, 320 km/h), and the best pre-sag against speed (docs/problems.md, 'Experiments').

The design problems BPresag and SWPresag: a parabolic contact-wire pre-sag s (m at mid-span). The pantograph's
uplift is set once per catenary and speed on the level reference design (docs/problems.md, 'Reference design
and uplift'). Quick: the "test" fidelity (5 spans, coarse) on a coarse grid; full: the study fidelity (20
spans) on the problems' 1 cm grid.

    python -m experiments.presag [--full] [--workers 2] [--out results]
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenary_env.problems import evaluate_problem, get_problem

from .common import (
    DEFAULT_OUT,
    add_full_option,
    add_out_option,
    add_workers_option,
    markdown_table,
    read_csv,
    run_cli,
    run_study,
    study_dir,
    write_csv,
)
from .model_stamp import catenaries_of, stamp_study

NAME = "presag"
PROBLEMS = ("BPresag", "SWPresag")


@dataclass(frozen=True)
class Config:
    full: bool = False
    out: Path = DEFAULT_OUT
    workers: int = 2

    @property
    def fidelity(self) -> str:
        return "study" if self.full else "test"

    @property
    def presags(self) -> tuple[float, ...]:
        step = 0.01 if self.full else 0.02
        return tuple(np.round(np.arange(-0.02, 0.10 + 1e-9, step), 3))

    @property
    def speeds_kmh(self) -> tuple[float, ...]:
        return (200.0, 220.0, 240.0, 260.0, 280.0, 300.0, 320.0) if self.full else (200.0, 260.0, 320.0)


def main(config: Config) -> Path:
    tasks = [(name, speed) for name in PROBLEMS for speed in config.speeds_kmh]
    # The uplift is calibrated once per catenary and speed, here, so the workers need not repeat it.
    uplift = {(name, speed): get_problem(name).uplift_force(speed, config.fidelity) for name, speed in tasks}
    jobs = [
        (name, (s,), speed, config.fidelity, uplift[(name, speed)])
        for name, speed in tasks
        for s in config.presags
    ]
    with ProcessPoolExecutor(max_workers=config.workers) as pool:
        results = list(pool.map(evaluate_problem, *zip(*jobs, strict=True)))
    rows = []
    for (name, (s,), speed, _, force), ev in zip(jobs, results, strict=True):
        stats = ev.statistics
        rows.append(
            {
                "problem": name,
                "catenary": get_problem(name).catenary,
                "speed_kmh": speed,
                "presag_m": s,
                "feasible": int(ev.feasible),
                "sigma_N": stats.std if stats else float("nan"),
                "mean_N": stats.mean if stats else float("nan"),
                "uplift_N": force,
                "reason": ev.reason,
            }
        )
    folder = study_dir(config.out, NAME)
    write_csv(folder / "presag.csv", rows)
    stamp_study(folder, catenaries_of(PROBLEMS))
    report(folder)
    return folder


def best_presag(rows: list[dict]) -> list[dict]:
    """The feasible pre-sag with the lowest σ per problem and speed."""
    out = []
    for name in dict.fromkeys(r["problem"] for r in rows):
        for speed in sorted({r["speed_kmh"] for r in rows if r["problem"] == name}):
            candidates = [
                r for r in rows if r["problem"] == name and r["speed_kmh"] == speed and r["feasible"]
            ]
            level = next((r for r in candidates if r["presag_m"] == 0.0), None)
            if candidates:
                best = min(candidates, key=lambda r: r["sigma_N"])
                out.append(
                    {
                        "problem": name,
                        "speed_kmh": speed,
                        "best_presag_m": best["presag_m"],
                        "sigma_N": best["sigma_N"],
                        "level_sigma_N": level["sigma_N"] if level else float("nan"),
                    }
                )
    return out


def report(folder: Path) -> str:
    """Tables and figures from the CSV (no simulation)."""
    rows = read_csv(folder / "presag.csv")
    best = best_presag(rows)
    for b in best:
        b["reduction_percent"] = 100.0 * (1.0 - b["sigma_N"] / b["level_sigma_N"])
    table = markdown_table(
        best,
        [
            ("problem", "problem", "s"),
            ("speed_kmh", "speed (km/h)", "g"),
            ("best_presag_m", "best pre-sag (m)", ".2f"),
            ("sigma_N", "σ (N)", ".2f"),
            ("level_sigma_N", "σ level (N)", ".2f"),
            ("reduction_percent", "reduction (%)", ".1f"),
        ],
    )
    (folder / "presag.md").write_text(table + "\n", encoding="utf-8")
    _figure(rows, best, folder / "presag.png")
    return table


DESIGN_SPEED_KMH = 300.0
"""The speed of the left panel, σ against pre-sag: the design studies' speed, or the data's nearest."""


def figure_speed(rows: list[dict]) -> float:
    """The speed of the data nearest to :data:`DESIGN_SPEED_KMH`, km/h (the higher one on a tie)."""
    return min({r["speed_kmh"] for r in rows}, key=lambda v: (abs(v - DESIGN_SPEED_KMH), -v))


def _figure(rows: list[dict], best: list[dict], path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    speed = figure_speed(rows)
    for i, name in enumerate(PROBLEMS):
        pick = [r for r in rows if r["problem"] == name and r["speed_kmh"] == speed]
        if pick:
            feasible = [r for r in pick if r["feasible"]]
            left.plot(
                [1e3 * r["presag_m"] for r in feasible],
                [r["sigma_N"] for r in feasible],
                "o-",
                color=f"C{i}",
                label=f"{pick[0]['catenary']} ({name})",
            )
        b = [r for r in best if r["problem"] == name]
        right.plot(
            [r["speed_kmh"] for r in b],
            [1e3 * r["best_presag_m"] for r in b],
            "o-",
            color=f"C{i}",
            label=name,
        )
    left.set_xlabel("pre-sag at mid-span (mm)")
    left.set_ylabel("σ of the contact force (N)")
    left.set_title(f"σ against pre-sag at {speed:g} km/h")
    left.legend()
    right.set_xlabel("speed (km/h)")
    right.set_ylabel("best pre-sag (mm)")
    right.set_title("best pre-sag against speed")
    right.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment presag`` and ``python -m experiments.presag``)."""
    add_full_option(
        parser, "20 spans, pre-sags on a 1 cm grid, 7 speeds from 200 to 320 km/h (minutes: 182 simulations)"
    )
    add_workers_option(parser, 2)
    add_out_option(parser)


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.presag``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.presag")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.presag"))
