"""catenary-env: finite element pantograph-catenary simulation and design environments.

The package's folders follow the data: ``model/`` (definitions, presets, designs) → ``fem/`` (mesh and
elements) → ``statics/`` (shape-finding) → ``dynamics/`` (linearisation, pantograph, passage) →
``analysis/`` (statistics, stiffness) → :mod:`~catenary_env.pipeline` (evaluate, simulate) →
``problems/`` → ``envs/``; the command line and plots sit at the edge. The names below are the stable
API; the modules behind them may move.

Examples
--------
>>> import catenary_env
>>> catenary = catenary_env.load_catenary("benchmark")
>>> catenary_env.presag_design(catenary, 0.0) == catenary_env.level_design(catenary)
True
"""

from .model.definition import CatenaryDefinition, DefinitionError, PantographDefinition
from .model.design import Design, DesignError, level_design, presag_design, symmetric_design
from .model.presets import load_catenary, load_pantograph
from .pipeline import (
    FIDELITIES,
    Evaluation,
    Fidelity,
    Simulation,
    calibrate_uplift,
    en50367_mean_force,
    evaluate,
    simulate,
)
from .problems import PROBLEMS, DesignProblem, get_problem

__all__ = [
    "FIDELITIES",
    "PROBLEMS",
    "CatenaryDefinition",
    "DefinitionError",
    "Design",
    "DesignError",
    "DesignProblem",
    "Evaluation",
    "Fidelity",
    "PantographDefinition",
    "Simulation",
    "calibrate_uplift",
    "en50367_mean_force",
    "evaluate",
    "get_problem",
    "level_design",
    "load_catenary",
    "load_pantograph",
    "presag_design",
    "simulate",
    "symmetric_design",
]
__version__ = "0.1.0"


def _register_gymnasium_envs() -> None:
    """Register ``Catenary-<problem>-v0`` when Gymnasium is installed (idempotent; docs/problems.md,
    'Environments').

    Since Gymnasium 1.0 third-party packages register on import; without Gymnasium the simulator
    works as it is and the environments are simply not there.
    """
    try:
        import gymnasium  # noqa: F401
    except ImportError:
        return
    from .envs import register_envs

    register_envs()


_register_gymnasium_envs()
