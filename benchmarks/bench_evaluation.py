"""Benchmark: one full evaluation of a catenary design (docs/performance.md, 'Benchmark').

Shape-finding, linearisation, preparation (the exact model's factorisation with the unit dropper
responses, or the span-mode model's reduction and Schur complements), the pantograph passage and the
statistics of the "benchmark" preset at 300 km/h, Δt = 1 ms, on the study mesh, for both models in
the same run, alternately (docs/performance.md, 'Model fidelities'). Prints the median over several
runs of each phase, the real-time factor, the ratio of the two models, the memory peak, the time for
several section lengths (their runs in turn, with each run's cost per span against the main section's run
of the same round), full passages and as the studies run them (``evaluate``: the passage stops one span
after the central half it analyses), and the exact passage's compiled (numba) and numpy backends on the same
prepared system, alternately, with the largest difference of their contact forces.

Scaling: a step of the exact model costs in proportion to the DOFs, so its passage grows as the
square of the number of spans; a step of the span-mode model costs in proportion to the spans' kept
modes, most of them the far field's, so its passage also grows faster than the spans.

    python benchmarks/bench_evaluation.py               # 20 spans, 5 runs, spans 10/20/40
    python benchmarks/bench_evaluation.py --runs 3 --spans 20 --json
    python benchmarks/bench_evaluation.py --backend numpy --numpy-runs 0
    python benchmarks/bench_evaluation.py --runs 1 --spans 20 --batch 8   # + a generation's throughput
    python benchmarks/bench_evaluation.py --pantographs 2 --runs 5    # two pantographs 200 m apart vs one
    python benchmarks/bench_evaluation.py --speeds 200 220 240 260 280 300 320   # one design at 7 speeds

Run it on an otherwise idle core (OPENBLAS_NUM_THREADS=1 is set here): timings on shared
machines are noisy, so quote medians and ratios. The first compiled passage in a process loads
numba's cached machine code (or compiles it, some ten seconds, on a new machine or band width):
that is timed apart, as "warm-up".
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402

import numpy as np  # noqa: E402

from catenary_env.analysis.statistics import passage_statistics  # noqa: E402
from catenary_env.dynamics import exact  # noqa: E402
from catenary_env.dynamics.exact import kernel_preparation as preparation  # noqa: E402
from catenary_env.dynamics.linear_system import linearise  # noqa: E402
from catenary_env.dynamics.models import DYNAMIC_MODELS  # noqa: E402
from catenary_env.dynamics.protocol import Passage  # noqa: E402
from catenary_env.fem.layout import build_layout  # noqa: E402
from catenary_env.model.definition import CatenaryDefinition  # noqa: E402
from catenary_env.model.design import level_design, presag_design  # noqa: E402
from catenary_env.model.presets import load_catenary, load_pantograph  # noqa: E402
from catenary_env.pipeline import Fidelity, analysis_window, evaluate, evaluate_speeds_unchecked  # noqa: E402
from catenary_env.statics.equal_spans import find_equal_spans_shape  # noqa: E402
from catenary_env.statics.shape_finding import StaticSolution  # noqa: E402
from catenary_env.train import SINGLE, Train  # noqa: E402

PHASES = ("shape_finding", "linearisation", "preparation", "passage", "statistics")
MODELS = ("span-modes", "exact")


def level_static(catenary: CatenaryDefinition, n_spans: int, fidelity: Fidelity) -> StaticSolution:
    """The level design's static shape on ``fidelity``'s mesh, found as an evaluation finds it."""
    elements = (fidelity.contact_wire_element, fidelity.messenger_wire_element)
    layout = build_layout(catenary, level_design(catenary), n_spans, *elements)
    return find_equal_spans_shape(layout, *elements)


class _Phases:
    """Wall-clock and CPU time (this process's) of each phase, s: on a shared machine the CPU time is
    the steadier of the two (the wall clock adds the time other processes hold the core)."""

    def __init__(self) -> None:
        self.times: dict[str, float] = {}
        self._start = (time.perf_counter(), time.process_time())

    def lap(self, phase: str) -> None:
        now = (time.perf_counter(), time.process_time())
        self.times[phase] = now[0] - self._start[0]
        self.times["cpu_" + phase] = now[1] - self._start[1]
        self._start = now


def one_evaluation(
    preset: str, n_spans: int, speed_kmh: float, uplift: float, fidelity: Fidelity, backend: str
) -> dict[str, float]:
    """Time each phase of one evaluation on ``fidelity.dynamics``' model (wall and CPU), s; also
    returns σ."""
    catenary = load_catenary(preset)
    pantograph = load_pantograph(catenary.pantograph)
    phases = _Phases()
    static = level_static(catenary, n_spans, fidelity)
    phases.lap("shape_finding")
    system = linearise(static)
    phases.lap("linearisation")
    model = DYNAMIC_MODELS[fidelity.dynamics]
    prepared = model.prepare(system, fidelity)
    phases.lap("preparation")
    trajectory = model.run(
        prepared, Passage.one_pantograph(pantograph, uplift, speed_kmh / 3.6, backend=backend)
    )
    phases.lap("passage")
    window = analysis_window(catenary, Fidelity(n_spans=n_spans, analysis_spans=max(1, n_spans // 2)))
    stats = passage_statistics(trajectory, window)
    phases.lap("statistics")
    times = phases.times
    times["total"] = sum(times[p] for p in PHASES)
    times["cpu_total"] = sum(times["cpu_" + p] for p in PHASES)
    times["simulated_time"] = float(trajectory.time[-1])
    times["steps"] = trajectory.time.size
    times["n_dofs"] = system.n_dofs
    times["sigma"] = stats.std
    return times


def study_evaluation(preset: str, n_spans: int, speed_kmh: float, uplift: float, fidelity: Fidelity) -> dict:
    """One evaluation as the design studies run it (:func:`catenary_env.pipeline.evaluate`: the checks,
    and on the span-mode model a passage that stops one span after the analysis section), s."""
    catenary = load_catenary(preset)
    fidelity = dataclasses.replace(fidelity, n_spans=n_spans, analysis_spans=max(1, n_spans // 2))
    phases = _Phases()
    pantograph = load_pantograph(catenary.pantograph)
    evaluation = evaluate(catenary, pantograph, level_design(catenary), speed_kmh / 3.6, fidelity, uplift)
    phases.lap("total")
    return dict(phases.times, sigma=evaluation.statistics.std)


def train_comparison(args: argparse.Namespace) -> dict[str, float]:
    """A study evaluation (:func:`study_evaluation`'s, the span-mode model) with ``--pantographs``
    pantographs ``--spacing`` m apart against one pantograph, alternately: medians, s, and their ratio."""
    catenary = load_catenary(args.preset)
    pantograph = load_pantograph(catenary.pantograph)
    train = Train.behind([pantograph] * (args.pantographs - 1), args.spacing)
    fidelity = dataclasses.replace(
        Fidelity(), n_spans=args.main_spans, analysis_spans=max(1, args.main_spans // 2)
    )
    design, speed = level_design(catenary), args.speed / 3.6
    times: dict[str, list[float]] = {"one": [], "train": []}
    for run in range(args.runs + 1):  # the first of each warms numba's cache up, untimed
        for key, which in (("one", SINGLE), ("train", train)):
            t = time.perf_counter()
            evaluation = evaluate(catenary, pantograph, design, speed, fidelity, args.uplift, train=which)
            if run:
                times[key].append(time.perf_counter() - t)
    one, two = statistics.median(times["one"]), statistics.median(times["train"])
    sigmas = [s.std for s in evaluation.pantograph_statistics]
    if not args.json:
        print(
            f"span-modes {args.main_spans} spans: one pantograph {one:.2f} s, {args.pantographs} pantographs "
            f"{args.spacing:g} m apart {two:.2f} s (medians of {args.runs}): ratio {two / one:.2f}; "
            "σ " + ", ".join(f"{s:.2f}" for s in sigmas) + " N",
            flush=True,
        )
    return {"one_s": one, "train_s": two, "ratio": two / one, "sigmas_n": sigmas}


def speeds_comparison(args: argparse.Namespace) -> dict[str, object]:
    """A study evaluation (:func:`study_evaluation`'s) of the level design at each of ``--speeds``: one
    :func:`~catenary_env.pipeline.evaluate` per speed against one
    :func:`~catenary_env.pipeline.evaluate_speeds_unchecked` for them all (the statics and the preparation
    made once), alternately: medians, s, and their ratio."""
    catenary = load_catenary(args.preset)
    pantograph = load_pantograph(catenary.pantograph)
    fidelity = dataclasses.replace(
        Fidelity(), n_spans=args.main_spans, analysis_spans=max(1, args.main_spans // 2)
    )
    design, speeds = level_design(catenary), [v / 3.6 for v in args.speeds]
    times: dict[str, list[float]] = {"apart": [], "together": []}
    for run in range(args.runs + 1):  # the first of each warms numba's cache up, untimed
        t = time.perf_counter()
        apart = [evaluate(catenary, pantograph, design, v, fidelity, args.uplift) for v in speeds]
        t_apart = time.perf_counter() - t
        t = time.perf_counter()
        together = evaluate_speeds_unchecked(
            catenary, pantograph, design, [(v, args.uplift) for v in speeds], fidelity
        )
        t_together = time.perf_counter() - t
        if run:
            times["apart"].append(t_apart)
            times["together"].append(t_together)
    if len(together) != len(speeds) or [e.statistics for e in apart] != [e.statistics for e in together]:
        raise RuntimeError("the evaluations at several speeds differ from those one speed at a time")
    one, all_ = statistics.median(times["apart"]), statistics.median(times["together"])
    if not args.json:
        print(
            f"span-modes {args.main_spans} spans, the level design at "
            + ", ".join(f"{v:g}" for v in args.speeds)
            + f" km/h: one evaluation per speed {one:.2f} s, all speeds in one {all_:.2f} s (medians of "
            f"{args.runs}): ratio {all_ / one:.2f}; the same statistics",
            flush=True,
        )
    return {"apart_s": one, "together_s": all_, "ratio": all_ / one, "speeds_kmh": list(args.speeds)}


def backend_comparison(
    preset: str, n_spans: int, speed_kmh: float, uplift: float, fidelity: Fidelity, runs: int
) -> dict[str, float]:
    """Passage times of both backends on one prepared system, alternately; medians and their ratio."""
    catenary = load_catenary(preset)
    pantograph = load_pantograph(catenary.pantograph)
    system = linearise(level_static(catenary, n_spans, fidelity))
    prepared = exact.prepare(system, fidelity)
    times: dict[str, list[float]] = {"numba": [], "numpy": []}
    forces = {}
    for _ in range(runs):
        for backend in times:
            t = time.perf_counter()
            passage = Passage.one_pantograph(pantograph, uplift, speed_kmh / 3.6, backend=backend)
            trajectory = exact.run(prepared, passage)
            times[backend].append(time.perf_counter() - t)
            forces[backend] = trajectory.contact_force
    numba, numpy = statistics.median(times["numba"]), statistics.median(times["numpy"])
    return {
        "runs": runs,
        "numba_passage_median_s": numba,
        "numpy_passage_median_s": numpy,
        "numba_over_numpy": numba / numpy,
        "speed_up": numpy / numba,
        "max_contact_force_difference_n": float(np.max(np.abs(forces["numba"] - forces["numpy"]))),
    }


def solve_floor(preset: str, n_spans: int, fidelity: Fidelity, calls: int = 200) -> dict[str, float] | None:
    """The compiled banded solve alone, µs per call (best of several batches), and the passage it implies.

    Every step of the exact method solves the whole section once, so this is a floor under the
    passage's time per step, whatever else the loop does. None without numba.
    """
    try:
        from catenary_env.dynamics.exact import kernels
    except ImportError:
        return None
    system = linearise(level_static(load_catenary(preset), n_spans, fidelity))
    factor = exact.prepare(system, fidelity).factor
    w = preparation.padded_width(factor.bandwidth)
    unit = preparation.unit_factor(factor.factor, w)
    n = factor.factor.shape[1]
    b, sweep = np.zeros(n + w), np.zeros(n + w)
    b[:n] = np.random.default_rng(0).standard_normal(n)
    kernels.solve(*unit, b, sweep, (0,) * w)
    best = np.inf
    for _ in range(10):  # the best batch: the machine's other load only ever adds time
        t = time.perf_counter()
        for _ in range(calls // 10):
            kernels.solve(*unit, b, sweep, (0,) * w)
        best = min(best, (time.perf_counter() - t) / (calls // 10))
    return {"solve_per_step_us": 1e6 * best, "factor_mib": 2 * unit.upper.nbytes / 2**20}


def _evaluate_presag(
    preset: str, presag: float, speed_kmh: float, uplift: float, fidelity: Fidelity
) -> float:
    """σ of one pre-sag design (a process-pool task: module level, so that it pickles)."""
    catenary = load_catenary(preset)
    evaluation = evaluate(
        catenary,
        load_pantograph(catenary.pantograph),
        presag_design(catenary, presag),
        speed_kmh / 3.6,
        fidelity,
        uplift_force=uplift,
    )
    return evaluation.statistics.std if evaluation.statistics is not None else float("nan")


def batch_throughput(
    preset: str, size: int, workers: list[int], speed_kmh: float, uplift: float, fidelity: Fidelity
) -> dict[str, dict[str, float]]:
    """Evaluations per minute of a generation of ``size`` pre-sag designs (0 to 100 mm), per pool size.

    Each pool is started and warmed (imports, numba cache) before the clock starts, as an
    optimiser's pool is; designs are then evaluated one per task, as the optimisers do.
    """
    presags = np.linspace(0.0, 0.1, size)
    out = {}
    for n_workers in workers:
        with ProcessPoolExecutor(n_workers) as pool:
            small = Fidelity(n_spans=3, analysis_spans=1)
            list(
                pool.map(
                    _evaluate_presag,
                    [preset] * n_workers,
                    [0.0] * n_workers,
                    [speed_kmh] * n_workers,
                    [uplift] * n_workers,
                    [small] * n_workers,
                )
            )
            t = time.perf_counter()
            sigmas = list(
                pool.map(
                    _evaluate_presag,
                    [preset] * size,
                    presags,
                    [speed_kmh] * size,
                    [uplift] * size,
                    [fidelity] * size,
                )
            )
            wall = time.perf_counter() - t
        out[str(n_workers)] = {
            "wall_s": wall,
            "evaluations_per_minute": 60.0 * size / wall,
            "per_worker_per_minute": 60.0 * size / wall / n_workers,
            "sigma_first_last": [sigmas[0], sigmas[-1]],
        }
    return out


def memory_peak(
    preset: str, n_spans: int, speed_kmh: float, uplift: float, fidelity: Fidelity, backend: str
) -> float:
    """Peak of memory allocated by Python and numpy during one evaluation, MiB (an untimed run)."""
    tracemalloc.start()
    one_evaluation(preset, n_spans, speed_kmh, uplift, fidelity, backend)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20


def measure_models(
    args: argparse.Namespace, fidelities: dict[str, Fidelity], spans: list[int]
) -> dict[str, dict[int, dict[str, float]]]:
    """Medians of each model's phases per section length; the exact model on the main section (and
    ``--exact-spans``) only. The models and the section lengths run alternately, a run of each in turn, so
    that the machine's drift hits all of them (the cost per span of one length against another's is a
    ratio of runs made minutes apart otherwise)."""
    results: dict[str, dict[int, dict[str, float]]] = {model: {} for model in MODELS}
    models_of = {
        n: MODELS if n in args.exact_spans or n == args.main_spans else ("span-modes",) for n in spans
    }
    runs = {(n, model): [] for n in spans for model in models_of[n]}
    for _ in range(args.runs):
        for n in spans:
            for model in models_of[n]:
                runs[n, model].append(
                    one_evaluation(args.preset, n, args.speed, args.uplift, fidelities[model], args.backend)
                )
    for n in spans:
        for model in models_of[n]:
            med = {key: statistics.median(r[key] for r in runs[n, model]) for key in runs[n, model][0]}
            med["min_total"] = min(r["total"] for r in runs[n, model])
            med["max_total"] = max(r["total"] for r in runs[n, model])
            main_runs = runs.get((args.main_spans, model))
            if main_runs is not None and n != args.main_spans:
                med.update(per_span_ratio(runs[n, model], n, main_runs, args.main_spans))
            med["real_time_factor"] = med["total"] / med["simulated_time"]
            med["passage_per_step_us"] = 1e6 * med["passage"] / (med["steps"] - 1)
            med["cpu_passage_per_step_us"] = 1e6 * med["cpu_passage"] / (med["steps"] - 1)
            med["passage_per_step_dof_ns"] = 1e3 * med["passage_per_step_us"] / med["n_dofs"]
            results[model][n] = med
            if not args.json:
                print(
                    f"{model:<10} {n:3d} spans: {med['n_dofs']:.0f} DOFs, median {med['total']:.2f} s "
                    f"(min {med['min_total']:.2f}, max {med['max_total']:.2f}; CPU {med['cpu_total']:.2f}) "
                    f"over {args.runs} runs, passage {med['passage']:.2f} s "
                    f"({med['passage_per_step_us']:.0f} µs/step; CPU {med['cpu_passage_per_step_us']:.0f}), "
                    "real-time factor "
                    f"{med['real_time_factor']:.2f}, σ = {med['sigma']:.3f} N",
                    flush=True,
                )
    return results


def per_span_ratio(runs: list[dict], n: int, main_runs: list[dict], main_spans: int) -> dict[str, object]:
    """Each run's cost per span at ``n`` spans against the main section's run of the same round: their
    median and range."""
    ratios = [(r["total"] / n) / (m["total"] / main_spans) for r, m in zip(runs, main_runs, strict=True)]
    return {"per_span_ratio": statistics.median(ratios), "per_span_ratio_range": (min(ratios), max(ratios))}


def study_scaling(
    args: argparse.Namespace, study: Fidelity, spans: list[int]
) -> dict[int, dict[str, object]]:
    """:func:`study_evaluation` at each section length, the lengths in turn ``--runs`` times: medians, and
    the cost per span against the main section's run by run."""
    runs: dict[int, list[dict]] = {n: [] for n in spans}
    for _ in range(args.runs):
        for n in spans:
            runs[n].append(study_evaluation(args.preset, n, args.speed, args.uplift, study))
    scaling = {}
    for n in spans:
        scaling[n] = {key: statistics.median(r[key] for r in runs[n]) for key in runs[n][0]}
        if n != args.main_spans:
            scaling[n].update(per_span_ratio(runs[n], n, runs[args.main_spans], args.main_spans))
    return scaling


def print_ratio(n: int, main_spans: int, med: dict) -> None:
    """The cost per span at ``n`` spans against the main section's, run by run (:func:`per_span_ratio`)."""
    low, high = med["per_span_ratio_range"]
    print(
        f"  cost per span at {n} spans / at {main_spans}, run by run: median "
        f"{med['per_span_ratio']:.2f} ({low:.2f}-{high:.2f})"
    )


def print_scaling(results: dict[str, dict[int, dict[str, float]]], main_spans: int) -> None:
    """Each model's total time per span at each section length, and against the main section's, run by run."""
    for model in MODELS:
        print(
            f"scaling, {model} (total per span, s): "
            + ", ".join(f"{n}: {med['total'] / n:.3f}" for n, med in sorted(results[model].items()))
        )
        for n, med in sorted(results[model].items()):
            if "per_span_ratio" in med:
                print_ratio(n, main_spans, med)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="benchmark", help="catenary preset (default: benchmark)")
    parser.add_argument("--speed", type=float, default=300.0, help="train speed, km/h (default 300)")
    parser.add_argument(
        "--uplift",
        type=float,
        default=170.0,
        help="pantograph uplift force, N (default 170: the EN 50367 mean at 300 km/h)",
    )
    parser.add_argument("--runs", type=int, default=5, help="timed runs per section length (default 5)")
    parser.add_argument("--spans", type=int, nargs="+", default=[10, 20, 40], help="section lengths, spans")
    parser.add_argument(
        "--main-spans", type=int, default=20, help="section of the headline figures (default 20)"
    )
    parser.add_argument(
        "--backend", default="auto", choices=("auto", "numba", "numpy"), help="passage backend (default auto)"
    )
    parser.add_argument(
        "--numpy-runs",
        type=int,
        default=1,
        help="passages per backend in the numba / numpy comparison on the main section (default 1; 0: none)",
    )
    parser.add_argument(
        "--batch",
        type=int,
        default=0,
        help="designs in a generation for the batch throughput, on the main section (default 0: none)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        nargs="+",
        default=[1, os.cpu_count() or 1],
        help="process-pool sizes for the batch throughput (default: 1 and the CPU count)",
    )
    parser.add_argument(
        "--exact-spans",
        type=int,
        nargs="*",
        default=[],
        help="section lengths on which the exact model runs too (default: the main section only)",
    )
    parser.add_argument(
        "--pantographs",
        type=int,
        default=1,
        help="with 2 or more: time a study evaluation of that many pantographs against one, alone",
    )
    parser.add_argument("--spacing", type=float, default=200.0, help="pantograph spacing, m (default 200)")
    parser.add_argument(
        "--speeds",
        type=float,
        nargs="+",
        default=[],
        help="with 2 or more, km/h: time a study evaluation at these speeds, together and one by one, alone",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON summary")
    args = parser.parse_args()
    if len(args.speeds) > 1 or args.pantographs > 1:
        comparison = speeds_comparison(args) if len(args.speeds) > 1 else train_comparison(args)
        if args.json:
            print(json.dumps(comparison))
        return 0
    study = Fidelity()  # the study mesh: 0.5 m / 1.0 m elements, 1 ms, the span-mode model
    fidelities = {"span-modes": study, "exact": dataclasses.replace(study, dynamics="exact")}
    fidelity = fidelities["exact"]
    spans = sorted(set(args.spans) | {args.main_spans})

    t = time.perf_counter()
    for f in fidelities.values():  # imports, numba cache
        one_evaluation(args.preset, 3, args.speed, args.uplift, f, args.backend)
    warm_up = time.perf_counter() - t
    results = measure_models(args, fidelities, spans)
    main = results["exact"][args.main_spans]
    reduced = results["span-modes"][args.main_spans]
    comparison = None
    if args.numpy_runs > 0:
        comparison = backend_comparison(
            args.preset, args.main_spans, args.speed, args.uplift, fidelity, args.numpy_runs
        )
    floor = solve_floor(args.preset, args.main_spans, fidelity)
    if floor is not None:
        floor["passage_floor_s"] = floor["solve_per_step_us"] * 1e-6 * (main["steps"] - 1)
    batch = None
    if args.batch > 0:
        batch_fidelity = dataclasses.replace(
            study, n_spans=args.main_spans, analysis_spans=max(1, args.main_spans // 2)
        )
        batch = batch_throughput(
            args.preset, args.batch, sorted(set(args.workers)), args.speed, args.uplift, batch_fidelity
        )
    peak = {
        model: memory_peak(
            args.preset, args.main_spans, args.speed, args.uplift, fidelities[model], args.backend
        )
        for model in MODELS
    }
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    studies = study_scaling(args, study, spans)
    study_run = studies[args.main_spans]

    def figures(med: dict[str, float]) -> dict[str, object]:
        return {
            "phases_median_s": {p: med[p] for p in PHASES},
            "phases_cpu_median_s": {p: med["cpu_" + p] for p in PHASES},
            "total_cpu_median_s": med["cpu_total"],
            "total_median_s": med["total"],
            "total_min_s": med["min_total"],
            "total_max_s": med["max_total"],
            "passage_per_step_us": med["passage_per_step_us"],
            "real_time_factor": med["real_time_factor"],
            "n_dofs": med["n_dofs"],
            "sigma_n": med["sigma"],
        }

    summary = {
        "preset": args.preset,
        "speed_kmh": args.speed,
        "backend": args.backend,
        "runs": args.runs,
        "main_spans": args.main_spans,
        "warm_up_s": warm_up,
        "simulated_time_s": main["simulated_time"],
        "models": {model: figures(results[model][args.main_spans]) for model in MODELS},
        "study_over_exact": reduced["total"] / main["total"],
        "study_over_exact_cpu": reduced["cpu_total"] / main["cpu_total"],
        "study_evaluation": {
            "total_median_s": study_run["total"],
            "total_cpu_median_s": study_run["cpu_total"],
            "scaling": {
                str(n): {
                    "total_median_s": med["total"],
                    "per_span_s": med["total"] / n,
                    "per_span_over_main_section": med.get("per_span_ratio"),
                }
                for n, med in studies.items()
            },
        },
        "memory_peak_traced_mib": peak,
        "process_max_rss_mib": rss,
        "scaling": {
            model: {
                str(n): {
                    "total_median_s": med["total"],
                    "passage_median_s": med["passage"],
                    "per_span_s": med["total"] / n,
                    "passage_per_step_us": med["passage_per_step_us"],
                    "per_span_over_main_section": med.get("per_span_ratio"),
                }
                for n, med in sorted(results[model].items())
            }
            for model in MODELS
        },
        "backends": comparison,
        "solve_floor": floor,
        "batch": batch,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(
        f"\n{args.main_spans} spans at {args.speed:g} km/h ({main['simulated_time']:.1f} s simulated), "
        "medians:"
    )
    print(f"  {'phase':<14} {'span-modes':>10} {'exact':>10}   CPU: {'span-modes':>10} {'exact':>10}")
    for p in (*PHASES, "total"):
        print(
            f"  {p:<14} {reduced[p]:9.3f}s {main[p]:9.3f}s        {reduced['cpu_' + p]:9.3f}s "
            f"{main['cpu_' + p]:9.3f}s"
        )
    print(
        f"span-modes / exact = {reduced['total'] / main['total']:.3f} "
        f"({main['total'] / reduced['total']:.1f}x faster; "
        f"CPU {reduced['cpu_total'] / main['cpu_total']:.3f}); "
        f"real-time factors {reduced['real_time_factor']:.2f} and {main['real_time_factor']:.2f}; "
        f"σ {reduced['sigma']:.3f} N and {main['sigma']:.3f} N"
    )
    print(
        f"span-modes evaluation as the studies run it (evaluate: checks, and the passage stops one span "
        f"after the analysis section): {study_run['total']:.3f} s (CPU {study_run['cpu_total']:.3f} s)"
    )
    print(
        "scaling, span-modes as the studies run it (total per span, s): "
        + ", ".join(f"{n}: {med['total'] / n:.3f}" for n, med in sorted(studies.items()))
    )
    for n, med in sorted(studies.items()):
        if "per_span_ratio" in med:
            print_ratio(n, args.main_spans, med)
    print(f"warm-up (imports, numba cache or compilation, 3 spans): {warm_up:.1f} s")
    print(
        f"memory: traced peak {peak['span-modes']:.0f} MiB (span-modes), {peak['exact']:.0f} MiB (exact); "
        f"process max RSS {rss:.0f} MiB"
    )
    print_scaling(results, args.main_spans)
    if comparison is not None:
        print(
            f"exact passage, {args.main_spans} spans, {comparison['runs']} run(s) each, alternately: "
            f"numba {comparison['numba_passage_median_s']:.2f} s, "
            f"numpy {comparison['numpy_passage_median_s']:.2f} s, "
            f"numba / numpy = {comparison['numba_over_numpy']:.3f} ({comparison['speed_up']:.1f}x), "
            f"max |ΔF| = {comparison['max_contact_force_difference_n']:.1e} N"
        )
    if floor is not None:
        print(
            f"banded solve alone ({floor['factor_mib']:.1f} MiB of factor read per step): "
            f"{floor['solve_per_step_us']:.0f} µs/step at best, "
            f"{floor['passage_floor_s']:.2f} s over the {args.main_spans}-span passage: "
            "the floor of the exact method, which solves the whole section every step"
        )
    for n_workers, b in (batch or {}).items():
        print(
            f"batch of {args.batch} designs, {args.main_spans} spans, {n_workers} worker(s): "
            f"{b['wall_s']:.1f} s, {b['evaluations_per_minute']:.1f} evaluations/min, "
            f"{b['per_worker_per_minute']:.1f} per worker"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
