"""The straightforward pantograph passage, kept as the test oracle of the fast method (docs/model.md, 'Time
integration and the fast method').

Every time step re-assembles the coupled catenary–pantograph system with the current contact and
slack-dropper states (contact as a penalty spring between the head and the contact wire, slack
droppers removed with their damping) and solves it with a sparse direct solver, iterating until
the states are consistent: Newton's method on the piecewise-linear problem. No superposition, no
pre-computed responses, no factorisation reused between steps. Slow by design; use it on short
sections only.

It takes the system's damping matrix as it is, so it also integrates the modelling choices the fast
loops do not (:attr:`~catenary_env.dynamics.linear_system.LinearSystem.rayleigh`); it is the exact model's
``"oracle"`` backend (:mod:`~catenary_env.dynamics.exact.passage`): Rayleigh damping over
the wires only, and slack droppers that keep their damping (only their spring force is removed, and
slackness is judged on it).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..active_set import MAX_ACTIVE_SET_ITERATIONS, switch_states
from ..contact_point import StartedPoint
from ..history import PassageHistory, record
from ..pantograph import pantograph_matrices
from ..protocol import ContactPoint
from .preparation import PreparedExact


def run_steps(
    prepared: PreparedExact,
    point: ContactPoint,
    started: StartedPoint,
    history: PassageHistory,
    progress: Callable[[float], None] | None,
) -> None:
    """The whole passage of the contact point ``started`` (from ``point``), into ``history``."""
    system, nm = prepared.system, prepared.constants
    cat = system.static.layout.catenary
    M, K = system.mass.tocsr(), system.stiffness.tocsr()
    C = system.damping
    B = system.dropper_elongation.tocsr()
    rate, N0, beta = system.dropper_rate, system.dropper_force, system.beta
    # The damping share a slack dropper drops with its spring: β k, or none where it keeps its damping.
    beta_slack = 0.0 if system.slack_dropper_damping else beta
    pm = pantograph_matrices(point.pantograph)
    head = pm.head
    n, n_p = system.n_dofs, pm.mass.shape[0]
    kh = cat.contact_stiffness
    element, shape, wire_z = started.arrays.element, started.arrays.shape, started.arrays.wire_z

    # Effective matrices of the coupled system [u; y] without contact and with every dropper taut.
    Khat = K + nm.a1 * C + nm.a0 * M
    Kp_hat = pm.stiffness + nm.a1 * pm.damping + nm.a0 * pm.mass
    base = sp.block_diag([Khat, sp.csr_matrix(Kp_hat)]).tocsr()
    M_all = sp.block_diag([M, sp.csr_matrix(pm.mass)]).tocsr()
    C_all = sp.block_diag([C, sp.csr_matrix(pm.damping)]).tocsr()

    U = np.r_[np.zeros(n), started.state.y]
    V = np.zeros(n + n_p)
    N_row0 = np.zeros(n + n_p)
    N_row0[system.contact_wire.z_dofs[element[0]]] = shape[0]
    A = np.r_[spla.spsolve(M.tocsc(), N_row0[:n] * started.force0), np.zeros(n_p)]

    steps = element.size
    report_every = max(1, steps // 100)
    contact, slack = np.array([started.force0 > 0.0]), np.zeros(N0.size, dtype=bool)
    for k in range(1, steps):
        if progress is not None and k % report_every == 0:
            progress(k / steps)
        rhs = M_all @ (nm.a0 * U + nm.a2 * V + nm.a3 * A) + C_all @ (nm.a1 * U + nm.a4 * V + nm.a5 * A)
        rhs[n] += point.frame_force
        # Contact row: the wire's height at the pantograph is N·u, the head's is y_head.
        N_row = np.zeros(n + n_p)
        N_row[system.contact_wire.z_dofs[element[k]]] = shape[k]
        N_row[n + head] = -1.0  # N_row · U = wire uplift - head height
        velocity_part = B @ (nm.a1 * U[:n] + nm.a4 * V[:n] + nm.a5 * A[:n])
        resolved = False
        for iteration in range(MAX_ACTIVE_SET_ITERATIONS):
            matrix = base.copy()
            r = rhs.copy()
            if contact[0]:
                # f = kh (y_head - wire_z - N u), acting up on the wire and down on the head.
                on = np.flatnonzero(N_row)
                outer = np.outer(N_row[on], N_row[on]).ravel()
                rows, cols = np.repeat(on, on.size), np.tile(on, on.size)
                matrix = matrix + kh * sp.csr_matrix((outer, (rows, cols)), shape=matrix.shape)
                r += kh * (-wire_z[k]) * N_row
            if np.any(slack):
                Bs = B[slack]
                k_s = rate[slack] * (1.0 + beta_slack * nm.a1)
                extra = sp.csr_matrix(Bs.T @ sp.diags(k_s) @ Bs)
                matrix = matrix - sp.block_diag([extra, sp.csr_matrix((n_p, n_p))])
                r[:n] += Bs.T @ (N0[slack] - beta_slack * rate[slack] * velocity_part[slack])
            U_new = spla.spsolve(matrix.tocsc(), r)
            gap = -(N_row @ U_new) - wire_z[k]
            elongation = B @ U_new[:n]
            elastic = N0 + rate * ((1.0 + beta_slack * nm.a1) * elongation - beta_slack * velocity_part)
            new_contact, new_slack = np.array([gap > 0.0]), elastic < 0.0
            if new_contact[0] == contact[0] and np.array_equal(new_slack, slack):
                resolved = True
                break
            contact, slack = switch_states(
                contact, slack, new_contact, new_slack, np.array([kh * gap]), elastic, iteration
            )
        V, A = nm.update(U, V, A, U_new)
        U = U_new
        record(
            history,
            k,
            kh * gap if contact[0] else 0.0,
            U[n + head],
            shape[k] @ U[system.contact_wire.z_dofs[element[k]]],
            U[system.support_z],
            elastic,
            slack,
            bool(np.any(slack)),
            resolved,
        )
    if progress is not None:
        progress(1.0)
