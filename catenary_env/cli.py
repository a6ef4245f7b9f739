"""The command line of catenary-env, ``catenary`` (README.md, 'Command line').

    catenary static PRESET [--presag S | --offsets ...] [--json] [--plot FILE]
    catenary simulate PRESET --speed KMH [...] [--json] [--plot FILE]
    catenary validate [--json]
    catenary evaluate PROBLEM --x V1 V2 ... [--speed KMH] [--json]
    catenary optimize PROBLEM --optimizer NAME --budget N --seed S [...]
    catenary propose POLICY --speed KMH [--evaluate]
    catenary experiment NAME [--full]
    catenary report
    catenary presets [--copy NAME DEST]

Bad input exits with status 2 and a message naming the field and its range, before any solve.

The simulator's own commands import the simulator only when they run, and the commands of the packages
above (optimize, propose, experiment, report) are loaded only when one of them is asked for, so that
``catenary presets`` or ``catenary --help`` starts at once.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import shutil
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from .cli_errors import EXIT_USAGE, UsageError, check_output_path, interruption, print_error, raise_on_sigterm
from .model.definition import CatenaryDefinition, DefinitionError, PantographDefinition
from .model.presets import catenary_names, load_catenary, load_pantograph, pantograph_names, preset_path

if TYPE_CHECKING:
    from .model.design import Design
    from .pipeline import Fidelity

FIDELITY_NAMES = ("reference", "study", "test")
"""The names of :data:`~catenary_env.pipeline.FIDELITIES` (kept here so that building the parser imports
no simulator; tests/test_cli.py checks that they agree)."""


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
        choices=FIDELITY_NAMES,
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
    from .model.design import Design, level_design, presag_design

    positions = tuple(args.droppers) if args.droppers else None
    if args.presag is not None and args.offsets is not None:
        raise DefinitionError("give --presag or --offsets, not both")
    if args.presag is not None:
        return presag_design(catenary, args.presag, positions)
    if args.offsets is not None:
        return Design(positions or catenary.dropper_positions, tuple(args.offsets))
    return level_design(catenary, positions)


def _fidelity(catenary: CatenaryDefinition, args: argparse.Namespace) -> Fidelity:
    from .pipeline import FIDELITIES, Fidelity

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


def _load_catenary(name: str) -> CatenaryDefinition:
    """The catenary preset or file; a pantograph file given in its place is named as such."""
    hint = "is a pantograph file, not a catenary; give a catenary here, and this one with --pantograph"
    return _load(load_catenary, load_pantograph, name, "", hint)


def _load_pantograph(name: str) -> PantographDefinition:
    """The pantograph preset or file; a catenary file given in its place is named as such."""
    hint = "is a catenary file, not a pantograph; give it as the PRESET argument, and a pantograph here"
    return _load(load_pantograph, load_catenary, name, "--pantograph ", hint)


def _load(
    load: Callable[[str], Any], other: Callable[[str], object], name: str, option: str, hint: str
) -> Any:
    try:
        return load(name)
    except DefinitionError as error:
        if _loads(other, name):
            raise UsageError(f"{option}{name}: {hint}") from error
        raise


def _loads(load: Callable[[str], object], name: str) -> bool:
    """Whether ``name`` is a file that ``load`` reads (only files: every pantograph preset name is also
    a catenary preset name)."""
    if not Path(name).is_file():
        return False
    try:
        load(name)
    except (DefinitionError, OSError, ValueError):
        return False
    return True


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
    from .statics.shape_finding import ShapeFindingError

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


STATIC_UNITS = {
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

SIMULATE_UNITS = {
    "speed_kmh": "km/h",
    "uplift_force": "N",
    "analysis_window": "m",
    "statistics.mean, std, statistical_max, statistical_min, actual_max, actual_min": "N",
    "statistics.std_over_mean": "1",
    "statistics.contact_loss_percent": "%",
    "statistics.max_support_uplift": "m",
    "wall_time, shape_time, calibration_time, passage_time": "s",
}
"""Units of the numbers in ``catenary simulate --json`` (SI; the text output shows the support uplift in
mm)."""


def cmd_static(args: argparse.Namespace) -> int:
    from .analysis.static_analysis import stiffness_profile
    from .pipeline import solve_static

    _check_outputs(args)
    if args.points < 2:
        raise UsageError(f"--points {args.points}: give at least 2 load points along the span")
    catenary = _load_catenary(args.preset)
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
        "units": STATIC_UNITS,
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
    from .model.design import check_design, check_speed, level_design, physical_warnings
    from .pipeline import check_fidelity, check_uplift, en50367_mean_force, run_passage, solve_static

    _check_outputs(args)
    if args.target_mean is not None and not (math.isfinite(args.target_mean) and args.target_mean > 0.0):
        raise UsageError(f"--target-mean {args.target_mean}: must be a mean contact force > 0 N")
    catenary = _load_catenary(args.preset)
    pantograph = _load_pantograph(args.pantograph or catenary.pantograph)
    design = _design(catenary, args)
    fidelity = _fidelity(catenary, args)
    speed = args.speed / 3.6
    check_speed(catenary, speed)
    check_design(catenary, design)
    check_fidelity(catenary, fidelity)
    calibrate = args.uplift is None and pantograph.uplift_force is None
    uplift = None if calibrate else check_uplift(pantograph, args.uplift)
    for warning in physical_warnings(catenary, speed, uplift):
        print(f"catenary simulate: warning: {warning}", file=sys.stderr)
    # The design's own static shape first: a design without one is refused before the calibration.
    start = time.perf_counter()
    with _static_shape_of(args):
        static = solve_static(catenary, design, fidelity)
    reason = static.infeasibility()
    if reason:
        raise UsageError(f"{_design_options(args)}: the design is statically infeasible: {reason}")
    shape_time = time.perf_counter() - start
    calibration_time = 0.0
    if calibrate:
        from .problems.calibration_cache import cached_uplift

        target = args.target_mean if args.target_mean is not None else en50367_mean_force(speed)
        start = time.perf_counter()
        with _static_shape_of(None):
            uplift = cached_uplift(catenary, pantograph, level_design(catenary), args.speed, fidelity, target)
        calibration_time = time.perf_counter() - start
    progress = Progress("simulate", args.json)
    start = time.perf_counter()
    sim = run_passage(static, pantograph, speed, fidelity, uplift, progress=progress)
    passage_time = time.perf_counter() - start
    elapsed = shape_time + calibration_time + passage_time
    stats = sim.statistics.as_dict()
    result = {
        "preset": catenary.name,
        "pantograph": pantograph.name,
        "speed_kmh": args.speed,
        "uplift_force": sim.uplift_force,
        "uplift_calibrated": calibrate,
        "n_spans": fidelity.n_spans,
        "analysis_window": list(sim.window),
        "statistics": stats,
        "feasible": stats["contact_loss_percent"] == 0.0,
        "wall_time": elapsed,
        "shape_time": shape_time,
        "calibration_time": calibration_time,
        "passage_time": passage_time,
        "units": SIMULATE_UNITS,
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        how = "calibrated" if calibrate else "given" if args.uplift is not None else "the pantograph's"
        calibration = f", calibration {calibration_time:.2f} s" if calibrate else ""
        print(
            f"{catenary.name} at {args.speed:g} km/h, uplift {sim.uplift_force:.2f} N ({how}), "
            f"{fidelity.n_spans} spans, analysis {sim.window[0]:.0f}–{sim.window[1]:.0f} m; "
            f"{elapsed:.2f} s (shape {shape_time:.2f} s{calibration}, passage {passage_time:.2f} s)"
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
                    "units": {
                        "speed_kmh": "km/h",
                        "uplift_force": "N",
                        "rows.value, low, high, margin": "N; m for max_support_uplift; % for "
                        "contact_loss_percent",
                    },
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
    """The commands of the ``catenary_env.commands`` entry points.

    One that fails to load stays a command, whose run says why (the real error, and the module that shadows
    the package where one does), so that a broken or shadowed package never makes a command vanish.
    """
    import importlib.metadata

    handlers: dict[str, Handler] = {}
    for entry in sorted(importlib.metadata.entry_points(group=COMMANDS_GROUP), key=lambda e: e.name):
        try:
            add_commands = entry.load()
        except Exception as error:  # a broken plug-in must not take the simulator's commands down
            unavailable = _Unavailable(entry.name, _load_failure(entry.value, error), error)
            sub.add_parser(entry.name, help=f"unavailable: run it for the reason ({type(error).__name__})")
            handlers[entry.name] = unavailable
            continue
        handlers.update(add_commands(sub))
    return handlers


@dataclasses.dataclass(frozen=True)
class _Unavailable:
    """The handler of a plug-in command that failed to load: it reports why (``--debug``: the traceback)."""

    name: str
    reason: str
    error: BaseException

    def __call__(self, args: argparse.Namespace) -> int:
        if getattr(args, "debug", False):
            raise self.error
        return print_error(
            self.name, UsageError(f"the '{self.name}' command could not be loaded: {self.reason}")
        )


def _load_failure(target: str, error: BaseException) -> str:
    """Why the entry point ``target`` (``module:function``) failed, and where its package came from."""
    reason = f"{target} raised {type(error).__name__}: {error}"
    import importlib.util

    package = target.partition(":")[0].partition(".")[0]
    try:
        spec = importlib.util.find_spec(package)
    except (ImportError, ValueError):
        spec = None
    if spec is None:
        return f"{reason}; no package '{package}' is installed (pip install catenary-env)"
    origin = spec.origin or next(iter(spec.submodule_search_locations or []), None)
    home = Path(__file__).resolve().parents[1]
    if origin is not None and home not in Path(origin).resolve().parents:
        return (
            f"{reason}; '{package}' is imported from {origin}, not from this project ({home}): a module of "
            "that name shadows it; rename that module or run from another folder"
        )
    return reason


def _optional_commands(sub: argparse._SubParsersAction) -> dict[str, Handler]:
    """Commands at the package's edges: ``evaluate`` (the design problems) and the plug-ins' commands."""
    from . import cli_evaluate

    cli_evaluate.add_parser(sub)
    return {"evaluate": cli_evaluate.run, **_plugin_commands(sub)}


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, like the commands' own (cli_errors.py)."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see: {self.prog} --help)\n")


def _add_static(sub: argparse._SubParsersAction) -> None:
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
    p.add_argument("--json", action="store_true", help="print one JSON object (for scripts; SI units)")
    p.add_argument(
        "--plot",
        metavar="FILE",
        help="save the span geometry, heights, stiffness and dropper forces (PNG/SVG)",
    )


def _add_simulate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="pantograph passage: contact-force statistics")
    p.add_argument("preset", help=f"catenary preset ({', '.join(catenary_names())}) or a .toml file")
    p.add_argument("--speed", type=float, required=True, help="train speed, km/h")
    p.add_argument("--pantograph", help="pantograph preset or .toml file (default: the catenary's)")
    p.add_argument(
        "--uplift",
        type=float,
        help="static uplift force, N (default: the pantograph's, or calibrated on the level design: once "
        "per catenary, speed and fidelity, then kept in the user's cache folder)",
    )
    p.add_argument(
        "--target-mean",
        type=float,
        help="calibrate the uplift so the reference design's mean contact force is this, N "
        "(default: EN 50367, 0.00097 v² + 70 with v in km/h)",
    )
    _design_arguments(p)
    _fidelity_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object (for scripts; SI units)")
    p.add_argument("--plot", metavar="FILE", help="save the contact force along the track (PNG/SVG)")


def _add_validate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("validate", help="EN 50318:2002 validation table (value, accepted range, pass/fail)")
    p.add_argument(
        "--speeds", type=float, nargs="+", default=[250.0, 300.0], help="speeds, km/h (250 and 300)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object (for scripts; SI units)")


def _add_presets(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("presets", help="list the presets, or copy one to edit")
    p.add_argument(
        "--copy", nargs=2, metavar=("NAME", "DEST"), help="copy a catenary preset's TOML file to DEST"
    )
    p.add_argument("--pantograph", action="store_true", help="with --copy: copy the pantograph preset NAME")
    p.add_argument("--force", action="store_true", help="with --copy: overwrite DEST if it exists")


CORE_COMMANDS: dict[str, tuple[Callable[[argparse._SubParsersAction], None], Handler]] = {
    "static": (_add_static, cmd_static),
    "simulate": (_add_simulate, cmd_simulate),
    "validate": (_add_validate, cmd_validate),
    "presets": (_add_presets, cmd_presets),
}
"""The simulator's own commands: how each adds its parser, and its handler."""


