"""Optimisation problems by name: the synthetic ones, else the catenary design problems."""

from __future__ import annotations

from catenary_env.errors import UnknownNameError

from .catenary_adapter import catenary_problem
from .problem import GridProblem
from .synthetic import SYNTHETIC_PROBLEMS

__all__ = ["resolve_problem"]


def resolve_problem(problem: GridProblem | str) -> GridProblem:
    """A problem object from a problem or a name: a synthetic problem's name, else a catenary problem's."""
    if not isinstance(problem, str):
        if not isinstance(problem, GridProblem):
            raise TypeError(
                f"{problem!r} is not a GridProblem (needs name, variable_names, bounds, step, simulate)"
            )
        return problem
    if problem in SYNTHETIC_PROBLEMS:
        return SYNTHETIC_PROBLEMS[problem]
    try:
        return catenary_problem(problem)
    except KeyError as error:
        message = error.args[0] if error.args else repr(problem)
        raise UnknownNameError(
            f"{message}; or a synthetic problem: {', '.join(SYNTHETIC_PROBLEMS)}"
        ) from None
