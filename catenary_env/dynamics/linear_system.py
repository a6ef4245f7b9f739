"""Linearised dynamics about the static state: M ü + C u̇ + K u = F (docs/model.md, 'Linearised dynamics').

K is the tangent stiffness at equilibrium, including the geometric stiffness of the wire tension,
plus the support springs; M the constant consistent mass plus point masses; C = αM + βK.
Droppers enter K as axial springs k nnᵀ only: their geometric stiffness N/l acts across the
dropper (horizontally) and is below 1e-3 of the wires' axial stiffness; leaving it out keeps a
dropper's whole contribution one scalar force, which a slack dropper can switch off exactly.

The catenary's modelling choices (:class:`~catenary_env.model.options.ModellingOptions`; docs/model.md,
'Modelling choices') decide the rest. By default the wires move vertically only, at their static axial
force (``linearisation = "transverse-only"``: no x coordinate, no axial stiffness EA in K); the messenger
supports and steady arms are vertical springs. Extensible wires keep their x coordinates, anchored at both
ends of the section and, with ``axial_restraint = "every-support"``, at every messenger support. The
other choices add the droppers' geometric stiffness, Rayleigh damping over the wires only, or slack
droppers that keep their damping; the last two give a system whose damping is not C = αM + βK with slack
droppers dropping their whole force (:attr:`LinearSystem.rayleigh` is False), which only the
straightforward loop (:mod:`~catenary_env.dynamics.exact.oracle`) integrates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..fem.ancf import hermite, hermite_dxi
from ..fem.assembly import assemble, assemble_mass, free_matrix_scatter
from ..fem.bar import bar_state, geometric_tangent
from ..fem.layout import CONTACT, DROPPER
from ..statics.shape_finding import StaticSolution

LOCATE_TOLERANCE = 1e-10
"""Newton's last step in the element coordinate ξ ∈ [0, 1] when a track position is located on the contact
wire (some 5e-11 m on a 0.5 m element; the round-off floor is some 1e-12)."""


@dataclass(frozen=True)
class ContactWireGeometry:
    """The static contact wire, for locating the pantograph and interpolating heights.

    Attributes
    ----------
    x_start : ndarray (Ew,)
        Static x of each contact-wire element's first node, increasing, m.
    q : ndarray (Ew, 8)
        Static coordinates of each element.
    length : ndarray (Ew,)
        Reference lengths, m.
    z_dofs : ndarray (Ew, 4)
        Free-DOF indices of (z_i, z'_i, z_j, z'_j).
    """

    x_start: np.ndarray
    q: np.ndarray
    length: np.ndarray
    z_dofs: np.ndarray

    def locate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Element, shape row and static height at track positions ``x``.

        Returns
        -------
        element : ndarray (n,) of int
        shape : ndarray (n, 4)
            Row h with z(x) = h · (z_i, z'_i, z_j, z'_j).
        height : ndarray (n,)
            Static contact-wire height, m.
        """
        x = np.asarray(x, dtype=float)
        e = np.clip(np.searchsorted(self.x_start, x, side="right") - 1, 0, self.x_start.size - 1)
        qx = self.q[e][:, [0, 2, 4, 6]]
        L = self.length[e]
        xi = (x - qx[:, 0]) / (qx[:, 2] - qx[:, 0])
        # Newton on x(ξ) = x; the map is nearly linear, so one or two steps reach the round-off floor
        # (some 1e-12 in ξ, the rounding of x ~ 1 km), where the steps stop.
        for _ in range(8):
            step = (np.einsum("nk,nk->n", hermite(xi, L), qx) - x) / np.einsum(
                "nk,nk->n", hermite_dxi(xi, L), qx
            )
            xi -= step
            if np.max(np.abs(step), initial=0.0) < LOCATE_TOLERANCE:
                break
        h = hermite(xi, L)
        height = np.einsum("nk,nk->n", h, self.q[e][:, [1, 3, 5, 7]])
        return e, h, height


@dataclass(frozen=True)
class LinearSystem:
    """Matrices of the linearised catenary on its free DOFs.

    Attributes
    ----------
    static : StaticSolution
    free : ndarray (n,)
        Coordinates of the full configuration that are dynamic DOFs.
    mass, stiffness : scipy.sparse.csr_matrix (n, n)
        kg and N/m.
    alpha, beta : float
        Rayleigh coefficients, C = alpha M + beta K.
    dropper_elongation : scipy.sparse.csr_matrix (D, n)
        B: dropper elongations Δl = B u, m per m.
    dropper_rate : ndarray (D,)
        Axial spring rates, N/m.
    dropper_force : ndarray (D,)
        Static dropper forces, N.
    contact_wire : ContactWireGeometry
    support_z : ndarray (n_spans + 1,)
        Free-DOF index of the contact wire's height at each support.
    damping_matrix : scipy.sparse.csr_matrix (n, n) or None
        C where it is not alpha M + beta K (Rayleigh damping over the wires only), N·s/m.
    slack_dropper_damping : bool
        True when a slack dropper keeps its damping share beta k Δl̇ and drops only its spring force.
    """

    static: StaticSolution
    free: np.ndarray
    mass: sp.csr_matrix
    stiffness: sp.csr_matrix
    alpha: float
    beta: float
    dropper_elongation: sp.csr_matrix
    dropper_rate: np.ndarray
    dropper_force: np.ndarray
    contact_wire: ContactWireGeometry
    support_z: np.ndarray
    damping_matrix: sp.csr_matrix | None = None
    slack_dropper_damping: bool = False

    @property
    def n_dofs(self) -> int:
        return int(self.free.size)

    @property
    def damping(self) -> sp.csr_matrix:
        """C, N·s/m."""
        if self.damping_matrix is not None:
            return self.damping_matrix
        return (self.alpha * self.mass + self.beta * self.stiffness).tocsr()

    @property
    def rayleigh(self) -> bool:
        """True when C = alpha M + beta K and a slack dropper drops its whole force: what the fast loops
        (:mod:`~catenary_env.dynamics.exact`, the span-mode model) integrate."""
        return self.damping_matrix is None and not self.slack_dropper_damping


