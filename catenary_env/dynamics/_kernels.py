"""Compiled time loop of the fast pantograph passage (docs/performance.md, 'Benchmark'), with numba.

The same method as the numpy backend of :func:`catenary_env.dynamics.passage.simulate_passage`, step for
step: superposition of unit responses, one small contact / slack-dropper problem per step solved by
the same active-set iteration, so the two backends agree to rounding (about 1e-9 N on the contact
force). One compiled loop replaces a dozen numpy and LAPACK calls per step; the per-step work is
then one product with M, one banded solve with K̂'s factor and one Newmark update, each a single
pass over the DOFs. What the profile asked for, beyond compiling:

- No product with K: with Rayleigh damping K̂ = c_k K + c_m M (c_k = 1 + β a1, c_m = a0 + α a1),
  so K y = (K̂ y - c_m M y) / c_k and the Newmark right-hand side M x + K y gives

      u_known = K̂⁻¹ M (x - (c_m / c_k) y) + y / c_k,

  one product with the (sparser, constant) mass matrix per step instead of one with M and K.
- The factor is stored with a unit diagonal, K̂ = Ûᵀ D² Û: the forward sweep Ûᵀ z = b and the
  backward sweep Û x = D⁻² z need no division. Each sweep is a row-by-row dot product with the
  w unknowns found last, summed oldest first with the newest four kept in registers, so that the
  newest unknown reaches the next one through a single FMA (letting LLVM reassociate put the
  newest far unknown first in a chain of 16 FMAs, twice as slow). The forward sweep reads a second
  copy of Û by columns, in reverse row order so that its indices are the row plus a positive
  offset (see below). w is a compile-time constant, the length of the tuple ``width`` (one
  compiled version per band width, rounded up to WIDTH_STEP): LLVM unrolls the sums.
- A unit force's response K̂⁻¹ e decays away from the force (K̂ is dominated by M / (β Δt²)):
  below 1e-30 of its peak within some 1,500 to 3,000 DOFs on the study mesh (the axial waves decay
  slowest), a fifth of the 20-span section. The contact element's unit responses are computed,
  and the dropper responses applied, only there (TRUNCATION).

Indices into arrays are kept provably non-negative (or unsigned): numba tests a signed index for
wrap-around, which costs as much as the arithmetic in these loops. No slice assignment or ``@``
appears in the loop: their typing alone cost seconds of compile time.

numba is optional: :mod:`catenary_env.dynamics.passage` imports this module only for the numba backend.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, uint64

from .active_set import FULL_SWITCH_ITERATIONS, MAX_ACTIVE_SET_ITERATIONS
from .kernel_preparation import TRUNCATION

# Slots of the step coefficients (PassageArrays.coefficients; the span-mode loop's too): the right-hand
# side's e = E1 u + E2 v + E3 a and y = G1 u + G2 v + G3 a, Newmark's a0..a5, k_h, Rayleigh β, and for the
# span-mode loop c_m and 1 / c_k.
(
    E1,
    E2,
    E3,
    G1,
    G2,
    G3,
    A0,
    A1,
    A2,
    A3,
    A4,
    A5,
    CONTACT_STIFFNESS,
    RAYLEIGH_BETA,
    MASS_FACTOR,
    INVERSE_STIFFNESS_FACTOR,
) = range(16)
# Slots of PassageState.flags: in contact (0/1), current contact-wire element (-1: none yet), slack
# steps, unresolved steps, first and last row of the unit responses.
CONTACT, ELEMENT, SLACK_STEPS, UNRESOLVED, FIRST_ROW, LAST_ROW = range(6)


class PassageArrays(NamedTuple):
    """What the compiled loop reads, in the factor's DOF order. n DOFs, band width w, D droppers.

    Attributes
    ----------
    upper, lower, scale :
        K̂ = Ûᵀ D² Û by rows and by columns, and D⁻² (``kernel_preparation.unit_factor``).
    m_ptr, m_offset, m_values :
        Upper triangle of M by rows (``kernel_preparation.upper_rows``).
    b_ptr, b_index, b_values :
        CSR of the dropper elongation matrix B (D, n).
    dropper_response_t : ndarray (D, n)
        Wᵀ, C-contiguous.
    dropper_window : ndarray (D, 2)
        First and last DOF where each W_d is above 1e-30 of its largest entry (see
        :func:`unit_responses`); the rest is left out of u₁.
    dropper_flexibility : ndarray (D, D)
        G = B W.
    dropper_rate, dropper_force, dropper_kappa : ndarray (D,)
        k (N/m), N₀ (N), k (1 + β a1).
    z_dofs : ndarray (E, 4)
        Contact-wire z DOFs of each element.
    support_z : ndarray (S,)
    element : ndarray (steps,)
    shape : ndarray (steps, 4)
    wire_z : ndarray (steps,)
        Static contact-wire height at the pantograph, m above nominal.
    pantograph_inverse, pantograph_mass, pantograph_damping : ndarray (p, p)
        K̂_p⁻¹, M_p, C_p.
    y_star : ndarray (p,)
        Pantograph response to a unit downward head force (negated).
    load_p : ndarray (p,)
        Uplift force vector.
    coefficients : ndarray (16,)
        e1, e2, e3, g1, g2, g3, a0, a1, a2, a3, a4, a5, k_h, Rayleigh β, 0, 0: the step's
        right-hand side is M (e1 u + e2 v + e3 a) and y / c_k = g1 u + g2 v + g3 a
        (built in :func:`catenary_env.dynamics.passage._kernel_arrays`).
    """

    upper: np.ndarray
    lower: np.ndarray
    scale: np.ndarray
    m_ptr: np.ndarray
    m_offset: np.ndarray
    m_values: np.ndarray
    b_ptr: np.ndarray
    b_index: np.ndarray
    b_values: np.ndarray
    dropper_response_t: np.ndarray
    dropper_window: np.ndarray
    dropper_flexibility: np.ndarray
    dropper_rate: np.ndarray
    dropper_force: np.ndarray
    dropper_kappa: np.ndarray
    z_dofs: np.ndarray
    support_z: np.ndarray
    element: np.ndarray
    shape: np.ndarray
    wire_z: np.ndarray
    pantograph_inverse: np.ndarray
    pantograph_mass: np.ndarray
    pantograph_damping: np.ndarray
    y_star: np.ndarray
    load_p: np.ndarray
    coefficients: np.ndarray


class PassageState(NamedTuple):
    """What the compiled loop updates: the state after the last step done, and the histories.

    Attributes
    ----------
    u, v, a : ndarray (n,)
        Catenary displacement, velocity, acceleration.
    x, y : ndarray (n,)
        The next step's u_known is K̂⁻¹ M x + y (PassageArrays.coefficients).
    work : ndarray (n + w,)
        Right-hand side M x, then K̂⁻¹ M x, then u₁ - y.
    sweep : ndarray (n + w,)
        The forward sweep's unknowns, in reverse order.
    unit : ndarray (n + w, 4)
        Unit responses of the current contact-wire element, non-zero in rows flags[FIRST_ROW] to
        flags[LAST_ROW].
    y_p, yd_p, ydd_p : ndarray (p,)
        Pantograph state.
    slack : ndarray (D,) of bool
    flags : ndarray (6,) of int
        Contact (0/1), current contact-wire element (-1: none yet), slack steps, unresolved steps,
        first and last row of ``unit``.
    force, head_height, wire_uplift, support_uplift, dropper_min, dropper_max :
        The histories and extremes of :class:`~catenary_env.dynamics.newmark.Trajectory`.
    """

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    x: np.ndarray
    y: np.ndarray
    work: np.ndarray
    sweep: np.ndarray
    unit: np.ndarray
    y_p: np.ndarray
    yd_p: np.ndarray
    ydd_p: np.ndarray
    slack: np.ndarray
    flags: np.ndarray
    force: np.ndarray
    head_height: np.ndarray
    wire_uplift: np.ndarray
    support_uplift: np.ndarray
    dropper_min: np.ndarray
    dropper_max: np.ndarray


@njit(cache=True, fastmath={"contract"})
def symmetric_product(ptr, offset, values, x, out, width):  # pragma: no cover - compiled
    """out = A x from A's upper triangle (``kernel_preparation.upper_rows``); out (n + w,), its last w
    entries zeroed."""
    w = len(width)
    n = ptr.size - 1
    for i in range(w):
        out[i] = 0.0
    for i in range(n):
        out[i + w] = 0.0  # row i is the first to add to row i + w
        xi = x[i]
        q0 = ptr[i]
        t = out[i] + values[q0] * xi
        for q in range(q0 + 1, ptr[i + 1]):
            j = i + offset[q]
            t += values[q] * x[j]
            out[j] += values[q] * xi
        out[i] = t


@njit(cache=True, fastmath={"contract"})
def _sweep(rows, rhs, scale, out, width):  # pragma: no cover - compiled
    """out[r] = rhs[n - 1 - r] s_r - Σ_m rows[r, m - 1] out[r + m], r = n - 1 to 0; s = ``scale`` or 1.

    The sum takes the far unknowns first, in two partial sums, and the four newest from registers
    last: the chain from one row to the next is then one FMA.
    """
    w = len(width)
    n = rows.shape[0] - w
    x1 = 0.0
    x2 = 0.0
    x3 = 0.0
    x4 = 0.0
    for jj in range(n):
        r = uint64(n - 1 - jj)
        s0 = 0.0
        s1 = 0.0
        for m in range(w, 5, -2):
            s0 += rows[r, m - 1] * out[r + uint64(m)]
            s1 += rows[r, m - 2] * out[r + uint64(m - 1)]
        t = (rhs[jj] * scale[r] if scale.size else rhs[jj]) - (s0 + s1)
        t -= rows[r, 3] * x4
        t -= rows[r, 2] * x3
        t -= rows[r, 1] * x2
        x0 = t - rows[r, 0] * x1
        out[r] = x0
        x4 = x3
        x3 = x2
        x2 = x1
        x1 = x0


@njit(cache=True)
def solve(upper, lower, scale, b, sweep, width):  # pragma: no cover - compiled
    """Solve Ûᵀ D² Û x = b in place (``kernel_preparation.UnitFactor``); b and ``sweep`` (n + w,) with
    zero tails.

    Forward Ûᵀ z = b into ``sweep`` in reverse order (row j at n - 1 - j, so that both sweeps
    read their unknowns at positive offsets), then Û x = D⁻² z into b.
    """
    _sweep(lower, b, scale[:0], sweep, width)
    _sweep(upper, sweep, scale, b, width)


@njit(cache=True, fastmath={"contract"})
def unit_responses(upper, scale, b, dofs, width):  # pragma: no cover - compiled
    """K̂⁻¹ E, E the unit columns at ``dofs`` (4,), in b (n + w, 4), to relative precision 1e-30.

    A unit force's response decays away from it (K̂ is dominated by M / (β Δt²)), so the
    sweeps stop once w + 1 successive rows are below 1e-30 of the largest entry: what is left
    out changes nothing at double precision. b must be zero on entry outside the rows returned
    by the previous call, ``(first, last)``; it is zero outside the new ones on return.
    """
    w = len(width)
    n = upper.shape[0] - w
    start = min(min(dofs[0], dofs[1]), min(dofs[2], dofs[3]))
    end = max(max(dofs[0], dofs[1]), max(dofs[2], dofs[3]))
    for c in range(4):
        b[dofs[c], c] = 1.0
    peak = 0.0
    quiet = 0
    last = n - 1
    for j in range(start, n):  # Ûᵀ z = e by columns of Ûᵀ, then D⁻² z
        for m in range(1, w + 1):
            r = upper[j, m - 1]
            for c in range(4):
                b[j + m, c] -= r * b[j, c]
        big = 0.0
        for c in range(4):
            z = b[j, c] * scale[j]
            b[j, c] = z
            big = max(big, abs(z))
        peak = max(peak, big)
        quiet = quiet + 1 if big <= TRUNCATION * peak else 0
        if quiet > w and j > end:
            last = j
            for m in range(1, w + 1):
                for c in range(4):
                    b[j + m, c] = 0.0
            break
    peak = 0.0
    quiet = 0
    first = 0
    for jj in range(last + 1):  # Û x = D⁻² z by rows
        j = last - jj
        big = 0.0
        for c in range(4):
            s = b[j, c]
            for m in range(w, 0, -1):
                s -= upper[j, m - 1] * b[j + m, c]
            b[j, c] = s
            big = max(big, abs(s))
        peak = max(peak, big)
        quiet = quiet + 1 if big <= TRUNCATION * peak else 0
        if quiet > w and j < start:
            first = j
            break
    return first, last


@njit(cache=True)
def _element_responses(upper, scale, unit, first, last, zd, response_t, Wz, width):  # pragma: no cover
    """unit_responses for a new element after clearing the last one's rows; Wz = W[zd]. Returns the rows."""
    for i in range(first, last + 1):
        for c in range(4):
            unit[i, c] = 0.0
    for i in range(4):
        for q in range(Wz.shape[1]):
            Wz[i, q] = response_t[q, zd[i]]
    return unit_responses(upper, scale, unit, zd, width)


