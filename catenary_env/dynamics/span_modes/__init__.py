"""The span-mode model: the linearised catenary in component modes per span (docs/performance.md, 'Model
fidelities'): the reduction (:mod:`.reduction`), :func:`prepare` (:mod:`.preparation`) and :func:`run`
(:mod:`.passage`), with its loops in numpy (:mod:`.loop`) and compiled (:mod:`.kernels`)."""

from .passage import BACKENDS, run
from .preparation import PreparedSpanModes, prepare, prepare_reduced
from .state import SpanModeState

__all__ = ["BACKENDS", "PreparedSpanModes", "SpanModeState", "prepare", "prepare_reduced", "run"]
