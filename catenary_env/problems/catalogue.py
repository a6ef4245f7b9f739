"""The eight design problems (docs/problems.md, 'The eight problems') and their registry.

Examples
--------
>>> from catenary_env.problems import PROBLEMS
>>> list(PROBLEMS)
['BPresag', 'B1', 'B2', 'B3', 'SWPresag', 'SW1', 'SW2', 'SW3']
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence

import numpy as np

from ..errors import UnknownNameError
from ..pipeline import Evaluation, Fidelity
from ..registry import Registry
from ..train import SINGLE, Train
from .design_problem import DesignProblem
from .grid import HEIGHT_STEP, POSITION_STEP

__all__ = ["PROBLEMS", "ProblemRegistry", "evaluate_problem", "get_problem", "register_problem"]


class ProblemRegistry(Registry[DesignProblem]):
    """The design problems by name: a dict that refuses to replace an entry."""

    kind = "design problem"


PROBLEMS = ProblemRegistry()
"""Every design problem by name, in the order of docs/problems.md, 'The eight problems'."""


def register_problem(problem: DesignProblem) -> DesignProblem:
    """Add a problem to :data:`PROBLEMS`; raises ValueError if the name is taken."""
    return PROBLEMS.register(problem)


def get_problem(name: str) -> DesignProblem:
    """The registered problem called ``name``; raises KeyError naming the problems available."""
    if name not in PROBLEMS:
        by_lower = {known.lower(): known for known in PROBLEMS}
        close = difflib.get_close_matches(str(name).lower(), list(by_lower), n=1)
        hint = f" (did you mean {by_lower[close[0]]!r}?)" if close else ""
        raise UnknownNameError(f"unknown design problem {name!r}{hint}; available: {', '.join(PROBLEMS)}")
    return PROBLEMS[name]


def evaluate_problem(
    name: str,
    x: tuple[float, ...],
    speed_kmh: float,
    fidelity: str | Fidelity,
    uplift_force: float | None = None,
    train: Train = SINGLE,
    contact_wire_tension: float | None = None,
) -> Evaluation:
    """:meth:`DesignProblem.evaluate` of a registered problem, as a picklable function for process pools.

    Each worker process calibrates the uplift force once per catenary, speed and fidelity unless
    ``uplift_force`` (N) is given: pass :meth:`DesignProblem.uplift_force` from the parent to spare it.
    ``train``: the pantographs behind the leading one and the objective's (default one pantograph);
    ``contact_wire_tension``: N, the problem on its catenary with that tension (default the preset's).
    """
    problem = get_problem(name).with_contact_wire_tension(contact_wire_tension)
    return problem.evaluate(x, speed_kmh, fidelity, uplift_force=uplift_force, train=train)


# -- the eight problems (docs/problems.md, 'The eight problems') ---------------------------------------


def _problem(
    name: str, catenary: str, n_droppers: int, bounds: Sequence[tuple[str, float, float]], description: str
) -> DesignProblem:
    names = tuple(b[0] for b in bounds)
    return DesignProblem(
        name=name,
        catenary=catenary,
        n_droppers=n_droppers,
        variables=names,
        units=("m",) * len(names),
        lower=np.array([b[1] for b in bounds]),
        upper=np.array([b[2] for b in bounds]),
        step=np.array([POSITION_STEP if v.startswith("d_") else HEIGHT_STEP for v in names]),
        description=description,
    )


def _heights(n: int) -> list[tuple[str, float, float]]:
    return [(f"dh_{i}", -0.02, 0.02) for i in range(1, n + 1)]


_BENCHMARK = "the benchmark simple catenary (55 m spans, 9 droppers in the reference)"
_STITCHED = "the stitched catenary (65 m spans, 7 droppers in the reference)"

for _p in (
    _problem(
        "BPresag",
        "benchmark",
        9,
        [("s", -0.02, 0.10)],
        f"Pre-sag of {_BENCHMARK}: parabolic contact-wire profile, s below the level at mid-span "
        "(negative = raised), on the preset's droppers.",
    ),
    _problem(
        "B1",
        "benchmark",
        9,
        _heights(5),
        f"Contact-wire heights of {_BENCHMARK}: dh_i is the height change at dropper i and its mirror "
        "(dropper 1 at the support side, 5 at mid-span), on the preset's droppers.",
    ),
    _problem(
        "B2",
        "benchmark",
        9,
        [("d_1", 0.1, 7.4), ("d_2", 7.5, 13.1), ("d_3", 13.2, 18.8), ("d_4", 18.9, 27.4)],
        f"Dropper positions of {_BENCHMARK}: d_i is the distance of dropper i (and, mirrored, of its "
        "twin) from the span's first support; the mid-span dropper stays; level contact wire.",
    ),
    _problem(
        "B3",
        "benchmark",
        5,
        [("d_1", 0.1, 13.0), ("d_2", 13.1, 27.4)] + _heights(3),
        f"Five droppers per span instead of nine on {_BENCHMARK}: positions d_1, d_2 (mirrored) and "
        "the mid-span dropper, with height changes dh_1..dh_3 (dh_3 at mid-span).",
    ),
    _problem(
        "SWPresag",
        "stitched",
        7,
        [("s", -0.02, 0.10)],
        f"Pre-sag of {_STITCHED}: parabolic contact-wire profile, s below the level at mid-span "
        "(negative = raised), on the preset's droppers.",
    ),
    _problem(
        "SW1",
        "stitched",
        7,
        _heights(4),
        f"Contact-wire heights of {_STITCHED}: dh_i is the height change at dropper i and its mirror "
        "(dropper 1, on the stitch wire, at the support side; 4 at mid-span).",
    ),
    _problem(
        "SW2",
        "stitched",
        7,
        [("d_1", 0.1, 8.9), ("d_2", 9.1, 20.4), ("d_3", 20.5, 32.4)],
        f"Dropper positions of {_STITCHED}: d_i is the distance of dropper i (and its mirror) from the "
        "span's first support; dropper 1 hangs from the stitch wire; level contact wire.",
    ),
    _problem(
        "SW3",
        "stitched",
        5,
        [("d_1", 2.0, 9.0), ("d_2", 10.0, 30.0)] + _heights(3),
        f"Five droppers per span instead of seven on {_STITCHED}: positions d_1 (on the stitch wire), "
        "d_2 (mirrored) and the mid-span dropper, with height changes dh_1..dh_3 (dh_3 at mid-span).",
    ),
):
    register_problem(_p)
del _p
