"""Benchmark: one full evaluation of a catenary design (SPEC 9).

Shape-finding, linearisation, factorisation (with the unit dropper responses), the pantograph
passage and the statistics of the "benchmark" preset at 300 km/h, Δt = 1 ms, on the study mesh.
Prints the median over several runs of each phase, the real-time factor, the memory peak, and the
time for several section lengths (the cost must grow linearly with the number of spans).

    python benchmarks/bench_evaluation.py               # 20 spans, 5 runs, spans 10/20/40
    python benchmarks/bench_evaluation.py --runs 3 --spans 20 --json

Run it on an otherwise idle core (OPENBLAS_NUM_THREADS=1 is set here): timings on shared
machines are noisy, so quote medians.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402

from catenary_env.design import level_design  # noqa: E402
from catenary_env.dynamics import prepare_passage, simulate_passage  # noqa: E402
from catenary_env.layout import build_layout  # noqa: E402
from catenary_env.linear_system import linearise  # noqa: E402
from catenary_env.presets import load_catenary, load_pantograph  # noqa: E402
from catenary_env.shape_finding import find_shape  # noqa: E402
from catenary_env.simulation import Fidelity, analysis_window  # noqa: E402
from catenary_env.statistics import contact_statistics  # noqa: E402

PHASES = ("shape_finding", "linearisation", "factorisation", "passage", "statistics")


def one_evaluation(preset: str, n_spans: int, speed_kmh: float, uplift: float, fidelity: Fidelity) -> dict[str, float]:
    """Time each phase of one evaluation, s; also returns σ to show the runs agree."""
    catenary = load_catenary(preset)
    pantograph = load_pantograph(catenary.pantograph)
    times: dict[str, float] = {}
    t = time.perf_counter()
    layout = build_layout(catenary, level_design(catenary), n_spans, fidelity.contact_wire_element,
                          fidelity.messenger_wire_element)
    static = find_shape(layout)
    times["shape_finding"] = time.perf_counter() - t
    t = time.perf_counter()
    system = linearise(static)
    times["linearisation"] = time.perf_counter() - t
    t = time.perf_counter()
    prepared = prepare_passage(system, fidelity.time_step)
    times["factorisation"] = time.perf_counter() - t
    t = time.perf_counter()
    trajectory = simulate_passage(system, pantograph, uplift, speed_kmh / 3.6, fidelity.time_step, prepared=prepared)
    times["passage"] = time.perf_counter() - t
    t = time.perf_counter()
    window = analysis_window(catenary, Fidelity(n_spans=n_spans, analysis_spans=max(1, n_spans // 2)))
    stats = contact_statistics(trajectory.position, trajectory.contact_force, fidelity.time_step, window,
                               trajectory.support_x, trajectory.support_uplift)
    times["statistics"] = time.perf_counter() - t
    times["total"] = sum(times[p] for p in PHASES)
    times["simulated_time"] = float(trajectory.time[-1])
    times["n_dofs"] = system.n_dofs
    times["sigma"] = stats.std
    return times


def memory_peak(preset: str, n_spans: int, speed_kmh: float, uplift: float, fidelity: Fidelity) -> float:
    """Peak of memory allocated by Python and numpy during one evaluation, MiB (an untimed run)."""
    tracemalloc.start()
    one_evaluation(preset, n_spans, speed_kmh, uplift, fidelity)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="benchmark", help="catenary preset (default: benchmark)")
    parser.add_argument("--speed", type=float, default=300.0, help="train speed, km/h (default 300)")
    parser.add_argument("--uplift", type=float, default=170.0,
                        help="pantograph uplift force, N (default 170: the EN 50367 mean at 300 km/h)")
    parser.add_argument("--runs", type=int, default=5, help="timed runs per section length (default 5)")
    parser.add_argument("--spans", type=int, nargs="+", default=[10, 20, 40], help="section lengths, spans")
    parser.add_argument("--main-spans", type=int, default=20, help="section of the headline figures (default 20)")
    parser.add_argument("--json", action="store_true", help="print one JSON summary")
    args = parser.parse_args()
    fidelity = Fidelity()  # the study mesh: 0.5 m / 1.0 m elements, 1 ms
    spans = sorted(set(args.spans) | {args.main_spans})

    one_evaluation(args.preset, 3, args.speed, args.uplift, fidelity)  # warm-up (imports, caches)
    results = {}
    for n in spans:
        runs = [one_evaluation(args.preset, n, args.speed, args.uplift, fidelity) for _ in range(args.runs)]
        med = {key: statistics.median(r[key] for r in runs) for key in runs[0]}
        med["min_total"] = min(r["total"] for r in runs)
        med["max_total"] = max(r["total"] for r in runs)
        med["real_time_factor"] = med["total"] / med["simulated_time"]
        results[n] = med
        if not args.json:
            print(f"{n:3d} spans: {med['n_dofs']:.0f} DOFs, median {med['total']:.2f} s "
                  f"(min {med['min_total']:.2f}, max {med['max_total']:.2f}) over {args.runs} runs, "
                  f"real-time factor {med['real_time_factor']:.2f}, σ = {med['sigma']:.3f} N", flush=True)
    main = results[args.main_spans]
    peak = memory_peak(args.preset, args.main_spans, args.speed, args.uplift, fidelity)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    per_span = {n: results[n]["total"] / n for n in spans}
    summary = {
        "preset": args.preset, "speed_kmh": args.speed, "runs": args.runs, "main_spans": args.main_spans,
        "phases_median_s": {p: main[p] for p in PHASES}, "total_median_s": main["total"],
        "real_time_factor": main["real_time_factor"], "simulated_time_s": main["simulated_time"],
        "n_dofs": main["n_dofs"], "memory_peak_traced_mib": peak, "process_max_rss_mib": rss,
        "scaling": {str(n): {"total_median_s": results[n]["total"], "per_span_s": per_span[n]} for n in spans},
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"\n{args.main_spans} spans at {args.speed:g} km/h ({main['simulated_time']:.1f} s simulated), medians:")
        for p in PHASES:
            print(f"  {p:<14} {main[p]:8.3f} s  ({100 * main[p] / main['total']:4.1f} %)")
        print(f"  {'total':<14} {main['total']:8.3f} s, real-time factor {main['real_time_factor']:.2f}")
        print(f"memory: traced peak {peak:.0f} MiB, process max RSS {rss:.0f} MiB")
        print("scaling (time per span, s): " + ", ".join(f"{n}: {per_span[n]:.3f}" for n in spans))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
