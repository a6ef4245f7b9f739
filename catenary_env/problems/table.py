"""The problem table of docs/problems.md ('The eight problems'), written from the problems themselves.

The table is printed in one place, docs/problems.md; tests/test_problems.py checks that it equals
:func:`problem_table` of the registered problems, so the bounds the docs show are the ones the code uses.

Examples
--------
>>> from catenary_env.problems import PROBLEMS
>>> print(problem_table([PROBLEMS["B1"], PROBLEMS["SW1"]]))
| problem | catenary | droppers / span | variables | bounds (m) | grid points |
|---|---|---|---|---|---|
| B1 | benchmark (55 m spans) | 9 | dh_1 … dh_5 | each [-0.02, 0.02] | 41⁵ ≈ 1.2·10⁸ |
| SW1 | stitched (65 m spans) | 7 | dh_1 … dh_4 | each [-0.02, 0.02] | 41⁴ ≈ 2.8·10⁶ |
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable

from .design_problem import DesignProblem

__all__ = ["problem_table"]

_SUPERSCRIPTS = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


def problem_table(problems: Iterable[DesignProblem]) -> str:
    """The Markdown table of ``problems``: catenary, droppers, variables, bounds and grid size.

    The first problem on each catenary names its span length.
    """
    lines = [
        "| problem | catenary | droppers / span | variables | bounds (m) | grid points |",
        "|---|---|---|---|---|---|",
    ]
    catenaries_named: set[str] = set()
    for problem in problems:
        catenary = problem.catenary
        if catenary not in catenaries_named:
            catenaries_named.add(catenary)
            catenary = f"{catenary} ({problem.catenary_definition.span_length:g} m spans)"
        groups = _groups(problem)
        variables = ", ".join(_names(names) for _, names, _ in groups)
        bounds = "; ".join(
            (f"{kind}: " if len(groups) > 1 else "") + _bounds(pairs) for kind, _, pairs in groups
        )
        cells = [problem.name, catenary, str(problem.n_droppers), variables, bounds, _grid_points(problem)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _groups(problem: DesignProblem) -> list[tuple[str, list[str], list[tuple[float, float]]]]:
    """The variables by kind (``s``, ``d``, ``dh``), in order, each with its bounds."""
    rows = zip(problem.variables, problem.lower.tolist(), problem.upper.tolist(), strict=True)
    groups = []
    for kind, members in itertools.groupby(rows, key=lambda row: row[0].rsplit("_", 1)[0]):
        members = list(members)
        groups.append((kind, [name for name, _, _ in members], [(lo, hi) for _, lo, hi in members]))
    return groups


def _names(names: list[str]) -> str:
    return f"{names[0]} … {names[-1]}" if len(names) > 2 else ", ".join(names)


def _bounds(pairs: list[tuple[float, float]]) -> str:
    if len(pairs) > 1 and len(set(pairs)) == 1:
        return f"each [{pairs[0][0]:g}, {pairs[0][1]:g}]"
    return ", ".join(f"[{lo:g}, {hi:g}]" for lo, hi in pairs)


def _grid_points(problem: DesignProblem) -> str:
    levels = problem.n_levels.tolist()
    if len(levels) == 1:
        return str(levels[0])
    total = math.prod(levels)
    exponent = math.floor(math.log10(total))
    size = f"≈ {total / 10**exponent:.1f}·10{str(exponent).translate(_SUPERSCRIPTS)}"
    if len(set(levels)) == 1:
        return f"{levels[0]}{str(len(levels)).translate(_SUPERSCRIPTS)} {size}"
    return size
