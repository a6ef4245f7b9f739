"""The exact model: the linearised catenary, every DOF every step (docs/model.md, 'Time integration and the
fast method'): :func:`prepare` (:mod:`.preparation`) and :func:`run` (:mod:`.passage`), with its loops in
numpy (:mod:`.loop`), compiled (:mod:`.kernels`, :mod:`.kernel_preparation`) and straightforward
(:mod:`.oracle`)."""

from .passage import BACKENDS, run
from .preparation import PreparedExact, prepare
from .state import ExactState

__all__ = ["BACKENDS", "ExactState", "PreparedExact", "prepare", "run"]
