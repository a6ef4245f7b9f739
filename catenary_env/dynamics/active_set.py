"""The step's contact force and slack droppers: the active-set rules every passage backend follows.

docs/model.md, 'Time integration and the fast method'. Given what the step would be without the
two nonlinear forces (the contact gap ``gap_known``, the droppers' elongations ``dl_known``), and
the one-step compliances (the contact point's ``c_cc``, the droppers' ``g_dc`` to the contact and
``G`` among themselves), find the contact force f ≥ 0 and the slack droppers' forces λ that cancel
their whole linear force (spring and damping share). Each step is a linear complementarity problem
with a P-matrix, so its solution is unique; the iteration below finds it.

The numpy loops call :func:`settle`; the compiled ones (``_kernels._settle``) follow the same rules
with these constants.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

MAX_ACTIVE_SET_ITERATIONS = 40
FULL_SWITCH_ITERATIONS = 8


def switch_states(
    contact: bool,
    slack: np.ndarray,
    new_contact: bool,
    new_slack: np.ndarray,
    contact_force: float,
    elastic: np.ndarray,
    iteration: int,
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


class Settled(NamedTuple):
    """The step's nonlinear forces.

    contact : bool
    slack : ndarray (D,) of bool
    force : float
        Contact force f, N.
    slack_droppers : ndarray (m,) of int
        The slack droppers' indices.
    slack_forces : ndarray (m,)
        Their forces λ, N.
    dropper_forces : ndarray (D,)
        Every dropper's linear force (spring plus damping share), N; a slack dropper transmits none.
    resolved : bool
        False when the iteration limit was reached.
    """

    contact: bool
    slack: np.ndarray
    force: float
    slack_droppers: np.ndarray
    slack_forces: np.ndarray
    dropper_forces: np.ndarray
    resolved: bool


def settle(
    contact: bool,
    slack: np.ndarray,
    gap_known: float,
    c_cc: float,
    g_dc: np.ndarray,
    dl_known: np.ndarray,
    rate_term: np.ndarray,
    contact_stiffness: float,
    kappa: np.ndarray,
    static_force: np.ndarray,
    flexibility: np.ndarray,
) -> Settled:
    """The contact force and slack droppers of one step, starting from the last step's state.

    Parameters
    ----------
    gap_known : float
        Head minus wire height without the step's contact and dropper forces, m.
    c_cc : float
        The contact point's compliance, m/N (the wire's and the pantograph head's).
    g_dc : ndarray (D,)
        The droppers' elongations per unit contact force, m/N.
    dl_known, rate_term : ndarray (D,)
        The droppers' elongations without the step's forces, m, and their damping share, N.
    contact_stiffness : float
        k_h, N/m.
    kappa, static_force : ndarray (D,)
        k (1 + β a1), N/m, and the static forces N₀, N.
    flexibility : ndarray (D, D)
        G, dropper elongations per unit dropper force, m/N.
    """
    kh, N0, G = contact_stiffness, static_force, flexibility
    resolved = False
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
            resolved = True
            break
        contact, slack = switch_states(contact, slack, new_contact, new_slack, kh * gap, elastic, iteration)
    return Settled(contact, slack, float(f), idx, lam, elastic, resolved)
