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
    python benchmarks/loop_work.py --window 8 12                # what windows of spans would leave to do
    python benchmarks/loop_work.py --window 8 12 --ahead        # ... windows on both sides of the pantograph
    python benchmarks/loop_work.py --horizon 200                # ... a hold behind that waits for causality

With ``--window W``, each row also gives the modal multiply-adds a passage would count if it stepped only the
spans at most W behind the pantograph's (``--ahead``: and at most W ahead of it, among those behind the wave
front): what a window of spans would leave of the work, counted on the same passage (the passage itself is the
model's, the window's numbers are not simulated), and the spans a step advances on average behind and ahead of
the pantograph's (docs/performance.md, 'A window of spans behind the pantograph, counted, made and dropped').
A lower bound on the window's work, and not on its time: the loop's time does not fall in proportion.

With ``--horizon M``, the count of a hold that changes nothing the pantograph meets: a span is left out once
what it sends forward, at the wave front's speed c, could reach the pantograph only after the passage has
ended, with M metres to spare (the spans behind the pantograph's span's start by more than (c - v) times the
passage's time left, plus M; docs/performance.md, 'A hold behind the pantograph that waits for causality').

The level design at 300 km/h and 170 N, one BLAS thread; medians over ``--runs`` passages in one process.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Sequence

import numpy as np

from catenary_env.blas_threads import one_blas_thread
from catenary_env.dynamics.span_modes import passage
from catenary_env.dynamics.span_modes.passage import front_speed
from catenary_env.model.design import level_design
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.pipeline import Fidelity, evaluate, simulate

COUNTS = ("multiply-adds", "modes", "droppers", "interface DOFs")


class CountingLoop:
    """The compiled loop, wrapped: each call's time, and the work of the steps it takes."""

    def __init__(
        self, windows: Sequence[int] = (), ahead: bool = False, horizons: Sequence[float] = ()
    ) -> None:
        self.kernel = passage.BACKENDS["numba"]()
        self.windows = tuple(windows)
        self.ahead = ahead
        self.horizons = tuple(horizons)
        self.passage = (0.0, 0.0, 0.0, 0.0)  # span length (m), speed, front speed (m/s), time step (s)
        self.reset()

    def reset(self) -> None:
        self.seconds = 0.0
        self.steps = 0
        self.work = dict.fromkeys(COUNTS, 0.0)
        self.windowed = dict.fromkeys(self.windows, 0.0)  # multiply-adds left by each window
        self.held = dict.fromkeys(self.horizons, 0.0)  # ... by each causal hold
        self.around = {"behind": 0.0, "ahead": 0.0}  # spans stepped behind and ahead of the pantograph's

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
        cumulative = {name: np.r_[0, np.cumsum(values)] for name, values in per_span.items()}
        for name, summed in cumulative.items():
            self.work[name] += float(summed[spans].sum())
        self.work["interface DOFs"] += float(d.interface_end[spans - 1].sum())
        self.steps += spans.size
        element = points[0].element[first:stop]
        on = element >= 0  # the (first) pantograph on the section
        span, stepped_on = d.element_span[element[on]], spans[on]
        self.around["behind"] += float(span.sum())
        self.around["ahead"] += float((stepped_on - span - 1).sum())
        products = cumulative["multiply-adds"]
        for width in self.windows:
            low = np.clip(span - width, 0, None)
            high = np.minimum(stepped_on, span + width + 1) if self.ahead else stepped_on
            self.windowed[width] += float((products[high] - products[low]).sum())
        span_length, speed, front, time_step = self.passage
        time_left = (points[0].element.size - 1 - np.arange(first, stop)[on]) * time_step
        for margin in self.horizons:  # spans ending this far behind the pantograph's span's start are held
            reach = span * span_length - (front - speed) * time_left - margin
            low = np.minimum(np.floor(reach / span_length).clip(0).astype(np.int64), stepped_on)
            self.held[margin] += float((products[stepped_on] - products[low]).sum())


def measure(loop: CountingLoop, preset: str, spans: int, full: bool, runs: int) -> dict:
    """Per span of the section: the loop's seconds (median over ``runs``) and its work (counts)."""
    catenary = load_catenary(preset)
    pantograph = load_pantograph(catenary.pantograph)
    fidelity = Fidelity(n_spans=spans, analysis_spans=spans // 2)
    speed = 300 / 3.6
    loop.passage = (catenary.span_length, speed, front_speed(catenary), fidelity.time_step)
    run = simulate if full else evaluate
    run(catenary, pantograph, level_design(catenary), speed, fidelity, 170.0)  # compiled, warmed
    seconds = []
    for _ in range(runs):
        loop.reset()
        run(catenary, pantograph, level_design(catenary), speed, fidelity, 170.0)
        seconds.append(loop.seconds)
    row = {name: value / spans for name, value in loop.work.items()}
    row.update({f"window {width}": value / spans for width, value in loop.windowed.items()})
    row.update({f"horizon {margin:g}": value / spans for margin, value in loop.held.items()})
    row.update({f"spans {side}": value / loop.steps for side, value in loop.around.items()})
    row.update(steps=loop.steps, seconds=statistics.median(seconds) / spans)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["benchmark"], help="catenary presets (benchmark)")
    parser.add_argument("--spans", nargs="+", type=int, default=[20, 40], help="section lengths (20 40)")
    parser.add_argument("--full", action="store_true", help="full passages (not as the studies run them)")
    parser.add_argument("--runs", type=int, default=5, help="passages timed for each (default 5)")
    parser.add_argument(
        "--window", nargs="+", type=int, default=[], metavar="W", help="count windows of W spans behind"
    )
    parser.add_argument("--ahead", action="store_true", help="the windows on both sides of the pantograph")
    parser.add_argument(
        "--horizon", nargs="+", type=float, default=[], metavar="M", help="count causal holds, M m to spare"
    )
    args = parser.parse_args()
    if any(width < 0 for width in args.window):
        parser.error(f"--window: spans behind the pantograph's, 0 or more (got {args.window})")
    if any(margin < 0 for margin in args.horizon):
        parser.error(f"--horizon: metres to spare, 0 or more (got {args.horizon})")
    loop = CountingLoop(args.window, args.ahead, args.horizon)
    passage.BACKENDS["numba"] = lambda: loop
    rows = {}
    with one_blas_thread():
        for preset in args.presets:
            for spans in args.spans:
                rows[preset, spans] = row = measure(loop, preset, spans, args.full, args.runs)
                counts = ", ".join(f"{name} {row[name]:,.0f}" for name in COUNTS)
                print(
                    f"{preset}, {spans} spans, {'full passage' if args.full else 'as the studies run it'}: "
                    f"{row['steps']:,} steps; per span: loop {row['seconds'] * 1e3:.2f} ms; work {counts}; "
                    f"a step advances {row['spans behind']:.1f} spans behind the pantograph's and "
                    f"{row['spans ahead']:.1f} ahead"
                )
    names = COUNTS + tuple(f"window {width}" for width in args.window)
    names += tuple(f"horizon {margin:g}" for margin in args.horizon)
    first = next(iter(rows))
    for key, row in list(rows.items())[1:]:
        # a longer section against the same catenary's first, another catenary against the first one's
        base = (key[0], args.spans[0]) if key[1] != args.spans[0] else first
        ratios = ", ".join(f"{name} {row[name] / rows[base][name]:.3f}" for name in names)
        time_ratio = row["seconds"] / rows[base]["seconds"]
        against = f"{key[0]} {key[1]} against {base[0]} {base[1]}"
        print(f"{against}, per span: loop time {time_ratio:.3f}; work {ratios}")


if __name__ == "__main__":
    main()
