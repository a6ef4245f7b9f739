"""Shape-finding: the configuration in which the catenary hangs exactly as designed (docs/model.md,
'Shape-finding').

Unknowns are the nodal coordinates and the reference (unstretched) lengths of all elements;
equations are static equilibrium under gravity plus the design constraints:

* every node's x is prescribed (supports, droppers, stitch-wire ends, and the mesh points between
  them); the reference length of each element is the unknown that lets the node stand there;
* the contact-wire height is prescribed at every dropper (the dropper's length is the unknown) and
  at the supports (the steady arm carries the reaction); the messenger height is prescribed at the
  supports (the support spring carries the reaction);
* each wire is pulled at its first node by its tension T along x; the x-equilibrium of every node
  then makes the horizontal component of the wire force equal to T in every element (the droppers
  are vertical). Imposing the full force norm T in every element, as the tension constraint is
  sometimes written, over-determines a sagging wire under gravity (the force grows with the slope);
  the horizontal component is the one that equilibrium keeps constant.
* each stitch wire's horizontal tension is imposed by one extra equation.

The coupled system is solved by Newton–Raphson with the analytic tangent (assembled in
:mod:`catenary_env.fem.assembly`) and a direct solver in track order (:mod:`catenary_env.fem.track_order`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import CatenaryError
from ..fem.assembly import (
    Assembled,
    RecentPlans,
    SparseScatter,
    assemble,
    dlength_coordinates,
    matrix_coordinates,
)
from ..fem.bar import bar_state
from ..fem.layout import CONTACT, MESSENGER, STITCH, Layout
from ..fem.track_order import TrackOrderSolver
from ..model.design import GRAVITY


class ShapeFindingError(CatenaryError, RuntimeError):
    """Shape-finding did not converge: the design has no static shape; the message gives the residual."""


@dataclass(frozen=True)
class StaticSolution:
    """The static equilibrium configuration of a section.

    Attributes
    ----------
    layout : Layout
    positions : ndarray (n_dofs,)
        Nodal coordinates at equilibrium, m.
    lengths : ndarray (Ec + Eb,)
        Reference (unstretched) lengths, cables first then bars, m.
    bar_forces : ndarray (Eb,)
        Static axial forces of bars (droppers, stitch wires), N.
    reactions : ndarray (n_dofs,)
        Forces the supports and anchors exert where an equation was replaced by a prescribed
        coordinate (support springs, steady arms, wire anchors), N; zero elsewhere.
    residual_history : tuple of float
        Infinity norm of the equilibrium residual at the start and after each Newton iteration, N.
    load_scale : float
        Largest wire tension, N; residuals are judged relative to it.
    start_spans : int
        Spans of the shorter section whose solution Newton started from
        (:mod:`~catenary_env.statics.equal_spans`); 0 where it started from the parabolic start.
    """

    layout: Layout
    positions: np.ndarray
    lengths: np.ndarray
    bar_forces: np.ndarray
    reactions: np.ndarray
    residual_history: tuple[float, ...]
    load_scale: float
    start_spans: int = 0

    @property
    def dropper_forces(self) -> np.ndarray:
        """Static dropper forces, N, in the layout's dropper order."""
        return self.bar_forces[self.layout.dropper_bars]

    @property
    def dropper_lengths(self) -> np.ndarray:
        """Unstretched dropper lengths, m."""
        n_c = self.layout.cable_nodes.shape[0]
        return self.lengths[n_c + self.layout.dropper_bars]

    @property
    def wire_tensions(self) -> dict[str, np.ndarray]:
        """Axial force at the middle of every cable element, N, keyed "contact_wire" / "messenger_wire".

        The horizontal component equals the wire's tension (module docstring); the axial force exceeds it
        by the slope's share, most on the messenger near the supports.
        """
        from ..fem.ancf import axial_force
        from ..fem.layout import CONTACT

        lay = self.layout
        n_c = lay.cable_nodes.shape[0]
        force = axial_force(
            self.positions[lay.cable_dofs()], self.lengths[:n_c], lay.cable_axial_stiffness, 0.5
        )
        return {
            "contact_wire": force[lay.cable_wire == CONTACT],
            "messenger_wire": force[lay.cable_wire != CONTACT],
        }

    def infeasibility(self) -> str:
        """Why the design is statically infeasible, or an empty string (docs/model.md, 'Statistics and
        feasibility')."""
        lengths = self.dropper_lengths
        forces = self.dropper_forces
        lay = self.layout
        if np.min(lengths) <= 0.0:
            i = int(np.argmin(lengths))
            return (
                f"static: dropper {lay.dropper_index[i] + 1} of span {lay.dropper_span[i] + 1} needs a "
                f"negative length ({lengths[i]:.4f} m)"
            )
        if np.min(forces) < 0.0:
            i = int(np.argmin(forces))
            return (
                f"static: dropper {lay.dropper_index[i] + 1} of span {lay.dropper_span[i] + 1} is in "
                f"compression ({forces[i]:.2f} N)"
            )
        return ""


