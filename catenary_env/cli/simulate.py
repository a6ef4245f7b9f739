"""``catenary simulate PRESET --speed KMH``: one pantograph passage, its contact-force statistics."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from typing import TYPE_CHECKING, Any

from ..analysis.statistics import STATISTICS_UNITS
from ..errors import UsageError
from . import options
from .progress import ProgressDisplay

if TYPE_CHECKING:
    from ..model.definition import CatenaryDefinition, PantographDefinition
    from ..pipeline import Fidelity
    from ..train import Train

UNITS = {
    "speed_kmh": "km/h",
    "uplift_force": "N",
    "analysis_window": "m",
    **STATISTICS_UNITS,
    "wall_time, shape_time, calibration_time, passage_time": "s",
}
"""Units of the numbers in ``catenary simulate --json`` (SI; the text output shows the support uplift in
mm)."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``simulate`` to the sub-commands of ``catenary``."""
    p = sub.add_parser("simulate", help="pantograph passage: contact-force statistics")
    options.add_catenary_argument(p)
    p.add_argument("--speed", type=float, required=True, metavar="KMH", help="train speed, km/h")
    p.add_argument("--pantograph", help="pantograph preset or .toml file (default: the catenary's)")
    p.add_argument(
        "--uplift",
        type=float,
        metavar="FORCE",
        help="static uplift force, N (default: the pantograph's, or calibrated on the level design: once "
        "per catenary, speed and fidelity, then kept in the user's cache folder)",
    )
    p.add_argument(
        "--target-mean",
        type=float,
        metavar="FORCE",
        help="calibrate the uplift so the reference design's mean contact force is this, N "
        "(default: EN 50367, 0.00097 v² + 70 with v in km/h)",
    )
    options.add_train_arguments(p)
    options.add_design_arguments(p)
    options.add_buildability_argument(p)
    options.add_acceptance_argument(p)
    options.add_fidelity_arguments(p)
    options.add_output_arguments(p, "the contact force (N) along the track (m)")


def run(args: argparse.Namespace) -> int:
    """Simulate the passage and print its statistics (text or JSON); 0."""
    from ..model.design import check_design, check_speed, physical_warnings
    from ..pipeline import analysis_window, check_fidelity, check_uplift, run_passage, solve_static

    options.check_plot(args)
    if args.target_mean is not None and not (math.isfinite(args.target_mean) and args.target_mean > 0.0):
        raise UsageError(f"--target-mean {args.target_mean}: must be a mean contact force > 0 N")
    catenary = options.catenary_of(args.preset)
    pantograph = options.pantograph_of(args.pantograph or catenary.pantograph)
    limits = options.acceptance_limits(args)
    pantograph, train = options.train_of(args, pantograph)
    design = options.design(catenary, args)
    fidelity = options.fidelity(catenary, args)
    speed = args.speed / 3.6
    check_speed(catenary, speed)
    check_design(catenary, design)
    check_fidelity(catenary, fidelity)
    train.check(catenary, fidelity.n_spans, analysis_window(catenary, fidelity)[1])
    calibrate = args.uplift is None and pantograph.uplift_force is None
    uplift = None if calibrate else check_uplift(pantograph, args.uplift)
    for warning in physical_warnings(catenary, speed, uplift):
        print(f"catenary simulate: warning: {warning}", file=sys.stderr)
    # The design's own static shape first: a design without one is refused before the calibration.
    start = time.perf_counter()
    with options.static_shape_of(args):
        static = solve_static(catenary, design, fidelity)
    reason = static.infeasibility() or options.buildability_violation_of(static, args)
    if reason:
        raise UsageError(f"{options.design_options(args)}: the design is statically infeasible: {reason}")
    times = {"shape_time": time.perf_counter() - start, "calibration_time": 0.0}
    if calibrate:
        start = time.perf_counter()
        uplift = _calibrated_uplift(catenary, pantograph, args, fidelity)
        times["calibration_time"] = time.perf_counter() - start
    progress = ProgressDisplay("simulate", 1.0, quiet=args.json)
    start = time.perf_counter()
    sim = run_passage(static, pantograph, speed, fidelity, uplift, progress=progress.fraction, train=train)
    progress.finish()
    sim = dataclasses.replace(
        sim, acceptance=options.reassessed(limits, sim.statistics, args.speed, sim.acceptance)
    )
    times["passage_time"] = time.perf_counter() - start
    result = _record(args, catenary, pantograph, fidelity, sim, calibrate, times, train)
    print(json.dumps(result, indent=2) if args.json else _text(result, args, sim))
    if args.plot:
        _figure(sim, catenary.name, args.speed, args.plot)
    return 0


