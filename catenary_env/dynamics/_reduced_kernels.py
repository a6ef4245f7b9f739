"""The span-mode passage's time loop, compiled by numba (optional; the numpy loop in
:mod:`reduced_passage` is the reference and follows the same steps).

Each step:

1. The interface part of K̂⁻¹ M e: x_b = S⁻¹ (Y e_b + Σ_s M_cq w e_q), w = 1 - c_m / D.
2. The droppers' elongations and the contact point's displacement from x_b and e, without the
   modes' full solution: B x = (B_q D⁻¹) e_q + (B_q D⁻¹ M_qc)(e_c - c_m x_c) + B_c x_c.
3. The contact force and the slack droppers (active set, :func:`_kernels._settle`).
4. Their response on the interface, Δx_b = S⁻¹ (F_b - c_m Σ M_cq D⁻¹ F_q), precomputed per
   contact-wire element and per dropper; then every span's modes in one pass,
   x_q = D⁻¹ (e_q + F_q + M_qc (e_c - c_m x_c)), fused with the Newmark update.

S and Y depend on the configuration (the span the pantograph is in); S is a banded Cholesky factor.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ._kernels import (
    A0,
    A1,
    A2,
    A3,
    A4,
    A5,
    CONTACT,
    CONTACT_STIFFNESS,
    E1,
    E2,
    E3,
    G1,
    G2,
    G3,
    INVERSE_STIFFNESS_FACTOR,
    MASS_FACTOR,
    RAYLEIGH_BETA,
    SLACK_STEPS,
    UNRESOLVED,
    _settle,
    pantograph_known,
    settle_workspace,
)

CONFIGURATION = 1
"""Slot of ReducedState.flags holding the configuration (the others as the exact loop's)."""

FAST = {"contract", "reassoc"}
"""Floating-point licences: fused multiply-adds, and sums in any order so that the dot products
vectorise (the results change by rounding only)."""


class ReducedArrays(NamedTuple):
    """What the loop reads: the fields of :func:`reduced_passage.prepare_reduced_passage`'s arrays
    plus the passage's. Shapes: S spans, T types, C = S configurations, D droppers, n_b interface
    DOFs, w the Schur complement's band width, m, n_c, n_i the padded modes, coupled interface and
    internal DOFs of a span type, E contact-wire elements, K droppers per span.
    """

    span_type: np.ndarray  # (S,)
    modal_offset: np.ndarray  # (S + 1,)
    coupled: np.ndarray  # (S, n_c) interface positions
    n_coupled: np.ndarray  # (T,)
    n_modes: np.ndarray  # (T,)
    kept: np.ndarray  # (C, S) modes each span keeps in configuration c
    coupling: np.ndarray  # (T, n_c, m) M_cq
    inverse_diagonal: np.ndarray  # (T, m) 1 / D
    weight: np.ndarray  # (T, m) 1 - c_m / D
    shapes: np.ndarray  # (T, n_i, m) Φ
    constraint: np.ndarray  # (T, n_i, n_c) Ψ
    schur_band: np.ndarray  # (C, w + 1, n_b) U in LAPACK band storage (the numpy loop's)
    schur_columns: np.ndarray  # (C, n_b, w) the Cholesky factor U of S by columns (_band_solve)
    schur_rows: np.ndarray  # (C, n_b, w) U by rows
    schur_inverse_diagonal: np.ndarray  # (C, n_b)
    interface_rhs_band: np.ndarray  # (C, 2 w + 1, n_b) Y[r, r + k] at [w + k, r]
    dropper_span: np.ndarray  # (D,)
    dropper_q: np.ndarray  # (D, m) B_q D⁻¹
    dropper_q_plain: np.ndarray  # (D, m) B_q
    dropper_c: np.ndarray  # (D, n_c) B_c
    dropper_h: np.ndarray  # (C, D, n_c) B_q D⁻¹ M_qc over the kept modes
    dropper_interface: np.ndarray  # (C, D, n_b) x_b of a unit dropper force
    dropper_flexibility: np.ndarray  # (C, D, D) G with the residual
    dropper_modal_flexibility: np.ndarray  # (C, D, D) G of the kept modes
    dropper_rate: np.ndarray  # (D,)
    dropper_force: np.ndarray  # (D,)
    dropper_kappa: np.ndarray  # (D,)
    element_span: np.ndarray  # (E,)
    element_local: np.ndarray  # (E, 4) internal index, or -1 - position in the span's coupled list
    element_compliance: np.ndarray  # (E, 4, 4) residual
    element_droppers: np.ndarray  # (E, K) the span's droppers, -1 pads
    element_dropper_residual: np.ndarray  # (E, 4, K)
    support: np.ndarray  # (supports,) interface position of each contact-wire support
    coefficients: np.ndarray  # (16,) e1..e3, g1..g3, a0..a5, k_h, β, c_m, 1 / c_k
    config: np.ndarray  # (steps,) the pantograph's span
    element: np.ndarray  # (steps,)
    shape: np.ndarray  # (steps, 4)
    wire_z: np.ndarray  # (steps,)
    pantograph_inverse: np.ndarray
    pantograph_mass: np.ndarray
    pantograph_damping: np.ndarray
    y_star: np.ndarray
    load_p: np.ndarray


class ReducedState(NamedTuple):
    """State and histories. u, v, a, e, y (n_r,): the next u_known is K̂⁻¹ M e + y / c_k; Bu, Bv, Ba
    (D,): the droppers' elongations of u, v, a; flags: contact, configuration, slack steps, unresolved."""

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    e: np.ndarray
    y: np.ndarray
    Bu: np.ndarray
    Bv: np.ndarray
    Ba: np.ndarray
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


@njit(cache=True, fastmath=FAST)
def _dot(a, b, m):  # pragma: no cover - compiled
    """a[:m] · b[:m] (1-D views, so that the loop vectorises)."""
    acc = 0.0
    for i in range(m):
        acc += a[i] * b[i]
    return acc


@njit(cache=True, fastmath=FAST)
def _axpy(a, alpha, out, m):  # pragma: no cover - compiled
    """out[:m] += alpha a[:m]."""
    for i in range(m):
        out[i] += alpha * a[i]


@njit(cache=True, fastmath=FAST)
def _band_solve(factor, b, x):  # pragma: no cover - compiled
    """x = (Uᵀ U)⁻¹ b for the banded upper factor U in :func:`reduced_passage.band_rows` form: row j of
    ``factor[0]`` holds U[j - w .. j - 1, j], row i of ``factor[1]`` holds U[i, i + 1 .. i + w], and
    ``factor[2]`` the reciprocal diagonal."""
    columns, rows, inverse = factor[0], factor[1], factor[2]
    w = columns.shape[1]
    n = b.size
    for j in range(n):
        col = columns[j]
        acc = 0.0
        lo = max(0, j - w)
        for i in range(lo, j):
            acc += col[w - j + i] * x[i]
        x[j] = (b[j] - acc) * inverse[j]
    for i in range(n - 1, -1, -1):
        row = rows[i]
        acc = 0.0
        hi = min(n, i + w + 1)
        for j in range(i + 1, hi):
            acc += row[j - i - 1] * x[j]
        x[i] = (x[i] - acc) * inverse[i]


@njit(cache=True, fastmath=FAST)
def _band_solve4(factor, b, x):  # pragma: no cover - compiled
    """:func:`_band_solve` for four right-hand sides at once, b and x of shape (n, 4)."""
    columns, rows, inverse = factor[0], factor[1], factor[2]
    w = columns.shape[1]
    n = b.shape[0]
    for j in range(n):
        col = columns[j]
        a0 = a1 = a2 = a3 = 0.0
        for i in range(max(0, j - w), j):
            cij = col[w - j + i]
            a0 += cij * x[i, 0]
            a1 += cij * x[i, 1]
            a2 += cij * x[i, 2]
            a3 += cij * x[i, 3]
        x[j, 0] = (b[j, 0] - a0) * inverse[j]
        x[j, 1] = (b[j, 1] - a1) * inverse[j]
        x[j, 2] = (b[j, 2] - a2) * inverse[j]
        x[j, 3] = (b[j, 3] - a3) * inverse[j]
    for i in range(n - 1, -1, -1):
        row = rows[i]
        a0 = a1 = a2 = a3 = 0.0
        for j in range(i + 1, min(n, i + w + 1)):
            rij = row[j - i - 1]
            a0 += rij * x[j, 0]
            a1 += rij * x[j, 1]
            a2 += rij * x[j, 2]
            a3 += rij * x[j, 3]
        x[i, 0] = (x[i, 0] - a0) * inverse[i]
        x[i, 1] = (x[i, 1] - a1) * inverse[i]
        x[i, 2] = (x[i, 2] - a2) * inverse[i]
        x[i, 3] = (x[i, 3] - a3) * inverse[i]


@njit(cache=True, fastmath=FAST)
def _element_rows(d, e, rows_q, rows_c):  # pragma: no cover - compiled
    """The contact-wire element's rows of T: modal part (4, m) and coupled-interface part (4, n_c)."""
    t = d.span_type[d.element_span[e]]
    rows_q[:] = 0.0
    rows_c[:] = 0.0
    for i in range(4):
        local = d.element_local[e, i]
        if local >= 0:
            for j in range(d.n_modes[t]):
                rows_q[i, j] = d.shapes[t, local, j]
            for j in range(d.n_coupled[t]):
                rows_c[i, j] = d.constraint[t, local, j]
        else:
            rows_c[i, -1 - local] = 1.0


@njit(cache=True, fastmath=FAST)
def _element_responses(d, c, e, rows_q, rows_c, p_b, comp, g_modal, g_full, work_b, tmp):  # pragma: no cover
    """A unit force at each of the element's 4 DOFs: interface response p_b (n_b, 4), compliance
    (4, 4) with the residual, and the droppers' elongations, of the kept modes and with the residual."""
    c_m = d.coefficients[MASS_FACTOR]
    s = d.element_span[e]
    t = d.span_type[s]
    m = d.kept[c, s]
    nc = d.n_coupled[t]
    n_b = p_b.shape[0]
    cpl = d.coupling[t]
    inv_d = d.inverse_diagonal[t]
    rq = np.empty((4, m))  # rows_q D⁻¹
    mq = np.empty((4, nc))  # rows_q D⁻¹ M_qc
    for r in range(4):
        for i in range(m):
            rq[r, i] = rows_q[r, i] * inv_d[i]
        for j in range(nc):
            mq[r, j] = _dot(rq[r], cpl[j], m)
    schur = (d.schur_columns[c], d.schur_rows[c], d.schur_inverse_diagonal[c])
    forces = np.zeros((n_b, 4))  # F_b - c_m M_cq D⁻¹ F_q, then S⁻¹
    for col in range(4):
        for j in range(nc):
            forces[d.coupled[s, j], col] += rows_c[col, j] - c_m * mq[col, j]
    _band_solve4(schur, forces, p_b)
    for r in range(4):  # rows_q D⁻¹ rows_qᵀ + (rows_c - c_m rows_q D⁻¹ M_qc) p_c, plus the residual
        for col in range(4):
            acc = d.element_compliance[e, r, col] + _dot(rq[r], rows_q[col], m)
            for j in range(nc):
                acc += (rows_c[r, j] - c_m * mq[r, j]) * p_b[d.coupled[s, j], col]
            comp[r, col] = acc
    for q in range(d.dropper_force.size):
        sd = d.dropper_span[q]
        h_q = d.dropper_h[c, q]
        c_q = d.dropper_c[q]
        for col in range(4):
            acc = _dot(d.dropper_q[q], rows_q[col], m) if sd == s else 0.0
            for j in range(d.n_coupled[d.span_type[sd]]):
                acc += (c_q[j] - c_m * h_q[j]) * p_b[d.coupled[sd, j], col]
            g_modal[q, col] = acc
            g_full[q, col] = acc
    for k in range(d.element_droppers.shape[1]):
        q = d.element_droppers[e, k]
        if q >= 0:
            for col in range(4):
                g_full[q, col] += d.element_dropper_residual[e, col, k]


@njit(cache=True, fastmath=FAST)
def _dropper_elongations(d, c, vec, out):  # pragma: no cover - compiled
    """out = B T vec over the kept modes."""
    n_q = d.modal_offset[d.span_type.size]
    for q in range(out.size):
        s = d.dropper_span[q]
        off = d.modal_offset[s]
        acc = _dot(d.dropper_q_plain[q], vec[off:], d.kept[c, s])
        for j in range(d.n_coupled[d.span_type[s]]):
            acc += d.dropper_c[q, j] * vec[n_q + d.coupled[s, j]]
        out[q] = acc


@njit(cache=True, fastmath=FAST)
def _configure(d, st, c):  # pragma: no cover - compiled
    """Enter configuration c: drop the state of the modes no longer kept, re-derive Bu, Bv, Ba."""
    for s in range(d.span_type.size):
        off = d.modal_offset[s]
        for i in range(d.kept[c, s], d.modal_offset[s + 1] - off):
            st.u[off + i] = 0.0
            st.v[off + i] = 0.0
            st.a[off + i] = 0.0
            st.e[off + i] = 0.0
            st.y[off + i] = 0.0
    _dropper_elongations(d, c, st.u, st.Bu)
    _dropper_elongations(d, c, st.v, st.Bv)
    _dropper_elongations(d, c, st.a, st.Ba)
    st.flags[CONFIGURATION] = c


@njit(cache=True, fastmath=FAST)
def run_reduced(d, st, first, stop):  # pragma: no cover - compiled  # noqa: C901
    """Steps ``first`` to ``stop - 1`` of the passage, updating ``st`` in place."""
    cf = d.coefficients
    e1, e2, e3, g1, g2, g3 = cf[E1], cf[E2], cf[E3], cf[G1], cf[G2], cf[G3]
    a0, a1, a2, a3, a4, a5 = cf[A0], cf[A1], cf[A2], cf[A3], cf[A4], cf[A5]
    kh, beta, c_m, inv_ck = (
        cf[CONTACT_STIFFNESS],
        cf[RAYLEIGH_BETA],
        cf[MASS_FACTOR],
        cf[INVERSE_STIFFNESS_FACTOR],
    )
    n_spans = d.span_type.size
    n_b = d.schur_inverse_diagonal.shape[1]
    n_q = d.modal_offset[n_spans]
    n_drop = d.dropper_force.size
    head = d.y_star.size - 1
    n_p = head + 1
    m_max = d.coupling.shape[2]
    nc_max = d.coupling.shape[1]
    width = (d.interface_rhs_band.shape[1] - 1) // 2
    u, v, acc_s, e_vec, y = st.u, st.v, st.a, st.e, st.y
    rows_q = np.zeros((4, m_max))
    rows_c = np.zeros((4, nc_max))
    p_b = np.zeros((n_b, 4))
    comp = np.zeros((4, 4))
    g_modal = np.zeros((n_drop, 4))
    g_full = np.zeros((n_drop, 4))
    work_b = np.zeros(n_b)
    z = np.zeros(n_b)
    x_b = np.zeros(n_b)
    g_c = np.zeros((n_spans, nc_max))
    g_dc = np.zeros(n_drop)
    gm_dc = np.zeros(n_drop)
    dl_known = np.zeros(n_drop)
    rate_term = np.zeros(n_drop)
    work = settle_workspace(n_drop)
    lam, idx, elastic = work[2], work[3], work[4]
    y_known = np.zeros(n_p)
    rhs_p = np.zeros(n_p)
    fq = np.zeros(m_max)
    contact = st.flags[CONTACT] != 0
    current = -1

    for k in range(first, stop):
        c = d.config[k]
        if c != st.flags[CONFIGURATION]:
            _configure(d, st, c)
            current = -1
        el = d.element[k]
        if el != current:
            _element_rows(d, el, rows_q, rows_c)
            _element_responses(d, c, el, rows_q, rows_c, p_b, comp, g_modal, g_full, work_b, z)
            current = el
        h = d.shape[k]
        s_el = d.element_span[el]
        t_el = d.span_type[s_el]
        flex = d.dropper_flexibility[c]
        # 1. Interface part of K̂⁻¹ M e.
        band = d.interface_rhs_band[c]
        e_b = e_vec[n_q:]
        diag = band[width]
        for r in range(n_b):
            work_b[r] = diag[r] * e_b[r]
        for kk in range(1, width + 1):
            upper = band[width + kk]
            lower = band[width - kk]
            for r in range(n_b - kk):
                work_b[r] += upper[r] * e_b[r + kk]
            for r in range(kk, n_b):
                work_b[r] += lower[r] * e_b[r - kk]
        for s in range(n_spans):
            t = d.span_type[s]
            off = d.modal_offset[s]
            m = d.kept[c, s]
            w_t = d.weight[t]
            for i in range(m):
                fq[i] = w_t[i] * e_vec[off + i]
            cpl = d.coupling[t]
            for j in range(d.n_coupled[t]):
                work_b[d.coupled[s, j]] += _dot(cpl[j], fq, m)
        _band_solve((d.schur_columns[c], d.schur_rows[c], d.schur_inverse_diagonal[c]), work_b, x_b)
        for s in range(n_spans):
            t = d.span_type[s]
            for j in range(d.n_coupled[t]):
                g_c[s, j] = e_vec[n_q + d.coupled[s, j]] - c_m * x_b[d.coupled[s, j]]
        # 2. Droppers' elongations of u_known = K̂⁻¹ M e + y / c_k.
        for q in range(n_drop):
            sd = d.dropper_span[q]
            td = d.span_type[sd]
            off = d.modal_offset[sd]
            acc = _dot(d.dropper_q[q], e_vec[off:], d.kept[c, sd])
            for j in range(d.n_coupled[td]):
                acc += d.dropper_h[c, q, j] * g_c[sd, j] + d.dropper_c[q, j] * x_b[d.coupled[sd, j]]
            dl_known[q] = acc + inv_ck * (g1 * st.Bu[q] + g2 * st.Bv[q] + g3 * st.Ba[q])
            rate_term[q] = beta * d.dropper_rate[q] * (a1 * st.Bu[q] + a4 * st.Bv[q] + a5 * st.Ba[q])
        # The contact point: its span's modes of u_known.
        off = d.modal_offset[s_el]
        m = d.kept[c, s_el]
        for i in range(m):
            fq[i] = e_vec[off + i]
        cpl = d.coupling[t_el]
        for j in range(d.n_coupled[t_el]):
            _axpy(cpl[j], g_c[s_el, j], fq, m)
        for i in range(m):
            fq[i] = fq[i] * d.inverse_diagonal[t_el, i] + inv_ck * y[off + i]
        wire = 0.0
        for r in range(4):
            val = 0.0
            val = _dot(rows_q[r], fq, m)
            for j in range(d.n_coupled[t_el]):
                val += rows_c[r, j] * (x_b[d.coupled[s_el, j]] + inv_ck * y[n_q + d.coupled[s_el, j]])
            wire += h[r] * val
        pantograph_known(d, st.y_p, st.yd_p, st.ydd_p, rhs_p, y_known)
        gap_known = y_known[head] - d.wire_z[k] - wire
        c_cc = d.y_star[head]
        for r in range(4):
            for cc in range(4):
                c_cc += h[r] * comp[r, cc] * h[cc]
        for q in range(n_drop):
            g_dc[q] = g_full[q, 0] * h[0] + g_full[q, 1] * h[1] + g_full[q, 2] * h[2] + g_full[q, 3] * h[3]
            gm_dc[q] = (
                g_modal[q, 0] * h[0] + g_modal[q, 1] * h[1] + g_modal[q, 2] * h[2] + g_modal[q, 3] * h[3]
            )
        # 3. Contact force and slack droppers.
        contact, f, n_slack, resolved = _settle(
            contact,
            st.slack,
            gap_known,
            c_cc,
            g_dc,
            dl_known,
            rate_term,
            kh,
            d.dropper_kappa,
            d.dropper_force,
            flex,
            work,
        )
        st.flags[UNRESOLVED] += 0 if resolved else 1
        # 4. Their interface response, then every span's modes with the Newmark update.
        for i in range(n_b):
            x_b[i] += f * (p_b[i, 0] * h[0] + p_b[i, 1] * h[1] + p_b[i, 2] * h[2] + p_b[i, 3] * h[3])
        for qq in range(n_slack):
            for i in range(n_b):
                x_b[i] += lam[qq] * d.dropper_interface[c, idx[qq], i]
        for s in range(n_spans):
            t = d.span_type[s]
            off = d.modal_offset[s]
            m = d.kept[c, s]
            for i in range(m):
                fq[i] = e_vec[off + i]
            if s == s_el:
                for i in range(m):
                    fq[i] += f * (
                        rows_q[0, i] * h[0] + rows_q[1, i] * h[1] + rows_q[2, i] * h[2] + rows_q[3, i] * h[3]
                    )
            for qq in range(n_slack):
                if d.dropper_span[idx[qq]] == s:
                    _axpy(d.dropper_q_plain[idx[qq]], lam[qq], fq, m)
            cpl = d.coupling[t]
            for j in range(d.n_coupled[t]):
                _axpy(cpl[j], e_vec[n_q + d.coupled[s, j]] - c_m * x_b[d.coupled[s, j]], fq, m)
            inv_d = d.inverse_diagonal[t]
            for i in range(m):
                p = off + i
                u_new = fq[i] * inv_d[i] + inv_ck * y[p]
                du = u_new - u[p]
                acc_new = a0 * du - a2 * v[p] - a3 * acc_s[p]
                v_new = a1 * du - a4 * v[p] - a5 * acc_s[p]
                u[p] = u_new
                v[p] = v_new
                acc_s[p] = acc_new
                e_vec[p] = e1 * u_new + e2 * v_new + e3 * acc_new
                y[p] = g1 * u_new + g2 * v_new + g3 * acc_new
        for i in range(n_b):
            p = n_q + i
            u_new = x_b[i] + inv_ck * y[p]
            du = u_new - u[p]
            acc_new = a0 * du - a2 * v[p] - a3 * acc_s[p]
            v_new = a1 * du - a4 * v[p] - a5 * acc_s[p]
            u[p] = u_new
            v[p] = v_new
            acc_s[p] = acc_new
            e_vec[p] = e1 * u_new + e2 * v_new + e3 * acc_new
            y[p] = g1 * u_new + g2 * v_new + g3 * acc_new
        mflex = d.dropper_modal_flexibility[c]
        for q in range(n_drop):
            bu = dl_known[q] + gm_dc[q] * f
            for qq in range(n_slack):
                bu += mflex[q, idx[qq]] * lam[qq]
            du = bu - st.Bu[q]
            ba = a0 * du - a2 * st.Bv[q] - a3 * st.Ba[q]
            st.Bv[q] = a1 * du - a4 * st.Bv[q] - a5 * st.Ba[q]
            st.Ba[q] = ba
            st.Bu[q] = bu
        for i in range(n_p):
            du = y_known[i] - f * d.y_star[i] - st.y_p[i]
            acc_new = a0 * du - a2 * st.yd_p[i] - a3 * st.ydd_p[i]
            st.yd_p[i] = a1 * du - a4 * st.yd_p[i] - a5 * st.ydd_p[i]
            st.ydd_p[i] = acc_new
            st.y_p[i] += du
        # Histories.
        st.force[k] = f
        st.head_height[k] = st.y_p[head]
        off = d.modal_offset[s_el]
        upl = 0.0
        for r in range(4):
            val = 0.0
            for i in range(d.kept[c, s_el]):
                val += rows_q[r, i] * u[off + i]
            for j in range(d.n_coupled[t_el]):
                val += rows_c[r, j] * u[n_q + d.coupled[s_el, j]]
            upl += h[r] * val
        st.wire_uplift[k] = upl
        for i in range(d.support.size):
            st.support_uplift[k, i] = u[n_q + d.support[i]]
        for q in range(n_drop):
            force = 0.0 if st.slack[q] else elastic[q]
            st.dropper_min[q] = min(st.dropper_min[q], force)
            st.dropper_max[q] = max(st.dropper_max[q], force)
        st.flags[SLACK_STEPS] += 1 if n_slack else 0
    st.flags[CONTACT] = 1 if contact else 0
