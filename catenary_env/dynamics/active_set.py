"""The step's contact force and slack droppers: the active-set rules every passage backend follows.

docs/model.md, 'Time integration and the fast method'. Given what the step would be without the
two nonlinear forces (the contact gap ``gap_known``, the droppers' elongations ``dl_known``), and
the one-step compliances (the contact points' ``c_cc`` among themselves, the droppers' ``g_dc`` to
the contact points and ``G`` among themselves), find the contact forces f ≥ 0 of every pantograph and
the slack droppers' forces λ that cancel their whole linear force (spring and damping share). Each step
is a linear complementarity problem with a P-matrix, so its solution is unique; the iteration below finds it.

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
    contact: np.ndarray,
    slack: np.ndarray,
    new_contact: np.ndarray,
    new_slack: np.ndarray,
    contact_forces: np.ndarray,
    elastic: np.ndarray,
    iteration: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Next contact / slack-dropper states of the active-set iteration.

    The first iterations switch every inconsistent state at once (Newton's method on the
    piecewise-linear problem, quadratic when it works); should that cycle, later iterations switch
    only the most violated one (a contact, by its force k_h gap, or a dropper), which cannot cycle on
    this problem's P-matrix.
    """
    if iteration < FULL_SWITCH_ITERATIONS:
        return new_contact, new_slack
    violation = np.where(new_slack != slack, np.abs(elastic), 0.0)
    contact_violation = np.where(new_contact != contact, np.abs(contact_forces), 0.0)
    if contact_violation.max() >= violation.max(initial=0.0):
        contact = contact.copy()
        worst = int(np.argmax(contact_violation))
        contact[worst] = new_contact[worst]
        return contact, slack
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
    """The step's nonlinear forces. P contact points, D droppers.

    contact : ndarray (P,) of bool
    slack : ndarray (D,) of bool
    force : ndarray (P,)
        Contact forces f, N.
    slack_droppers : ndarray (m,) of int
        The slack droppers' indices.
    slack_forces : ndarray (m,)
        Their forces λ, N.
    dropper_forces : ndarray (D,)
        Every dropper's linear force (spring plus damping share), N; a slack dropper transmits none.
    resolved : bool
        False when the iteration limit was reached.
    """

    contact: np.ndarray
    slack: np.ndarray
    force: np.ndarray
    slack_droppers: np.ndarray
    slack_forces: np.ndarray
    dropper_forces: np.ndarray
    resolved: bool


def settle(
    contact: np.ndarray,
    slack: np.ndarray,
    gap_known: np.ndarray,
    c_cc: np.ndarray,
    g_dc: np.ndarray,
    dl_known: np.ndarray,
    rate_term: np.ndarray,
    contact_stiffness: float,
    droppers: Droppers,
    flexibility: np.ndarray,
) -> Settled:
    """The contact forces and slack droppers of one step, starting from the last step's state.

    Parameters
    ----------
    contact : ndarray (P,) of bool
        Each contact point's last contact state.
    gap_known : ndarray (P,)
        Head minus wire height without the step's contact and dropper forces, m.
    c_cc : ndarray (P, P)
        The contact points' compliances, m/N: the wire's at each point under a unit force at each point,
        plus the pantograph head's own on the diagonal.
    g_dc : ndarray (P, D)
        The droppers' elongations per unit contact force at each point, m/N.
    dl_known, rate_term : ndarray (D,)
        The droppers' elongations without the step's forces, m, and their damping share, N.
    contact_stiffness : float
        k_h, N/m.
    droppers : Droppers
    flexibility : ndarray (D, D)
        G, dropper elongations per unit dropper force, m/N.
    """
    kh, N0, kappa, G = contact_stiffness, droppers.force, droppers.kappa, flexibility
    n_c = gap_known.size
    points = np.arange(n_c)
    resolved = False
    for iteration in range(MAX_ACTIVE_SET_ITERATIONS):
        idx = np.flatnonzero(slack)
        m = idx.size
        A = np.eye(n_c + m)
        r = np.zeros(n_c + m)
        touching = points[contact]
        A[touching, :n_c] = kh * c_cc[touching]
        A[touching, touching] += 1.0
        A[np.ix_(touching, n_c + np.arange(m))] = kh * g_dc[np.ix_(touching, idx)]
        r[touching] = kh * gap_known[touching]
        if m:
            A[n_c:, :n_c] = -kappa[idx, None] * g_dc[:, idx].T
            A[n_c:, n_c:] -= kappa[idx, None] * G[np.ix_(idx, idx)]
            r[n_c:] = N0[idx] + kappa[idx] * dl_known[idx] - rate_term[idx]
        sol = np.linalg.solve(A, r) if m or n_c > 1 else r / A[0, 0]
        f, lam = sol[:n_c], sol[n_c:]
        dl = dl_known + g_dc.T @ f + G[:, idx] @ lam
        elastic = N0 + kappa * dl - rate_term  # spring plus damping share
        gap = gap_known - c_cc @ f - g_dc[:, idx] @ lam
        new_contact = gap > 0.0
        new_slack = elastic < 0.0
        if np.array_equal(new_contact, contact) and np.array_equal(new_slack, slack):
            resolved = True
            break
        contact, slack = switch_states(contact, slack, new_contact, new_slack, kh * gap, elastic, iteration)
    return Settled(contact, slack, f, idx, lam, elastic, resolved)