@njit(cache=True)
def _small_solve(A, r, size):  # pragma: no cover - compiled
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


@njit(cache=True)
def settle_workspace(n_drop):  # pragma: no cover - compiled
    """The arrays :func:`_settle` works in, for ``n_drop`` droppers: A, r, λ, the slack indices, the
    droppers' forces and the new slack states."""
    return (
        np.zeros((n_drop + 1, n_drop + 1)),
        np.zeros(n_drop + 1),
        np.zeros(n_drop),
        np.zeros(n_drop, dtype=np.int64),
        np.zeros(n_drop),
        np.zeros(n_drop, dtype=np.bool_),
    )


@njit(cache=True)
def _settle(contact, slack, gap_known, c_cc, g_dc, dl_known, rate_term, kh, kappa, N0, G, work):  # noqa: C901
    """The step's contact force and slack droppers' λ, by the numpy backend's active-set iteration.

    Returns (contact, f, m, resolved); ``slack`` is updated in place, and ``work`` holds λ and the
    slack droppers' indices in ``lam[:m]``, ``idx[:m]``, and the droppers' forces in ``elastic``.
    """  # pragma: no cover - compiled
    A, r, lam, idx, elastic, new_slack = work
    n_drop = slack.size
    f = 0.0
    m = 0
    for iteration in range(MAX_ACTIVE_SET_ITERATIONS):
        m = 0
        for q in range(n_drop):
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
        f = r[0]
        gap = gap_known - c_cc * f
        for i in range(m):
            lam[i] = r[1 + i]
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
        if iteration < FULL_SWITCH_ITERATIONS:  # as active_set.switch_states
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


