"""Static stiffness of the contact wire along a span (docs/model.md, 'Static analysis').

A vertical force F pushes the contact wire up at one point; the section's nonlinear static
equilibrium is solved again with tension-only droppers (a dropper that would be compressed goes
slack), and the uplift there gives the stiffness k(x) = F / uplift(x). The wires are extensible; the
supports hold as in the dynamic model: wire ends fixed in x, the messenger at the supports as the
catenary's ``modelling.axial_restraint`` says, support springs and steady arms vertical springs about
their static reactions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse.linalg as spla

from ..dynamics.linear_system import LinearSystem, linearise
from ..fem.assembly import SparseScatter, assemble, free_matrix_scatter
from ..statics.shape_finding import ShapeFindingError, StaticSolution


@dataclass(frozen=True)
class StiffnessProfile:
    """Contact-wire stiffness along one span.

    Attributes
    ----------
    positions : ndarray (m,)
        Load points, m from the span's first support.
    force : float
        Upward force, N.
    uplift : ndarray (m,)
        Contact-wire uplift at the load point, m.
    stiffness : ndarray (m,)
        F / uplift, N/m.
    span : int
        Span index (0-based) in the section.
    """

    positions: np.ndarray
    force: float
    uplift: np.ndarray
    stiffness: np.ndarray
    span: int

    @property
    def variability(self) -> float:
        """α = (k_max - k_min) / (k_max + k_min), dimensionless."""
        k = self.stiffness
        return float((k.max() - k.min()) / (k.max() + k.min()))


def _uplift_at(
    static: StaticSolution,
    system: LinearSystem,
    tangent: SparseScatter,
    x: float,
    force: float,
    start: np.ndarray,
    max_iterations: int = 30,
) -> tuple[float, np.ndarray]:
    """Newton solve of the section pushed up by ``force`` at track position ``x``; returns uplift and X.

    ``tangent`` is :func:`free_matrix_scatter` on ``system.free``, planned once for all load points.
    """
    lay = static.layout
    c = lay.catenary
    free = system.free
    springs = np.zeros(lay.n_dofs)
    springs[lay.node_dof[lay.messenger_supports] + 1] = c.supports.messenger_stiffness
    springs[lay.node_dof[lay.contact_supports] + 1] = c.supports.steady_arm_stiffness
    X0, lengths = static.positions, static.lengths
    reference = assemble(lay, X0, lengths, tangent=False, tension_only=True).force
    e, h, _ = system.contact_wire.locate(np.array([x]))
    zd = system.contact_wire.z_dofs[e[0]]
    load = np.zeros(free.size)
    load[zd] = h[0] * force
    X = start.copy()
    # Same round-off floor as shape-finding: 1e-8 of the largest tension (about 2e-4 N).
    tolerance = 1e-8 * max(c.contact_wire.tension, c.messenger_wire.tension)
    for _ in range(max_iterations):
        state = assemble(lay, X, lengths, tangent=True, tension_only=True)
        r = (state.force - reference + springs * (X - X0))[free] - load
        if np.max(np.abs(r)) < tolerance:
            break
        J = tangent(state.cable_stiffness, state.bar_stiffness, springs)
        X[free] -= spla.spsolve(J, r)
    else:
        raise ShapeFindingError(
            f"uplift solve at x = {x:.2f} m did not converge: residual {np.max(np.abs(r)):.3e} N"
        )
    du = X[free] - X0[free]
    return float(h[0] @ du[zd]), X


def stiffness_profile(
    static: StaticSolution,
    force: float = 100.0,
    n_points: int = 23,
    span: int | None = None,
    system: LinearSystem | None = None,
) -> StiffnessProfile:
    """Stiffness of the contact wire at ``n_points`` equally spaced points of a span (ends included).

    Parameters
    ----------
    force : float
        Upward force, N (docs/model.md, 'Static analysis' uses 100 N and 200 N).
    span : int, optional
        Span index; the central span by default.
    system : LinearSystem, optional
        An extensible linearisation of ``static`` (:func:`~catenary_env.dynamics.linear_system.linearise`),
        for its free coordinates and contact-wire geometry.
    """
    lay = static.layout
    span = lay.n_spans // 2 if span is None else span
    # The extensible wires' coordinates, whatever the dynamics' linearisation: this is a nonlinear solve.
    system = linearise(static, linearisation="extensible") if system is None else system
    positions = np.linspace(0.0, lay.span_length, n_points)
    uplift = np.empty(n_points)
    X = static.positions
    tangent = free_matrix_scatter(lay, system.free, "csc")
    for i, s in enumerate(positions):
        uplift[i], X = _uplift_at(static, system, tangent, span * lay.span_length + s, force, X)
    return StiffnessProfile(positions, force, uplift, force / uplift, span)
