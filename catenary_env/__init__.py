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