@njit(cache=True, fastmath={"contract"})
def _advance(u, v, acc, x, y, b, cf):  # pragma: no cover - compiled
    """Newmark update to u₁ = b + y (n,), then x = e1 u + e2 v + e3 a, y = g1 u + g2 v + g3 a."""
    e1, e2, e3, g1, g2, g3 = cf[E1], cf[E2], cf[E3], cf[G1], cf[G2], cf[G3]
    a0, a1, a2, a3, a4, a5 = cf[A0], cf[A1], cf[A2], cf[A3], cf[A4], cf[A5]
    for i in range(u.size):
        u_new = b[i] + y[i]
        du = u_new - u[i]
        acc_new = a0 * du - a2 * v[i] - a3 * acc[i]
        v_new = a1 * du - a4 * v[i] - a5 * acc[i]
        u[i] = u_new
        v[i] = v_new
        acc[i] = acc_new
        x[i] = e1 * u_new + e2 * v_new + e3 * acc_new
        y[i] = g1 * u_new + g2 * v_new + g3 * acc_new


@njit(cache=True)
def pantograph_known(d, y_p, yd_p, ydd_p, rhs_p, y_known):  # pragma: no cover - compiled
    """The pantograph without the step's contact force: K̂_p y_known = M_p (a0 y + a2 ẏ + a3 ÿ)
    + C_p (a1 y + a4 ẏ + a5 ÿ) + uplift. ``d`` holds load_p, pantograph_mass, pantograph_damping,
    pantograph_inverse and the Newmark a0..a5 at coefficients[6:12] (both passages' arrays do)."""
    cf = d.coefficients
    a0, a1, a2, a3, a4, a5 = cf[A0], cf[A1], cf[A2], cf[A3], cf[A4], cf[A5]
    n_p = y_p.size
    for i in range(n_p):
        t = d.load_p[i]
        for j in range(n_p):
            t += d.pantograph_mass[i, j] * (a0 * y_p[j] + a2 * yd_p[j] + a3 * ydd_p[j])
            t += d.pantograph_damping[i, j] * (a1 * y_p[j] + a4 * yd_p[j] + a5 * ydd_p[j])
        rhs_p[i] = t
    for i in range(n_p):
        t = 0.0
        for j in range(n_p):
            t += d.pantograph_inverse[i, j] * rhs_p[j]
        y_known[i] = t


