"""Compiled time loop of the fast pantograph passage (docs/performance.md, 'Benchmark'), with numba.

The same method as the numpy loop (:mod:`~catenary_env.dynamics.exact.loop`), step for step:
superposition of unit responses, one small contact / slack-dropper problem per step solved by the same
active-set iteration, so the two backends agree to rounding (about 1e-9 N on the contact force). One
compiled loop replaces a dozen numpy and LAPACK calls per step; the per-step work is then one product with
M, one banded solve with K̂'s factor and one Newmark update, each a single pass over the DOFs. What the
profile asked for, beyond compiling:

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

It reads :class:`~catenary_env.dynamics.exact.kernel_preparation.ExactArrays`, the contact point's
:class:`~catenary_env.dynamics.contact_point.ContactPointArrays` and updates an
:class:`~catenary_env.dynamics.exact.state.ExactState`; the active set, the Newmark update, the pantograph's
part of the step and the history are the shared compilable functions
(:mod:`~catenary_env.dynamics.compilable`).

numba is optional: :mod:`~catenary_env.dynamics.exact.passage` imports this module only for the numba backend.
"""

from __future__ import annotations

import numpy as np
from numba import njit, uint64

from ..active_set import settle_in_place, settle_workspace
from ..contact_point import advance_pantograph_in_place, known_response_in_place
from ..history import record_in_place
from ..newmark import advance
from .kernel_preparation import TRUNCATION

ELEMENT, FIRST_ROW, LAST_ROW = range(3)
"""Slots of ExactState.element: the current contact-wire element (-1: none yet), and the first and last row
of its unit responses."""


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
def _dropper_known(d, b, y, u, v, acc, dl_known, rate_term):  # pragma: no cover - compiled
    """The droppers' elongations dl_known = B u_known (u_known = b + y) and damping shares rate_term =
    β k B (a1 u₀ + a4 v₀ + a5 a₀)."""
    cf = d.coefficients
    for q in range(dl_known.size):
        t_known = 0.0
        t_rate = 0.0
        for p in range(d.b_ptr[q], d.b_ptr[q + 1]):
            j = d.b_index[p]
            t_known += d.b_values[p] * (b[j] + y[j])
            t_rate += d.b_values[p] * (cf.a1 * u[j] + cf.a4 * v[j] + cf.a5 * acc[j])
        dl_known[q] = t_known
        rate_term[q] = cf.rayleigh_beta * d.droppers.rate[q] * t_rate


@njit(cache=True)
def _gap_known(d, point, ps, k, h, zd, b, y, rhs_p, y_known):  # pragma: no cover - compiled
    """The pantograph without contact (y_known) and its contact gap without contact force, m."""
    known_response_in_place(point, d.coefficients, ps, rhs_p, y_known)
    wire = 0.0
    for i in range(4):
        wire += h[i] * (b[zd[i]] + y[zd[i]])
    return y_known[ps.y.size - 1] - point.wire_z[k] - wire


@njit(cache=True)
def _resume(u, v, acc, x, y, cf, start, elements, z_dofs, response_t, Wz):  # pragma: no cover - compiled
    """At a call's start: x, y of the first right-hand side (later calls find them in the state) and
    W[zd] of each contact point's current element, if any."""
    if start:
        for i in range(u.size):
            x[i] = cf.e1 * u[i] + cf.e2 * v[i] + cf.e3 * acc[i]
            y[i] = cf.g1 * u[i] + cf.g2 * v[i] + cf.g3 * acc[i]
    for p in range(elements.shape[0]):
        element = elements[p, ELEMENT]
        if element >= 0:
            for i in range(4):
                for q in range(Wz.shape[2]):
                    Wz[p, i, q] = response_t[q, z_dofs[element, i]]


@njit(cache=True)
def _contact_point(d, slots, point, k, unit, Wz, g_dc, width):  # pragma: no cover - compiled
    """The contact point at step k (on the section): its element's unit responses (when it enters a new
    one; ``slots`` its ExactState.element row); fills its coupling to the droppers g = W[zd]ᵀ h."""
    e = point.element[k]
    zd = d.z_dofs[e]
    if e != slots[ELEMENT]:  # the unit responses of the new contact-wire element, P = K̂⁻¹ E, and W[zd]
        slots[FIRST_ROW], slots[LAST_ROW] = _element_responses(
            d.upper,
            d.scale,
            unit,
            slots[FIRST_ROW],
            slots[LAST_ROW],
            zd,
            d.dropper_response_t,
            Wz,
            width,
        )
        slots[ELEMENT] = e
    h = point.shape[k]
    for q in range(g_dc.size):
        g_dc[q] = Wz[0, q] * h[0] + Wz[1, q] * h[1] + Wz[2, q] * h[2] + Wz[3, q] * h[3]


