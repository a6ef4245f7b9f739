"""The span-mode passage's time loop, compiled by numba (optional; the numpy loop, :mod:`.loop`, follows
the same steps).

Each step:

1. The interface part of K̂⁻¹ M e: x_b = S⁻¹ (Y e_b + Σ_s M_cq w e_q), w = 1 - c_m / D; two spans of one
   type and as many kept modes in one pass over the type's rows (:func:`_span_pairs`), so that each row
   is read once for both (docs/performance.md, 'Speed').
2. The droppers' elongations and the contact point's displacement from x_b and e, without the
   modes' full solution: B x = (B_q D⁻¹) e_q + (B_q D⁻¹ M_qc)(e_c - c_m x_c) + B_c x_c.
3. The contact force and the slack droppers (:func:`~catenary_env.dynamics.active_set.settle_in_place`).
4. Their response on the interface, Δx_b = S⁻¹ (F_b - c_m Σ M_cq D⁻¹ F_q), computed per contact-wire
   element as the pantograph enters it and per dropper as it first goes slack in a configuration
   (:func:`_dropper_row`, with the dropper's row of G that step 3 reads); then every span's modes in one pass,
   x_q = D⁻¹ (e_q + F_q + M_qc (e_c - c_m x_c)), fused with the Newmark update.

S and Y depend on the configuration (the spans the pantographs are in); S is a banded Cholesky factor.
With several pantographs each has its element's responses, and their mutual compliance goes through the
interface (they are a span apart at least).

It reads :class:`~catenary_env.dynamics.span_modes.preparation.SpanModeArrays`, the contact point's
:class:`~catenary_env.dynamics.contact_point.ContactPointArrays` and updates a
:class:`~catenary_env.dynamics.span_modes.passage.SpanModeState`; the active set, the Newmark update, the
pantograph's part of the step and the history are the shared compilable functions
(:mod:`~catenary_env.dynamics.compilable`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..active_set import settle_in_place, settle_workspace
from ..contact_point import advance_pantograph_in_place, known_response_in_place
from ..history import record_in_place
from ..newmark import advance

FAST = {"contract", "reassoc"}
"""Floating-point licences: fused multiply-adds, and sums in any order so that the dot products
vectorise (the results change by rounding only). A loop that sums under them stores nothing, so that its
order of summation is always the vectorised one (see :func:`_contact_point`)."""

inlined = njit(cache=True, fastmath=FAST, inline="always")
"""The decorator of the helpers a step calls: inlined into the loop (numba's own inlining). Called, each took
its arrays as views whose reference counts (atomic increments and decrements, some ten a call) the compiler
could not prune, about a tenth of a step (docs/performance.md, 'Speed')."""


@inlined
def _dot(a, b, m):  # pragma: no cover - compiled
    """a[:m] · b[:m] (1-D views, so that the loop vectorises)."""
    acc = 0.0
    for i in range(m):
        acc += a[i] * b[i]
    return acc


@inlined
def _axpy(a, alpha, out, m):  # pragma: no cover - compiled
    """out[:m] += alpha a[:m]."""
    for i in range(m):
        out[i] += alpha * a[i]


@inlined
def _band_solve(factor, b, x):  # pragma: no cover - compiled
    """x = (Uᵀ U)⁻¹ b for the banded upper factor U in :func:`.preparation.band_rows` form: row j of
    ``factor[0]`` holds U[j - w .. j - 1, j], row i of ``factor[1]`` holds U[i, i + 1 .. i + w], and
    ``factor[2]`` the reciprocal diagonal. Both sweeps by columns (each unknown, once found, is
    subtracted from the w that follow), so that the inner loops carry no dependency."""
    columns, rows, inverse = factor[0], factor[1], factor[2]
    w = columns.shape[1]
    n = b.size
    for j in range(n):
        x[j] = b[j]
    for j in range(n):  # Uᵀ z = b
        xj = x[j] * inverse[j]
        x[j] = xj
        count = min(w, n - 1 - j)
        row = rows[j]
        below = x[j + 1 : j + 1 + count]
        for k in range(count):
            below[k] -= row[k] * xj
    for j in range(n - 1, -1, -1):  # U x = z
        xj = x[j] * inverse[j]
        x[j] = xj
        lo = max(0, j - w)
        column = columns[j, w - j + lo :]
        above = x[lo:j]
        for k in range(j - lo):
            above[k] -= column[k] * xj


@inlined
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


@inlined
def _element_responses(d, c, slot, e, rows_c, p_b, comp, g_modal, g_full, mq, forces):  # pragma: no cover
    """A unit force at each of the element's 4 DOFs: interface response p_b (4, n_b), compliance
    (4, 4) with the residual, the droppers' elongations (4, D), of the kept modes and with the
    residual, and mq = rows_q D⁻¹ M_qc (4, n_c). The element lies in pantograph ``slot``'s span, which
    keeps all its modes in configuration c: its interface forces F = rows_c - c_m mq act at that span's
    coupled DOFs, whose S⁻¹ columns and droppers' responses the configuration holds."""
    c_m = d.coefficients.mass_factor
    s = d.element_span[e]
    t = d.span_type[s]
    nc = d.n_coupled[t]
    for r in range(4):
        local = d.element_local[e, r]
        for j in range(nc):
            mq[r, j] = d.shape_coupling[t, local, j] if local >= 0 else 0.0
            forces[r, j] = rows_c[r, j] - c_m * mq[r, j]
    p_b[:] = 0.0
    g_modal[:] = 0.0
    for r in range(4):
        for j in range(nc):
            _axpy(d.element_interface[c, slot, j], forces[r, j], p_b[r], p_b.shape[1])
            _axpy(d.dropper_element_interface[c, slot, j], forces[r, j], g_modal[r], g_modal.shape[1])
    for r in range(4):  # rows_q D⁻¹ rows_qᵀ + residual + (rows_c - c_m rows_q D⁻¹ M_qc) p_c
        for col in range(4):
            acc = d.element_compliance[e, r, col] + d.element_modal_compliance[e, r, col]
            for j in range(nc):
                acc += forces[r, j] * p_b[col, d.coupled[s, j]]
            comp[r, col] = acc
    g_full[:] = g_modal
    for k in range(d.element_droppers.shape[1]):
        q = d.element_droppers[e, k]
        if q >= 0:
            for col in range(4):
                g_modal[col, q] += d.element_dropper_modal[e, col, k]
                g_full[col, q] += d.element_dropper_modal[e, col, k] + d.element_dropper_residual[e, col, k]


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
    st.configuration[0] = c


@njit(cache=True, fastmath=FAST)
def _dropper_row(d, c, q, rhs, x, modal, full):  # pragma: no cover - compiled
    """Dropper q's row of :func:`.preparation.dropper_responses` in configuration c: the interface's motion
    x = S⁻¹ (B_c - c_m H)_qᵀ under a unit force at q, and the droppers' elongations under it, of the kept
    modes and with the residual (G's row q: G is symmetric). ``rhs``: work space (n_b,)."""
    s = d.dropper_span[q]
    rhs[:] = 0.0
    for j in range(d.n_coupled[d.span_type[s]]):
        rhs[d.coupled[s, j]] = d.dropper_interface_force[c, q, j]
    _band_solve((d.schur_columns[c], d.schur_rows[c], d.schur_inverse_diagonal[c]), rhs, x)
    for r in range(modal.size):
        sr = d.dropper_span[r]
        acc = 0.0
        for j in range(d.n_coupled[d.span_type[sr]]):
            acc += d.dropper_interface_force[c, r, j] * x[d.coupled[sr, j]]
        modal[r] = acc
        full[r] = acc
    first = d.dropper_start[s]
    n = d.dropper_start[s + 1] - first
    block = d.block_start[s] + (q - first) * n
    for j in range(n):
        modal[first + j] += d.dropper_blocks[c, 0, block + j]
        full[first + j] += d.dropper_blocks[c, 1, block + j]


@njit(cache=True, fastmath=FAST)
def _fill_rows(d, c, slack, count, ready, rhs, x_rows, g_modal_rows, g_rows):  # pragma: no cover - compiled
    """The rows (:func:`_dropper_row`) of the slack droppers among the first ``count`` whose rows are not
    ready."""
    for q in range(count):
        if slack[q] and not ready[q]:
            _dropper_row(d, c, q, rhs, x_rows[q], g_modal_rows[q], g_rows[q])
            ready[q] = True


@inlined
def _rows_dot(rows, first, count, x, m, out):  # pragma: no cover - compiled
    """out[k] = rows[first + k, :m] · x[:m] for k < count, four rows per pass over x."""
    k = 0
    while k + 4 <= count:
        r0, r1, r2, r3 = rows[first + k], rows[first + k + 1], rows[first + k + 2], rows[first + k + 3]
        s0 = s1 = s2 = s3 = 0.0
        for i in range(m):
            xi = x[i]
            s0 += r0[i] * xi
            s1 += r1[i] * xi
            s2 += r2[i] * xi
            s3 += r3[i] * xi
        out[k], out[k + 1], out[k + 2], out[k + 3] = s0, s1, s2, s3
        k += 4
    while k < count:
        out[k] = _dot(rows[first + k], x, m)
        k += 1


@inlined
def _rows_dot_pair(rows, count, x, z, m, out_x, out_z):  # pragma: no cover - compiled
    """out_x[k] = rows[k, :m] · x[:m] and out_z[k] = rows[k, :m] · z[:m] for k < count: two spans of one type
    in one pass over their rows, four rows a pass (each row read once for both spans)."""
    k = 0
    while k + 4 <= count:
        r0, r1, r2, r3 = rows[k], rows[k + 1], rows[k + 2], rows[k + 3]
        s0 = s1 = s2 = s3 = 0.0
        t0 = t1 = t2 = t3 = 0.0
        for i in range(m):
            xi = x[i]
            zi = z[i]
            a0, a1, a2, a3 = r0[i], r1[i], r2[i], r3[i]
            s0 += a0 * xi
            s1 += a1 * xi
            s2 += a2 * xi
            s3 += a3 * xi
            t0 += a0 * zi
            t1 += a1 * zi
            t2 += a2 * zi
            t3 += a3 * zi
        out_x[k], out_x[k + 1], out_x[k + 2], out_x[k + 3] = s0, s1, s2, s3
        out_z[k], out_z[k + 1], out_z[k + 2], out_z[k + 3] = t0, t1, t2, t3
        k += 4
    while k < count:
        r = rows[k]
        s0 = t0 = 0.0
        for i in range(m):
            s0 += r[i] * x[i]
            t0 += r[i] * z[i]
        out_x[k], out_z[k] = s0, t0
        k += 1


@inlined
def _span_pairs(d, c, partner, stepped):  # pragma: no cover - compiled
    """Pair the first ``stepped`` spans of configuration c that share a type and a number of kept modes:
    partner[s] is the later span of s's pair, -1 for a span without one, -2 for the later span of a pair."""
    n = partner.size
    for s in range(n):
        partner[s] = -1
    for s in range(stepped):
        if partner[s] != -1:
            continue
        for s2 in range(s + 1, stepped):
            if partner[s2] == -1 and d.span_type[s2] == d.span_type[s] and d.kept[c, s2] == d.kept[c, s]:
                partner[s] = s2
                partner[s2] = -2
                break


@inlined
def _rows_axpy(rows, g, count, out, m):  # pragma: no cover - compiled
    """out[:m] += Σ_k g[k] rows[k, :m] over k < count, four rows per pass over out."""
    k = 0
    while k + 4 <= count:
        r0, r1, r2, r3 = rows[k], rows[k + 1], rows[k + 2], rows[k + 3]
        g0, g1, g2, g3 = g[k], g[k + 1], g[k + 2], g[k + 3]
        for i in range(m):
            out[i] += r0[i] * g0 + r1[i] * g1 + r2[i] * g2 + r3[i] * g3
        k += 4
    while k < count:
        _axpy(rows[k], g[k], out, m)
        k += 1


@inlined
def _contact_point(  # pragma: no cover - compiled
    d, point, ps, k, c, el, rows_q, rows_c, m_qc, comp, g_full, g_modal, e_vec, y, x_b, g_c, h_q, g_dc, gm_dc,
    rhs_p, y_known,
):  # fmt: skip
    """The contact point at step k, on element ``el`` (its rows and responses from :func:`_element_rows` and
    :func:`_element_responses`): the gap without the step's forces (m) and its compliance (m/N), returned;
    fills h_q = h rows_q, its couplings to the droppers, with the residual (g_dc) and of the kept modes
    (gm_dc), and the pantograph's known response y_known."""
    h = point.shape[k]
    s_el = d.element_span[el]
    t_el = d.span_type[s_el]
    n_q = d.modal_offset[d.span_type.size]
    # The wire under it: h rows_q (D⁻¹ (e_q + M_qc g_c) + y_q) + h rows_c u_c.
    off = d.modal_offset[s_el]
    m = d.kept[c, s_el]
    inv_d = d.inverse_diagonal[t_el]
    r0, r1, r2, r3 = rows_q[0], rows_q[1], rows_q[2], rows_q[3]
    # Two loops, not one: a loop that stores h_q and sums `wire` is vectorised behind a run-time check that
    # h_q lies clear of what it reads, and that check (on the distance between addresses) now and then
    # fails for arrays that merely lie close; the scalar fallback then sums in another order, so the forces
    # changed in their 13th digit with where the allocator put a work array (docs/model.md, 'Results and
    # the model that made them'). A loop that sums stores nothing.
    for i in range(m):
        h_q[i] = h[0] * r0[i] + h[1] * r1[i] + h[2] * r2[i] + h[3] * r3[i]
    wire = 0.0
    for i in range(m):
        wire += h_q[i] * (inv_d[i] * e_vec[off + i] + y[off + i])
    for j in range(d.n_coupled[t_el]):
        cj = d.coupled[s_el, j]
        hm = h[0] * m_qc[0, j] + h[1] * m_qc[1, j] + h[2] * m_qc[2, j] + h[3] * m_qc[3, j]
        hc = h[0] * rows_c[0, j] + h[1] * rows_c[1, j] + h[2] * rows_c[2, j] + h[3] * rows_c[3, j]
        wire += hm * g_c[s_el, j] + hc * (x_b[cj] + y[n_q + cj])
    known_response_in_place(point, d.coefficients, ps, rhs_p, y_known)
    head = ps.y.size - 1
    gap_known = y_known[head] - point.wire_z[k] - wire
    c_cc = point.y_star[head]
    for r in range(4):
        for cc in range(4):
            c_cc += h[r] * comp[r, cc] * h[cc]
    for q in range(g_dc.size):
        g_dc[q] = g_full[0, q] * h[0] + g_full[1, q] * h[1] + g_full[2, q] * h[2] + g_full[3, q] * h[3]
        gm_dc[q] = g_modal[0, q] * h[0] + g_modal[1, q] * h[1] + g_modal[2, q] * h[2] + g_modal[3, q] * h[3]
    return gap_known, c_cc


@njit(cache=True, fastmath=FAST)
def _cross_compliance(d, points, k, forces, p_b, c_cc):  # pragma: no cover - compiled
    """c_cc[i, j] (m/N) of the pantographs in different spans: the displacement under pantograph i of a unit
    force under pantograph j, through the interface, h_i (rows_c - c_m mq)_i p_b,j h_j."""
    n_c = len(points)
    for i in range(n_c):
        ei = points[i].element[k]
        if ei < 0:
            continue
        hi = points[i].shape[k]
        si = d.element_span[ei]
        nc = d.n_coupled[d.span_type[si]]
        for j in range(n_c):
            if j == i or points[j].element[k] < 0:
                continue
            hj = points[j].shape[k]
            acc = 0.0
            for r in range(4):
                for col in range(4):
                    t = 0.0
                    for jj in range(nc):
                        t += forces[i, r, jj] * p_b[j, col, d.coupled[si, jj]]
                    acc += hi[r] * t * hj[col]
            c_cc[i, j] = acc


@njit(cache=True, fastmath=FAST)
def run_steps(d, points, st, configuration, stepped, first, stop):  # pragma: no cover - compiled  # noqa: C901
    """Steps ``first`` to ``stop - 1`` of the passage, updating the SpanModeState ``st`` in place.

    ``points`` holds the contact points' arrays, ``configuration`` (steps,) each step's configuration and
    ``stepped`` (steps,) the spans each step advances, the first ones: those beyond lie ahead of the wave
    front, at rest to rounding, and are held there with the interface DOFs only they reach (step 1's
    band solve is then the leading block of S's factor, that of the spans stepped with the next support
    held; docs/performance.md, 'The spans ahead of the wave front')."""
    ps = st.pantographs
    n_c = len(points)
    cf = d.coefficients
    g1, g2, g3 = cf.g1, cf.g2, cf.g3
    a0, a1, a2, a3, a4, a5 = cf.a0, cf.a1, cf.a2, cf.a3, cf.a4, cf.a5
    kh, beta, c_m = cf.contact_stiffness, cf.rayleigh_beta, cf.mass_factor
    n_spans = d.span_type.size
    n_b = d.schur_inverse_diagonal.shape[1]
    n_q = d.modal_offset[n_spans]
    n_drop = d.droppers.force.size
    p_max = 0
    for i in range(n_c):
        p_max = max(p_max, ps[i].y.size)
    m_max = d.coupling.shape[2]
    nc_max = d.coupling.shape[1]
    width = (d.interface_rhs_rows.shape[2] - 1) // 2
    u, v, acc_s, e_vec, y = st.u, st.v, st.a, st.e, st.y
    rows_q = np.zeros((n_c, 4, m_max))
    rows_c = np.zeros((n_c, 4, nc_max))
    p_b = np.zeros((n_c, 4, n_b))
    comp = np.zeros((n_c, 4, 4))
    g_modal = np.zeros((n_c, 4, n_drop))
    g_full = np.zeros((n_c, 4, n_drop))
    m_qc = np.zeros((n_c, 4, nc_max))  # each element's rows_q D⁻¹ M_qc
    forces = np.zeros((n_c, 4, nc_max))  # its interface forces rows_c - c_m rows_q D⁻¹ M_qc
    work_b = np.zeros(n_b)
    e_pad = np.zeros(n_b + 2 * width)  # the interface's e between w zeros each side
    x_b = np.zeros(n_b)
    g_c = np.zeros((n_spans, nc_max))  # e_c - c_m x_c of each span's coupled interface DOFs
    x_c = np.zeros((n_spans, nc_max))  # x_c
    sums = np.zeros(nc_max)  # a span's sums over its coupled interface DOFs
    span_sums = np.zeros((n_spans, nc_max))  # every span's, summed into the interface in track order
    partner = np.full(n_spans, -1, dtype=np.int64)  # the spans paired in this configuration
    paired = -1  # the spans stepped when they were paired
    g_dc = np.zeros((n_c, n_drop))
    gm_dc = np.zeros((n_c, n_drop))
    c_cc = np.zeros((n_c, n_c))
    gap_known = np.zeros(n_c)
    dl_known = np.zeros(n_drop)
    b_new = np.zeros(n_drop)  # the droppers' new elongations B u over the kept modes
    rate_term = np.zeros(n_drop)
    work = settle_workspace(n_c, n_drop)
    lam, idx, elastic, f = work[2], work[3], work[4], work[6]
    # The slack droppers' rows of dropper_responses, each filled when its dropper first goes slack in the
    # configuration (_dropper_row): X, G of the kept modes and G with the residual.
    x_rows = np.empty((n_drop, n_b))
    g_modal_rows = np.empty((n_drop, n_drop))
    g_rows = np.empty((n_drop, n_drop))
    ready = np.zeros(n_drop, dtype=np.bool_)
    row_rhs = np.zeros(n_b)
    rows_of = -1  # the configuration they are of
    y_known = np.zeros((n_c, p_max))
    rhs_p = np.zeros(p_max)
    fq = np.zeros(m_max)  # a span's modes' right-hand side
    h_q = np.zeros((n_c, m_max))  # h rows_q: each contact point's row over its span's modes
    contact = np.zeros(n_c, dtype=np.bool_)
    current = np.full(n_c, -1, dtype=np.int64)
    for i in range(n_c):
        contact[i] = ps[i].contact[0] != 0

    for k in range(first, stop):
        c = configuration[k]
        if c != st.configuration[0]:
            _configure(d, st, c)
            paired = -1
            for i in range(n_c):
                current[i] = -1
        if c != rows_of:  # the droppers slack as the loop enters the configuration
            ready[:] = False
            _fill_rows(d, c, st.slack, n_drop, ready, row_rhs, x_rows, g_modal_rows, g_rows)
            rows_of = c
        n_s = stepped[k]
        if n_s != paired:
            _span_pairs(d, c, partner, n_s)
            paired = n_s
        n_bs = d.interface_end[n_s - 1]  # the interface DOFs stepped
        n_ds = d.dropper_start[n_s]  # the droppers stepped
        for i in range(n_c):
            el = points[i].element[k]
            if el >= 0 and el != current[i]:
                _element_rows(d, el, rows_q[i], rows_c[i])
                _element_responses(
                    d, c, i, el, rows_c[i], p_b[i], comp[i], g_modal[i], g_full[i], m_qc[i], forces[i]
                )
                current[i] = el
        # 1. Interface part of K̂⁻¹ M e, and the droppers' modal part of step 2, span by span.
        band = d.interface_rhs_rows[c]
        e_pad[width : width + n_b] = e_vec[n_q:]
        for r in range(n_bs):
            work_b[r] = _dot(band[r], e_pad[r:], 2 * width + 1)
        for s in range(n_s):  # a pair of spans of one type in one pass over its rows
            z = partner[s]
            if z == -2:
                continue
            t = d.span_type[s]
            off = d.modal_offset[s]
            m = d.kept[c, s]
            e_s = e_vec[off : off + m]
            nc = d.n_coupled[t]
            first_q = d.dropper_start[s]
            n_dq = d.dropper_start[s + 1] - first_q
            if z < 0:
                _rows_dot(d.weighted_coupling[t], 0, nc, e_s, m, span_sums[s])
                _rows_dot(d.type_dropper_q[t], 0, n_dq, e_s, m, dl_known[first_q:])
            else:
                e_z = e_vec[d.modal_offset[z] : d.modal_offset[z] + m]
                _rows_dot_pair(d.weighted_coupling[t], nc, e_s, e_z, m, span_sums[s], span_sums[z])
                first_z = d.dropper_start[z]
                _rows_dot_pair(d.type_dropper_q[t], n_dq, e_s, e_z, m, dl_known[first_q:], dl_known[first_z:])
        for s in range(n_s):
            for j in range(d.n_coupled[d.span_type[s]]):
                work_b[d.coupled[s, j]] += span_sums[s, j]
        _band_solve(
            (d.schur_columns[c, :n_bs], d.schur_rows[c, :n_bs], d.schur_inverse_diagonal[c, :n_bs]),
            work_b[:n_bs],
            x_b[:n_bs],
        )
        for s in range(n_s):
            t = d.span_type[s]
            for j in range(d.n_coupled[t]):
                x_c[s, j] = x_b[d.coupled[s, j]]
                g_c[s, j] = e_vec[n_q + d.coupled[s, j]] - c_m * x_c[s, j]
        # 2. Droppers' elongations of u_known = K̂⁻¹ M e + y.
        for q in range(n_ds):
            sd = d.dropper_span[q]
            nc = d.n_coupled[d.span_type[sd]]
            hd, cd, g_s, x_s = d.dropper_h[c, q], d.dropper_c[q], g_c[sd], x_c[sd]
            acc = 0.0
            for j in range(nc):  # one sum, one horizontal reduction
                acc += hd[j] * g_s[j] + cd[j] * x_s[j]
            dl_known[q] += acc
        for q in range(n_ds):  # apart, so that it vectorises
            dl_known[q] += g1 * st.Bu[q] + g2 * st.Bv[q] + g3 * st.Ba[q]
            rate_term[q] = beta * d.droppers.rate[q] * (a1 * st.Bu[q] + a4 * st.Bv[q] + a5 * st.Ba[q])
        for i in range(n_c):
            for j in range(n_c):
                c_cc[i, j] = 0.0
            el = points[i].element[k]
            if el < 0:  # off the section: out of contact, no coupling
                gap_known[i] = -1.0
                c_cc[i, i] = 1.0
                for q in range(n_drop):
                    g_dc[i, q] = 0.0
                    gm_dc[i, q] = 0.0
                continue
            gap_known[i], c_cc[i, i] = _contact_point(
                d, points[i], ps[i], k, c, el, rows_q[i], rows_c[i], m_qc[i], comp[i], g_full[i], g_modal[i],
                e_vec, y, x_b, g_c, h_q[i], g_dc[i, :n_ds], gm_dc[i, :n_ds], rhs_p, y_known[i],
            )  # fmt: skip
        if n_c > 1:
            _cross_compliance(d, points, k, forces, p_b, c_cc)
        # 3. Contact forces and slack droppers, with the rows of the droppers gone slack filled as they go.
        iteration = 0
        while iteration >= 0:
            n_slack, resolved, iteration = settle_in_place(
                contact,
                st.slack[:n_ds],
                gap_known,
                c_cc,
                g_dc[:, :n_ds],
                dl_known[:n_ds],
                rate_term[:n_ds],
                kh,
                d.droppers,
                g_rows,
                work,
                ready,
                iteration,
            )
            if iteration >= 0 or not resolved:  # gone slack (an unresolved step's: for the next step)
                _fill_rows(d, c, st.slack, n_ds, ready, row_rhs, x_rows, g_modal_rows, g_rows)
        # 4. Their interface response, then every span's modes with the Newmark update.
        for p in range(n_c):
            if points[p].element[k] < 0:
                continue
            h = points[p].shape[k]
            pb = p_b[p]
            for i in range(n_bs):
                x_b[i] += f[p] * (pb[0, i] * h[0] + pb[1, i] * h[1] + pb[2, i] * h[2] + pb[3, i] * h[3])
        for qq in range(n_slack):
            for i in range(n_bs):
                x_b[i] += lam[qq] * x_rows[idx[qq], i]
        for s in range(n_s):  # x_q = D⁻¹ (e_q + F_q + M_qc (e_c - c_m x_c)), then Newmark
            t = d.span_type[s]
            off = d.modal_offset[s]
            m = d.kept[c, s]
            end = off + m
            e_s = e_vec[off:end]
            for i in range(m):
                fq[i] = e_s[i]
            for p in range(n_c):
                el = points[p].element[k]
                if el >= 0 and d.element_span[el] == s:
                    _axpy(h_q[p], f[p], fq, m)
            for qq in range(n_slack):
                if d.dropper_span[idx[qq]] == s:
                    _axpy(d.dropper_q_plain[idx[qq]], lam[qq], fq, m)
            nc = d.n_coupled[t]
            for j in range(nc):
                sums[j] = e_vec[n_q + d.coupled[s, j]] - c_m * x_b[d.coupled[s, j]]
            _rows_axpy(d.coupling[t], sums, nc, fq, m)
            inv_d = d.inverse_diagonal[t]
            for i in range(m):
                fq[i] *= inv_d[i]
            advance(u[off:end], v[off:end], acc_s[off:end], e_s, y[off:end], fq, cf)
        i_s = n_q + n_bs
        advance(u[n_q:i_s], v[n_q:i_s], acc_s[n_q:i_s], e_vec[n_q:i_s], y[n_q:i_s], x_b[:n_bs], cf)
        for q in range(n_ds):
            b_new[q] = dl_known[q]
        for p in range(n_c):  # by rows, so that it vectorises
            _axpy(gm_dc[p], f[p], b_new, n_ds)
        for qq in range(n_slack):  # symmetric: rows, as in settle_in_place
            _axpy(g_modal_rows[idx[qq]], lam[qq], b_new, n_ds)
        for q in range(n_ds):
            bu = b_new[q]
            du = bu - st.Bu[q]
            ba = a0 * du - a2 * st.Bv[q] - a3 * st.Ba[q]
            st.Bv[q] = a1 * du - a4 * st.Bv[q] - a5 * st.Ba[q]
            st.Ba[q] = ba
            st.Bu[q] = bu
        for p in range(n_c):
            head = ps[p].y.size - 1
            el = points[p].element[k]
            if el < 0:
                st.history.force[p, k] = 0.0
                st.history.head_height[p, k] = ps[p].y[head]
                st.history.wire_uplift[p, k] = 0.0
                continue
            advance_pantograph_in_place(points[p], cf, ps[p], y_known[p], f[p])
            h = points[p].shape[k]
            s_el = d.element_span[el]
            t_el = d.span_type[s_el]
            off = d.modal_offset[s_el]
            upl = _dot(h_q[p], u[off:], d.kept[c, s_el])
            rc = rows_c[p]
            for j in range(d.n_coupled[t_el]):
                hc = h[0] * rc[0, j] + h[1] * rc[1, j] + h[2] * rc[2, j] + h[3] * rc[3, j]
                upl += hc * u[n_q + d.coupled[s_el, j]]
            st.history.force[p, k] = f[p]
            st.history.head_height[p, k] = ps[p].y[head]
            st.history.wire_uplift[p, k] = upl
        record_in_place(st.history, k, elastic, st.slack[:n_ds], n_slack > 0, resolved)
        for i in range(d.support.size):
            st.history.support_uplift[k, i] = u[n_q + d.support[i]]
    for i in range(n_c):
        ps[i].contact[0] = 1 if contact[i] else 0
