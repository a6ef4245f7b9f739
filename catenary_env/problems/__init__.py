"""The eight catenary design problems: the design grid, the problems, their reference and registry.

``grid`` owns the variables' grid (bounds, steps, snapping, actions, cache keys); ``design_problem`` maps
variables to a design and evaluates it; ``reference`` calibrates the pantograph on the reference
design once per process; ``catalogue`` holds the eight problems and their registry (a
:class:`~catenary_env.registry.Registry`).
"""

from .catalogue import PROBLEMS, ProblemRegistry, evaluate_problem, get_problem, register_problem
from .design_problem import DesignProblem, resolve_fidelity
from .grid import HEIGHT_STEP, POSITION_STEP, DesignGrid
from .reference import clear_caches

__all__ = [
    "HEIGHT_STEP",
    "POSITION_STEP",
    "PROBLEMS",
    "DesignGrid",
    "DesignProblem",
    "ProblemRegistry",
    "clear_caches",
    "evaluate_problem",
    "get_problem",
    "register_problem",
    "resolve_fidelity",
]