@dataclass(frozen=True)
class _System:
    """Which coordinates are unknown and which equations are kept."""

    free: np.ndarray  # indices of unknown coordinates
    rows: np.ndarray  # indices of kept equilibrium equations
    prescribed: np.ndarray  # coordinate values (used where not free)
    external: np.ndarray  # applied end tensions, N


def _system(layout: Layout) -> _System:
    c = layout.catenary
    n = layout.n_dofs
    prescribed = np.zeros(n)
    fixed = np.zeros(n, dtype=bool)
    dropped = np.zeros(n, dtype=bool)
    xd = layout.node_dof
    prescribed[xd] = layout.node_x
    fixed[xd] = True
    for nodes, height in (
        (layout.messenger_supports, c.messenger_height),
        (layout.contact_supports, c.contact_wire_height),
    ):
        prescribed[xd[nodes] + 1] = height
        fixed[xd[nodes] + 1] = True
        dropped[xd[nodes] + 1] = True
    cw_drop = layout.bar_nodes[layout.dropper_bars, 1]
    prescribed[xd[cw_drop] + 1] = layout.dropper_height
    fixed[xd[cw_drop] + 1] = True
    external = np.zeros(n)
    for wire, (first, last) in zip((c.contact_wire, c.messenger_wire), layout.wire_ends, strict=True):
        external[xd[first]] = -wire.tension
        external[xd[last]] = wire.tension
        # The anchor at the last node takes the x-reaction: that equation is implied by the others.
        dropped[xd[last]] = True
    return _System(np.flatnonzero(~fixed), np.flatnonzero(~dropped), prescribed, external)


