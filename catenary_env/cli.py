"""The ``catenary`` command line (README.md, 'Command line').

    catenary static PRESET [--presag S | --offsets ...] [--json] [--plot FILE]
    catenary simulate PRESET --speed KMH [...] [--json] [--plot FILE]
    catenary validate [--json]
    catenary evaluate PROBLEM --x V1 V2 ... [--speed KMH] [--json]
    catenary optimize PROBLEM --optimizer NAME --budget N --seed S [...]
    catenary experiment NAME [--full]
    catenary report
    catenary presets [--copy NAME DEST]

Bad input exits with status 2 and a message naming the field and its range, before any solve.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import importlib.metadata
import json
import math
import shutil
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import NoReturn

from .cli_errors import EXIT_USAGE, UsageError, check_output_path, interruption, print_error, raise_on_sigterm
from .model.definition import CatenaryDefinition, DefinitionError
from .model.design import (
    Design,
    check_design,
    check_speed,
    level_design,
    physical_warnings,
    presag_design,
)
from .model.presets import catenary_names, load_catenary, load_pantograph, pantograph_names, preset_path
from .pipeline import (
    FIDELITIES,
    Fidelity,
    calibrate_uplift,
    check_fidelity,
    en50367_mean_force,
    simulate,
    solve_static,
)
from .statics.shape_finding import ShapeFindingError


class Progress:
    """A one-line progress bar on stderr, silent when stderr is not a terminal or when quiet."""

    def __init__(self, label: str, quiet: bool = False) -> None:
        self.label = label
        self.enabled = not quiet and sys.stderr.isatty()
        self.start = time.perf_counter()

    def __call__(self, fraction: float, note: str = "") -> None:
        if not self.enabled:
            return
        width = 30
        filled = int(round(width * fraction))
        elapsed = time.perf_counter() - self.start
        sys.stderr.write(
            f"\r{self.label} [{'#' * filled}{'.' * (width - filled)}] {100 * fraction:5.1f} % "
            f"{elapsed:6.1f} s {note}"
        )
        if fraction >= 1.0:
            sys.stderr.write("\n")
        sys.stderr.flush()


def _design_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("design (default: level contact wire on the preset's droppers)")
    group.add_argument(
        "--presag",
        type=float,
        metavar="S",
        help="parabolic pre-sag of the contact wire at mid-span, m (positive = lower)",
    )
    group.add_argument(
        "--offsets",
        type=float,
        nargs="+",
        metavar="DH",
        help="contact-wire height change at every dropper of a span, m (negative = lower), "
        "symmetric about mid-span",
    )
    group.add_argument(
        "--droppers",
        type=float,
        nargs="+",
        metavar="X",
        help="dropper positions in a span, m from its first support (default: the preset's)",
    )


def _fidelity_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("model size and resolution")
    group.add_argument(
        "--fidelity",
        choices=sorted(FIDELITIES),
        default=None,
        help="'study': 20 spans, 0.5 m contact-wire elements, 1 ms step, the span-mode (reduced) dynamics; "
        "'reference': the same on the exact dynamics; 'test': 5 spans, coarse, exact "
        "(default: the preset's own number of spans with the study mesh and the span-mode dynamics)",
    )
    group.add_argument("--spans", type=int, metavar="N", help="number of spans in the section (overrides)")
    group.add_argument("--analysis-spans", type=int, metavar="N", help="central spans analysed (overrides)")
    group.add_argument(
        "--element", type=float, metavar="M", help="largest contact-wire element, m (overrides)"
    )
    group.add_argument("--time-step", type=float, metavar="S", help="Newmark time step, s (overrides)")


def _design(catenary: CatenaryDefinition, args: argparse.Namespace) -> Design:
    positions = tuple(args.droppers) if args.droppers else None
    if args.presag is not None and args.offsets is not None:
        raise DefinitionError("give --presag or --offsets, not both")
    if args.presag is not None:
        return presag_design(catenary, args.presag, positions)
    if args.offsets is not None:
        return Design(positions or catenary.dropper_positions, tuple(args.offsets))
    return level_design(catenary, positions)


def _fidelity(catenary: CatenaryDefinition, args: argparse.Namespace) -> Fidelity:
    if args.fidelity is not None:
        base = FIDELITIES[args.fidelity]
    else:
        base = Fidelity(n_spans=catenary.n_spans, analysis_spans=catenary.analysis_spans)
    element = base.contact_wire_element if args.element is None else args.element
    return dataclasses.replace(
        base,
        n_spans=base.n_spans if args.spans is None else args.spans,
        analysis_spans=base.analysis_spans if args.analysis_spans is None else args.analysis_spans,
        contact_wire_element=element,
        messenger_wire_element=2.0 * element,
        time_step=base.time_step if args.time_step is None else args.time_step,
    )


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse an output file that cannot be written before computing anything."""
    if args.plot:
        check_output_path(args.plot, "--plot")


