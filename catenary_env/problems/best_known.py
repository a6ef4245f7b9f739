"""The best-known design of each problem (docs/problems.md, 'Best-known designs'), so that an optimiser
can report its gap: ``(σ - best.sigma_N) / best.sigma_N``.

The table ``best_known.json`` beside this module is written by ``python -m experiments.best_known`` from
the committed results (the design studies' GA histories, ``results/design/``, and the optimiser
comparison's runs, ``results/optimizers/``): per problem, the lowest σ any recorded evaluation reached at
the study fidelity and 300 km/h, the design, which run found it, and its σ simulated again on the exact
model (the ``reference`` fidelity). A value is served only for the model it was computed on: after a change
of the physics (another :meth:`~catenary_env.problems.DesignProblem.store_fingerprint`) a problem has none
until the table is rebuilt.

Examples
--------
>>> from catenary_env.problems import get_problem
>>> best = get_problem("B1").best_known
>>> round(best.sigma_N, 2), best.fidelity, best.speed_kmh
(25.47, 'study', 300.0)
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

__all__ = ["TABLE", "BestKnown", "best_known_table"]

TABLE = Path(__file__).with_name("best_known.json")
"""The committed table."""


@dataclass(frozen=True)
class BestKnown:
    """A problem's best-known design.

    Attributes
    ----------
    problem : str
        Problem id.
    sigma_N : float
        σ of the filtered contact force at ``speed_kmh`` on the ``fidelity`` model, N.
    x : tuple of float
        The design's variables, m.
    speed_kmh : float
        Train speed, km/h.
    fidelity : str
        The model fidelity σ was computed on (``"study"``).
    model_fingerprint : str
        The problem's :meth:`~catenary_env.problems.DesignProblem.store_fingerprint` then.
    simulator : str
        :func:`~catenary_env.fingerprint.simulator_fingerprint` then.
    found_by : str
        Which run found it, e.g. ``"design study GA (results/design/B1/history.csv, evaluation 1313)"``.
    confirmed_sigma_N : float
        σ of the same design on the exact model (``confirmed_fidelity``), N.
    confirmed_fidelity : str
        ``"reference"``.
    """

    problem: str
    sigma_N: float
    x: tuple[float, ...]
    speed_kmh: float
    fidelity: str
    model_fingerprint: str
    simulator: str
    found_by: str
    confirmed_sigma_N: float
    confirmed_fidelity: str

    def gap(self, sigma_N: float) -> float:
        """The relative gap of a σ (N) to this one: 0.02 is 2 % above the best known."""
        return (float(sigma_N) - self.sigma_N) / self.sigma_N


@functools.cache
def best_known_table() -> dict[str, BestKnown]:
    """The committed table by problem (empty when the file is absent)."""
    if not TABLE.exists():
        return {}
    rows = json.loads(TABLE.read_text(encoding="utf-8"))
    return {row["problem"]: BestKnown(**{**row, "x": tuple(row["x"])}) for row in rows}
