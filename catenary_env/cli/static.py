"""``catenary static PRESET``: shape-finding and static analysis of a catenary design (the dropper lengths
and forces, the wire tensions; with ``--stiffness``, the stiffness profile along the central span)."""

from __future__ import annotations

import argparse
import json
import time
from typing import TYPE_CHECKING, Any

from ..errors import UsageError
from . import options
from .progress import ProgressDisplay

if TYPE_CHECKING:
    from ..analysis.static_analysis import StiffnessProfile
    from ..model.design import Design
    from ..statics.shape_finding import StaticSolution

UNITS = {
    "design.dropper_positions": "m",
    "design.contact_wire_offsets": "m",
    "dropper_lengths": "m",
    "dropper_forces": "N",
    "wire_tension_range": "N",
    "residual": "N",
    "wall_time": "s",
    "stiffness.*.positions": "m",
    "stiffness.*.stiffness": "N/m",
    "stiffness.*.alpha": "1",
}
"""Units of the numbers in ``catenary static --json`` (SI; the text output shows heights in mm)."""

STIFFNESS_FORCES = (100.0, 200.0)
"""Static loads of the stiffness profiles, N."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``static`` to the sub-commands of ``catenary``."""
    p = sub.add_parser("static", help="shape-finding and static analysis of a catenary design")
    options.add_catenary_argument(p)
    options.add_design_arguments(p)
    options.add_buildability_argument(p)
    options.add_fidelity_arguments(p)
    p.add_argument(
        "--stiffness", action="store_true", help="also compute the stiffness profile at 100 N and 200 N"
    )
    p.add_argument(
        "--points",
        type=int,
        default=23,
        metavar="N",
        help="load points along the span for the stiffness, at least 2 (default 23)",
    )
    options.add_output_arguments(p, "the span geometry, heights, stiffness (N/m) and dropper forces (N)")


def run(args: argparse.Namespace) -> int:
    """Find the static shape and print it (text or JSON); 0."""
    from ..analysis.static_analysis import stiffness_profile
    from ..pipeline import solve_static

    options.check_plot(args)
    if args.points < 2:
        raise UsageError(f"--points {args.points}: give at least 2 load points along the span")
    catenary = options.catenary_of(args.preset)
    design = options.design(catenary, args)
    fidelity = options.fidelity(catenary, args)
    start = time.perf_counter()
    with options.static_shape_of(args):
        static = solve_static(catenary, design, fidelity)
    elapsed = time.perf_counter() - start
    profiles = []
    if args.stiffness or args.plot:
        progress = ProgressDisplay("stiffness", len(STIFFNESS_FORCES), "profiles", quiet=args.json)
        for force in STIFFNESS_FORCES:
            profiles.append(stiffness_profile(static, force, args.points))
            progress.update(len(profiles))
        progress.finish()
    reason = static.infeasibility() or options.buildability_violation_of(static, args)
    result = _record(catenary.name, design, static, profiles, elapsed, reason)
    print(json.dumps(result, indent=2) if args.json else _text(result, design, profiles))
    if args.plot:
        _figure(catenary.name, static, profiles, args.plot)
    return 0


def _record(
    name: str,
    design: Design,
    static: StaticSolution,
    profiles: list[StiffnessProfile],
    elapsed: float,
    reason: str,
) -> dict[str, Any]:
    """The result as the JSON object of ``--json`` (SI units, :data:`UNITS`)."""
    lay = static.layout
    central = lay.dropper_span == lay.n_spans // 2
    result = {
        "preset": name,
        "design": {
            "dropper_positions": list(design.dropper_positions),
            "contact_wire_offsets": list(design.contact_wire_offsets),
        },
        "n_spans": lay.n_spans,
        "feasible": not reason,
        "reason": reason,
        "dropper_lengths": static.dropper_lengths[central].tolist(),
        "dropper_forces": static.dropper_forces[central].tolist(),
        "wire_tension_range": {
            wire: [float(t.min()), float(t.max())] for wire, t in static.wire_tensions.items()
        },
        "residual": static.residual_history[-1],
        "newton_iterations": len(static.residual_history) - 1,
        "start_spans": static.start_spans,
        "wall_time": elapsed,
        "units": UNITS,
    }
    if profiles:
        result["stiffness"] = {
            f"{p.force:.0f}N": {"positions": p.positions.tolist(), "stiffness": p.stiffness.tolist(),
                                "alpha": p.variability}
            for p in profiles
        }  # fmt: skip
    return result


def _text(result: dict[str, Any], design: Design, profiles: list[StiffnessProfile]) -> str:
    """The result as text: feasibility, wire tensions, the droppers of the central span, the stiffness."""
    short = result["start_spans"]
    start = f"{short} spans solved first, then " if short else ""
    lines = [
        f"{result['preset']}: {result['n_spans']} spans, shape found in {result['wall_time']:.2f} s "
        f"({start}{result['newton_iterations']} Newton iterations, residual {result['residual']:.1e} N)",
        "feasible" if result["feasible"] else f"INFEASIBLE: {result['reason']}",
    ]
    for wire, (low, high) in result["wire_tension_range"].items():
        lines.append(f"{wire.replace('_', ' ')} axial force: {low:.0f} to {high:.0f} N")
    lines.append(f"{'dropper':>8} {'x (m)':>8} {'Δh (mm)':>8} {'length (m)':>11} {'force (N)':>10}")
    droppers = zip(
        design.dropper_positions,
        design.contact_wire_offsets,
        result["dropper_lengths"],
        result["dropper_forces"],
        strict=True,
    )
    for i, (x, dh, length, force) in enumerate(droppers):
        lines.append(f"{i + 1:>8} {x:>8.2f} {1e3 * dh:>8.1f} {length:>11.4f} {force:>10.2f}")
    for p in profiles:
        lines.append(
            f"stiffness at {p.force:.0f} N: {p.stiffness.min():.0f} to {p.stiffness.max():.0f} N/m, "
            f"α = {p.variability:.3f}"
        )
    return "\n".join(lines)


def _figure(name: str, static: StaticSolution, profiles: list[StiffnessProfile], path: str) -> None:
    from .. import plots

    plt = plots.pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 7))
    plots.span_geometry(static, axes[0, 0])
    plots.contact_wire_height(static, axes[0, 1])
    plots.stiffness(profiles, axes[1, 0])
    plots.dropper_forces(static, axes[1, 1])
    fig.suptitle(f"{name}: static analysis of the central span")
    options.save_figure(fig, path)