def build_parser(command: str | None = None) -> tuple[argparse.ArgumentParser, dict[str, Handler]]:
    """The ``catenary`` parser and the handler of each command.

    Parameters
    ----------
    command : str, optional
        The command about to run. One of the simulator's own (:data:`CORE_COMMANDS`) builds that command
        alone and loads no plug-in, for a quick start; otherwise every command is built.
    """
    parser = _Parser(
        prog="catenary",
        description="The command line of catenary-env (README.md, 'Command line'): a railway overhead-line "
        "(catenary) simulator, its design problems and optimisers.",
    )
    parser.add_argument(
        "--debug", action="store_true", help="show the traceback of an error instead of its one-line message"
    )
    sub = parser.add_subparsers(dest="command", required=True)
    handlers: dict[str, Handler] = {}
    for name, (add, handler) in CORE_COMMANDS.items():
        if command in CORE_COMMANDS and name != command:
            continue
        add(sub)
        handlers[name] = handler
    if command not in CORE_COMMANDS:
        handlers.update(_optional_commands(sub))
    return parser, handlers


def _command_of(argv: Sequence[str]) -> str | None:
    """The command named in ``argv`` (its first word that is not an option), or None."""
    return next((word for word in argv if not word.startswith("-")), None)


def _user_errors() -> tuple[type[BaseException], ...]:
    """Failures the user causes (a file, a field, an option value, a path): one line and exit status 2.

    A design without a static shape is one (``ShapeFindingError``, looked up only where shape-finding was
    imported: elsewhere none can have been raised)."""
    errors: list[type[BaseException]] = [DefinitionError, ValueError, KeyError, OSError]
    shape_finding = sys.modules.get("catenary_env.statics.shape_finding")
    if shape_finding is not None:
        errors.append(shape_finding.ShapeFindingError)
    return tuple(errors)


