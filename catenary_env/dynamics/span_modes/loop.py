"""The span-mode model's time loop in numpy: the compiled loop's steps
(:mod:`~catenary_env.dynamics.span_modes.kernels`), with scipy's banded solves (docs/performance.md,
'Model fidelities').

It reads the same named records as the compiled loop: the design's
:class:`~catenary_env.dynamics.span_modes.preparation.SpanModeArrays`, the contact point's
:class:`~catenary_env.dynamics.contact_point.ContactPointArrays` and the
:class:`~catenary_env.dynamics.newmark.StepCoefficients`, and updates a
:class:`~catenary_env.dynamics.span_modes.passage.SpanModeState`.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from numpy.lib.stride_tricks import sliding_window_view

from ..active_set import settle
from ..contact_point import ContactPointArrays, advance_pantograph, known_response
from ..history import record
from .preparation import SpanModeArrays, dropper_responses
from .state import SpanModeState


def run_steps(  # noqa: C901
    d: SpanModeArrays,
    points: tuple[ContactPointArrays, ...],
    st: SpanModeState,
    configuration: np.ndarray,
    stepped: np.ndarray,
    first: int,
    stop: int,
) -> None:
    """Steps ``first`` to ``stop - 1`` of the passage, updating ``st`` in place: the compiled loop's steps in
    numpy. ``configuration`` (steps,) is each step's configuration, ``stepped`` (steps,) the spans it
    advances, the first ones (the others are held, with the interface DOFs only they reach)."""
    cf = d.coefficients
    g1, g2, g3 = cf.g1, cf.g2, cf.g3
    a0, a1, a2, a3, a4, a5 = cf.a0, cf.a1, cf.a2, cf.a3, cf.a4, cf.a5
    kh, beta, c_m = cf.contact_stiffness, cf.rayleigh_beta, cf.mass_factor
    n_spans = d.span_type.size
    n_q = d.modal_offset[-1]
    n_c = len(points)
    heads = [point.y_star.size - 1 for point in points]
    width = (d.interface_rhs_rows.shape[2] - 1) // 2
    N0 = d.droppers.force
    contact = np.array([bool(ps.contact[0]) for ps in st.pantographs])
    current = [-1] * n_c
    element: list = [None] * n_c  # each point's element: rows_q, rows_c, p_b, comp, g_modal, g_full, forces
    u, v, acc_s, e_vec, y = st.u, st.v, st.a, st.e, st.y
    spans = [
        (s, d.span_type[s], d.modal_offset[s], d.coupled[s, : d.n_coupled[d.span_type[s]]])
        for s in range(n_spans)
    ]
    responses_of = -1  # the configuration whose droppers' responses X, G (of the kept modes) and G_full
    for k in range(first, stop):
        c = configuration[k]
        if c != responses_of:
            X, G_modal, G_full = dropper_responses(d, c)
            responses_of = c
        if c != st.configuration[0]:
            for s, _, off, _ in spans:
                drop = slice(off + d.kept[c, s], d.modal_offset[s + 1])
                for vec in (u, v, acc_s, e_vec, y):
                    vec[drop] = 0.0
            st.Bu[:] = _dropper_elongations(d, c, u)
            st.Bv[:] = _dropper_elongations(d, c, v)
            st.Ba[:] = _dropper_elongations(d, c, acc_s)
            st.configuration[0] = c
            current = [-1] * n_c
        on = [i for i, point in enumerate(points) if point.element[k] >= 0]
        for i in on:
            el = points[i].element[k]
            if el != current[i]:
                rows_q, rows_c = _element_rows(d, el)
                element[i] = (rows_q, rows_c, *_element_responses(d, c, el, rows_q, rows_c))
                current[i] = el
        kept = d.kept[c]
        n_s = stepped[k]
        n_bs, n_ds = d.interface_end[n_s - 1], d.dropper_start[n_s]
        # 1. Interface part of K̂⁻¹ M e.
        e_b = np.pad(e_vec[n_q:], width)
        z = np.einsum("rk,rk->r", d.interface_rhs_rows[c], sliding_window_view(e_b, 2 * width + 1))
        for s, t, off, cpl in spans[:n_s]:
            m = kept[s]
            z[cpl] += d.coupling[t, : cpl.size, :m] @ (d.weight[t, :m] * e_vec[off : off + m])
        x_b = np.zeros(z.size)
        x_b[:n_bs] = _schur_solve(d, c, z[:n_bs])
        g_c = [e_vec[n_q + cpl] - c_m * x_b[cpl] for s, t, off, cpl in spans]
        # 2. Droppers' elongations of u_known.
        dl_known = np.empty(n_ds)
        for q in range(n_ds):
            sd = d.dropper_span[q]
            s, t, off, cpl = spans[sd]
            m = kept[sd]
            dl_known[q] = (
                d.dropper_q[q, :m] @ e_vec[off : off + m]
                + d.dropper_h[c, q, : cpl.size] @ g_c[sd]
                + d.dropper_c[q, : cpl.size] @ x_b[cpl]
            )
        Bu, Bv, Ba = st.Bu[:n_ds], st.Bv[:n_ds], st.Ba[:n_ds]
        dl_known += g1 * Bu + g2 * Bv + g3 * Ba
        rate_term = beta * d.droppers.rate[:n_ds] * (a1 * Bu + a4 * Bv + a5 * Ba)
        gap_known = np.full(n_c, -1.0)  # a point off the section stays out of contact
        c_cc = np.eye(n_c)
        g_dc = np.zeros((n_c, n_ds))
        gm_dc = np.zeros((n_c, n_ds))
        y_known: list = [None] * n_c
        for i in on:
            point, h, el = points[i], points[i].shape[k], points[i].element[k]
            rows_q, rows_c, p_b, comp, g_modal, g_full, forces = element[i]
            s_el = d.element_span[el]
            s, t, off, cpl = spans[s_el]
            m = kept[s_el]
            x_q = (e_vec[off : off + m] + g_c[s_el] @ d.coupling[t, : cpl.size, :m]) * d.inverse_diagonal[
                t, :m
            ]
            u_q = x_q + y[off : off + m]
            u_c = x_b[cpl] + y[n_q + cpl]
            wire = h @ (rows_q[:, :m] @ u_q + rows_c[:, : cpl.size] @ u_c)
            y_known[i] = known_response(point, cf, st.pantographs[i])
            gap_known[i] = y_known[i][heads[i]] - point.wire_z[k] - wire
            c_cc[i, i] = h @ comp @ h + point.y_star[heads[i]]
            for j in on:  # another span's pantograph: through the interface only
                if j != i:
                    c_cc[i, j] = h @ forces @ element[j][2][cpl] @ points[j].shape[k]
            g_dc[i] = (g_full @ h)[:n_ds]
            gm_dc[i] = (g_modal @ h)[:n_ds]
        G = G_full[:n_ds, :n_ds]
        droppers = type(d.droppers)(*(field[:n_ds] for field in d.droppers))
        # 3. Contact forces and slack droppers (the exact passage's active set).
        slack = st.slack[:n_ds].copy()
        step = settle(contact, slack, gap_known, c_cc, g_dc, dl_known, rate_term, kh, droppers, G)
        contact, st.slack[:n_ds], f, idx, lam, elastic = step[:6]
        # 4. The response on the interface, then every span's modes with the Newmark update.
        for i in on:
            x_b[:n_bs] += f[i] * (element[i][2] @ points[i].shape[k])[:n_bs]
        x_b[:n_bs] += (lam @ X[idx])[:n_bs]
        for s, t, off, cpl in spans[:n_s]:
            m = kept[s]
            fq = e_vec[off : off + m].copy()
            for i in on:
                if d.element_span[points[i].element[k]] == s:
                    fq += f[i] * (points[i].shape[k] @ element[i][0][:, :m])
            for q, lq in zip(idx, lam, strict=True):
                if d.dropper_span[q] == s:
                    fq += lq * d.dropper_q_plain[q, :m]
            fq += (e_vec[n_q + cpl] - c_m * x_b[cpl]) @ d.coupling[t, : cpl.size, :m]
            p = slice(off, off + m)
            u_new = fq * d.inverse_diagonal[t, :m] + y[p]
            _newmark(u, v, acc_s, e_vec, y, p, u_new, cf)
        b = slice(n_q, n_q + n_bs)
        _newmark(u, v, acc_s, e_vec, y, b, x_b[:n_bs] + y[b], cf)
        bu = dl_known + gm_dc.T @ f + G_modal[:n_ds, idx] @ lam
        du = bu - Bu
        ba = a0 * du - a2 * Bv - a3 * Ba
        st.Bv[:n_ds] = a1 * du - a4 * Bv - a5 * Ba
        st.Ba[:n_ds] = ba
        st.Bu[:n_ds] = bu
        uplift = np.zeros(n_c)
        for i in on:
            advance_pantograph(points[i], cf, st.pantographs[i], y_known[i], f[i])
            rows_q, rows_c = element[i][:2]
            s, t, off, cpl = spans[d.element_span[points[i].element[k]]]
            m = kept[s]
            h = points[i].shape[k]
            uplift[i] = h @ (rows_q[:, :m] @ u[off : off + m] + rows_c[:, : cpl.size] @ u[n_q + cpl])
        heights = np.array([ps.y[head] for ps, head in zip(st.pantographs, heads, strict=True)])
        forces = N0.copy()  # a dropper held ahead of the wave front keeps its static force
        forces[:n_ds] = elastic
        record(
            st.history, k, f, heights, uplift, u[n_q + d.support], forces, st.slack, idx.size > 0,
            step.resolved,
        )  # fmt: skip
    for ps, touching in zip(st.pantographs, contact, strict=True):
        ps.contact[0] = int(touching)


def _schur_solve(d: SpanModeArrays, c: int, b: np.ndarray) -> np.ndarray:
    """S⁻¹ b, or for b shorter than the interface the leading block's: the first interface DOFs' system with
    the others held."""
    return sla.cho_solve_banded((d.schur_band[c][:, : b.shape[0]], False), b, check_finite=False)


def _element_rows(d: SpanModeArrays, e: int) -> tuple[np.ndarray, np.ndarray]:
    t = d.span_type[d.element_span[e]]
    rows_q = np.zeros((4, d.coupling.shape[2]))
    rows_c = np.zeros((4, d.coupling.shape[1]))
    for i in range(4):
        local = d.element_local[e, i]
        if local >= 0:
            rows_q[i] = d.shapes[t, local]
            rows_c[i] = d.constraint[t, local]
        else:
            rows_c[i, -1 - local] = 1.0
    return rows_q, rows_c


def _element_responses(
    d: SpanModeArrays, c: int, e: int, rows_q: np.ndarray, rows_c: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """As the compiled loop's: p_b (n_b, 4), compliance (4, 4), g_modal and g_full (D, 4), and the
    element's interface forces rows_c - c_m rows_q D⁻¹ M_qc (4, n_c): its displacement under the
    interface's motion, through which another span's pantograph moves it."""
    c_m = d.coefficients.mass_factor
    s = d.element_span[e]
    t = d.span_type[s]
    m = d.kept[c, s]
    nc = d.n_coupled[t]
    idiag = d.inverse_diagonal[t, :m]
    coupling = d.coupling[t, :nc, :m]  # M_cq
    n_b = d.schur_inverse_diagonal.shape[1]
    F_b = np.zeros((n_b, 4))
    np.add.at(F_b, d.coupled[s, :nc], rows_c[:, :nc].T - c_m * coupling @ (idiag[:, None] * rows_q[:, :m].T))
    p_b = _schur_solve(d, c, F_b)
    p_c = p_b[d.coupled[s, :nc]]
    rq = rows_q[:, :m] * idiag
    comp = d.element_compliance[e] + rq @ rows_q[:, :m].T + (rows_c[:, :nc] - c_m * rq @ coupling.T) @ p_c
    g = np.zeros((d.droppers.force.size, 4))
    for q in range(d.droppers.force.size):
        sd = d.dropper_span[q]
        ncd = d.n_coupled[d.span_type[sd]]
        g[q] = (d.dropper_c[q, :ncd] - c_m * d.dropper_h[c, q, :ncd]) @ p_b[d.coupled[sd, :ncd]]
        if sd == s:
            g[q] += rows_q[:, :m] @ d.dropper_q[q, :m]
    g_full = g.copy()
    drops = d.element_droppers[e]
    ok = drops >= 0
    g_full[drops[ok]] += d.element_dropper_residual[e][:, ok].T
    return p_b, comp, g, g_full, rows_c[:, :nc] - c_m * rq @ coupling.T


def _dropper_elongations(d: SpanModeArrays, c: int, vec: np.ndarray) -> np.ndarray:
    n_q = d.modal_offset[-1]
    out = np.zeros(d.droppers.force.size)
    for q in range(out.size):
        s = d.dropper_span[q]
        off = d.modal_offset[s]
        k = d.kept[c, s]
        nc = d.n_coupled[d.span_type[s]]
        out[q] = (
            d.dropper_q_plain[q, :k] @ vec[off : off + k] + d.dropper_c[q, :nc] @ vec[n_q + d.coupled[s, :nc]]
        )
    return out


def _newmark(u, v, acc, e_vec, y, p, u_new, cf) -> None:  # noqa: ANN001
    """Newmark update of the coordinates ``p`` to ``u_new``, and the next step's e and y there."""
    du = u_new - u[p]
    acc_new = cf.a0 * du - cf.a2 * v[p] - cf.a3 * acc[p]
    v_new = cf.a1 * du - cf.a4 * v[p] - cf.a5 * acc[p]
    u[p], v[p], acc[p] = u_new, v_new, acc_new
    e_vec[p] = cf.e1 * u_new + cf.e2 * v_new + cf.e3 * acc_new
    y[p] = cf.g1 * u_new + cf.g2 * v_new + cf.g3 * acc_new
