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

from typing import TYPE_CHECKING, Any

from .model.definition import CatenaryDefinition, DefinitionError, PantographDefinition
from .model.presets import load_catenary, load_pantograph

if TYPE_CHECKING:
    from .model.design import Design, DesignError, level_design, presag_design, symmetric_design
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

# The simulator's names are imported on first use (PEP 562), so that a command that needs none of them
# (``catenary presets``, ``catenary --help``) does not import numpy and scipy.
_LAZY = {
    **dict.fromkeys(
        ("Design", "DesignError", "level_design", "presag_design", "symmetric_design"), "model.design"
    ),
    **dict.fromkeys(
        (
            "FIDELITIES",
            "Evaluation",
            "Fidelity",
            "Simulation",
            "calibrate_uplift",
            "en50367_mean_force",
            "evaluate",
            "simulate",
        ),
        "pipeline",
    ),
    **dict.fromkeys(("PROBLEMS", "DesignProblem", "get_problem"), "problems"),
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'catenary_env' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


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
    """Register ``Catenary-<problem>-v0`` with Gymnasium (idempotent; docs/problems.md, 'Environments').

    Since Gymnasium 1.0 third-party packages register on import; without Gymnasium the simulator
    works as it is and the environments are simply not there. Gymnasium already imported: registered
    now; else registered right after Gymnasium's own import, whenever that comes, so that a command that
    never uses the envs does not import Gymnasium (and numpy) at all.
    """
    import importlib.util
    import sys

    if "gymnasium" in sys.modules:
        from .envs import register_envs

        register_envs(builtin_only=True)
    elif importlib.util.find_spec("gymnasium") is not None:
        sys.meta_path.insert(0, _AfterGymnasiumImport())


class _AfterGymnasiumImport:
    """A one-shot import hook: Gymnasium's module runs as usual, then the envs are registered."""

    def find_spec(self, name: str, path: object = None, target: object = None) -> Any:
        import importlib.util
        import sys

        if name != "gymnasium":
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        run_module = spec.loader.exec_module

        def exec_module(module: Any) -> None:
            run_module(module)
            envs = sys.modules.get(f"{__name__}.envs")
            if envs is not None and not hasattr(envs, "register_envs"):
                return  # catenary_env.envs is importing Gymnasium: it registers them itself when done
            from .envs import register_envs

            register_envs(builtin_only=True)

        spec.loader.exec_module = exec_module  # type: ignore[method-assign]
        return spec


_register_gymnasium_envs()
