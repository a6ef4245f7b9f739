"""``catenary evaluate PROBLEM --x V1 V2 ...``: simulate one design of a design problem, given in its physical
variables.

Examples
--------
``catenary evaluate B1 --x 0 0 0 0 -0.005 --speed 300``: σ of the B1 design with the mid-span
contact wire 5 mm lower, at 300 km/h. ``--json`` prints one JSON object instead of a table.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from typing import Any

import numpy as np

from ..analysis.statistics import STATISTICS_UNITS
from ..errors import UsageError
from ..model.design import check_speed
from ..pipeline import FIDELITIES, Evaluation
from ..problems import PROBLEMS, DesignProblem
from . import options


def add_parser(subparsers: Any) -> None:
    """Add ``evaluate`` to the sub-commands of ``catenary``."""
    table = "; ".join(f"{name}: {' '.join(p.variables)}" for name, p in PROBLEMS.items())
    parser = subparsers.add_parser(
        "evaluate",
        help="simulate one design of a design problem and print its contact-force statistics",
        description="Simulate one design of a design problem (docs/problems.md) at one speed and print its "
        "feasibility and contact-force statistics. The pantograph's uplift force is set on the problem's "
        "reference design so that its mean contact force meets EN 50367 at the speed.",
        epilog=f"Variables, in order: {table}.",
    )
    parser.add_argument("problem", choices=list(PROBLEMS), help="design problem")
    parser.add_argument(
        "--x",
        nargs="+",
        type=float,
        required=True,
        metavar="V",
        help="the problem's variables in order, m (heights on a 1 mm grid, positions on 1 cm; "
        "off-grid values are rounded)",
    )
    parser.add_argument(
        "--speed", type=float, default=300.0, metavar="KMH", help="train speed, km/h (default 300)"
    )
    parser.add_argument(
        "--contact-wire-tension",
        type=float,
        default=None,
        metavar="N",
        help="the contact wire's tension, N, within 70-130 %% of the preset's (default: the preset's); the "
        "preset's uplift force at the speed (docs/problems.md, 'Contact-wire tension')",
    )
    parser.add_argument(
        "--fidelity",
        choices=list(FIDELITIES),
        default="study",
        help="model size: study (20 spans, the design setting; default) or test (5 spans, coarse "
        "mesh; for quick checks, not for design conclusions)",
    )
    options.add_buildability_argument(parser)
    options.add_acceptance_argument(parser)
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")


def run(args: argparse.Namespace) -> int:
    """Evaluate the design and print it (feasible or not); 0. Bad variables or speed are refused before any
    solve."""
    from ..model.buildability import buildability_named

    problem = PROBLEMS[args.problem].with_options(buildability=buildability_named(args.buildability))
    problem = problem.with_contact_wire_tension(args.contact_wire_tension)  # out of range: refused here
    x = checked_variables(problem, list(args.x))
    check_speed(problem.catenary_definition, args.speed / 3.6)
    limits = options.acceptance_limits(args)  # a bad file is refused before any solve
    evaluation = problem.evaluate(x, args.speed, args.fidelity)
    acceptance = options.reassessed(limits, evaluation.statistics, args.speed, evaluation.acceptance)
    evaluation = dataclasses.replace(evaluation, acceptance=acceptance)
    record = _record(problem, x, list(args.x), args.speed, args.fidelity, evaluation)
    if args.json:
        print(json.dumps(finite_or_null(record), allow_nan=False))
    else:
        print(_table(record, evaluation))
    return 0


def checked_variables(problem: DesignProblem, values: list[float]) -> np.ndarray:
    bounds = ", ".join(
        f"{n} in [{lo:g}, {hi:g}] m"
        for n, lo, hi in zip(problem.variables, problem.lower, problem.upper, strict=True)
    )
    if len(values) != problem.n_variables:
        raise UsageError(
            f"--x: {problem.name} takes {problem.n_variables} values ({bounds}), got {len(values)}"
        )
    try:
        return problem.check_variables(values)
    except ValueError as error:  # the problem's own check of the values just given
        raise UsageError(f"--x: {error}") from error


def _record(
    problem: DesignProblem,
    x: np.ndarray,
    given: list[float],
    speed: float,
    fidelity: str,
    evaluation: Evaluation,
) -> dict[str, Any]:
    statistics = evaluation.statistics.as_dict() if evaluation.statistics is not None else None
    return {
        "problem": problem.name,
        "speed_kmh": speed,
        "contact_wire_tension": problem.catenary_definition.contact_wire.tension,
        "fidelity": fidelity,
        "variables": dict(zip(problem.variables, x.tolist(), strict=True)),
        "rounded_to_grid": bool(np.any(np.abs(x - np.asarray(given)) > 1e-12)),
        "feasible": evaluation.feasible,
        "reason": evaluation.reason,
        "statistics": statistics,
        "acceptance": evaluation.acceptance.as_dict() if evaluation.acceptance is not None else None,
        "uplift_force": evaluation.uplift_force,
        "dropper_lengths": list(evaluation.dropper_lengths),
        "dropper_forces": list(evaluation.dropper_forces),
        "wall_time": evaluation.wall_time,
        "units": UNITS,
    }


UNITS = {
    "speed_kmh": "km/h",
    "variables, dropper_lengths": "m",
    "contact_wire_tension, uplift_force, dropper_forces": "N",
    **STATISTICS_UNITS,
    "wall_time": "s",
}
"""Units of the numbers in ``catenary evaluate --json`` (SI; the table shows the support uplift in mm)."""


def finite_or_null(value: Any) -> Any:
    # JSON has no NaN or infinity: write null, as most JSON readers expect.
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: finite_or_null(v) for k, v in value.items()}
    if isinstance(value, list):
        return [finite_or_null(v) for v in value]
    return value


def _table(record: dict[str, Any], evaluation: Evaluation) -> str:
    statistics = evaluation.statistics
    where = f"{record['speed_kmh']:g} km/h, contact wire at {record['contact_wire_tension'] / 1000:g} kN"
    lines = [f"problem {record['problem']} at {where} ({record['fidelity']} fidelity)"]
    lines += [f"  {name:<8} = {value:.3f} m" for name, value in record["variables"].items()]
    if record["rounded_to_grid"]:
        lines.append("  (variables rounded to the grid: heights 1 mm, positions 1 cm)")
    lines.append(f"feasible: {'yes' if record['feasible'] else 'no: ' + record['reason']}")
    lines.append(f"  {'pantograph uplift force':<26} {record['uplift_force']:10.2f} N")
    if statistics is not None:
        lines += statistics.text_lines()
    if evaluation.acceptance is not None:
        lines += evaluation.acceptance.text_lines()
    lines.append(f"  {'wall time':<26} {record['wall_time']:10.2f} s")
    return "\n".join(lines)
