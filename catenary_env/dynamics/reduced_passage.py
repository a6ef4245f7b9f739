"""The pantograph passage on the span-mode model (docs/performance.md, 'Model fidelities').

The same Newmark scheme, superposition and active-set rules as the exact passage, in the
coordinates of :mod:`span_modes`. The effective matrix K̂ = c_k K + c_m M of the reduced system is
diagonal in each span's modes, D = c_k ω² + c_m, and couples them only through the interface DOFs,
so a solve eliminates the modes span by span and leaves a small banded system on the interface,
its Schur complement S:

    x_b = S⁻¹ (r_b - c_m Σ_s M_cq D⁻¹ r_q),     x_q = D⁻¹ (r_q - c_m M_qc x_c).

A step costs dense products with the spans' mode-interface couplings instead of two sweeps over
the whole section's banded factor.

Near field and far field. High-frequency motion is excited by the contact and the droppers near the
pantograph and dies out over a few spans (Rayleigh damping βω/2 grows with frequency), so the spans
within ``near_spans`` of the pantograph keep their modes up to the near cut-off and the others only
those below the far cut-off. The model therefore changes, by a span's high modes, when the pantograph
crosses a support: a *configuration* per span the pantograph is in, each a proper Galerkin reduction
with its own Schur complement. A span leaving the near field drops its high modes' state.

Residual flexibility. Within one step a force at the contact point or at a dropper also moves the
truncated modes. Their share of the one-step compliance, R = K̂_ii⁻¹ - Φ D⁻¹ Φᵀ per span, is added
where the forces act, so that the contact and the slack droppers see the exact one-step compliance;
the truncated modes carry no state.

Both loops, numpy (:func:`_run_numpy`) and compiled (:mod:`_reduced_kernels`), read the same
:class:`ReducedArrays` and follow the same steps (see :mod:`_reduced_kernels`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.lib.stride_tricks import sliding_window_view

from ..model.definition import PantographDefinition
from .active_set import settle
from .history import PassageHistory
from .newmark import NewmarkConstants, Trajectory
from .passage import _Passage, _start_passage
from .span_modes import ReducedSystem, band_storage, band_width, submatrix


def band_rows(ab: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An upper band factor U (LAPACK storage, (w + 1, n)) as its columns above the diagonal (n, w),
    its rows right of the diagonal (n, w) and its reciprocal diagonal (n,): the compiled loop reads
    each contiguously (see ``_reduced_kernels._band_solve``)."""
    w = ab.shape[0] - 1
    n = ab.shape[1]
    columns = np.ascontiguousarray(ab[:w].T)  # columns[j, w - k] = U[j - k, j]
    rows = np.zeros((n, w))  # rows[i, k - 1] = U[i, i + k]
    for k in range(1, w + 1):
        rows[: n - k, k - 1] = ab[w - k, k:]
    return columns, rows, 1.0 / ab[w]


@dataclass(frozen=True)
class PreparedReducedPassage:
    """The design's part of the reduced passage, computed once per design and time step.

    Attributes
    ----------
    reduced : ReducedSystem
    constants : NewmarkConstants
    near_spans : int
    arrays : dict of str to ndarray
        The loop's arrays (:class:`catenary_env._reduced_kernels.ReducedArrays` fields without the
        per-passage ones).
    """

    reduced: ReducedSystem
    constants: NewmarkConstants
    near_spans: int
    arrays: dict


def prepare_reduced_passage(
    reduced: ReducedSystem, time_step: float, near_spans: int
) -> PreparedReducedPassage:
    """The Schur complements, dropper responses and residual compliances of every configuration."""
    system = reduced.system
    nm = NewmarkConstants.for_step(time_step)
    c_k = 1.0 + system.beta * nm.a1
    c_m = nm.a0 + system.alpha * nm.a1
    modes = _mode_arrays(reduced, c_k, c_m)
    kept = _kept_modes(reduced, near_spans)
    droppers = _dropper_arrays(reduced, modes["inverse_diagonal"])
    residual = _Residuals(reduced, c_k, c_m, droppers["dropper_span"])
    configurations = _configurations(reduced, c_k, c_m, kept, modes, droppers, residual)
    elements = _element_arrays(reduced, droppers, residual)
    arrays = modes | droppers | configurations | elements
    arrays.update(
        kept=kept,
        dropper_rate=system.dropper_rate.astype(float),
        dropper_force=system.dropper_force.astype(float),
        dropper_kappa=system.dropper_rate * c_k,
        support=residual.interface_position[system.support_z],
        coefficients=_coefficients(reduced, nm, c_k, c_m),
    )
    return PreparedReducedPassage(reduced, nm, near_spans, arrays)