def _calibrated_uplift(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    args: argparse.Namespace,
    fidelity: Fidelity,
) -> float:
    """The uplift force that gives the level design the target mean contact force at the speed, N."""
    from ..calibration_cache import cached_uplift
    from ..model.design import level_design
    from ..pipeline import en50367_mean_force

    target = args.target_mean if args.target_mean is not None else en50367_mean_force(args.speed / 3.6)
    with options.static_shape_of(None):
        return cached_uplift(catenary, pantograph, level_design(catenary), args.speed, fidelity, target)


def _record(
    args: argparse.Namespace,
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    fidelity: Fidelity,
    sim: Any,
    calibrated: bool,
    times: dict[str, float],
    train: Train,
) -> dict[str, Any]:
    """The result as the JSON object of ``--json`` (SI units, :data:`UNITS`); with several pantographs,
    ``statistics`` is the leading one's and ``pantographs`` lists each one's, ``feasible`` covers all."""
    stats = sim.statistics.as_dict()
    record = {
        "preset": catenary.name,
        "pantograph": pantograph.name,
        "speed_kmh": args.speed,
        "uplift_force": sim.uplift_force,
        "uplift_calibrated": calibrated,
        "n_spans": fidelity.n_spans,
        "analysis_window": list(sim.window),
        "statistics": stats,
        "acceptance": sim.acceptance.as_dict() if sim.acceptance is not None else None,
        "feasible": stats["contact_loss_percent"] == 0.0,
        "wall_time": sum(times.values()),
        **times,
        "units": UNITS,
    }
    if train.trailing:
        offsets = (0.0, *(t.offset for t in train.trailing))
        names = (pantograph.name, *(t.pantograph.name for t in train.trailing))
        record["pantographs"] = [
            {"pantograph": name, "offset": offset, "statistics": s.as_dict()}
            for name, offset, s in zip(names, offsets, sim.pantograph_statistics, strict=True)
        ]
        record["feasible"] = all(s.contact_loss_percent == 0.0 for s in sim.pantograph_statistics)
    return record


def _text(result: dict[str, Any], args: argparse.Namespace, sim: Any) -> str:
    """The result as text: the run on one line, then the statistics block."""
    calibrated = result["uplift_calibrated"]
    how = "calibrated" if calibrated else "given" if args.uplift is not None else "the pantograph's"
    calibration = f", calibration {result['calibration_time']:.2f} s" if calibrated else ""
    window = result["analysis_window"]
    head = (
        f"{result['preset']} at {args.speed:g} km/h, uplift {sim.uplift_force:.2f} N ({how}), "
        f"{result['n_spans']} spans, analysis {window[0]:.0f}–{window[1]:.0f} m; {result['wall_time']:.2f} s "
        f"(shape {result['shape_time']:.2f} s{calibration}, passage {result['passage_time']:.2f} s)"
    )
    acceptance = sim.acceptance.text_lines() if sim.acceptance is not None else []
    if "pantographs" not in result:
        return "\n".join([head, *sim.statistics.text_lines(), *acceptance])
    lines = [head]
    for i, (entry, stats) in enumerate(zip(result["pantographs"], sim.pantograph_statistics, strict=True)):
        lines.append(f"pantograph {i + 1} ({entry['pantograph']}, {entry['offset']:g} m behind the first):")
        lines.extend(stats.text_lines())
    return "\n".join([*lines, *acceptance])


def _figure(sim: Any, name: str, speed_kmh: float, path: str) -> None:
    from .. import plots

    plt = plots.pyplot()
    fig, ax = plt.subplots(figsize=(12, 4))
    plots.contact_force(sim, ax)
    ax.set_title(f"{name}, {speed_kmh:g} km/h")
    options.save_figure(fig, path)