def linearise(static: StaticSolution, linearisation: str | None = None) -> LinearSystem:
    """Build M, K, C and the dropper and contact-wire data about a static solution.

    Parameters
    ----------
    linearisation : {"extensible", "transverse-only"}, optional
        Overrides the catenary's ``modelling.linearisation`` (the static analysis solves the equilibrium of
        extensible wires whatever the dynamics use).
    """
    lay = static.layout
    c = lay.catenary
    options = c.modelling
    transverse = (linearisation or options.linearisation) == "transverse-only"
    n_all = lay.n_dofs
    X, lengths = static.positions, static.lengths
    fixed = np.zeros(n_all, dtype=bool)
    fixed[lay.node_dof[lay.wire_ends.ravel()]] = True
    if options.axial_restraint == "every-support":
        fixed[lay.node_dof[lay.messenger_supports]] = True
    if transverse:
        fixed |= lay.axial_coordinates()
    free = np.flatnonzero(~fixed)
    index = np.full(n_all, -1)
    index[free] = np.arange(free.size)

    state = assemble(lay, X, lengths, tangent=True, axial_material=not transverse)
    n_c = lay.cable_nodes.shape[0]
    bars = bar_state(X[lay.bar_dofs()], lengths[n_c:], lay.bar_stiffness, lay.bar_axial_stiffness)
    drop = lay.dropper_bars
    bdofs = lay.bar_dofs()[drop]
    n = bars.direction[drop]
    rate = np.where(
        np.isfinite(lay.bar_stiffness[drop]),
        lay.bar_stiffness[drop],
        lay.bar_axial_stiffness[drop] / lengths[n_c + drop],
    )
    b_row = np.hstack([-n, n])  # Δl = b_row · (u_a, u_b)
    assert state.cable_stiffness is not None and state.bar_stiffness is not None
    bar_stiffness = state.bar_stiffness.copy()
    if options.dropper_geometric_stiffness == "excluded":
        # The droppers' axial springs only (module docstring).
        bar_stiffness[drop] = rate[:, None, None] * b_row[:, :, None] * b_row[:, None, :]
    if transverse:  # stitch wires at their static force too: the geometric part of their tangent only
        stitch = lay.bar_kind != DROPPER
        bar_stiffness[stitch] = geometric_tangent(bars)[stitch]
    springs = np.zeros(n_all)
    springs[lay.node_dof[lay.messenger_supports] + 1] += c.supports.messenger_stiffness
    springs[lay.node_dof[lay.contact_supports] + 1] += c.supports.steady_arm_stiffness
    cable_mass, bar_mass, point_mass = assemble_mass(lay, lengths)
    scatter = free_matrix_scatter(lay, free)  # K and M share one pattern
    K = scatter(state.cable_stiffness, bar_stiffness, springs)
    M = scatter(cable_mass, bar_mass, point_mass)
    # Drop the stored zeros (the x-z couplings of the mass blocks): the time loop reads every entry.
    K.eliminate_zeros()
    M.eliminate_zeros()
    C = None
    if options.rayleigh_damping_scope == "wires-only":
        # The wires' (and stitch wires') own mass and tangent: no droppers, springs or point masses.
        wire = (lay.bar_kind != DROPPER)[:, None, None]
        no_points = np.zeros(n_all)
        C = c.damping.alpha * scatter(cable_mass, bar_mass * wire, no_points) + c.damping.beta * scatter(
            state.cable_stiffness, bar_stiffness * wire, no_points
        )
        C.eliminate_zeros()

    rows = np.repeat(np.arange(drop.size), 4)
    cols = index[bdofs].ravel()
    keep = cols >= 0
    B = sp.csr_matrix((b_row.ravel()[keep], (rows[keep], cols[keep])), shape=(drop.size, free.size))

    cw = np.flatnonzero(lay.cable_wire == CONTACT)
    cdofs = lay.cable_dofs()[cw]
    order = np.argsort(X[cdofs[:, 0]])
    cw, cdofs = cw[order], cdofs[order]
    geometry = ContactWireGeometry(
        x_start=X[cdofs[:, 0]], q=X[cdofs], length=lengths[cw], z_dofs=index[cdofs[:, [1, 3, 5, 7]]]
    )
    return LinearSystem(
        static=static,
        free=free,
        mass=M,
        stiffness=K,
        alpha=c.damping.alpha,
        beta=c.damping.beta,
        dropper_elongation=B,
        dropper_rate=rate,
        dropper_force=static.dropper_forces.copy(),
        contact_wire=geometry,
        support_z=index[lay.node_dof[lay.contact_supports] + 1],
        damping_matrix=C,
        slack_dropper_damping=options.slack_dropper_damping == "stiffness-proportional",
    )
