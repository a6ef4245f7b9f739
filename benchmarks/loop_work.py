"""Benchmark: the span-mode time loop's work, counted, beside its time (docs/performance.md, 'The stitched
catenary's size, a long section's work, ...').

Each step advances the first spans of the section (those behind the wave front: its ``stepped`` count); for
each, its kept modes go through the modal products of a step (two products with the span's coupled interface
DOFs, one with its droppers: (2 n_c + n_d) m multiply-adds), and its droppers and interface DOFs through the
step's other work. This sums those counts over a passage's steps and times the compiled loop, so that a
ratio of times (a longer section, another catenary) can be set against the ratio of the work that the model
asks for, which no implementation of it does less of.

    python benchmarks/loop_work.py                              # benchmark catenary, 20 and 40 spans
    python benchmarks/loop_work.py --presets benchmark stitched --spans 20
    python benchmarks/loop_work.py --full                       # full passages, not as the studies run them

The level design at 300 km/h and 170 N, one BLAS thread; medians over ``--runs`` passages in one process.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from catenary_env.blas_threads import one_blas_thread
from catenary_env.dynamics.span_modes import passage
from catenary_env.model.design import level_design
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.pipeline import Fidelity, evaluate, simulate

COUNTS = ("multiply-adds", "modes", "droppers", "interface DOFs")


class CountingLoop:
    """The compiled loop, wrapped: each call's time, and the work of the steps it takes."""

    def __init__(self) -> None:
        self.kernel = passage.BACKENDS["numba"]()
        self.reset()

    def reset(self) -> None:
        self.seconds = 0.0
        self.steps = 0
        self.work = dict.fromkeys(COUNTS, 0.0)

    def __call__(self, d, points, state, configuration, stepped, first, stop) -> None:  # noqa: ANN001
        start = time.perf_counter()
        self.kernel(d, points, state, configuration, stepped, first, stop)
        self.seconds += time.perf_counter() - start
        spans = stepped[first:stop]
        kept = d.kept[configuration[first]]
        droppers = np.diff(d.dropper_start)
        per_span = {
            "multiply-adds": (2 * d.n_coupled[d.span_type] + droppers) * kept,
            "modes": kept,
            "droppers": droppers,
        }
        for name, values in per_span.items():
            self.work[name] += float(np.r_[0, np.cumsum(values)][spans].sum())
        self.work["interface DOFs"] += float(d.interface_end[spans - 1].sum())
        self.steps += spans.size


def measure(loop: CountingLoop, preset: str, spans: int, full: bool, runs: int) -> dict:
    """Per span of the section: the loop's seconds (median over ``runs``) and its work (counts)."""
    catenary = load_catenary(preset)
    pantograph = load_pantograph(catenary.pantograph)
    fidelity = Fidelity(n_spans=spans, analysis_spans=spans // 2)
    run = simulate if full else evaluate
    run(catenary, pantograph, level_design(catenary), 300 / 3.6, fidelity, 170.0)  # compiled, warmed
    seconds = []
    for _ in range(runs):
        loop.reset()
        run(catenary, pantograph, level_design(catenary), 300 / 3.6, fidelity, 170.0)
        seconds.append(loop.seconds)
    row = {name: value / spans for name, value in loop.work.items()}
    row.update(steps=loop.steps, seconds=statistics.median(seconds) / spans)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["benchmark"], help="catenary presets (benchmark)")
    parser.add_argument("--spans", nargs="+", type=int, default=[20, 40], help="section lengths (20 40)")
    parser.add_argument("--full", action="store_true", help="full passages (not as the studies run them)")
    parser.add_argument("--runs", type=int, default=5, help="passages timed for each (default 5)")
    args = parser.parse_args()
    loop = CountingLoop()
    passage.BACKENDS["numba"] = lambda: loop
    rows = {}
    with one_blas_thread():
        for preset in args.presets:
            for spans in args.spans:
                rows[preset, spans] = row = measure(loop, preset, spans, args.full, args.runs)
                counts = ", ".join(f"{name} {row[name]:,.0f}" for name in COUNTS)
                print(
                    f"{preset}, {spans} spans, {'full passage' if args.full else 'as the studies run it'}: "
                    f"{row['steps']:,} steps; per span: loop {row['seconds'] * 1e3:.2f} ms; work {counts}"
                )
    base = next(iter(rows))
    for key, row in list(rows.items())[1:]:
        ratios = ", ".join(f"{name} {row[name] / rows[base][name]:.3f}" for name in COUNTS)
        time_ratio = row["seconds"] / rows[base]["seconds"]
        against = f"{key[0]} {key[1]} against {base[0]} {base[1]}"
        print(f"{against}, per span: loop time {time_ratio:.3f}; work {ratios}")


if __name__ == "__main__":
    main()
