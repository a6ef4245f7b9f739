"""The dynamic models by name: the one table the pipeline chooses from (docs/performance.md, 'Model
fidelities').

Each model implements the passage protocol (:mod:`~catenary_env.dynamics.protocol`): ``prepare(system,
fidelity)`` and ``run(prepared, passage)``. The names are :attr:`catenary_env.pipeline.Fidelity.dynamics`'.
"""

from __future__ import annotations

from . import exact, span_modes
from .protocol import DynamicModel

DYNAMIC_MODELS: dict[str, DynamicModel] = {
    # Component modes per span, cut off by frequency: the design studies' model, with its accuracy contract.
    "span-modes": DynamicModel(span_modes.prepare, span_modes.run, stops_early=True),
    # Every DOF every step: the yardstick, and the only model of a system that is not Rayleigh-damped.
    "exact": DynamicModel(exact.prepare, exact.run, stops_early=False),
}