def initial_guess(layout: Layout) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates and reference lengths to start Newton from: parabolic wires, straight bars."""
    c = layout.catenary
    L = layout.span_length
    X = _system(layout).prescribed.copy()
    xd = layout.node_dof
    x = layout.node_x
    xi = (x % L) / L
    w = (c.messenger_wire.linear_mass + c.contact_wire.linear_mass) * GRAVITY
    sag = w * L**2 / (8.0 * c.messenger_wire.tension)
    mw_z = c.messenger_height - 4.0 * sag * xi * (1.0 - xi)
    kind = layout.node_kind
    mw = kind == MESSENGER
    X[xd[mw] + 1] = mw_z[mw]
    X[xd[kind == STITCH] + 1] = mw_z[kind == STITCH] - 0.15
    # Contact wire: straight lines between its prescribed heights.
    cw_drop = layout.bar_nodes[layout.dropper_bars, 1]
    known = np.r_[layout.contact_supports, cw_drop]
    order = np.argsort(x[known])
    heights = np.r_[np.full(layout.contact_supports.size, c.contact_wire_height), layout.dropper_height]
    cw = kind == CONTACT
    X[xd[cw] + 1] = np.interp(x[cw], x[known][order], heights[order])
    for wire_kind, wire in ((CONTACT, c.contact_wire), (MESSENGER, c.messenger_wire)):
        nodes = np.flatnonzero(kind == wire_kind)
        stretch = 1.0 + wire.tension / wire.axial_stiffness
        slope = stretch * np.gradient(X[xd[nodes] + 1], x[nodes])
        X[xd[nodes] + 2] = stretch
        X[xd[nodes] + 3] = slope
        hinge = layout.node_size(nodes) == 6
        X[xd[nodes[hinge]] + 4] = stretch
        X[xd[nodes[hinge]] + 5] = slope[hinge]
    n_c = layout.cable_nodes.shape[0]
    ends = layout.cable_nodes
    chord = np.hypot(X[xd[ends[:, 1]]] - X[xd[ends[:, 0]]], X[xd[ends[:, 1]] + 1] - X[xd[ends[:, 0]] + 1])
    tension = np.where(layout.cable_wire == CONTACT, c.contact_wire.tension, c.messenger_wire.tension)
    lengths = np.empty(n_c + layout.bar_nodes.shape[0])
    lengths[:n_c] = chord / (1.0 + tension / layout.cable_axial_stiffness)
    bends = layout.bar_nodes
    bar_len = np.hypot(
        X[xd[bends[:, 1]]] - X[xd[bends[:, 0]]], X[xd[bends[:, 1]] + 1] - X[xd[bends[:, 0]] + 1]
    )
    lengths[n_c:] = bar_len * (1.0 - 1e-3)
    return X, lengths


def _stitch_equations(layout: Layout, X: np.ndarray, lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Residual (horizontal force of each stitch wire's first bar minus its tension) and its gradient.

    Returns
    -------
    residual : ndarray (S,)
        N.
    gradient : ndarray (S, 5)
        With respect to the bar's four coordinates (:meth:`Layout.bar_dofs`) and its length, N/m.
    """
    bars = layout.stitch_bars[:, 0]
    if bars.size == 0:
        return np.zeros(0), np.zeros((0, 5))
    n_c = layout.cable_nodes.shape[0]
    dofs = layout.bar_dofs()[bars]
    bs = bar_state(X[dofs], lengths[n_c + bars], layout.bar_stiffness[bars], layout.bar_axial_stiffness[bars])
    # The force on the bar's far end along x is N n_x, the horizontal tension.
    residual = bs.force[:, 2] - layout.catenary.stitch_wire.tension
    return residual, np.c_[bs.stiffness[:, 2, :], bs.force_dlength[:, 2]]


_PLANS = RecentPlans()
"""The Jacobian's scatter and solver of the last few topologies (every design of a problem has one)."""


def _plan(layout: Layout, system: _System) -> tuple[SparseScatter, TrackOrderSolver]:
    """The Jacobian's sparsity pattern and the linear solver's ordering, which depend on the layout's
    topology only: planned once for all Newton iterations, and all designs of a problem."""
    n_free = system.free.size
    n, n_c = layout.n_dofs, layout.cable_nodes.shape[0]
    n_unknowns = n_free + n_c + layout.bar_nodes.shape[0]
    # Equation (row) of each coordinate's equilibrium and unknown (column) of each coordinate;
    # -1 where the equation is dropped or the coordinate prescribed.
    equation = np.full(n, -1)
    equation[system.rows] = np.arange(system.rows.size)
    unknown = np.full(n, -1)
    unknown[system.free] = np.arange(n_free)
    stitch_bars = layout.stitch_bars[:, 0]
    stitch_dofs = layout.bar_dofs()[stitch_bars]
    # The Jacobian's entries: element tangents and length derivatives at their equation (row) and
    # unknown (column), then the gradients of the stitch equations.
    m_rows, m_cols = matrix_coordinates(layout)
    d_rows, d_lengths = dlength_coordinates(layout)
    stitch_rows = np.repeat(system.rows.size + np.arange(stitch_bars.size), 5)
    stitch_cols = np.c_[unknown[stitch_dofs], n_free + n_c + stitch_bars].ravel()
    rows = np.r_[equation[m_rows], equation[d_rows], stitch_rows]
    cols = np.r_[unknown[m_cols], n_free + d_lengths, stitch_cols]
    jacobian = SparseScatter(rows, cols, (n_unknowns, n_unknowns), "csc")
    # Nodes are numbered along the track, so a coordinate's index is its track position; an element's
    # length and a stitch wire's equation stand at the mean index of their coordinates.
    solver = TrackOrderSolver(
        jacobian.pattern,
        np.r_[system.rows, stitch_dofs.mean(axis=1)],
        np.r_[system.free, layout.cable_dofs().mean(axis=1), layout.bar_dofs().mean(axis=1)],
    )
    return jacobian, solver


