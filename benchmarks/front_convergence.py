"""The convergence study of the margin a span-mode passage steps beyond its wave front (docs/performance.md,
'The spans ahead of the wave front').

A passage steps only the spans that begin less than ``front_margin`` beyond its wave front (the front leaves
the foremost pantograph's start at the wires' fastest transverse wave speed); the spans further ahead are
held at rest. This runs the same prepared design with every span stepped and with each margin,
the whole passage over the section (the front is furthest from the section's end there), and prints, for
each case and margin, the largest difference of the contact force over the passage (N), and the changes of
σ and of the actual extremes over the central half of the section, relative to σ and to the mean.

    python benchmarks/front_convergence.py               # the table
    python benchmarks/front_convergence.py --json        # the same as data
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from catenary_env.analysis.statistics import passage_statistics  # noqa: E402
from catenary_env.dynamics import span_modes  # noqa: E402
from catenary_env.dynamics.linear_system import linearise  # noqa: E402
from catenary_env.dynamics.protocol import Passage  # noqa: E402
from catenary_env.dynamics.span_modes.passage import FRONT_MARGIN, front_speed  # noqa: E402
from catenary_env.fem.layout import build_layout  # noqa: E402
from catenary_env.fingerprint import simulator_fingerprint  # noqa: E402
from catenary_env.model.design import level_design  # noqa: E402
from catenary_env.model.presets import load_catenary, load_pantograph  # noqa: E402
from catenary_env.pipeline import Fidelity, analysis_window  # noqa: E402
from catenary_env.statics.shape_finding import find_shape  # noqa: E402

MARGINS = (0.0, 50.0, 100.0, 150.0, 200.0, 250.0)
"""The margins tried, m beyond the front."""
UPLIFT = 170.0
"""N: the frame force of every case (a comparison of one model with itself)."""


def cases() -> list[tuple[str, str, int, float]]:
    """(name, preset, spans, km/h): both study catenaries at 20 and 40 spans over the contract's speeds, and
    the EN 50318:2002 model."""
    out = [
        (f"{preset} {spans} spans {kmh} km/h", preset, spans, kmh)
        for preset in ("benchmark", "stitched")
        for spans in (20, 40)
        for kmh in (200.0, 250.0, 300.0, 350.0)
    ]
    out += [("en50318-2002 20 spans 250 km/h", "en50318-2002", 20, 250.0)]
    return out


def run_case(preset: str, n_spans: int, kmh: float) -> dict:
    """Every span stepped, then each margin, on one prepared design: the differences and the times."""
    catenary = load_catenary(preset)
    pantograph = load_pantograph(catenary.pantograph)
    fidelity = Fidelity(n_spans=n_spans, analysis_spans=n_spans // 2)
    mesh = fidelity.contact_wire_element, fidelity.messenger_wire_element
    layout = build_layout(catenary, level_design(catenary), n_spans, *mesh)
    prepared = span_modes.prepare(linearise(find_shape(layout)), fidelity)
    window = analysis_window(catenary, fidelity)
    passage = Passage.one_pantograph(pantograph, UPLIFT, kmh / 3.6)

    def timed(margin: float | None):  # noqa: ANN202
        start = time.perf_counter()
        trajectory = span_modes.run(prepared, passage, front_margin=margin)
        return trajectory, time.perf_counter() - start

    timed(None)  # the configurations built once, for both
    every, t_every = timed(None)
    base = passage_statistics(every, window)
    row = {"front_speed_kmh": 3.6 * front_speed(catenary), "sigma": base.std, "time_every_span": t_every}
    for margin in MARGINS:
        trajectory, t = timed(margin)
        stats = passage_statistics(trajectory, window)
        row[str(margin)] = {
            "force": float(np.abs(trajectory.contact_force - every.contact_force).max()),
            "sigma": (stats.std - base.std) / base.std,
            "extremes": max(abs(stats.actual_max - base.actual_max), abs(stats.actual_min - base.actual_min))
            / base.mean,
            "time_ratio": t / t_every,
        }
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    args = parser.parse_args()
    results = {name: run_case(preset, n, kmh) for name, preset, n, kmh in cases()}
    if args.json:
        record = {"fingerprint": simulator_fingerprint(), "margins": MARGINS, "chosen": FRONT_MARGIN}
        print(json.dumps({**record, "cases": results}, indent=1))
        return
    print("largest contact-force difference over the passage (N) / σ change / extremes change (of the mean)")
    print("| case | front km/h | σ (N) | " + " | ".join(f"{m:.0f} m" for m in MARGINS) + " |")
    print("|---|---|---|" + "---|" * len(MARGINS))
    for name, row in results.items():
        cells = [_cell(row[str(m)]) for m in MARGINS]
        print(f"| {name} | {row['front_speed_kmh']:.0f} | {row['sigma']:.3f} | " + " | ".join(cells) + " |")
    print(f"\ntime of the passage with a margin of {FRONT_MARGIN:.0f} m / every span stepped:")
    for name, row in results.items():
        ratio = row[str(FRONT_MARGIN)]["time_ratio"]
        print(f"  {name}: {ratio:.3f} ({row['time_every_span']:.3f} s every span)")


def _cell(changes: dict) -> str:
    return f"{changes['force']:.0e} / {changes['sigma']:.0e} / {changes['extremes']:.0e}"


if __name__ == "__main__":
    main()
