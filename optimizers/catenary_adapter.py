"""The catenary design problems of ``catenary_env.problems`` (docs/problems.md, 'The eight problems') as
optimisation problems.

A :class:`CatenaryProblem` carries only names, bounds, steps and the model's fingerprint; its ``simulate``
is a picklable partial of :func:`simulate_catenary_design`, which a worker process runs.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from catenary_env.analysis.statistics import ContactStatistics
from catenary_env.fingerprint import model_fingerprint
from catenary_env.pipeline import CONSTRAINTS
from catenary_env.problems import evaluate_problem, get_problem
from catenary_env.train import SINGLE, Train

from .problem import Outcome, SimulateFunction

__all__ = ["STATISTICS", "CatenaryProblem", "catenary_problem", "simulate_catenary_design"]

STATISTICS = tuple(ContactStatistics.__dataclass_fields__)
"""The statistics an outcome of a catenary problem carries (``Outcome.statistics``), in this order."""


def simulate_catenary_design(
    problem_name: str,
    x: tuple[float, ...],
    speed_kmh: float,
    fidelity: str,
    train: Train = SINGLE,
    contact_wire_tension: float | None = None,
) -> Outcome:
    """Simulate a design of a registered catenary design problem: picklable, for worker processes.

    Parameters
    ----------
    problem_name : str
        A name in ``catenary_env.problems.PROBLEMS``.
    x : tuple of float
        Variables, physical units (m), on the grid.
    speed_kmh : float
        Train speed, km/h.
    fidelity : str
        ``"study"`` or ``"test"``.
    train : Train
        Pantographs behind the leading one and the objective's: σ is :attr:`Evaluation.sigma`.
    contact_wire_tension : float or None
        The contact wire's tension, N (default the preset's).
    """
    evaluation = evaluate_problem(
        problem_name,
        tuple(x),
        float(speed_kmh),
        fidelity,
        train=train,
        contact_wire_tension=contact_wire_tension,
    )
    statistics = evaluation.statistics
    sigma = None if evaluation.sigma is None else float(evaluation.sigma)
    constraints = tuple(float(v) for v in evaluation.constraints)
    values = () if statistics is None else tuple(float(getattr(statistics, n)) for n in STATISTICS)
    return Outcome(
        bool(evaluation.feasible),
        sigma,
        str(evaluation.reason),
        float(evaluation.wall_time),
        constraints,
        values,
    )


@dataclass(frozen=True, eq=False)
class CatenaryProblem:
    """A catenary design problem (docs/problems.md) as a :class:`GridProblem` (built by
    :func:`catenary_problem`); its outcomes carry the constraint values of
    :data:`catenary_env.pipeline.CONSTRAINTS` and the contact-force statistics of :data:`STATISTICS`."""

    name: str
    variable_names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    step: NDArray[np.float64]
    model_fingerprint: str = ""
    constraint_names: tuple[str, ...] = CONSTRAINTS
    statistic_names: tuple[str, ...] = STATISTICS
    train: Train = SINGLE
    contact_wire_tension: float | None = None
    registered: str = ""
    """The name of the problem of ``catenary_env.problems`` it adapts, where :attr:`name` is not (at another
    tension: ``"B1-T20kN"`` adapts ``"B1"``)."""

    @property
    def simulate(self) -> SimulateFunction:
        options: dict[str, object] = {} if self.train == SINGLE else {"train": self.train}
        if self.contact_wire_tension is not None:
            options["contact_wire_tension"] = self.contact_wire_tension
        return functools.partial(simulate_catenary_design, self.registered or self.name, **options)

    def with_contact_wire_tension(self, contact_wire_tension: float | None) -> CatenaryProblem:
        """The same problem with its contact wire at ``contact_wire_tension``, N (None: the preset's)."""
        return catenary_problem(self.registered or self.name, self.train, contact_wire_tension)


def catenary_problem(
    name: str, train: Train = SINGLE, contact_wire_tension: float | None = None
) -> CatenaryProblem:
    """Adapt the design problem ``name`` of ``catenary_env.problems`` (e.g. ``"B1"``), with the ``train``'s
    pantographs behind the leading one (its objective's σ; the stored results' key includes it) and its
    contact wire at ``contact_wire_tension``, N (default the preset's; the model's fingerprint, and so the
    stored results' key, includes it, and the name says it: ``"B1-T20kN"``).

    Raises
    ------
    KeyError
        No such problem (the message lists those available).
    ValueError
        A tension outside the range the problem allows (the message gives it).
    """
    problem = get_problem(name).with_contact_wire_tension(contact_wire_tension)
    # The problem module calls its names `variables`; the interface agreed in the issue says
    # `variable_names`: accept either, so that a rename there does not break the optimisers.
    names = getattr(problem, "variable_names", None) or problem.variables
    tension = problem.contact_wire_tension
    return CatenaryProblem(
        problem.name if tension is None else f"{problem.name}-T{tension / 1000:g}kN",
        tuple(names),
        np.array(problem.lower, dtype=np.float64),
        np.array(problem.upper, dtype=np.float64),
        np.array(problem.step, dtype=np.float64),
        problem.store_fingerprint()
        if train == SINGLE
        else model_fingerprint(problem.store_fingerprint(), train),
        train=train,
        contact_wire_tension=tension,
        registered=problem.name,
    )
