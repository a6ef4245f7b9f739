"""Options that several commands share: the catenary and pantograph, the design, the model size, the
output files (``catenary static``, ``catenary simulate``)."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import sys
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import UsageError
from ..model.definition import CatenaryDefinition, DefinitionError, PantographDefinition
from ..model.presets import catenary_names, load_catenary, load_pantograph
from .paths import check_output_path

if TYPE_CHECKING:
    from ..model.design import Design
    from ..pipeline import Fidelity
    from ..train import Train

FIDELITY_NAMES = ("reference", "study", "test")
"""The names of :data:`~catenary_env.pipeline.FIDELITIES` (kept here so that building the parser imports
no simulator; tests/test_cli.py checks that they agree)."""


def add_catenary_argument(parser: argparse.ArgumentParser) -> None:
    """The catenary, a preset name or a file (the first argument)."""
    parser.add_argument("preset", help=f"catenary preset ({', '.join(catenary_names())}) or a .toml file")


def add_design_arguments(parser: argparse.ArgumentParser) -> None:
    """The design options; :func:`design` reads them."""
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


def add_fidelity_arguments(parser: argparse.ArgumentParser) -> None:
    """The model size options; :func:`fidelity` reads them."""
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


def add_output_arguments(parser: argparse.ArgumentParser, plot: str) -> None:
    """``--json`` and ``--plot FILE`` (``plot``: what the figure shows)."""
    parser.add_argument("--json", action="store_true", help="print one JSON object (for scripts; SI units)")
    parser.add_argument("--plot", metavar="FILE", help=f"save {plot} (PNG/SVG)")


def design(catenary: CatenaryDefinition, args: argparse.Namespace) -> Design:
    """The design the options give."""
    from ..model.design import Design, level_design, presag_design

    positions = tuple(args.droppers) if args.droppers else None
    if args.presag is not None and args.offsets is not None:
        raise UsageError("give --presag or --offsets, not both")
    if args.presag is not None:
        return presag_design(catenary, args.presag, positions)
    if args.offsets is not None:
        return Design(positions or catenary.dropper_positions, tuple(args.offsets))
    return level_design(catenary, positions)


def fidelity(catenary: CatenaryDefinition, args: argparse.Namespace) -> Fidelity:
    """The model size the options give."""
    from ..pipeline import FIDELITIES, Fidelity

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


def catenary_of(name: str) -> CatenaryDefinition:
    """The catenary preset or file; a pantograph file given in its place is named as such. A field outside
    its usual range is warned about (docs/model.md, 'Plausible ranges')."""
    hint = "is a pantograph file, not a catenary; give a catenary here, and this one with --pantograph"
    return _warn_unusual(_load(load_catenary, load_pantograph, name, "", hint))


def pantograph_of(name: str) -> PantographDefinition:
    """The pantograph preset or file; a catenary file given in its place is named as such."""
    hint = "is a catenary file, not a pantograph; give it as the PRESET argument, and a pantograph here"
    return _warn_unusual(_load(load_pantograph, load_catenary, name, "--pantograph ", hint))


def _warn_unusual(definition: Any) -> Any:
    from ..model.plausibility import definition_warnings

    kind = "catenary" if isinstance(definition, CatenaryDefinition) else "pantograph"
    for message in definition_warnings(f"{kind} '{definition.name}'", definition):
        warnings.warn(message, stacklevel=2)
    return definition


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
    except DefinitionError:
        return False
    return True


def check_plot(args: argparse.Namespace) -> None:
    """Refuse a ``--plot`` file that cannot be written before computing anything."""
    if args.plot:
        check_output_path(args.plot, "--plot")


def design_options(args: argparse.Namespace | None) -> str:
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
def static_shape_of(args: argparse.Namespace | None) -> Iterator[None]:
    """Name the real cause when the catenary finds no static shape: the design options where some were given,
    the catenary's own data where none was (its level wire has no equilibrium)."""
    from ..statics.shape_finding import ShapeFindingError

    try:
        yield
    except ShapeFindingError as error:
        given = args is not None and any(
            getattr(args, name, None) is not None for name in ("presag", "offsets", "droppers")
        )
        advice = (
            "give a smaller pre-sag or smaller offsets (a few centimetres)"
            if given
            else "no design option was given, so the catenary's own data are the cause: check the wires' "
            "tensions and masses, the system height and the span length against docs/model.md, "
            "'Plausible ranges'"
        )
        raise UsageError(
            f"{design_options(args)}: the catenary finds no static equilibrium for this design ({error}); "
            f"{advice}"
        ) from error