def _mode_arrays(reduced: ReducedSystem, c_k: float, c_m: float) -> dict[str, np.ndarray]:
    """Each span type's modes, padded to the largest type: M_cq, 1 / D, 1 - c_m / D, Φ, Ψ, Φ D⁻¹ M_qc."""
    types = reduced.types
    n_types = len(types)
    m_max = max(t.n_modes for t in types)
    nc_max = max(c.size for c in reduced.coupled)
    ni_max = max(t.shapes.shape[0] for t in types)
    coupled = np.zeros((reduced.span_type.size, nc_max), dtype=np.int64)
    for s, c in enumerate(reduced.coupled):
        coupled[s, : c.size] = c
    coupling = np.zeros((n_types, nc_max, m_max))
    inv_d = np.zeros((n_types, m_max))
    weight = np.zeros((n_types, m_max))
    shapes = np.zeros((n_types, ni_max, m_max))
    constraint = np.zeros((n_types, ni_max, nc_max))
    shape_coupling = np.zeros((n_types, ni_max, nc_max))
    for t, modes in enumerate(types):
        m, nc = modes.mass_coupling.shape
        ni = modes.shapes.shape[0]
        diagonal = c_k * modes.omega2 + c_m
        coupling[t, :nc, :m] = modes.mass_coupling.T
        inv_d[t, :m] = 1.0 / diagonal
        weight[t, :m] = 1.0 - c_m / diagonal
        shapes[t, :ni, :m] = modes.shapes
        constraint[t, :ni, :nc] = modes.constraint
        shape_coupling[t, :ni, :nc] = modes.shapes @ (modes.mass_coupling / diagonal[:, None])
    return dict(
        span_type=reduced.span_type.astype(np.int64),
        modal_offset=reduced.modal_offset.astype(np.int64),
        coupled=coupled,
        n_coupled=np.array([t.mass_coupling.shape[1] for t in types], dtype=np.int64),
        n_modes=np.array([t.n_modes for t in types], dtype=np.int64),
        coupling=coupling,
        inverse_diagonal=inv_d,
        weight=weight,
        weighted_coupling=coupling * weight[:, None, :],
        shapes=shapes,
        constraint=constraint,
        shape_coupling=shape_coupling,
    )


def _kept_modes(reduced: ReducedSystem, near_spans: int) -> np.ndarray:
    """(C, S): the modes span s keeps while the pantograph is in span c."""
    n_spans = reduced.span_type.size
    far = np.array([t.far_modes for t in reduced.types])[reduced.span_type]
    full = np.array([t.n_modes for t in reduced.types])[reduced.span_type]
    near = np.abs(np.arange(n_spans)[:, None] - np.arange(n_spans)[None, :]) <= near_spans
    return np.where(near, full[None, :], far[None, :]).astype(np.int64)


def _dropper_arrays(reduced: ReducedSystem, inv_d: np.ndarray) -> dict[str, np.ndarray]:
    """Each dropper's row of B T, split into its span's modes (B_q) and coupled interface (B_c)."""
    system = reduced.system
    B = system.dropper_elongation.tocsr()
    d_span = system.static.layout.dropper_span.astype(np.int64)
    if np.any(np.diff(d_span) < 0):
        raise AssertionError("the droppers are not in order of span")  # a bug, never a user error
    d_q = np.zeros((d_span.size, inv_d.shape[1]))
    d_c = np.zeros((d_span.size, max(c.size for c in reduced.coupled)))
    row_size = np.asarray(abs(B).sum(axis=1)).ravel()
    basis = {}  # per span type: T on its internal and coupled interface DOFs, [[Φ, Ψ], [0, I]]
    for s, dofs in enumerate(reduced.internal):
        q = np.flatnonzero(d_span == s)
        modes = reduced.modes_of(s)
        c = reduced.coupled[s]
        B_s = submatrix(B, q, np.r_[dofs, reduced.interface[c]]).toarray()  # internal, then coupled
        if not np.allclose(np.abs(B_s).sum(axis=1), row_size[q], rtol=1e-12, atol=0.0):
            raise AssertionError("a dropper's row reaches outside its span")  # a bug, never a user error
        t, m = reduced.span_type[s], modes.n_modes
        if t not in basis:
            basis[t] = np.block([[modes.shapes, modes.constraint], [np.zeros((c.size, m)), np.eye(c.size)]])
        rows = B_s @ basis[t]
        d_q[q, :m], d_c[q, : c.size] = rows[:, :m], rows[:, m:]
    return dict(
        dropper_span=d_span,
        dropper_start=np.searchsorted(d_span, np.arange(len(reduced.internal) + 1)).astype(np.int64),
        dropper_q=d_q * inv_d[reduced.span_type[d_span]],
        dropper_q_plain=d_q,
        dropper_c=d_c,
    )