@njit(cache=True)
def _known_part(d, k, h, zd, b, y, u, v, acc, y_p, yd_p, ydd_p, rhs_p, y_known, dl_known, rate_term):
    """Pantograph without contact (y_known), the contact gap, dropper elongations and damping shares.

    u_known = b + y. Returns the gap without contact force, m; fills y_known, dl_known = B u_known and
    rate_term = β k B (a1 u₀ + a4 v₀ + a5 a₀).
    """  # pragma: no cover - compiled
    cf = d.coefficients
    a1, a4, a5, beta = cf[A1], cf[A4], cf[A5], cf[RAYLEIGH_BETA]
    n_p = y_p.size
    pantograph_known(d, y_p, yd_p, ydd_p, rhs_p, y_known)
    for q in range(dl_known.size):
        t_known = 0.0
        t_rate = 0.0
        for p in range(d.b_ptr[q], d.b_ptr[q + 1]):
            j = d.b_index[p]
            t_known += d.b_values[p] * (b[j] + y[j])
            t_rate += d.b_values[p] * (a1 * u[j] + a4 * v[j] + a5 * acc[j])
        dl_known[q] = t_known
        rate_term[q] = beta * d.dropper_rate[q] * t_rate
    wire = 0.0
    for i in range(4):
        wire += h[i] * (b[zd[i]] + y[zd[i]])
    return y_known[n_p - 1] - d.wire_z[k] - wire