def _warning_printer(command: str) -> Callable[..., None]:
    """Show a warning (an unreadable cache, say) on one line, like the commands' own warnings."""

    def show(message: Warning | str, *args: Any, **kwargs: Any) -> None:
        print(f"catenary {command}: warning: {message}", file=sys.stderr)

    return show


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's final flush finds no closed pipe."""
    import os

    with contextlib.suppress(OSError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def main(argv: Sequence[str] | None = None) -> int:
    words = list(sys.argv[1:] if argv is None else argv)
    parser, handlers = build_parser(_command_of(words))
    args, unknown = parser.parse_known_args(words)
    handler = handlers[args.command]
    if unknown and not isinstance(handler, _Unavailable):
        parser.error(f"unrecognized arguments: {' '.join(unknown)}")
    raise_on_sigterm()
    with warnings.catch_warnings():
        warnings.showwarning = _warning_printer(args.command)
        try:
            return handler(args)
        except BrokenPipeError:  # the reader went away (``catenary ... | head``): nothing left to say
            _silence_stdout()
            return 0
        except _user_errors() as error:
            if args.debug:
                raise
            return print_error(args.command, error)
        except KeyboardInterrupt as error:
            how, status = interruption(error)
            print(f"\ncatenary {args.command}: {how}", file=sys.stderr)
            return status


if __name__ == "__main__":
    sys.exit(main())
