"""The fast pantograph passage: Newmark with a constant effective matrix and superposition (SPEC 3.6).

K̂ = K + a1 C + a0 M does not change in time, so it is factorised once (banded Cholesky after a
reverse Cuthill–McKee ordering). The two nonlinearities, contact and slack droppers, are moved to
the right-hand side as unknown forces, and by superposition

    u₁ = u_known + u*_c f_c + Σ_d W_d λ_d,

with W_d = K̂⁻¹ B_dᵀ the responses to unit dropper force pairs (computed once per design) and
u*_c the response to a unit contact force (computed for the contact-wire element as the pantograph
reaches it). Each step then solves a small problem in f_c and the slack droppers' λ only, by
active-set iteration (Gregori et al. 2017, "An approach to geometric optimisation of railway
catenaries", Veh. Syst. Dyn. 56; the same method for slack droppers).

A slack dropper transmits nothing: λ_d cancels its whole linear force, spring and Rayleigh damping
share, N₀ + k (1 + β a1) Δl₁ - β k B (a1 u₀ + a4 v₀ + a5 a₀). A dropper is slack when that force
would be compressive: judging by the spring force alone while removing the damping share too
leaves droppers near zero force with no consistent state, whereas this rule makes each step a
linear complementarity problem with a unique solution.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import reverse_cuthill_mckee

from .linear_system import LinearSystem
from .newmark import NewmarkConstants, Trajectory, passage_positions
from .pantograph import pantograph_matrices, static_contact
from .definition import PantographDefinition

MAX_ACTIVE_SET_ITERATIONS = 40
FULL_SWITCH_ITERATIONS = 8


def switch_states(
    contact: bool, slack: np.ndarray, new_contact: bool, new_slack: np.ndarray, contact_force: float,
    elastic: np.ndarray, iteration: int,
) -> tuple[bool, np.ndarray]:
    """Next contact / slack-dropper state of the active-set iteration.

    The first iterations switch every inconsistent state at once (Newton's method on the
    piecewise-linear problem, quadratic when it works); should that cycle, later iterations switch
    only the most violated one, which cannot cycle on this problem's P-matrix.
    """
    if iteration < FULL_SWITCH_ITERATIONS:
        return new_contact, new_slack
    violation = np.where(new_slack != slack, np.abs(elastic), 0.0)
    contact_violation = abs(contact_force) if new_contact != contact else 0.0
    if contact_violation >= violation.max(initial=0.0):
        return new_contact, slack
    slack = slack.copy()
    worst = int(np.argmax(violation))
    slack[worst] = not slack[worst]
    return contact, slack


class BandedCholesky:
    """K̂ = Uᵀ U of a sparse SPD matrix in band storage; solves in the original order.

    The DOFs are numbered along the track already (:mod:`catenary_env.layout`); reverse
    Cuthill–McKee is used instead only where it gives a narrower band.
    """

    def __init__(self, matrix: sp.spmatrix) -> None:
        A = sp.csr_matrix(matrix)
        coo = A.tocoo()
        natural = int(np.max(np.abs(coo.row - coo.col)))
        rcm = reverse_cuthill_mckee(A, symmetric_mode=True)
        Ar = A[rcm][:, rcm].tocoo()
        if int(np.max(np.abs(Ar.row - Ar.col))) < natural:
            self.perm: np.ndarray | None = rcm
            coo = Ar
        else:
            self.perm = None
        upper = coo.row <= coo.col
        rows, cols, vals = coo.row[upper], coo.col[upper], coo.data[upper]
        self.bandwidth = int(np.max(cols - rows))
        ab = np.zeros((self.bandwidth + 1, A.shape[0]))
        ab[self.bandwidth + rows - cols, cols] = vals
        self.factor = sla.cholesky_banded(ab, lower=False, check_finite=False)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        if self.perm is None:
            return sla.cho_solve_banded((self.factor, False), rhs, check_finite=False)
        out = np.empty_like(rhs)
        out[self.perm] = sla.cho_solve_banded((self.factor, False), rhs[self.perm], check_finite=False)
        return out


@dataclass(frozen=True)
class PreparedPassage:
    """The design's part of the fast method, computed once per design and time step.

    Attributes
    ----------
    system : LinearSystem
    constants : NewmarkConstants
    factor : BandedCholesky
        Of K̂ = (1 + β a1) K + (a0 + α a1) M.
    dropper_response : ndarray (n, D)
        W = K̂⁻¹ Bᵀ, responses to unit dropper force pairs.
    dropper_flexibility : ndarray (D, D)
        G = B W, dropper elongations per unit dropper force.
    """

    system: LinearSystem
    constants: NewmarkConstants
    factor: BandedCholesky
    dropper_response: np.ndarray
    dropper_flexibility: np.ndarray


def prepare_passage(system: LinearSystem, time_step: float) -> PreparedPassage:
    """Factorise K̂ and compute the unit dropper responses (SPEC 3.6)."""
    nm = NewmarkConstants.for_step(time_step)
    factor = BandedCholesky((1.0 + system.beta * nm.a1) * system.stiffness
                            + (nm.a0 + system.alpha * nm.a1) * system.mass)
    B = system.dropper_elongation
    W = factor.solve(B.T.toarray())
    return PreparedPassage(system, nm, factor, W, np.asarray(B @ W))


def simulate_passage(
    system: LinearSystem,
    pantograph: PantographDefinition,
    uplift_force: float,
    speed: float,
    time_step: float,
    n_steps: int | None = None,
    progress: Callable[[float], None] | None = None,
    prepared: PreparedPassage | None = None,
) -> Trajectory:
    """Pantograph passage over the whole section at constant ``speed`` (m/s), fast method.

    Parameters
    ----------
    uplift_force : float
        Static uplift force on the pantograph's bottom mass, N.
    time_step : float
        Newmark step, s.
    n_steps : int, optional
        Stop after this many steps (the whole section by default).
    progress : callable, optional
        Called with the fraction done, about a hundred times.
    prepared : PreparedPassage, optional
        From :func:`prepare_passage` with the same system and time step, to reuse it.
    """
    if prepared is None:
        prepared = prepare_passage(system, time_step)
    if prepared.system is not system or prepared.constants.dt != time_step:
        raise ValueError("prepared: computed for another system or time step")
    lay = system.static.layout
    cat = lay.catenary
    nm = prepared.constants
    M, K = system.mass, system.stiffness
    alpha, beta = system.alpha, system.beta
    factor, W, G = prepared.factor, prepared.dropper_response, prepared.dropper_flexibility
    B = system.dropper_elongation
    rate, N0 = system.dropper_rate, system.dropper_force
    kappa = rate * (1.0 + beta * nm.a1)

    pm = pantograph_matrices(pantograph)
    head = pm.head
    Kp_hat = pm.stiffness + nm.a1 * pm.damping + nm.a0 * pm.mass
    Kp_inv = np.linalg.inv(Kp_hat)
    y_star = Kp_inv[:, head]  # pantograph response to a unit downward head force (negated)
    load_p = np.zeros(pm.mass.shape[0])
    load_p[0] = uplift_force

    time, position = passage_positions(lay.n_spans * lay.span_length, speed, time_step)
    if n_steps is not None:
        time, position = time[:n_steps], position[:n_steps]
    n_steps = time.size
    element, shape, wire_z = system.contact_wire.locate(position)
    wire_z = wire_z - cat.contact_wire_height  # static height above nominal
    kh = cat.contact_stiffness

    n = system.n_dofs
    u, v = np.zeros(n), np.zeros(n)
    y, yd = static_contact(pm, uplift_force, kh, wire_z[0])[0], np.zeros(head + 1)
    ydd = np.zeros(head + 1)
    f0 = kh * max(0.0, y[head] - wire_z[0])
    # Consistent initial acceleration: the catenary starts at rest under the initial contact force.
    z0 = system.contact_wire.z_dofs[element[0]]
    load0 = np.zeros(n)
    np.add.at(load0, z0, shape[0] * f0)
    a = spla.spsolve(M.tocsc(), load0)

    force = np.zeros(n_steps)
    force[0] = f0
    head_h = np.zeros(n_steps)
    head_h[0] = y[head]
    uplift = np.zeros(n_steps)
    supports = np.zeros((n_steps, system.support_z.size))
    d_min = N0.copy()
    d_max = N0.copy()
    contact = f0 > 0.0
    slack = np.zeros(N0.size, dtype=bool)
    slack_steps = unresolved = 0
    current_element = -1
    c1, c2, c3 = nm.a0 + alpha * nm.a1, nm.a2 + alpha * nm.a4, nm.a3 + alpha * nm.a5
    d1, d2, d3 = beta * nm.a1, beta * nm.a4, beta * nm.a5
    report_every = max(1, n_steps // 100)

    for k in range(1, n_steps):
        if progress is not None and k % report_every == 0:
            progress(k / n_steps)
        rhs = M @ (c1 * u + c2 * v + c3 * a) + K @ (d1 * u + d2 * v + d3 * a)
        u_known = factor.solve(rhs)
        e = element[k]
        if e != current_element:
            zd = system.contact_wire.z_dofs[e]
            unit = np.zeros((n, 4))
            unit[zd, np.arange(4)] = 1.0
            P = factor.solve(unit)
            Pzz, Wz = P[zd], W[zd]
            current_element = e
        h = shape[k]
        u_c = P @ h
        g_dc = Wz.T @ h
        c_cc = h @ Pzz @ h + y_star[head]
        rhs_p = pm.mass @ (nm.a0 * y + nm.a2 * yd + nm.a3 * ydd) + pm.damping @ (nm.a1 * y + nm.a4 * yd + nm.a5 * ydd)
        y_known = Kp_inv @ (rhs_p + load_p)
        gap_known = y_known[head] - wire_z[k] - h @ u_known[zd]
        dl_known = B @ u_known
        rate_term = beta * rate * (B @ (nm.a1 * u + nm.a4 * v + nm.a5 * a))

        for iteration in range(MAX_ACTIVE_SET_ITERATIONS):
            idx = np.flatnonzero(slack)
            m = idx.size
            A = np.eye(1 + m)
            r = np.zeros(1 + m)
            if contact:
                A[0, 0] = 1.0 + kh * c_cc
                A[0, 1:] = kh * g_dc[idx]
                r[0] = kh * gap_known
            if m:
                A[1:, 0] = -kappa[idx] * g_dc[idx]
                A[1:, 1:] -= kappa[idx, None] * G[np.ix_(idx, idx)]
                r[1:] = N0[idx] + kappa[idx] * dl_known[idx] - rate_term[idx]
            sol = np.linalg.solve(A, r) if m else r / A[0, 0]
            f, lam = sol[0], sol[1:]
            dl = dl_known + g_dc * f + G[:, idx] @ lam
            elastic = N0 + kappa * dl - rate_term  # spring plus damping share
            gap = gap_known - c_cc * f - g_dc[idx] @ lam
            new_contact = bool(gap > 0.0)
            new_slack = elastic < 0.0
            if new_contact == contact and np.array_equal(new_slack, slack):
                break
            contact, slack = switch_states(contact, slack, new_contact, new_slack, kh * gap, elastic, iteration)
        else:
            unresolved += 1

        u_new = u_known + u_c * f + W[:, idx] @ lam
        y_new = y_known - f * y_star
        v, a = nm.update(u, v, a, u_new)
        yd, ydd = nm.update(y, yd, ydd, y_new)
        u, y = u_new, y_new
        force[k] = f
        head_h[k] = y[head]
        uplift[k] = h @ u[zd]
        supports[k] = u[system.support_z]
        dropper = np.where(slack, 0.0, elastic)
        np.minimum(d_min, dropper, out=d_min)
        np.maximum(d_max, dropper, out=d_max)
        slack_steps += bool(m)

    if progress is not None:
        progress(1.0)
    return Trajectory(
        time=time,
        position=position,
        contact_force=force,
        head_height=head_h,
        wire_uplift=uplift,
        support_x=lay.support_x.copy(),
        support_uplift=supports,
        dropper_force_min=d_min,
        dropper_force_max=d_max,
        slack_steps=slack_steps,
        unresolved_steps=unresolved,
    )