@njit(cache=True)
def _compliance(d, points, ps, k, unit, c_cc, gap_known):  # pragma: no cover - compiled
    """The contact points' one-step compliances c_cc (P, P), m/N: h_i P_j[zd_i] h_j, plus the head's own on
    the diagonal (a unit response is zero outside its rows). A point off the section gets a negative gap
    and no coupling, so that it stays out of contact."""
    n_c = len(points)
    for i in range(n_c):
        for j in range(n_c):
            c_cc[i, j] = 0.0
        if points[i].element[k] < 0:
            gap_known[i] = -1.0
            c_cc[i, i] = 1.0
            continue
        h = points[i].shape[k]
        zd = d.z_dofs[points[i].element[k]]
        c_cc[i, i] = points[i].y_star[ps[i].y.size - 1]
        for j in range(n_c):
            if points[j].element[k] < 0:
                continue
            hj = points[j].shape[k]
            acc = c_cc[i, j]
            for r in range(4):
                for c in range(4):
                    acc += h[r] * unit[j, zd[r], c] * hj[c]
            c_cc[i, j] = acc


@njit(cache=True)
def run_steps(d, points, s, first, stop, width):  # pragma: no cover - compiled  # noqa: C901
    """Steps ``first`` to ``stop - 1`` of the passage (as the numpy loop), updating ``s`` in place.

    ``points`` holds the contact points' arrays, ``s`` is an ExactState.
    """
    ps = s.pantographs
    n_c = len(points)
    n_drop = d.droppers.force.size
    p_max = 0
    for i in range(n_c):
        p_max = max(p_max, ps[i].y.size)
    cf = d.coefficients
    u, v, acc, x, y, b, unit = s.u, s.v, s.a, s.x, s.y, s.work, s.unit
    Wz = np.zeros((n_c, 4, n_drop))
    g_dc = np.zeros((n_c, n_drop))
    c_cc = np.zeros((n_c, n_c))
    gap_known = np.zeros(n_c)
    dl_known = np.zeros(n_drop)
    rate_term = np.zeros(n_drop)
    work = settle_workspace(n_c, n_drop)
    lam, idx, elastic, f = work[2], work[3], work[4], work[6]
    every_row = np.ones(n_drop, dtype=np.bool_)  # the whole G is prepared
    y_known = np.zeros((n_c, p_max))
    rhs_p = np.zeros(p_max)
    contact = np.zeros(n_c, dtype=np.bool_)
    for i in range(n_c):
        contact[i] = ps[i].contact[0] != 0
    _resume(u, v, acc, x, y, cf, first == 1, s.element, d.z_dofs, d.dropper_response_t, Wz)

    for k in range(first, stop):
        symmetric_product(d.m_ptr, d.m_offset, d.m_values, x, b, width)  # u_known = K̂⁻¹ M x + y
        solve(d.upper, d.lower, d.scale, b, s.sweep, width)
        for i in range(n_c):
            for q in range(n_drop):
                g_dc[i, q] = 0.0
            if points[i].element[k] >= 0:
                _contact_point(d, s.element[i], points[i], k, unit[i], Wz[i], g_dc[i], width)
        _compliance(d, points, ps, k, unit, c_cc, gap_known)
        _dropper_known(d, b, y, u, v, acc, dl_known, rate_term)
        for i in range(n_c):
            if points[i].element[k] >= 0:
                h = points[i].shape[k]
                zd = d.z_dofs[points[i].element[k]]
                gap_known[i] = _gap_known(d, points[i], ps[i], k, h, zd, b, y, rhs_p, y_known[i])
        m, resolved, _ = settle_in_place(
            contact,
            s.slack,
            gap_known,
            c_cc,
            g_dc,
            dl_known,
            rate_term,
            cf.contact_stiffness,
            d.droppers,
            d.dropper_flexibility,
            work,
            every_row,
            0,
        )
        # u₁ = u_known + Σ u*_c f + Σ W_d λ_d (with u_known = b + y), over the rows where these
        # responses are not negligible.
        for j in range(n_c):
            if points[j].element[k] < 0:
                continue
            h = points[j].shape[k]
            uj = unit[j]
            p0, p1, p2, p3 = f[j] * h[0], f[j] * h[1], f[j] * h[2], f[j] * h[3]
            for i in range(s.element[j, FIRST_ROW], s.element[j, LAST_ROW] + 1):
                b[i] += uj[i, 0] * p0 + uj[i, 1] * p1 + uj[i, 2] * p2 + uj[i, 3] * p3
        for q in range(m):
            for i in range(d.dropper_window[idx[q], 0], d.dropper_window[idx[q], 1] + 1):
                b[i] += d.dropper_response_t[idx[q], i] * lam[q]
        advance(u, v, acc, x, y, b, cf)
        for j in range(n_c):
            point = points[j]
            if point.element[k] < 0:
                s.history.force[j, k] = 0.0
                s.history.head_height[j, k] = ps[j].y[ps[j].y.size - 1]
                s.history.wire_uplift[j, k] = 0.0
                continue
            advance_pantograph_in_place(point, cf, ps[j], y_known[j], f[j])
            h = point.shape[k]
            zd = d.z_dofs[point.element[k]]
            s.history.force[j, k] = f[j]
            s.history.head_height[j, k] = ps[j].y[ps[j].y.size - 1]
            s.history.wire_uplift[j, k] = (
                h[0] * u[zd[0]] + h[1] * u[zd[1]] + h[2] * u[zd[2]] + h[3] * u[zd[3]]
            )
        record_in_place(s.history, k, elastic, s.slack, m > 0, resolved)
        for i in range(d.support_z.size):
            s.history.support_uplift[k, i] = u[d.support_z[i]]
    for i in range(n_c):
        ps[i].contact[0] = 1 if contact[i] else 0