def _design_options(args: argparse.Namespace | None) -> str:
    """The options that chose the design, as typed (for a message)."""
    if args is None:
        return "the level reference design (used to calibrate the uplift)"
    parts = []
    if args.presag is not None:
        parts.append(f"--presag {args.presag:g}")
    if args.offsets is not None:
        parts.append("--offsets " + " ".join(f"{v:g}" for v in args.offsets))
    if args.droppers is not None:
        parts.append("--droppers " + " ".join(f"{v:g}" for v in args.droppers))
    return " ".join(parts) or f"the level design of {args.preset}"


@contextlib.contextmanager
def _static_shape_of(args: argparse.Namespace | None) -> Iterator[None]:
    """Name the design options when the catenary finds no static shape for them."""
    try:
        yield
    except ShapeFindingError as error:
        raise UsageError(
            f"{_design_options(args)}: the catenary finds no static equilibrium for this design ({error}); "
            "give a smaller pre-sag or smaller offsets (a few centimetres)"
        ) from error


def _save(fig, path: str) -> None:  # noqa: ANN001
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"saved {path}", file=sys.stderr)


def cmd_static(args: argparse.Namespace) -> int:
    from .analysis.static_analysis import stiffness_profile

    _check_outputs(args)
    if args.points < 2:
        raise UsageError(f"--points {args.points}: give at least 2 load points along the span")
    catenary = load_catenary(args.preset)
    design = _design(catenary, args)
    fidelity = _fidelity(catenary, args)
    start = time.perf_counter()
    with _static_shape_of(args):
        static = solve_static(catenary, design, fidelity)
    elapsed = time.perf_counter() - start
    lay = static.layout
    central = lay.dropper_span == lay.n_spans // 2
    result = {
        "preset": catenary.name,
        "design": {
            "dropper_positions": list(design.dropper_positions),
            "contact_wire_offsets": list(design.contact_wire_offsets),
        },
        "n_spans": lay.n_spans,
        "feasible": not static.infeasibility(),
        "reason": static.infeasibility(),
        "dropper_lengths": static.dropper_lengths[central].tolist(),
        "dropper_forces": static.dropper_forces[central].tolist(),
        "wire_tension_range": {
            wire: [float(t.min()), float(t.max())] for wire, t in static.wire_tensions.items()
        },
        "residual": static.residual_history[-1],
        "newton_iterations": len(static.residual_history) - 1,
        "wall_time": elapsed,
    }
    profiles = []
    if args.stiffness or args.plot:
        progress = Progress("stiffness", args.json)
        for i, force in enumerate((100.0, 200.0)):
            profiles.append(stiffness_profile(static, force, args.points))
            progress((i + 1) / 2)
        result["stiffness"] = {
            f"{p.force:.0f}N": {
                "positions": p.positions.tolist(),
                "stiffness": p.stiffness.tolist(),
                "alpha": p.variability,
            }
            for p in profiles
        }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(
            f"{catenary.name}: {lay.n_spans} spans, shape found in {elapsed:.2f} s "
            f"({result['newton_iterations']} Newton iterations, residual {result['residual']:.1e} N)"
        )
        print("feasible" if result["feasible"] else f"INFEASIBLE: {result['reason']}")
        for wire, (low, high) in result["wire_tension_range"].items():
            print(f"{wire.replace('_', ' ')} axial force: {low:.0f} to {high:.0f} N")
        print(f"{'dropper':>8} {'x (m)':>8} {'Δh (mm)':>8} {'length (m)':>11} {'force (N)':>10}")
        for i, (x, dh, length, force) in enumerate(
            zip(
                design.dropper_positions,
                design.contact_wire_offsets,
                result["dropper_lengths"],
                result["dropper_forces"],
                strict=True,
            )
        ):
            print(f"{i + 1:>8} {x:>8.2f} {1e3 * dh:>8.1f} {length:>11.4f} {force:>10.2f}")
        for p in profiles:
            print(
                f"stiffness at {p.force:.0f} N: {p.stiffness.min():.0f} to {p.stiffness.max():.0f} N/m, "
                f"α = {p.variability:.3f}"
            )
    if args.plot:
        from . import plots

        plt = plots.pyplot()
        fig, axes = plt.subplots(2, 2, figsize=(11, 7))
        plots.span_geometry(static, axes[0, 0])
        plots.contact_wire_height(static, axes[0, 1])
        plots.stiffness(profiles, axes[1, 0])
        plots.dropper_forces(static, axes[1, 1])
        fig.suptitle(f"{catenary.name}: static analysis of the central span")
        _save(fig, args.plot)
    return 0