class ShapeEquations:
    """The shape-finding system R(y) = 0 over the unknowns y = (free coordinates, reference lengths).

    The Jacobian's sparsity pattern and the linear solver's ordering depend on the layout's topology
    only, so they are planned once (:func:`_plan`), for all Newton iterations and the designs of a problem.
    """

    def __init__(self, layout: Layout) -> None:
        self.layout = layout
        self.system = system = _system(layout)
        self.n_free = system.free.size
        self._jacobian, self._solver = _PLANS.get(
            (*layout.topology(), system.rows, system.free), lambda: _plan(layout, system)
        )

    def unknowns(self, X: np.ndarray, lengths: np.ndarray) -> np.ndarray:
        return np.r_[X[self.system.free], lengths]

    def split(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        X = self.system.prescribed.copy()
        X[self.system.free] = y[: self.n_free]
        return X, y[self.n_free :]

    def residual(self, y: np.ndarray) -> tuple[np.ndarray, Assembled]:
        """Residual (N) at y, and the assembled forces it comes from (for the reactions)."""
        X, lengths = self.split(y)
        state = assemble(self.layout, X, lengths, tangent=False)
        r_st, _ = _stitch_equations(self.layout, X, lengths)
        return np.r_[(state.force - self.system.external)[self.system.rows], r_st], state

    def jacobian(self, y: np.ndarray) -> sp.csc_matrix:
        """Analytic Jacobian dR/dy, N/m."""
        X, lengths = self.split(y)
        state = assemble(self.layout, X, lengths, tangent=True, dlength=True)
        _, g_st = _stitch_equations(self.layout, X, lengths)
        return self._jacobian(
            state.cable_stiffness, state.bar_stiffness, state.cable_dlength, state.bar_dlength, g_st
        )

    def evaluate(self, y: np.ndarray, jacobian: bool = True) -> tuple[np.ndarray, sp.csc_matrix | None]:
        """Residual (N) and, optionally, its analytic Jacobian with respect to y."""
        return self.residual(y)[0], self.jacobian(y) if jacobian else None

    def factorize(self, J: sp.csc_matrix) -> Callable[[np.ndarray], np.ndarray]:
        """rhs ↦ J⁻¹ rhs, J factorised once by a direct method in track order
        (:mod:`catenary_env.fem.track_order`).

        Raises
        ------
        numpy.linalg.LinAlgError
            When J is singular.
        """
        return self._solver.factorize(J)


def find_shape(
    layout: Layout,
    tolerance: float = 1e-8,
    max_iterations: int = 30,
    chord: bool = True,
    start: tuple[np.ndarray, np.ndarray] | None = None,
) -> StaticSolution:
    """Solve the shape-finding problem of ``layout`` by Newton–Raphson.

    Each iteration evaluates the residual once per tried step (the residual of the accepted step is
    the next iteration's) and, but in Newton's quadratic phase, the Jacobian once: once each of the
    last two steps has cut the residual a hundredfold, the Jacobian changes too little over the next
    step to be worth a new factorisation, and the last one serves (a chord step; the presets then
    converge with three factorisations instead of four, to the same round-off floor:
    docs/performance.md, 'Speed').

    Parameters
    ----------
    tolerance : float
        Convergence when the infinity norm of the residual is below ``tolerance`` times the
        largest wire tension, or when it stalls at round-off: a step from below 1e-6 of that tension
        that cuts it less than a hundredfold. The default, 1e-8, stops at the round-off floor (some 4e-9
        of the tension on the presets' 20-span sections, reached in four Newton steps) without a fifth
        step that would only confirm it (docs/performance.md, 'Speed': 3 % of an evaluation, the forces
        moved by rounding only); on longer sections, whose floor lies higher, the stall ends it.
    chord : bool
        Reuse the last factorisation in Newton's quadratic phase (above); False: a Jacobian every
        iteration.
    start : (ndarray, ndarray), optional
        Coordinates (m) and reference lengths (m) to start Newton from; default :func:`initial_guess`.
        A section of equal spans starts from a short section's solution
        (:func:`~catenary_env.statics.equal_spans.find_equal_spans_shape`).

    Raises
    ------
    ShapeFindingError
        When Newton does not reach the tolerance; the message gives the residual.
    """
    c = layout.catenary
    equations = ShapeEquations(layout)
    y = equations.unknowns(*(initial_guess(layout) if start is None else start))
    n_free = equations.n_free
    scale = max(c.contact_wire.tension, c.messenger_wire.tension)
    history: list[float] = []
    r, state = equations.residual(y)
    solve = None  # the last factorised Jacobian
    converged = False
    for _ in range(max_iterations):
        norm = float(np.max(np.abs(r)))
        history.append(norm)
        # Round-off floor: in Newton's quadratic phase (below 1e-6 of the scale, where an exact step would
        # leave some 1e-12 and a chord step some 1e-10), a step that cuts the residual less than a
        # hundredfold means double precision is exhausted; the next step would only confirm it (a
        # factorisation more: docs/performance.md, 'Speed'). The floor grows with the section: some 4e-9 of
        # the tension at 20 spans, 1.3e-8 at 40.
        stalled = len(history) > 1 and history[-2] < 1e-6 * scale and norm > 1e-2 * history[-2]
        if norm < tolerance * scale or stalled:
            converged = True
            break
        quadratic = len(history) > 2 and history[-1] < 1e-2 * history[-2] and history[-2] < 1e-2 * history[-3]
        try:
            if solve is None or not (chord and quadratic):
                solve = equations.factorize(equations.jacobian(y))
            step = solve(-r)
        except np.linalg.LinAlgError as error:
            raise ShapeFindingError(
                f"shape-finding failed: singular tangent ({error}); residual {norm:.3e} N"
            ) from None
        # Backtrack when a full step raises the residual (far from the solution only). The last try
        # (factor 1/128 < 0.01) is always evaluated, so r and state below belong to the y kept.
        factor = 1.0
        for _ in range(8):
            y_new = y + factor * step
            if np.all(y_new[n_free:] > 0.0) or factor < 0.01:
                r_new, state_new = equations.residual(y_new)
                if np.all(np.isfinite(r_new)) and np.max(np.abs(r_new)) < 1.5 * norm:
                    break
            factor *= 0.5
        y, r, state = y_new, r_new, state_new
    if not converged:
        norm = float(np.max(np.abs(r)))
        history.append(norm)
        if not norm < 1e-8 * scale:
            raise ShapeFindingError(
                f"shape-finding did not converge in {max_iterations} Newton iterations: "
                f"residual {norm:.3e} N "
                f"({norm / scale:.1e} of the largest tension {scale:g} N)"
            )
    X, lengths = equations.split(y)
    reactions = state.force - equations.system.external
    reactions[equations.system.rows] = 0.0
    return StaticSolution(layout, X, lengths, state.bar_force, reactions, tuple(history), scale)