def add_buildability_argument(parser: argparse.ArgumentParser) -> None:
    """``--buildability {none,default}``: limits checked with the static verdict (docs/acceptance.md)."""
    parser.add_argument(
        "--buildability",
        choices=("none", "default"),
        default="none",
        help="buildability limits checked with the static verdict (docs/acceptance.md): none (default, the "
        "reference study's setting) or the documented defaults (dropper force >= 30 N, length >= 0.5 m, "
        "spacing <= 11 m)",
    )


def add_acceptance_argument(parser: argparse.ArgumentParser) -> None:
    """``--acceptance FILE``: acceptance limits of the acceptance block (docs/acceptance.md)."""
    parser.add_argument(
        "--acceptance",
        metavar="FILE",
        help="acceptance limits: a preset name or an edited copy of it (.toml; default en50367-ac, the "
        "EN 50367 criteria for AC lines; docs/acceptance.md)",
    )


def acceptance_limits(args: argparse.Namespace) -> Any:
    """The ``--acceptance`` limits, loaded and checked (before any solve), or None for the default."""
    from ..model.presets import load_acceptance

    name = getattr(args, "acceptance", None)
    return None if name is None else load_acceptance(name)


def reassessed(limits: Any, statistics: Any, speed_kmh: float, default: Any) -> Any:
    """The acceptance block of ``statistics`` under ``limits``; ``default`` (the pipeline's) without them."""
    from ..analysis.acceptance import assess

    return default if limits is None or statistics is None else assess(statistics, speed_kmh, limits)


def buildability_violation_of(static: Any, args: argparse.Namespace) -> str:
    """The static state's violation of the ``--buildability`` limits, or an empty string."""
    from ..analysis.buildability import buildability_violation
    from ..model.buildability import buildability_named

    return buildability_violation(static, buildability_named(getattr(args, "buildability", "none")))


def save_figure(fig: Any, path: str) -> None:
    """Write a figure to the ``--plot`` file (checked before the computation)."""
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"saved {path}", file=sys.stderr)


def add_train_arguments(parser: argparse.ArgumentParser, objective: bool = False) -> None:
    """``--pantographs`` and ``--spacing`` (and, for a design objective, ``--pantograph-objective``):
    pantographs behind the leading one (docs/model.md, 'Several pantographs')."""
    parser.add_argument(
        "--pantographs",
        metavar="NAME,NAME",
        help="the train's pantographs, leading one first (presets or .toml files, e.g. benchmark,benchmark); "
        "each trailing one has the leading one's uplift force (default: one pantograph, --pantograph)",
    )
    parser.add_argument(
        "--spacing",
        type=float,
        default=200.0,
        metavar="M",
        help="distance between successive pantographs, m (default 200)",
    )
    if objective:
        parser.add_argument(
            "--pantograph-objective",
            default="leading",
            metavar="WHOSE",
            help="whose σ the objective is with several pantographs: leading, trailing, worst (the larger) "
            "or mean (default leading)",
        )


def train_of(
    args: argparse.Namespace, pantograph: PantographDefinition
) -> tuple[PantographDefinition, Train]:
    """The leading pantograph (``pantograph`` unless ``--pantographs`` names one) and the train behind it."""
    from ..train import SINGLE, Train  # numpy: not at the command line's start

    if not getattr(args, "pantographs", None):
        return pantograph, SINGLE
    names = [name.strip() for name in args.pantographs.split(",")]
    if not all(names):
        raise UsageError(
            f"--pantographs {args.pantographs}: names separated by commas, e.g. benchmark,benchmark"
        )
    objective = getattr(args, "pantograph_objective", "leading")
    pantographs = [pantograph_of(name) for name in names]
    return pantographs[0], Train.behind(pantographs[1:], args.spacing, objective)