class _Residuals:
    """The truncated modes' one-step compliance R = K̂_ii⁻¹ - Φ D⁻¹ Φᵀ of each span type, with the near
    and with the far modes, on the internal DOFs where forces act ("selected": the contact wire's z
    DOFs and the droppers' ends), the near modes' own Φ D⁻¹ Φᵀ there, and each span's droppers as
    rows over those DOFs. R is the truncated eigenpairs' own sum Φ_t D_t⁻¹ Φ_tᵀ (the span's
    eigenvectors diagonalise K̂_ii), without a solve and without the cancellation of a difference."""

    def __init__(self, reduced: ReducedSystem, c_k: float, c_m: float, d_span: np.ndarray) -> None:
        system = reduced.system
        B = system.dropper_elongation.tocsr()
        n_spans = reduced.span_type.size
        self.local_of = np.full(system.n_dofs, -1, dtype=np.int64)
        self.span_of = np.full(system.n_dofs, -1, dtype=np.int64)
        for s, dofs in enumerate(reduced.internal):
            self.local_of[dofs] = np.arange(dofs.size)
            self.span_of[dofs] = s
        self.interface_position = np.full(system.n_dofs, -1, dtype=np.int64)
        self.interface_position[reduced.interface] = np.arange(reduced.interface.size)
        z_dofs = system.contact_wire.z_dofs.ravel()
        self.selected, self.modal, self.near, self.far = [], [], [], []
        for t, modes in enumerate(reduced.types):
            spans_t = np.flatnonzero(reduced.span_type == t)
            dofs = np.r_[z_dofs, B[np.isin(d_span, spans_t)].indices]
            sel = np.unique(self.local_of[dofs[np.isin(self.span_of[dofs], spans_t)]])
            phi = modes.shapes[sel] / np.sqrt(c_k * modes.omega2 + c_m)
            rest = modes.truncated_shapes[sel] / np.sqrt(c_k * modes.truncated_omega2 + c_m)
            k = modes.far_modes
            self.selected.append(sel)
            self.modal.append(phi @ phi.T)
            self.near.append(rest @ rest.T)
            self.far.append(self.near[-1] + phi[:, k:] @ phi[:, k:].T)
        self.span_droppers = []
        for s in range(n_spans):
            sel = self.selected[reduced.span_type[s]]
            position = np.full(reduced.internal[s].size, -1)
            position[sel] = np.arange(sel.size)
            B_s = submatrix(B, np.flatnonzero(d_span == s), reduced.internal[s])
            rows = np.zeros((B_s.shape[0], sel.size))
            np.add.at(rows, (B_s.row, position[B_s.col]), B_s.data)
            self.span_droppers.append(rows)

    def dropper_block(self, reduced: ReducedSystem, span: int, near: bool) -> np.ndarray:
        """The span's droppers' residual flexibility B R Bᵀ, m/N."""
        t = reduced.span_type[span]
        rows = self.span_droppers[span]
        return rows @ (self.near[t] if near else self.far[t]) @ rows.T