@compilable()
def settle_workspace(n_points, n_droppers):  # noqa: ANN001, ANN201 - compilable
    """The arrays :func:`settle_in_place` works in, for ``n_points`` contact points and ``n_droppers``
    droppers: A, r, λ, the slack indices, the droppers' forces, the new slack states, the contact forces f,
    the new contact states and the gaps."""
    size = n_points + n_droppers
    return (
        np.zeros((size, size)),
        np.zeros(size),
        np.zeros(n_droppers),
        np.zeros(n_droppers, dtype=np.int64),
        np.zeros(n_droppers),
        np.zeros(n_droppers, dtype=np.bool_),
        np.zeros(n_points),
        np.zeros(n_points, dtype=np.bool_),
        np.zeros(n_points),
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
    """Fill A, r of :func:`settle`'s system for the current states and solve it; returns m (f, λ and the
    slack droppers' indices in ``work``)."""
    A, r, lam, idx, f = work[0], work[1], work[2], work[3], work[6]
    kappa, N0 = droppers.kappa, droppers.force
    n_c = gap_known.size
    m = 0
    for q in range(slack.size):
        if slack[q]:
            idx[m] = q
            m += 1
    size = n_c + m
    for i in range(size):
        for j in range(size):
            A[i, j] = 1.0 if i == j else 0.0
        r[i] = 0.0
    for p in range(n_c):
        if contact[p]:
            for q in range(n_c):
                A[p, q] = 1.0 + kh * c_cc[p, p] if q == p else kh * c_cc[p, q]
            for i in range(m):
                A[p, n_c + i] = kh * g_dc[p, idx[i]]
            r[p] = kh * gap_known[p]
    for i in range(m):
        q = idx[i]
        for p in range(n_c):
            A[n_c + i, p] = -kappa[q] * g_dc[p, q]
        for j in range(m):
            A[n_c + i, n_c + j] -= kappa[q] * G[q, idx[j]]
        r[n_c + i] = N0[q] + kappa[q] * dl_known[q] - rate_term[q]
    if m or n_c > 1:
        _small_solve(A, r, size)
    else:
        r[0] = r[0] / A[0, 0]
    for p in range(n_c):
        f[p] = r[p]
    for i in range(m):
        lam[i] = r[n_c + i]
    return m


@compilable()
def settle_in_place(  # noqa: C901
    contact, slack, gap_known, c_cc, g_dc, dl_known, rate_term, kh, droppers, G, work, ready, first
):  # noqa: ANN001, ANN201
    """:func:`settle` in scalar loops, for the compiled loops; ``work`` from :func:`settle_workspace`.

    Returns (m, resolved, pending); ``contact`` and ``slack`` are updated in place, and ``work`` holds λ and
    the slack droppers' indices in ``lam[:m]``, ``idx[:m]``, the droppers' forces in ``elastic`` and the
    contact forces in ``f``. It reads G's rows of the slack droppers only. ``ready`` marks the rows G
    holds, for a caller that fills them as droppers go slack: the slack droppers' rows are to be ready as
    it starts (iteration ``first``, 0 for a new step). When an iteration makes a dropper slack whose row is
    not, it stops with that iteration's states in ``contact`` and ``slack`` and returns ``pending``, the
    next iteration's number: the caller fills the rows of the slack droppers and calls again with ``first =
    pending``, which goes on as if it had not stopped. ``pending`` is -1 once it is done.
    """
    lam, idx, elastic, new_slack, f, new_contact, gap = (
        work[2],
        work[3],
        work[4],
        work[5],
        work[6],
        work[7],
        work[8],
    )
    kappa, N0 = droppers.kappa, droppers.force
    n_drop = slack.size
    n_c = gap_known.size
    m = 0
    for iteration in range(first, MAX_ACTIVE_SET_ITERATIONS):
        m = _step_system(contact, slack, gap_known, c_cc, g_dc, dl_known, rate_term, kh, droppers, G, work)
        changed = False
        for p in range(n_c):
            g = gap_known[p]
            for q in range(n_c):
                g -= c_cc[p, q] * f[q]
            for i in range(m):
                g -= g_dc[p, idx[i]] * lam[i]
            gap[p] = g
            new_contact[p] = g > 0.0
            changed = changed or new_contact[p] != contact[p]
        for q in range(n_drop):
            elastic[q] = dl_known[q]
        for p in range(n_c):
            fp = f[p]
            row = g_dc[p]
            for q in range(n_drop):
                elastic[q] += row[q] * fp
        # G is symmetric (to rounding): the slack droppers' rows, each read along, not their columns, whose
        # every entry lies on a cache line of its own (docs/performance.md, 'Speed').
        for i in range(m):
            row = G[idx[i]]
            for q in range(n_drop):
                elastic[q] += row[q] * lam[i]
        switched = 0  # an integer sum, not a logical or, so that the loop vectorises
        for q in range(n_drop):
            force = N0[q] + kappa[q] * elastic[q] - rate_term[q]  # spring plus damping share
            elastic[q] = force
            new_slack[q] = force < 0.0
            switched += new_slack[q] != slack[q]
        if not changed and switched == 0:
            return m, True, -1
        missing = False  # a dropper gone slack whose row of G is not ready
        if iteration < FULL_SWITCH_ITERATIONS:  # as switch_states
            for p in range(n_c):
                contact[p] = new_contact[p]
            for q in range(n_drop):
                slack[q] = new_slack[q]
                missing = missing or (slack[q] and not ready[q])
        else:
            worst = -1
            violation = 0.0
            for q in range(n_drop):
                if new_slack[q] != slack[q] and (worst < 0 or abs(elastic[q]) > violation):
                    worst = q
                    violation = abs(elastic[q])
            worst_point = -1
            contact_violation = 0.0
            for p in range(n_c):
                if new_contact[p] != contact[p] and (worst_point < 0 or abs(kh * gap[p]) > contact_violation):
                    worst_point = p
                    contact_violation = abs(kh * gap[p])
            if contact_violation >= violation:
                if worst_point >= 0:
                    contact[worst_point] = new_contact[worst_point]
            else:
                slack[worst] = not slack[worst]
                missing = slack[worst] and not ready[worst]
        if missing and iteration + 1 < MAX_ACTIVE_SET_ITERATIONS:
            return m, False, iteration + 1
    return m, False, -1
