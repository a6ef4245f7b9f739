"""catenary-env: finite element pantograph-catenary simulation and design environments."""

from .definition import CatenaryDefinition, DefinitionError, PantographDefinition
from .design import Design, DesignError, level_design, presag_design

__all__ = [
    "CatenaryDefinition",
    "DefinitionError",
    "Design",
    "DesignError",
    "PantographDefinition",
    "level_design",
    "presag_design",
]
__version__ = "0.1.0"


def _register_gymnasium_envs() -> None:
    """Register ``Catenary-<problem>-v0`` when Gymnasium is installed (idempotent; SPEC 5).

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
