"""Convergence of the span-mode model with its cut-offs: the study that sets them once.

docs/performance.md, 'Model fidelities'. On a few representative cases (the level wire of both study
catenaries at 300 km/h, a moved-dropper design of B2, a B3 design with five droppers a span, whose long
unsupported contact wire carries the near field furthest, and the EN 50318:2002 model at 250 km/h), the
span-mode model's statistics against the exact model's, as the near-field cut-off rises, as the far-field
cut-off rises, and as the near field widens (the others fixed). The chosen values are the smallest
whose errors sit well inside the contract on every case; they are constants of the model
(``catenary_env.pipeline.NEAR_CUTOFF``, ``FAR_CUTOFF``, ``NEAR_SPANS``), never tuned per case.

    python benchmarks/fidelity_convergence.py          # runs it, writes results/fidelity_convergence.json
    python benchmarks/fidelity_convergence.py --table  # prints the table from that file
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from catenary_env.model.design import level_design  # noqa: E402
from catenary_env.model.presets import load_catenary, load_pantograph  # noqa: E402
from catenary_env.pipeline import (  # noqa: E402
    FAR_CUTOFF,
    FIDELITIES,
    NEAR_CUTOFF,
    NEAR_SPANS,
    Fidelity,
    evaluate,
)
from catenary_env.problems import PROBLEMS  # noqa: E402

RESULTS = Path(__file__).parent / "results" / "fidelity_convergence.json"
NEAR = (200.0, 300.0, 400.0, 500.0, 600.0)
FAR = (20.0, 30.0, 50.0, 100.0, 200.0)
SPANS = (1, 2, 3)


def cases() -> list[tuple[str, object, object, object, float, float, Fidelity]]:
    """(name, catenary, pantograph, design, speed m/s, uplift N, fidelity) of each case."""
    out = []
    designs = (
        ("B1", None),
        ("SW1", None),
        ("B2", (3.0, 9.0, 15.0, 21.0)),
        ("B3", (2.17, 14.18, -0.01, -0.02, -0.015)),  # five droppers a span: long unsupported wire
    )
    for problem_name, x in designs:
        problem = PROBLEMS[problem_name]
        design = problem.reference_design() if x is None else problem.design(x)
        label = f"{problem.catenary} level" if x is None else f"{problem_name} {x}"
        force = problem.uplift_force(300.0, "study")
        out.append(
            (
                label,
                problem.catenary_definition,
                problem.pantograph_definition,
                design,
                300 / 3.6,
                force,
                FIDELITIES["study"],
            )
        )
    en = load_catenary("en50318-2002")
    pantograph = load_pantograph("en50318-2002")
    fidelity = Fidelity(n_spans=en.n_spans, analysis_spans=en.analysis_spans)
    out.append(
        ("EN 50318 250 km/h", en, pantograph, level_design(en), 250 / 3.6, pantograph.uplift_force, fidelity)
    )
    return out


def run() -> dict:
    rows = []
    for name, catenary, pantograph, design, speed, force, fidelity in cases():
        start = time.perf_counter()
        exact = evaluate(
            catenary, pantograph, design, speed, dataclasses.replace(fidelity, dynamics="exact"), force
        )
        exact_time = time.perf_counter() - start
        settings = (
            [(near, FAR_CUTOFF, NEAR_SPANS) for near in NEAR]
            + [(NEAR_CUTOFF, far, NEAR_SPANS) for far in FAR if far != FAR_CUTOFF]
            + [(NEAR_CUTOFF, FAR_CUTOFF, spans) for spans in SPANS if spans != NEAR_SPANS]
        )
        for near, far, spans in settings:
            f = dataclasses.replace(
                fidelity, dynamics="span-modes", near_cutoff=near, far_cutoff=min(far, near), near_spans=spans
            )
            start = time.perf_counter()
            ev = evaluate(catenary, pantograph, design, speed, f, force)
            r, s = exact.statistics, ev.statistics
            rows.append(
                {
                    "case": name,
                    "near_cutoff": near,
                    "far_cutoff": far,
                    "near_spans": spans,
                    "std_exact": r.std,
                    "std": s.std,
                    "error_std": s.std / r.std - 1,
                    "error_mean": s.mean / r.mean - 1,
                    "error_max": (s.actual_max - r.actual_max) / r.mean,
                    "error_min": (s.actual_min - r.actual_min) / r.mean,
                    "error_uplift": s.max_support_uplift / r.max_support_uplift - 1,
                    "time": time.perf_counter() - start,
                    "time_exact": exact_time,
                }
            )
            print(json.dumps(rows[-1]), flush=True)
    return {"near_cutoff": NEAR_CUTOFF, "far_cutoff": FAR_CUTOFF, "near_spans": NEAR_SPANS, "rows": rows}


def table(data: dict) -> str:
    lines = [
        "| case | near (Hz) | far (Hz) | near spans | σ exact (N) | σ error | mean error | max error "
        "| min error |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in data["rows"]:
        lines.append(
            f"| {r['case']} | {r['near_cutoff']:.0f} | {r['far_cutoff']:.0f} | {r['near_spans']} | "
            f"{r['std_exact']:.2f} | "
            f"{100 * r['error_std']:+.3f} % | {100 * r['error_mean']:+.3f} % | "
            f"{100 * r['error_max']:+.2f} % | "
            f"{100 * r['error_min']:+.2f} % |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--table", action="store_true", help="print the table of the stored results")
    args = parser.parse_args()
    if not args.table:
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(json.dumps(run(), indent=1))
    print(table(json.loads(RESULTS.read_text())))


if __name__ == "__main__":
    main()
