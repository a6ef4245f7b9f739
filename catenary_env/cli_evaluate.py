"""``catenary evaluate``: simulate one design of a design problem, given in its physical variables.

Examples
--------
``catenary evaluate B1 --x 0 0 0 0 -0.005 --speed 300``: σ of the B1 design with the mid-span
contact wire 5 mm lower, at 300 km/h. ``--json`` prints one JSON object instead of a table.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

import numpy as np

from .model.design import check_speed
from .pipeline import FIDELITIES, Evaluation
from .problems import PROBLEMS, DesignProblem

EXIT_OK = 0
EXIT_USAGE = 2
"""Exit status of a bad command line (as argparse's own errors)."""


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``evaluate`` command to a main parser's subparsers; ``run`` is set as its ``handler``."""
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
        "--fidelity",
        choices=list(FIDELITIES),
        default="study",
        help="model size: study (20 spans, the design setting; default) or test (5 spans, coarse "
        "mesh; for quick checks, not for design conclusions)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Evaluate the design; 0 once printed (feasible or not), 2 for a bad command line."""
    problem = PROBLEMS[args.problem]
    try:  # bad variables or speed are refused before any solve; errors of the solve itself propagate
        x = _checked_variables(problem, list(args.x))
        check_speed(problem.catenary_definition, args.speed / 3.6)
    except ValueError as error:  # DesignError is a ValueError
        print(f"catenary evaluate: error: {error}", file=sys.stderr)
        return EXIT_USAGE
    evaluation = problem.evaluate(x, args.speed, args.fidelity)
    record = _record(problem, x, list(args.x), args.speed, args.fidelity, evaluation)
    if args.json:
        print(json.dumps(_finite_or_null(record), allow_nan=False))
    else:
        print(_table(record))
    return EXIT_OK


def _checked_variables(problem: DesignProblem, values: list[float]) -> np.ndarray:
    if len(values) != problem.n_variables:
        bounds = ", ".join(
            f"{n} in [{lo:g}, {hi:g}] m"
            for n, lo, hi in zip(problem.variables, problem.lower, problem.upper, strict=True)
        )
        raise ValueError(
            f"--x: {problem.name} takes {problem.n_variables} values ({bounds}), got {len(values)}"
        )
    return problem.check_variables(values)


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
        "fidelity": fidelity,
        "variables": dict(zip(problem.variables, x.tolist(), strict=True)),
        "rounded_to_grid": bool(np.any(np.abs(x - np.asarray(given)) > 1e-12)),
        "feasible": evaluation.feasible,
        "reason": evaluation.reason,
        "statistics": statistics,
        "uplift_force": evaluation.uplift_force,
        "dropper_lengths": list(evaluation.dropper_lengths),
        "dropper_forces": list(evaluation.dropper_forces),
        "wall_time": evaluation.wall_time,
        "units": UNITS,
    }


UNITS = {
    "speed_kmh": "km/h",
    "variables, dropper_lengths": "m",
    "uplift_force, dropper_forces": "N",
    "statistics.mean, std, statistical_max, statistical_min, actual_max, actual_min": "N",
    "statistics.std_over_mean": "1",
    "statistics.contact_loss_percent": "%",
    "statistics.max_support_uplift": "m",
    "wall_time": "s",
}
"""Units of the numbers in ``catenary evaluate --json`` (SI; the table shows the support uplift in mm)."""


def _finite_or_null(value: Any) -> Any:
    # JSON has no NaN or infinity: write null, as most JSON readers expect.
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite_or_null(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite_or_null(v) for v in value]
    return value


_ROWS = (
    ("mean", "mean contact force Fm", "N", 1.0),
    ("std", "standard deviation σ", "N", 1.0),
    ("std_over_mean", "σ / Fm", "-", 1.0),
    ("statistical_max", "statistical max Fm + 3σ", "N", 1.0),
    ("statistical_min", "statistical min Fm - 3σ", "N", 1.0),
    ("actual_max", "actual max", "N", 1.0),
    ("actual_min", "actual min", "N", 1.0),
    ("contact_loss_percent", "contact loss", "%", 1.0),
    ("max_support_uplift", "max uplift at a support", "mm", 1000.0),
)


def _table(record: dict[str, Any]) -> str:
    lines = [f"problem {record['problem']} at {record['speed_kmh']:g} km/h ({record['fidelity']} fidelity)"]
    lines += [f"  {name:<8} = {value:.3f} m" for name, value in record["variables"].items()]
    if record["rounded_to_grid"]:
        lines.append("  (variables rounded to the grid: heights 1 mm, positions 1 cm)")
    lines.append(f"feasible: {'yes' if record['feasible'] else 'no: ' + record['reason']}")
    lines.append(f"  {'pantograph uplift force':<26} {record['uplift_force']:10.2f} N")
    statistics = record["statistics"] or {}
    for key, label, unit, scale in _ROWS:
        if key in statistics:
            value = statistics[key] * scale
            text = f"{value:10.3f}" if math.isfinite(value) else f"{value!s:>10}"
            lines.append(f"  {label:<26} {text} {unit}")
    lines.append(f"  {'wall time':<26} {record['wall_time']:10.2f} s")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run ``evaluate`` alone (for testing before it is wired into ``catenary``)."""
    parser = argparse.ArgumentParser(prog="catenary")
    add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return int(args.handler(args))