def _configurations(
    reduced: ReducedSystem,
    c_k: float,
    c_m: float,
    kept: np.ndarray,
    modes: dict[str, np.ndarray],
    droppers: dict[str, np.ndarray],
    residual: _Residuals,
) -> dict[str, np.ndarray]:
    """Per configuration: S's banded factor, Y, H = B_q D⁻¹ M_qc, the droppers' interface responses
    and their flexibility G (of the kept modes, and with the residual); and for the pantograph's span,
    S⁻¹ at its coupled interface DOFs and the droppers' elongations there (B_c - c_m H) S⁻¹."""
    types = reduced.types
    n_spans = reduced.span_type.size
    n_b = reduced.interface.size
    d_span, d_q, d_qd, d_c = (
        droppers[k] for k in ("dropper_span", "dropper_q_plain", "dropper_q", "dropper_c")
    )
    n_drop, nc_max = d_c.shape
    inv_d, coupling = modes["inverse_diagonal"], modes["coupling"]
    width = max(
        max((int(np.ptp(c)) for c in reduced.coupled if c.size), default=0),
        band_width(reduced.interface_mass),
        band_width(reduced.interface_stiffness),
    )
    out = dict(
        schur_band=np.zeros((n_spans, width + 1, n_b)),
        schur_columns=np.zeros((n_spans, n_b, width)),
        schur_rows=np.zeros((n_spans, n_b, width)),
        schur_inverse_diagonal=np.zeros((n_spans, n_b)),
        interface_rhs_rows=np.zeros((n_spans, n_b, 2 * width + 1)),
        dropper_h=np.zeros((n_spans, n_drop, nc_max)),
        dropper_interface=np.zeros((n_spans, n_drop, n_b)),
        dropper_flexibility=np.zeros((n_spans, n_drop, n_drop)),
        dropper_modal_flexibility=np.zeros((n_spans, n_drop, n_drop)),
        element_interface=np.zeros((n_spans, nc_max, n_b)),
        dropper_element_interface=np.zeros((n_spans, nc_max, n_drop)),
    )
    # A span's share of Σ M_cq D⁻¹ M_qc, of its droppers' H, G and residual, per mode count kept.
    start = droppers["dropper_start"]
    span_sum, span_h, modal_block, residual_block = {}, {}, {}, {}
    for s in range(n_spans):
        t = reduced.span_type[s]
        q = slice(start[s], start[s + 1])
        for k in {types[t].far_modes, types[t].n_modes}:
            mqc = types[t].mass_coupling[:k] * np.sqrt(inv_d[t, :k, None])
            span_sum[s, k] = mqc.T @ mqc
            span_h[s, k] = d_qd[q, :k] @ coupling[t, :, :k].T
            modal_block[s, k] = (d_q[q, :k] * inv_d[t, :k]) @ d_q[q, :k].T
            residual_block[s, k] = residual.dropper_block(reduced, s, near=k == types[t].n_modes)
    d_cols = modes["coupled"][d_span]
    d_valid = np.arange(nc_max)[None, :] < modes["n_coupled"][reduced.span_type[d_span]][:, None]
    d_rows = np.repeat(np.arange(n_drop), nc_max)[d_valid.ravel()]
    # Every span with its far modes; a configuration adds its near spans' differences.
    far = np.array([types[t].far_modes for t in reduced.span_type])
    far_sum = np.zeros((n_b, n_b))
    far_h = np.zeros((n_drop, nc_max))
    far_blocks = np.zeros((2, n_drop, n_drop))  # the droppers' G of their span's modes, and with the residual
    for s, c in enumerate(reduced.coupled):
        q = slice(start[s], start[s + 1])
        far_sum[np.ix_(c, c)] += span_sum[s, far[s]]
        far_h[q] = span_h[s, far[s]]
        far_blocks[0, q, q] = modal_block[s, far[s]]
        far_blocks[1, q, q] = modal_block[s, far[s]] + residual_block[s, far[s]]
    diagonals = np.arange(n_b)[:, None] + np.arange(-width, width + 1)[None, :]  # Y[r, r + k] at [r, w + k]
    inside = (diagonals >= 0) & (diagonals < n_b)
    diagonals = np.clip(diagonals, 0, n_b - 1)
    for p in range(n_spans):
        sum_coupling = far_sum.copy()
        dropper_h = out["dropper_h"][p]
        dropper_h[:] = far_h
        G, G_full = out["dropper_modal_flexibility"][p], out["dropper_flexibility"][p]
        G[:], G_full[:] = far_blocks
        for s in np.flatnonzero(kept[p] != far):
            c, q, k = reduced.coupled[s], slice(start[s], start[s + 1]), kept[p, s]
            sum_coupling[np.ix_(c, c)] += span_sum[s, k] - span_sum[s, far[s]]
            dropper_h[q] = span_h[s, k]
            G[q, q] = modal_block[s, k]
            G_full[q, q] = modal_block[s, k] + residual_block[s, k]
        schur = c_k * reduced.interface_stiffness + c_m * reduced.interface_mass - c_m**2 * sum_coupling
        factor = sla.cholesky_banded(band_storage(0.5 * (schur + schur.T), width), check_finite=False)
        out["schur_band"][p] = factor
        out["schur_columns"][p], out["schur_rows"][p], out["schur_inverse_diagonal"][p] = band_rows(factor)
        Y = reduced.interface_mass - c_m * sum_coupling
        out["interface_rhs_rows"][p] = np.where(inside, Y[np.arange(n_b)[:, None], diagonals], 0.0)
        # B_c - c_m H on the interface: a unit dropper force's right-hand side (≤ n_c entries a row)
        H = np.zeros((n_drop, n_b))
        H[d_rows, d_cols[d_valid]] = (d_c - c_m * dropper_h)[d_valid]
        own = reduced.coupled[p]  # the pantograph's span: unit forces at its coupled interface DOFs
        unit = np.zeros((n_b, own.size))
        unit[own, np.arange(own.size)] = 1.0
        X = sla.cho_solve_banded((factor, False), np.c_[H.T, unit], check_finite=False)
        X, out["element_interface"][p, : own.size] = X[:, :n_drop], X[:, n_drop:].T
        out["dropper_interface"][p] = X.T
        out["dropper_element_interface"][p, : own.size] = X[own]
        HX = H @ X
        G += HX
        G_full += HX
    return out


