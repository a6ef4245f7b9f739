"""``catenary tolerance PROBLEM [--x V1 V2 ...]``: a design under installation tolerances (docs/acceptance.md,
'Installation tolerances').

Draws ``--draws`` built sections of the design (seeded: draw k of seed s is the same for every design with
the same droppers, so two designs run with the same seed are compared on the same sections), each with
random, independent deviations of the contact-wire height at every dropper and of every dropper's position,
and prints σ's median and 10th and 90th percentiles, the share of infeasible draws and the EN 50367
acceptance pass rate.

Examples
--------
``catenary tolerance B1 --x 0 0 0 0 -0.005 --height 0.005 --draws 20``: the B1 design under ±5 mm heights
and the default ±5 cm positions, 20 draws.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from ..errors import UsageError
from ..pipeline import FIDELITIES
from ..problems import PROBLEMS
from . import options
from .evaluate import checked_variables, finite_or_null
from .progress import ProgressDisplay

UNITS = {"speed_kmh": "km/h", "tolerances.height, tolerances.position, variables": "m", "sigma_*": "N"}
"""Units of the numbers in ``catenary tolerance --json``."""


def add_parser(subparsers: Any) -> None:
    """Add ``tolerance`` to the sub-commands of ``catenary``."""
    from ..model.tolerances import DISTRIBUTIONS, PRACTICE

    parser = subparsers.add_parser(
        "tolerance",
        help="σ of a design under random installation tolerances: percentiles, infeasible share, pass rate",
        description="Simulate seeded draws of a design of a design problem as built, with random independent "
        "deviations of the contact-wire height at every dropper and of every dropper's position in every "
        "span (docs/acceptance.md, 'Installation tolerances').",
    )
    parser.add_argument("problem", choices=list(PROBLEMS), help="design problem")
    parser.add_argument(
        "--x",
        nargs="+",
        type=float,
        metavar="V",
        help="the problem's variables in order, m (default: the reference design, the level wire)",
    )
    parser.add_argument(
        "--height",
        type=float,
        default=PRACTICE.height,
        metavar="M",
        help=f"contact-wire height tolerance at each dropper, ± m (default {PRACTICE.height:g}, an "
        "assumption: see docs/acceptance.md)",
    )
    parser.add_argument(
        "--position",
        type=float,
        default=PRACTICE.position,
        metavar="M",
        help=f"dropper position tolerance, ± m (default {PRACTICE.position:g}, an assumption)",
    )
    parser.add_argument(
        "--distribution",
        choices=DISTRIBUTIONS,
        default=PRACTICE.distribution,
        help="uniform on ± the tolerance, or normal with σ = tolerance / 2 cut at ± the tolerance",
    )
    parser.add_argument(
        "--draws", type=int, default=20, metavar="N", help="built sections drawn (default 20)"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the draws (default 0)")
    parser.add_argument("--speed", type=float, default=300.0, metavar="KMH", help="train speed, km/h")
    options.add_buildability_argument(parser)
    parser.add_argument(
        "--fidelity",
        choices=list(FIDELITIES),
        default="study",
        help="model size: study (20 spans, the design setting; default), reference (the same on the exact "
        "model) or test (5 coarse spans, for quick checks, not for design conclusions)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of text")


def run(args: argparse.Namespace) -> int:
    """Run the draws and print their summary; 0. Bad options are refused before any solve."""
    from ..model.buildability import buildability_named
    from ..model.definition import DefinitionError
    from ..model.design import check_speed
    from ..model.tolerances import Tolerances

    problem = PROBLEMS[args.problem]
    if args.x is None:
        reference = problem.reference_x()
        if reference is None:
            raise UsageError(f"--x: {problem.name} cannot express its reference design; give the variables")
        x = reference
    else:
        x = checked_variables(problem, list(args.x))
    if not 1 <= args.draws <= 10000:
        raise UsageError(f"--draws {args.draws}: must lie in [1, 10000]")
    if args.seed < 0:
        raise UsageError(f"--seed {args.seed}: must be >= 0")
    try:
        tolerances = Tolerances(args.height, args.position, args.distribution)
    except DefinitionError as error:
        raise UsageError(str(error).replace("tolerances.", "--")) from error
    check_speed(problem.catenary_definition, args.speed / 3.6)
    problem = problem.with_options(buildability=buildability_named(args.buildability))
    display = ProgressDisplay(f"tolerance {problem.name}", args.draws, "draws", quiet=args.json)
    result = problem.evaluate_tolerances(
        x, tolerances, args.draws, args.seed, args.speed, args.fidelity, progress=display.update
    )
    display.finish()
    if args.json:
        record = {
            "problem": problem.name,
            "variables": dict(zip(problem.variables, x.tolist(), strict=True)),
            "speed_kmh": args.speed,
            "fidelity": args.fidelity,
            "buildability": args.buildability,
            **result.as_dict(),
            "units": UNITS,
        }
        print(json.dumps(finite_or_null(record), allow_nan=False))
    else:
        head = (
            f"problem {problem.name} at {args.speed:g} km/h ({args.fidelity} fidelity), "
            f"buildability {args.buildability}"
        )
        print("\n".join([head, *result.text_lines()]))
    return 0