@njit(cache=True)
def _resume(u, v, acc, x, y, cf, start, element, z_dofs, response_t, Wz):  # pragma: no cover - compiled
    """At a call's start: x, y of the first right-hand side (later calls find them in the state) and
    W[zd] of the current element, if any."""
    if start:
        for i in range(u.size):
            x[i] = cf[E1] * u[i] + cf[E2] * v[i] + cf[E3] * acc[i]
            y[i] = cf[G1] * u[i] + cf[G2] * v[i] + cf[G3] * acc[i]
    if element >= 0:
        for i in range(4):
            for q in range(Wz.shape[1]):
                Wz[i, q] = response_t[q, z_dofs[element, i]]


@njit(cache=True)
def run_steps(d, s, first, stop, width):  # pragma: no cover - compiled
    """Steps ``first`` to ``stop - 1`` of the passage (as the numpy backend), updating ``s`` in place."""
    n_drop = d.dropper_force.size
    head = d.y_star.size - 1
    cf = d.coefficients
    a0, a1, a2, a3, a4, a5 = cf[A0], cf[A1], cf[A2], cf[A3], cf[A4], cf[A5]
    u, v, acc, x, y, b, unit = s.u, s.v, s.a, s.x, s.y, s.work, s.unit
    y_p, yd_p, ydd_p = s.y_p, s.yd_p, s.ydd_p
    Wz = np.zeros((4, n_drop))
    g_dc = np.zeros(n_drop)
    dl_known = np.zeros(n_drop)
    rate_term = np.zeros(n_drop)
    work = settle_workspace(n_drop)
    lam, idx, elastic = work[2], work[3], work[4]
    y_known = np.zeros(head + 1)
    rhs_p = np.zeros(head + 1)
    contact = s.flags[CONTACT] != 0
    _resume(u, v, acc, x, y, cf, first == 1, s.flags[ELEMENT], d.z_dofs, d.dropper_response_t, Wz)

    for k in range(first, stop):
        symmetric_product(d.m_ptr, d.m_offset, d.m_values, x, b, width)  # u_known = K̂⁻¹ M x + y
        solve(d.upper, d.lower, d.scale, b, s.sweep, width)
        e = d.element[k]
        zd = d.z_dofs[e]
        if e != s.flags[ELEMENT]:  # the unit responses of the new contact-wire element, P = K̂⁻¹ E, and W[zd]
            s.flags[FIRST_ROW], s.flags[LAST_ROW] = _element_responses(
                d.upper,
                d.scale,
                unit,
                s.flags[FIRST_ROW],
                s.flags[LAST_ROW],
                zd,
                d.dropper_response_t,
                Wz,
                width,
            )
            s.flags[ELEMENT] = e
        h = d.shape[k]
        c_cc = d.y_star[head]  # the contact point's compliance h P[zd] h, and its coupling g = W[zd]ᵀ h
        for i in range(4):
            for c in range(4):
                c_cc += h[i] * unit[zd[i], c] * h[c]
        for q in range(n_drop):
            g_dc[q] = Wz[0, q] * h[0] + Wz[1, q] * h[1] + Wz[2, q] * h[2] + Wz[3, q] * h[3]
        gap_known = _known_part(
            d, k, h, zd, b, y, u, v, acc, y_p, yd_p, ydd_p, rhs_p, y_known, dl_known, rate_term
        )
        contact, f, m, resolved = _settle(
            contact,
            s.slack,
            gap_known,
            c_cc,
            g_dc,
            dl_known,
            rate_term,
            cf[CONTACT_STIFFNESS],
            d.dropper_kappa,
            d.dropper_force,
            d.dropper_flexibility,
            work,
        )
        s.flags[UNRESOLVED] += 0 if resolved else 1

        # u₁ = u_known + u*_c f + Σ W_d λ_d (with u_known = b + y), over the rows where these
        # responses are not negligible.
        p0, p1, p2, p3 = f * h[0], f * h[1], f * h[2], f * h[3]
        for i in range(s.flags[FIRST_ROW], s.flags[LAST_ROW] + 1):
            b[i] += unit[i, 0] * p0 + unit[i, 1] * p1 + unit[i, 2] * p2 + unit[i, 3] * p3
        for q in range(m):
            for i in range(d.dropper_window[idx[q], 0], d.dropper_window[idx[q], 1] + 1):
                b[i] += d.dropper_response_t[idx[q], i] * lam[q]
        _advance(u, v, acc, x, y, b, cf)
        for i in range(head + 1):
            du = y_known[i] - f * d.y_star[i] - y_p[i]
            acc_new = a0 * du - a2 * yd_p[i] - a3 * ydd_p[i]
            yd_p[i] = a1 * du - a4 * yd_p[i] - a5 * ydd_p[i]
            ydd_p[i] = acc_new
            y_p[i] += du

        s.force[k] = f
        s.head_height[k] = y_p[head]
        s.wire_uplift[k] = h[0] * u[zd[0]] + h[1] * u[zd[1]] + h[2] * u[zd[2]] + h[3] * u[zd[3]]
        for i in range(d.support_z.size):
            s.support_uplift[k, i] = u[d.support_z[i]]
        for q in range(n_drop):
            force = 0.0 if s.slack[q] else elastic[q]
            s.dropper_min[q] = min(s.dropper_min[q], force)
            s.dropper_max[q] = max(s.dropper_max[q], force)
        s.flags[SLACK_STEPS] += 1 if m else 0
    s.flags[CONTACT] = 1 if contact else 0