def _element_arrays(
    reduced: ReducedSystem, droppers: dict[str, np.ndarray], residual: _Residuals
) -> dict[str, np.ndarray]:
    """Each contact-wire element's span, its DOFs' local indices (or interface positions), and its
    compliance and coupling to its span's droppers, of the residual and of the modes with the
    interface held (Φ D⁻¹ Φᵀ and Φ D⁻¹ B_qᵀ; near modes: the pantograph's span is always in the near
    field)."""
    d_span = droppers["dropper_span"]
    system = reduced.system
    lay = system.static.layout
    n_spans = reduced.span_type.size
    z_dofs = system.contact_wire.z_dofs
    n_el = z_dofs.shape[0]
    position = residual.interface_position
    in_coupled = np.full((n_spans, reduced.interface.size), -1, dtype=np.int64)
    for s, c in enumerate(reduced.coupled):
        in_coupled[s, c] = np.arange(c.size)
    x_start = system.contact_wire.x_start
    x_mid = np.r_[0.5 * (x_start[:-1] + x_start[1:]), x_start[-1] + 1e-3]
    el_span = np.minimum((x_mid // lay.span_length).astype(np.int64), n_spans - 1)
    inside = residual.span_of[z_dofs] >= 0
    if np.any(inside & (residual.span_of[z_dofs] != el_span[:, None])) or np.any(
        ~inside & (position[z_dofs] < 0)
    ):
        raise AssertionError("a contact-wire element reaches outside its span")  # a bug, never a user error
    el_local = np.where(
        inside, residual.local_of[z_dofs], -1 - in_coupled[el_span[:, None], np.maximum(position[z_dofs], 0)]
    )
    per_span = int(np.bincount(d_span, minlength=n_spans).max())
    el_droppers = np.full((n_el, per_span), -1, dtype=np.int64)
    el_comp = np.zeros((n_el, 4, 4))
    el_res = np.zeros((n_el, 4, per_span))
    el_modal = np.zeros((n_el, 4, 4))
    el_drop_modal = np.zeros((n_el, 4, per_span))
    for s in range(n_spans):
        els = np.flatnonzero(el_span == s)
        t = reduced.span_type[s]
        where = np.full(reduced.types[t].shapes.shape[0], -1)
        where[residual.selected[t]] = np.arange(residual.selected[t].size)
        R = residual.near[t]
        loc = np.where(el_local[els] >= 0, where[np.maximum(el_local[els], 0)], -1)
        ok = loc >= 0
        safe = np.maximum(loc, 0)
        both = ok[:, :, None] & ok[:, None, :]
        el_comp[els] = np.where(both, R[safe[:, :, None], safe[:, None, :]], 0.0)
        el_modal[els] = np.where(both, residual.modal[t][safe[:, :, None], safe[:, None, :]], 0.0)
        drops = np.flatnonzero(d_span == s)
        el_droppers[els, : drops.size] = drops
        rows = residual.span_droppers[s].T
        el_res[els, :, : drops.size] = np.where(ok[:, :, None], (R @ rows)[safe], 0.0)
        el_drop_modal[els, :, : drops.size] = np.where(ok[:, :, None], (residual.modal[t] @ rows)[safe], 0.0)
    return dict(
        element_span=el_span,
        element_local=el_local,
        element_compliance=el_comp,
        element_droppers=el_droppers,
        element_dropper_residual=el_res,
        element_modal_compliance=el_modal,
        element_dropper_modal=el_drop_modal,
    )


def _coefficients(reduced: ReducedSystem, nm: NewmarkConstants, c_k: float, c_m: float) -> np.ndarray:
    """e1..e3, g1..g3, a0..a5, k_h, β, c_m, 1 / c_k: the next u_known is K̂⁻¹ M e + y with
    e = e1 u + e2 v + e3 a and y = g1 u + g2 v + g3 a. With Rayleigh damping K̂ = c_k K + c_m M, so
    K̂⁻¹ (M x + K z) = K̂⁻¹ M (x - c_m z / c_k) + z / c_k: no product with K (y = z / c_k, the
    convention of the exact loop's ``_kernels._advance``)."""
    system = reduced.system
    x_coef = np.array(
        [nm.a0 + system.alpha * nm.a1, nm.a2 + system.alpha * nm.a4, nm.a3 + system.alpha * nm.a5]
    )
    g_coef = system.beta * np.array([nm.a1, nm.a4, nm.a5])
    contact = system.static.layout.catenary.contact_stiffness
    newmark = [nm.a0, nm.a1, nm.a2, nm.a3, nm.a4, nm.a5]
    return np.concatenate(
        [x_coef - (c_m / c_k) * g_coef, g_coef / c_k, newmark, [contact, system.beta, c_m, 1 / c_k]]
    )


class _Arrays:
    """Attribute access to the loop's arrays (the numpy loop reads what the compiled one reads)."""

    def __init__(self, fields: dict) -> None:
        self.__dict__.update(fields)


def _passage_arrays(prepared: PreparedReducedPassage, passage: _Passage) -> dict:
    pm = passage.pantograph
    element = passage.element.astype(np.int64)
    return dict(
        prepared.arrays,
        config=prepared.arrays["element_span"][element],
        element=element,
        shape=np.ascontiguousarray(passage.shape, dtype=float),
        wire_z=passage.wire_z.astype(float),
        pantograph_inverse=passage.pantograph_inverse,
        pantograph_mass=np.ascontiguousarray(pm.mass, dtype=float),
        pantograph_damping=np.ascontiguousarray(pm.damping, dtype=float),
        y_star=passage.y_star,
        load_p=passage.load_p,
    )


def _initial_acceleration(reduced: ReducedSystem, kept: np.ndarray, load: np.ndarray) -> np.ndarray:
    """a = M_r⁻¹ Tᵀ load over the kept modes, for the catenary at rest under the first contact force."""
    n_q = reduced.n_modal
    off = reduced.modal_offset
    rhs = reduced.rows(np.flatnonzero(load)).T @ load[np.flatnonzero(load)]
    schur = reduced.interface_mass.copy()
    r_b = rhs[n_q:].copy()
    for s, c in enumerate(reduced.coupled):
        coupling = reduced.modes_of(s).mass_coupling[: kept[s]]
        schur[np.ix_(c, c)] -= coupling.T @ coupling
        r_b[c] -= coupling.T @ rhs[off[s] : off[s] + kept[s]]
    x = np.zeros_like(rhs)
    x_b = np.linalg.solve(schur, r_b)
    x[n_q:] = x_b
    for s, c in enumerate(reduced.coupled):
        coupling = reduced.modes_of(s).mass_coupling[: kept[s]]
        x[off[s] : off[s] + kept[s]] = rhs[off[s] : off[s] + kept[s]] - coupling @ x_b[c]
    return x


def simulate_reduced_passage(
    prepared: PreparedReducedPassage,
    pantograph: PantographDefinition,
    uplift_force: float,
    speed: float,
    n_steps: int | None = None,
    backend: str = "auto",
    progress: Callable[[float], None] | None = None,
) -> Trajectory:
    """Pantograph passage over the whole section on the span-mode model (same rules as the exact one).

    backend : {"auto", "numpy", "numba"}
        ``"numba"`` compiles the loop (:mod:`catenary_env._reduced_kernels`); ``"numpy"`` is the
        reference; ``"auto"`` takes numba when it is installed.
    """
    red = prepared.reduced
    system = red.system
    if backend == "auto":
        backend = "numba" if _compiled_loop() is not None else "numpy"
    if backend not in BACKENDS:
        raise ValueError(f"backend = {backend!r}: one of auto, {', '.join(BACKENDS)}")
    passage = _start_passage(system, pantograph, uplift_force, speed, prepared.constants, n_steps)
    fields = _passage_arrays(prepared, passage)
    n = red.n_dofs
    n_steps = passage.time.size
    head = passage.pantograph.head
    N0 = system.dropper_force
    c0 = int(fields["config"][0])
    load = np.zeros(system.n_dofs)
    np.add.at(load, system.contact_wire.z_dofs[passage.element[0]], passage.shape[0] * passage.force0)
    a = _initial_acceleration(red, fields["kept"][c0], load)
    cf = fields["coefficients"]
    state = dict(
        u=np.zeros(n),
        v=np.zeros(n),
        a=a,
        e=cf[2] * a,
        y=cf[5] * a,
        Bu=np.zeros(N0.size),
        Bv=np.zeros(N0.size),
        Ba=np.zeros(N0.size),
        y_p=passage.y0.copy(),
        yd_p=np.zeros(head + 1),
        ydd_p=np.zeros(head + 1),
        slack=np.zeros(N0.size, dtype=np.bool_),
        flags=np.array([passage.force0 > 0.0, -1, 0, 0], dtype=np.int64),
        force=np.zeros(n_steps),
        head_height=np.zeros(n_steps),
        wire_uplift=np.zeros(n_steps),
        support_uplift=np.zeros((n_steps, system.support_z.size)),
        dropper_min=N0.copy(),
        dropper_max=N0.copy(),
    )
    state["force"][0] = passage.force0
    state["head_height"][0] = passage.y0[head]
    BACKENDS[backend](fields, state, progress)
    history = PassageHistory.from_arrays(_Arrays(state), state["flags"][2], state["flags"][3])
    return history.trajectory(passage.time, passage.position, system.static.layout.support_x)


def _compiled_loop():  # noqa: ANN202
    """:mod:`catenary_env.dynamics._reduced_kernels`, or None where numba is not installed."""
    try:
        from . import _reduced_kernels
    except ImportError:
        return None
    return _reduced_kernels


def _run_compiled(fields: dict, state: dict, progress: Callable[[float], None] | None) -> None:
    """The compiled loop (:mod:`catenary_env.dynamics._reduced_kernels`), in chunks for ``progress``."""
    kernels = _compiled_loop()
    if kernels is None:
        raise ImportError("backend='numba' needs numba: pip install numba")
    data = kernels.ReducedArrays(**fields)
    st = kernels.ReducedState(**state)
    n_steps = data.element.size
    bounds = np.unique(np.linspace(1, n_steps, 101 if progress is not None else 2).round().astype(int))
    for first, stop in zip(bounds[:-1], bounds[1:], strict=True):
        kernels.run_reduced(data, st, int(first), int(stop))
        if progress is not None:
            progress(stop / n_steps)


def _schur_solve(d: _Arrays, c: int, b: np.ndarray) -> np.ndarray:
    return sla.cho_solve_banded((d.schur_band[c], False), b, check_finite=False)


def _element_rows(d: _Arrays, e: int) -> tuple[np.ndarray, np.ndarray]:
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


def _element_responses(d: _Arrays, c: int, e: int, rows_q: np.ndarray, rows_c: np.ndarray):
    """As the compiled loop's: p_b (n_b, 4), compliance (4, 4), g_modal and g_full (D, 4)."""
    c_m = d.coefficients[14]
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
    g = np.zeros((d.dropper_force.size, 4))
    for q in range(d.dropper_force.size):
        sd = d.dropper_span[q]
        ncd = d.n_coupled[d.span_type[sd]]
        g[q] = (d.dropper_c[q, :ncd] - c_m * d.dropper_h[c, q, :ncd]) @ p_b[d.coupled[sd, :ncd]]
        if sd == s:
            g[q] += rows_q[:, :m] @ d.dropper_q[q, :m]
    g_full = g.copy()
    drops = d.element_droppers[e]
    ok = drops >= 0
    g_full[drops[ok]] += d.element_dropper_residual[e][:, ok].T
    return p_b, comp, g, g_full


def _dropper_elongations(d: _Arrays, c: int, vec: np.ndarray) -> np.ndarray:
    n_q = d.modal_offset[-1]
    out = np.zeros(d.dropper_force.size)
    for q in range(out.size):
        s = d.dropper_span[q]
        off = d.modal_offset[s]
        k = d.kept[c, s]
        nc = d.n_coupled[d.span_type[s]]
        out[q] = (
            d.dropper_q_plain[q, :k] @ vec[off : off + k] + d.dropper_c[q, :nc] @ vec[n_q + d.coupled[s, :nc]]
        )
    return out


def _run_numpy(d: _Arrays, st: _Arrays, progress: Callable[[float], None] | None) -> None:  # noqa: C901
    """The reference time loop: the compiled loop's steps in numpy."""
    cf = d.coefficients
    e1, e2, e3, g1, g2, g3 = cf[:6]
    a0, a1, a2, a3, a4, a5 = cf[6:12]
    kh, beta, c_m = cf[12:15]
    n_spans = d.span_type.size
    n_q = d.modal_offset[-1]
    head = d.y_star.size - 1
    width = (d.interface_rhs_rows.shape[2] - 1) // 2
    n_steps = d.element.size
    kappa, N0 = d.dropper_kappa, d.dropper_force
    contact = bool(st.flags[0])
    current = -1
    report_every = max(1, n_steps // 100)
    u, v, acc_s, e_vec, y = st.u, st.v, st.a, st.e, st.y
    history = PassageHistory.from_arrays(st, 0, 0)
    spans = [
        (s, d.span_type[s], d.modal_offset[s], d.coupled[s, : d.n_coupled[d.span_type[s]]])
        for s in range(n_spans)
    ]
    for k in range(1, n_steps):
        if progress is not None and k % report_every == 0:
            progress(k / n_steps)
        c = d.config[k]
        if c != st.flags[1]:
            for s, _, off, _ in spans:
                drop = slice(off + d.kept[c, s], d.modal_offset[s + 1])
                for vec in (u, v, acc_s, e_vec, y):
                    vec[drop] = 0.0
            st.Bu[:] = _dropper_elongations(d, c, u)
            st.Bv[:] = _dropper_elongations(d, c, v)
            st.Ba[:] = _dropper_elongations(d, c, acc_s)
            st.flags[1] = c
            current = -1
        el = d.element[k]
        if el != current:
            rows_q, rows_c = _element_rows(d, el)
            p_b, comp, g_modal, g_full = _element_responses(d, c, el, rows_q, rows_c)
            current = el
        h = d.shape[k]
        s_el = d.element_span[el]
        kept = d.kept[c]
        # 1. Interface part of K̂⁻¹ M e.
        e_b = np.pad(e_vec[n_q:], width)
        z = np.einsum("rk,rk->r", d.interface_rhs_rows[c], sliding_window_view(e_b, 2 * width + 1))
        for s, t, off, cpl in spans:
            m = kept[s]
            z[cpl] += d.coupling[t, : cpl.size, :m] @ (d.weight[t, :m] * e_vec[off : off + m])
        x_b = _schur_solve(d, c, z)
        g_c = [e_vec[n_q + cpl] - c_m * x_b[cpl] for s, t, off, cpl in spans]
        # 2. Droppers' elongations of u_known.
        dl_known = np.empty(N0.size)
        for q in range(N0.size):
            sd = d.dropper_span[q]
            s, t, off, cpl = spans[sd]
            m = kept[sd]
            dl_known[q] = (
                d.dropper_q[q, :m] @ e_vec[off : off + m]
                + d.dropper_h[c, q, : cpl.size] @ g_c[sd]
                + d.dropper_c[q, : cpl.size] @ x_b[cpl]
            )
        dl_known += g1 * st.Bu + g2 * st.Bv + g3 * st.Ba
        rate_term = beta * d.dropper_rate * (a1 * st.Bu + a4 * st.Bv + a5 * st.Ba)
        s, t, off, cpl = spans[s_el]
        m = kept[s_el]
        x_q = (e_vec[off : off + m] + g_c[s_el] @ d.coupling[t, : cpl.size, :m]) * d.inverse_diagonal[t, :m]
        u_q = x_q + y[off : off + m]
        u_c = x_b[cpl] + y[n_q + cpl]
        wire = h @ (rows_q[:, :m] @ u_q + rows_c[:, : cpl.size] @ u_c)
        rhs_p = d.pantograph_mass @ (a0 * st.y_p + a2 * st.yd_p + a3 * st.ydd_p) + d.pantograph_damping @ (
            a1 * st.y_p + a4 * st.yd_p + a5 * st.ydd_p
        )
        y_known = d.pantograph_inverse @ (rhs_p + d.load_p)
        gap_known = y_known[head] - d.wire_z[k] - wire
        c_cc = h @ comp @ h + d.y_star[head]
        g_dc = g_full @ h
        gm_dc = g_modal @ h
        G = d.dropper_flexibility[c]
        # 3. Contact force and slack droppers (the exact passage's active set).
        step = settle(contact, st.slack.copy(), gap_known, c_cc, g_dc, dl_known, rate_term, kh, kappa, N0, G)
        contact, st.slack[:], f, idx, lam, elastic = step[:6]
        # 4. The response on the interface, then every span's modes with the Newmark update.
        x_b = x_b + f * (p_b @ h) + lam @ d.dropper_interface[c, idx]
        for s, t, off, cpl in spans:
            m = kept[s]
            fq = e_vec[off : off + m].copy()
            if s == s_el:
                fq += f * (h @ rows_q[:, :m])
            for q, lq in zip(idx, lam, strict=True):
                if d.dropper_span[q] == s:
                    fq += lq * d.dropper_q_plain[q, :m]
            fq += (e_vec[n_q + cpl] - c_m * x_b[cpl]) @ d.coupling[t, : cpl.size, :m]
            p = slice(off, off + m)
            u_new = fq * d.inverse_diagonal[t, :m] + y[p]
            _newmark(u, v, acc_s, e_vec, y, p, u_new, cf)
        _newmark(u, v, acc_s, e_vec, y, slice(n_q, None), x_b + y[n_q:], cf)
        bu = dl_known + gm_dc * f + d.dropper_modal_flexibility[c][:, idx] @ lam
        du = bu - st.Bu
        ba = a0 * du - a2 * st.Bv - a3 * st.Ba
        st.Bv[:] = a1 * du - a4 * st.Bv - a5 * st.Ba
        st.Ba[:] = ba
        st.Bu[:] = bu
        du = y_known - f * d.y_star - st.y_p
        acc_p = a0 * du - a2 * st.yd_p - a3 * st.ydd_p
        st.yd_p[:] = a1 * du - a4 * st.yd_p - a5 * st.ydd_p
        st.ydd_p[:] = acc_p
        st.y_p[:] += du
        s, t, off, cpl = spans[s_el]
        m = kept[s_el]
        uplift = h @ (rows_q[:, :m] @ u[off : off + m] + rows_c[:, : cpl.size] @ u[n_q + cpl])
        history.record(
            k, f, st.y_p[head], uplift, u[n_q + d.support], elastic, st.slack, idx.size > 0, step.resolved
        )
    st.flags[2], st.flags[3] = history.slack_steps, history.unresolved_steps
    st.flags[0] = int(contact)


def _run_reference(fields: dict, state: dict, progress: Callable[[float], None] | None) -> None:
    _run_numpy(_Arrays(fields), _Arrays(state), progress)


BACKENDS = {"numpy": _run_reference, "numba": _run_compiled}
"""The span-mode passage's time loops by name; ``"auto"`` takes numba where it is installed."""


def _newmark(u, v, acc, e_vec, y, p, u_new, cf) -> None:
    """Newmark update of the coordinates ``p`` to ``u_new``, and the next step's e and y there."""
    du = u_new - u[p]
    acc_new = cf[6] * du - cf[8] * v[p] - cf[9] * acc[p]
    v_new = cf[7] * du - cf[10] * v[p] - cf[11] * acc[p]
    u[p], v[p], acc[p] = u_new, v_new, acc_new
    e_vec[p] = cf[0] * u_new + cf[1] * v_new + cf[2] * acc_new
    y[p] = cf[3] * u_new + cf[4] * v_new + cf[5] * acc_new