def cmd_simulate(args: argparse.Namespace) -> int:
    _check_outputs(args)
    if args.target_mean is not None and not (math.isfinite(args.target_mean) and args.target_mean > 0.0):
        raise UsageError(f"--target-mean {args.target_mean}: must be a mean contact force > 0 N")
    catenary = load_catenary(args.preset)
    pantograph = load_pantograph(args.pantograph or catenary.pantograph)
    design = _design(catenary, args)
    fidelity = _fidelity(catenary, args)
    speed = args.speed / 3.6
    check_speed(catenary, speed)
    check_design(catenary, design)
    check_fidelity(catenary, fidelity)
    uplift = args.uplift
    for warning in physical_warnings(
        catenary, speed, uplift if uplift is not None else pantograph.uplift_force
    ):
        print(f"catenary simulate: warning: {warning}", file=sys.stderr)
    if uplift is None and pantograph.uplift_force is None:
        target = args.target_mean if args.target_mean is not None else en50367_mean_force(speed)
        print(
            f"calibrating the uplift force for a mean contact force of {target:.1f} N on the level reference "
            "design...",
            file=sys.stderr,
        )
        with _static_shape_of(None):
            uplift = calibrate_uplift(catenary, pantograph, level_design(catenary), speed, fidelity, target)
    progress = Progress("simulate", args.json)
    start = time.perf_counter()
    with _static_shape_of(args):
        sim = simulate(catenary, pantograph, design, speed, fidelity, uplift, progress=progress)
    elapsed = time.perf_counter() - start
    stats = sim.statistics.as_dict()
    result = {
        "preset": catenary.name,
        "pantograph": pantograph.name,
        "speed_kmh": args.speed,
        "uplift_force": sim.uplift_force,
        "n_spans": fidelity.n_spans,
        "analysis_window": list(sim.window),
        "statistics": stats,
        "feasible": stats["contact_loss_percent"] == 0.0,
        "wall_time": elapsed,
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(
            f"{catenary.name} at {args.speed:g} km/h, uplift {sim.uplift_force:.2f} N, "
            f"{fidelity.n_spans} spans, "
            f"analysis {sim.window[0]:.0f}–{sim.window[1]:.0f} m, {elapsed:.2f} s"
        )
        units = {
            "max_support_uplift": ("mm", 1e3),
            "contact_loss_percent": ("%", 1.0),
            "std_over_mean": ("", 1.0),
        }
        for key, value in stats.items():
            unit, scale = units.get(key, ("N", 1.0))
            print(f"  {key:<22} {scale * value:10.3f} {unit}")
    if args.plot:
        from . import plots

        plt = plots.pyplot()
        fig, ax = plt.subplots(figsize=(12, 4))
        plots.contact_force(sim, ax)
        ax.set_title(f"{catenary.name}, {args.speed:g} km/h")
        _save(fig, args.plot)
    return 0


def cmd_validate(args: argparse.Namespace) -> int:
    from .validation import validate

    report = validate(tuple(args.speeds))
    if args.json:
        print(
            json.dumps(
                {
                    "passed": report.passed,
                    "uplift_force": report.uplift_force,
                    "rows": [
                        {
                            "speed_kmh": r.speed_kmh,
                            "quantity": r.quantity,
                            "value": r.value,
                            "low": r.low,
                            "high": r.high,
                            "passed": r.passed,
                            "margin": r.margin,
                        }
                        for r in report.rows
                    ],
                },
                indent=2,
            )
        )
    else:
        print(format_validation(report))
    return 0 if report.passed else 1


def format_validation(report) -> str:  # noqa: ANN001
    """The EN 50318:2002 table as Markdown."""
    lines = ["| speed (km/h) | quantity | value | accepted range | result |", "|---|---|---|---|---|"]
    for r in report.rows:
        scale, unit = (
            (1e3, "mm")
            if r.quantity == "max_support_uplift"
            else (1.0, "%" if "percent" in r.quantity else "N")
        )
        verdict = "pass" if r.passed else f"FAIL (by {scale * r.margin:.2f} {unit})"
        lines.append(
            f"| {r.speed_kmh:g} | {r.quantity} | {scale * r.value:.2f} {unit} | "
            f"{scale * r.low:g} – {scale * r.high:g} | {verdict} |"
        )
    return "\n".join(lines)


def cmd_presets(args: argparse.Namespace) -> int:
    if args.copy:
        name, dest = args.copy
        kind = "pantograph" if args.pantograph else "catenary"
        names = pantograph_names() if args.pantograph else catenary_names()
        if name not in names:
            other = "" if args.pantograph else " (for a pantograph preset add --pantograph)"
            raise UsageError(f"--copy {name}: unknown {kind} preset; available: {', '.join(names)}{other}")
        check_output_path(dest, "--copy")
        if Path(dest).exists() and not args.force:
            raise UsageError(f"--copy {name} {dest}: the file exists; add --force to overwrite it")
        shutil.copyfile(preset_path(kind, name), dest)
        print(f"copied the {kind} preset '{name}' to {dest}: edit it and pass the path instead of the name")
        return 0
    if args.pantograph or args.force:
        raise UsageError("--pantograph and --force go with --copy NAME DEST")
    print("catenaries: " + ", ".join(catenary_names()))
    print("pantographs: " + ", ".join(pantograph_names()))
    return 0


COMMANDS_GROUP = "catenary_env.commands"
"""Entry-point group of the packages that add sub-commands to ``catenary`` (``optimize``, ``experiment``).

An entry point names a function ``add_commands(subparsers) -> {command: handler}``; the packages built
on the simulator plug in this way, so the simulator never imports them."""

Handler = Callable[[argparse.Namespace], int]


def _plugin_commands(sub: argparse._SubParsersAction) -> dict[str, Handler]:
    """The commands of the ``catenary_env.commands`` entry points; one that fails to load says so."""
    handlers: dict[str, Handler] = {}
    for entry in sorted(importlib.metadata.entry_points(group=COMMANDS_GROUP), key=lambda e: e.name):
        try:
            add_commands = entry.load()
        except Exception as error:  # a broken plug-in must not take the simulator's commands down
            print(
                f"catenary: the '{entry.name}' commands are unavailable: {entry.value} failed to load "
                f"({type(error).__name__}: {error})",
                file=sys.stderr,
            )
            continue
        handlers.update(add_commands(sub))
    return handlers


def _optional_commands(sub: argparse._SubParsersAction) -> dict[str, Handler]:
    """Commands at the package's edges: ``evaluate`` (the design problems) and the plug-ins' commands."""
    from . import cli_evaluate

    cli_evaluate.add_parser(sub)
    return {"evaluate": cli_evaluate.run, **_plugin_commands(sub)}


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, like the commands' own (cli_errors.py)."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see: {self.prog} --help)\n")


def build_parser() -> tuple[argparse.ArgumentParser, dict[str, Callable[[argparse.Namespace], int]]]:
    parser = _Parser(
        prog="catenary",
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--debug", action="store_true", help="show the traceback of an error instead of its one-line message"
    )
    sub = parser.add_subparsers(dest="command", required=True)
    handlers: dict[str, Callable[[argparse.Namespace], int]] = {}

    p = sub.add_parser("static", help="shape-finding and static analysis of a catenary design")
    p.add_argument("preset", help=f"catenary preset ({', '.join(catenary_names())}) or a .toml file")
    _design_arguments(p)
    _fidelity_arguments(p)
    p.add_argument(
        "--stiffness", action="store_true", help="also compute the stiffness profile at 100 N and 200 N"
    )
    p.add_argument(
        "--points", type=int, default=23, help="load points along the span for the stiffness (default 23)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object (for scripts)")
    p.add_argument(
        "--plot",
        metavar="FILE",
        help="save the span geometry, heights, stiffness and dropper forces (PNG/SVG)",
    )
    handlers["static"] = cmd_static

    p = sub.add_parser("simulate", help="pantograph passage: contact-force statistics")
    p.add_argument("preset", help=f"catenary preset ({', '.join(catenary_names())}) or a .toml file")
    p.add_argument("--speed", type=float, required=True, help="train speed, km/h")
    p.add_argument("--pantograph", help="pantograph preset or .toml file (default: the catenary's)")
    p.add_argument(
        "--uplift", type=float, help="static uplift force, N (default: the pantograph's, or calibrated)"
    )
    p.add_argument(
        "--target-mean",
        type=float,
        help="calibrate the uplift so the reference design's mean contact force is this, N "
        "(default: EN 50367, 0.00097 v² + 70 with v in km/h)",
    )
    _design_arguments(p)
    _fidelity_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object (for scripts)")
    p.add_argument("--plot", metavar="FILE", help="save the contact force along the track (PNG/SVG)")
    handlers["simulate"] = cmd_simulate

    p = sub.add_parser("validate", help="EN 50318:2002 validation table (value, accepted range, pass/fail)")
    p.add_argument(
        "--speeds", type=float, nargs="+", default=[250.0, 300.0], help="speeds, km/h (250 and 300)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object (for scripts)")
    handlers["validate"] = cmd_validate

    p = sub.add_parser("presets", help="list the presets, or copy one to edit")
    p.add_argument(
        "--copy", nargs=2, metavar=("NAME", "DEST"), help="copy a catenary preset's TOML file to DEST"
    )
    p.add_argument("--pantograph", action="store_true", help="with --copy: copy the pantograph preset NAME")
    p.add_argument("--force", action="store_true", help="with --copy: overwrite DEST if it exists")
    handlers["presets"] = cmd_presets

    handlers.update(_optional_commands(sub))
    return parser, handlers


USER_ERRORS = (DefinitionError, ShapeFindingError, ValueError, KeyError, OSError)
"""Failures the user causes (a file, a field, an option value, a path): one line and exit status 2."""


def main(argv: Sequence[str] | None = None) -> int:
    parser, handlers = build_parser()
    args = parser.parse_args(argv)
    raise_on_sigterm()
    try:
        return handlers[args.command](args)
    except USER_ERRORS as error:
        if args.debug:
            raise
        return print_error(args.command, error)
    except KeyboardInterrupt as error:
        how, status = interruption(error)
        print(f"\ncatenary {args.command}: {how}", file=sys.stderr)
        return status


if __name__ == "__main__":
    sys.exit(main())
