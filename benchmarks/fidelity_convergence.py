"""Convergence of the span-mode model with its cut-offs: the study that sets them once.

docs/performance.md, 'Model fidelities'. On a few representative cases (the level wire of both study
catenaries at 300 km/h, a moved-dropper design of B2, two B2 designs with a dropper close to the support,
a B3 design with five droppers a span, whose long unsupported contact wire carries the near field
furthest, the benchmark's level wire at 350 km/h, which loses contact, and the EN 50318:2002 model at
250 km/h), the span-mode model's statistics against the exact model's, as the near-field cut-off rises
(up to every mode: the reduction is then a change of basis), as the far-field cut-off rises, and as
the near field widens (the others fixed). The chosen values are the smallest whose errors sit well
inside the contract on every case; they are constants of the model
(``catenary_env.pipeline.NEAR_CUTOFF``, ``FAR_CUTOFF``, ``NEAR_SPANS``), never tuned per case.

    python benchmarks/fidelity_convergence.py          # runs it, writes results/fidelity_convergence.json
    python benchmarks/fidelity_convergence.py --table  # prints the table from that file

The data file records the fingerprint of the model that made it
(:func:`~catenary_env.fingerprint.presets_fingerprint` of :data:`CATENARIES`).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from catenary_env.fingerprint import presets_fingerprint  # noqa: E402
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
CATENARIES = ("benchmark", "en50318-2002", "stitched")
"""The catenary presets of the cases."""
NEAR = (200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0, 1000.0, 1500.0, 2000.0, math.inf)
FAR = (20.0, 30.0, 50.0, 100.0, 200.0)
SPANS = (1, 2, 3)


def cases() -> list[tuple[str, object, object, object, float, float, Fidelity]]:
    """(name, catenary, pantograph, design, speed m/s, uplift N, fidelity) of each case."""
    out = []
    designs = (
        ("B1", None, 300.0),
        ("SW1", None, 300.0),
        ("B2", (3.0, 9.0, 15.0, 21.0), 300.0),
        ("B2", (0.5, 9.0, 15.0, 21.0), 300.0),  # a dropper 0.5 m from the support
        ("B2", (0.2, 9.0, 15.0, 21.0), 300.0),  # and 0.2 m
        ("B3", (2.17, 14.18, -0.01, -0.02, -0.015), 300.0),  # five droppers a span: long unsupported wire
        ("B1", None, 350.0),  # loses contact
    )
    for problem_name, x, kmh in designs:
        problem = PROBLEMS[problem_name]
        design = problem.reference_design() if x is None else problem.design(x)
        label = f"{problem.catenary} level" if x is None else f"{problem_name} {x}"
        label += "" if kmh == 300.0 else f" {kmh:.0f} km/h"
        force = problem.uplift_force(kmh, "study")
        out.append(
            (
                label,
                problem.catenary_definition,
                problem.pantograph_definition,
                design,
                kmh / 3.6,
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
                    "near_cutoff": None if math.isinf(near) else near,  # None: every mode
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
    near = None if math.isinf(NEAR_CUTOFF) else NEAR_CUTOFF
    return {"near_cutoff": near, "far_cutoff": FAR_CUTOFF, "near_spans": NEAR_SPANS, "rows": rows}


def _hz(cutoff: float | None) -> str:
    return "every mode" if cutoff is None else f"{cutoff:.0f} Hz"


def _pivot(rows: list[dict], column: str, title: str) -> list[str]:
    """One table: a row per case, a column per value of ``column``; each cell the error of σ and, after
    the slash, the larger error of the actual maximum and minimum (% of the mean)."""
    values = sorted(set(r[column] for r in rows), key=lambda v: math.inf if v is None else v)
    label = _hz if column != "near_spans" else (lambda n: f"{n} span{'s' if n > 1 else ''}")
    lines = [
        title,
        "",
        "| case | σ exact (N) | " + " | ".join(label(v) for v in values) + " |",
        "|---|---|" + "---|" * len(values),
    ]
    for case in dict.fromkeys(r["case"] for r in rows):
        cells = {r[column]: r for r in rows if r["case"] == case}
        text = [
            f"{100 * c['error_std']:+.3f} / {100 * max(abs(c['error_max']), abs(c['error_min'])):.2f}"
            for c in (cells[v] for v in values)
        ]
        lines.append(f"| {case} | {cells[values[0]]['std_exact']:.2f} | " + " | ".join(text) + " |")
    return lines


def table(data: dict) -> str:
    """The three tables of docs/performance.md: near cut-off, far cut-off, near field's width (errors, %)."""
    rows = data["rows"]
    near, far, spans = data["near_cutoff"], data["far_cutoff"], data["near_spans"]
    by_near = [r for r in rows if r["far_cutoff"] == far and r["near_spans"] == spans]
    by_far = [r for r in rows if r["near_cutoff"] == near and r["near_spans"] == spans]
    by_spans = [r for r in rows if r["near_cutoff"] == near and r["far_cutoff"] == far]
    return "\n".join(
        _pivot(by_near, "near_cutoff", f"Near cut-off (far {far:.0f} Hz, {spans} near spans each side):")
        + [""]
        + _pivot(by_far, "far_cutoff", f"Far cut-off (near: {_hz(near)}, {spans} near spans each side):")
        + [""]
        + _pivot(by_spans, "near_spans", f"Near field's width (near: {_hz(near)}, far {far:.0f} Hz):")
    )


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--table", action="store_true", help="print the table of the stored results")
    args = parser.parse_args()
    if not args.table:
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        data = {"fingerprint": presets_fingerprint(CATENARIES), **run()}
        RESULTS.write_text(json.dumps(data, indent=1))
    print(table(json.loads(RESULTS.read_text())))


if __name__ == "__main__":
    main()
