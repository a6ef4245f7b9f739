"""The step's contact force and slack droppers: the active-set rules every passage backend follows.

docs/model.md, 'Time integration and the fast method'. Given what the step would be without the
two nonlinear forces (the contact gap ``gap_known``, the droppers' elongations ``dl_known``), and
the one-step compliances (the contact point's ``c_cc``, the droppers' ``g_dc`` to the contact and
``G`` among themselves), find the contact force f ≥ 0 and the slack droppers' forces λ that cancel
their whole linear force (spring and damping share). Each step is a linear complementarity problem
with a P-matrix, so its solution is unique; the iteration below finds it.

The rules are written here only, twice side by side: :func:`settle` in numpy for the numpy loops and
:func:`settle_in_place` in scalar loops, which numba compiles into both models' compiled loops
(:mod:`~catenary_env.dynamics.compilable`). A change of the contact or slack-dropper rule changes both, here;
the numba = numpy tests hold them together (to 1e-9 N).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .compilable import compilable

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


class Droppers(NamedTuple):
    """The droppers as the active set sees them (D,): spring rates k (N/m), static forces N₀ (N) and
    κ = k (1 + β a1) (N/m), the rate of their whole linear force in a step's elongation."""

    rate: np.ndarray
    force: np.ndarray
    kappa: np.ndarray

    @classmethod
    def for_step(cls, rate: np.ndarray, force: np.ndarray, beta: float, a1: float) -> Droppers:
        """For the system's rates and static forces, Rayleigh β (s) and Newmark's a1 (1/s)."""
        rate = np.asarray(rate, dtype=float)
        return cls(rate, np.asarray(force, dtype=float), rate * (1.0 + beta * a1))


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
    droppers: Droppers,
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
    droppers : Droppers
    flexibility : ndarray (D, D)
        G, dropper elongations per unit dropper force, m/N.
    """
    kh, N0, kappa, G = contact_stiffness, droppers.force, droppers.kappa, flexibility
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


@compilable()
def settle_workspace(n_droppers):  # noqa: ANN001, ANN201 - compilable
    """The arrays :func:`settle_in_place` works in, for ``n_droppers`` droppers: A, r, λ, the slack
    indices, the droppers' forces and the new slack states."""
    return (
        np.zeros((n_droppers + 1, n_droppers + 1)),
        np.zeros(n_droppers + 1),
        np.zeros(n_droppers),
        np.zeros(n_droppers, dtype=np.int64),
        np.zeros(n_droppers),
        np.zeros(n_droppers, dtype=np.bool_),
    )


@compilable()
def _small_solve(A, r, size):  # noqa: ANN001, ANN202 - compilable
    """Gaussian elimination with partial pivoting on A[:size, :size]; the solution overwrites r."""
    for col in range(size):
        p = col
        for i in range(col + 1, size):
            if abs(A[i, col]) > abs(A[p, col]):
                p = i
        if p != col:
            for j in range(size):
                A[col, j], A[p, j] = A[p, j], A[col, j]
            r[col], r[p] = r[p], r[col]
        for i in range(col + 1, size):
            factor = A[i, col] / A[col, col]
            for j in range(col, size):
                A[i, j] -= factor * A[col, j]
            r[i] -= factor * r[col]
    for i in range(size - 1, -1, -1):
        s = r[i]
        for j in range(i + 1, size):
            s -= A[i, j] * r[j]
        r[i] = s / A[i, i]


@compilable()
def _step_system(contact, slack, gap_known, c_cc, g_dc, dl_known, rate_term, kh, droppers, G, work):  # noqa: ANN001, ANN202
    """Fill A, r of :func:`settle`'s system for the current states and solve it; returns f and m (λ and the
    slack droppers' indices in ``work``)."""
    A, r, lam, idx = work[0], work[1], work[2], work[3]
    kappa, N0 = droppers.kappa, droppers.force
    m = 0
    for q in range(slack.size):
        if slack[q]:
            idx[m] = q
            m += 1
    for i in range(m + 1):
        for j in range(m + 1):
            A[i, j] = 1.0 if i == j else 0.0
        r[i] = 0.0
    if contact:
        A[0, 0] = 1.0 + kh * c_cc
        for i in range(m):
            A[0, 1 + i] = kh * g_dc[idx[i]]
        r[0] = kh * gap_known
    for i in range(m):
        q = idx[i]
        A[1 + i, 0] = -kappa[q] * g_dc[q]
        for j in range(m):
            A[1 + i, 1 + j] -= kappa[q] * G[q, idx[j]]
        r[1 + i] = N0[q] + kappa[q] * dl_known[q] - rate_term[q]
    if m:
        _small_solve(A, r, m + 1)
    else:
        r[0] = r[0] / A[0, 0]
    for i in range(m):
        lam[i] = r[1 + i]
    return r[0], m


@compilable()
def settle_in_place(contact, slack, gap_known, c_cc, g_dc, dl_known, rate_term, kh, droppers, G, work):  # noqa: ANN001, ANN201
    """:func:`settle` in scalar loops, for the compiled loops; ``work`` from :func:`settle_workspace`.

    Returns (contact, f, m, resolved); ``slack`` is updated in place, and ``work`` holds λ and the slack
    droppers' indices in ``lam[:m]``, ``idx[:m]``, and the droppers' forces in ``elastic``.
    """
    lam, idx, elastic, new_slack = work[2], work[3], work[4], work[5]
    kappa, N0 = droppers.kappa, droppers.force
    n_drop = slack.size
    f = 0.0
    m = 0
    for iteration in range(MAX_ACTIVE_SET_ITERATIONS):
        f, m = _step_system(contact, slack, gap_known, c_cc, g_dc, dl_known, rate_term, kh, droppers, G, work)
        gap = gap_known - c_cc * f
        for i in range(m):
            gap -= g_dc[idx[i]] * lam[i]
        changed = False
        for q in range(n_drop):
            dl = dl_known[q] + g_dc[q] * f
            for i in range(m):
                dl += G[q, idx[i]] * lam[i]
            elastic[q] = N0[q] + kappa[q] * dl - rate_term[q]  # spring plus damping share
            new_slack[q] = elastic[q] < 0.0
            changed = changed or new_slack[q] != slack[q]
        new_contact = gap > 0.0
        if new_contact == contact and not changed:
            return contact, f, m, True
        if iteration < FULL_SWITCH_ITERATIONS:  # as switch_states
            contact = new_contact
            for q in range(n_drop):
                slack[q] = new_slack[q]
        else:
            worst = -1
            violation = 0.0
            for q in range(n_drop):
                if new_slack[q] != slack[q] and (worst < 0 or abs(elastic[q]) > violation):
                    worst = q
                    violation = abs(elastic[q])
            if (abs(kh * gap) if new_contact != contact else 0.0) >= violation:
                contact = new_contact
            else:
                slack[worst] = not slack[worst]
    return contact, f, m, False
