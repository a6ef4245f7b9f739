"""The pantograph passage on the span-mode model (docs/performance.md, 'Model fidelities').

The same Newmark scheme, superposition and active-set rules as the exact passage, in the
coordinates of :mod:`.reduction`. The effective matrix K̂ = c_k K + c_m M of the reduced system is
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
with its own Schur complement. A span leaving the near field drops its high modes' state. With several
pantographs the near field follows each (the near fields may merge): a configuration is the tuple of
spans the pantographs are in, and which spans keep which modes is one function of it,
:func:`kept_modes`; the configurations a passage meets are built when it first needs them
(:meth:`PreparedSpanModes.arrays_for`).

Residual flexibility. Within one step a force at the contact point or at a dropper also moves the
truncated modes. Their share of the one-step compliance, R = K̂_ii⁻¹ - Φ D⁻¹ Φᵀ per span, is added
where the forces act, so that the contact and the slack droppers see the exact one-step compliance;
the truncated modes carry no state.

This module prepares what both loops, numpy (:mod:`.loop`) and compiled (:mod:`.kernels`), read of the
design, :class:`SpanModeArrays`; they follow the same steps (see :mod:`.kernels`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..active_set import Droppers
from ..linear_system import LinearSystem
from ..newmark import NewmarkConstants, StepCoefficients
from ..protocol import DynamicsSettings
from .reduction import ReducedSystem, band_storage, band_width, reduce_system, submatrix


class SpanModeArrays(NamedTuple):
    """What both loops read of the design. Shapes: S spans, T types, C configurations (a passage hands the
    loops one at a time, C = 1), P pantographs, D droppers, n_b interface DOFs, w the Schur complement's band
    width, m, n_c, n_i the padded modes, coupled interface and internal DOFs of a span type, E contact-wire
    elements, K droppers per span.
    """

    span_type: np.ndarray  # (S,)
    modal_offset: np.ndarray  # (S + 1,)
    coupled: np.ndarray  # (S, n_c) interface positions
    n_coupled: np.ndarray  # (T,)
    n_modes: np.ndarray  # (T,)
    kept: np.ndarray  # (C, S) modes each span keeps in configuration c (kept_modes)
    coupling: np.ndarray  # (T, n_c, m) M_cq
    inverse_diagonal: np.ndarray  # (T, m) 1 / D
    weight: np.ndarray  # (T, m) 1 - c_m / D
    weighted_coupling: np.ndarray  # (T, n_c, m) M_cq (1 - c_m / D)
    shapes: np.ndarray  # (T, n_i, m) Φ
    constraint: np.ndarray  # (T, n_i, n_c) Ψ
    shape_coupling: np.ndarray  # (T, n_i, n_c) Φ D⁻¹ M_qc over all the type's modes
    schur_band: np.ndarray  # (C, w + 1, n_b) U in LAPACK band storage (the numpy loop's)
    schur_columns: np.ndarray  # (C, n_b, w) the Cholesky factor U of S by columns (_band_solve)
    schur_rows: np.ndarray  # (C, n_b, w) U by rows
    schur_inverse_diagonal: np.ndarray  # (C, n_b)
    interface_rhs_rows: np.ndarray  # (C, n_b, 2 w + 1) Y[r, r + k] at [r, w + k]
    dropper_span: np.ndarray  # (D,) in order of span
    dropper_start: np.ndarray  # (S + 1,) span s's droppers are dropper_start[s] .. dropper_start[s + 1] - 1
    interface_end: np.ndarray  # (S,) interface DOFs 0 .. interface_end[s] - 1: reached by spans 0 .. s only
    dropper_q: np.ndarray  # (D, m) B_q D⁻¹
    type_dropper_q: np.ndarray  # (T, K, m) the same, a span type's droppers
    dropper_q_plain: np.ndarray  # (D, m) B_q
    dropper_c: np.ndarray  # (D, n_c) B_c
    dropper_h: np.ndarray  # (C, D, n_c) B_q D⁻¹ M_qc over the kept modes
    dropper_interface_force: np.ndarray  # (C, D, n_c) B_c - c_m H: a unit dropper force on the interface
    dropper_blocks: np.ndarray  # (C, 2, Σ K_s²) each span's droppers' G within it, of the kept modes and
    # with the residual: span s's (K_s, K_s) block row by row from block_start[s] (dropper_responses)
    block_start: np.ndarray  # (S + 1,)
    element_span: np.ndarray  # (E,)
    element_local: np.ndarray  # (E, 4) internal index, or -1 - position in the span's coupled list
    element_compliance: np.ndarray  # (E, 4, 4) residual
    element_droppers: np.ndarray  # (E, K) the span's droppers, -1 pads
    element_dropper_residual: np.ndarray  # (E, 4, K)
    element_modal_compliance: np.ndarray  # (E, 4, 4) rows_q D⁻¹ rows_qᵀ
    element_dropper_modal: np.ndarray  # (E, 4, K) rows_q D⁻¹ B_qᵀ for the span's droppers
    element_interface: np.ndarray  # (C, P, n_c, n_b) S⁻¹ at pantograph p's span's coupled interface DOFs
    dropper_element_interface: np.ndarray  # (C, P, n_c, D) (B_c - c_m H) S⁻¹ there
    support: np.ndarray  # (supports,) interface position of each contact-wire support
    droppers: Droppers
    coefficients: StepCoefficients


def band_rows(ab: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An upper band factor U (LAPACK storage, (w + 1, n)) as its columns above the diagonal (n, w),
    its rows right of the diagonal (n, w) and its reciprocal diagonal (n,): the compiled loop reads
    each contiguously (see ``.kernels._band_solve``)."""
    w = ab.shape[0] - 1
    n = ab.shape[1]
    columns = np.ascontiguousarray(ab[:w].T)  # columns[j, w - k] = U[j - k, j]
    rows = np.zeros((n, w))  # rows[i, k - 1] = U[i, i + k]
    for k in range(1, w + 1):
        rows[: n - k, k - 1] = ab[w - k, k:]
    return columns, rows, 1.0 / ab[w]


@dataclass(frozen=True)
class PreparedSpanModes:
    """The design's part of the span-mode model, computed once per design and time step.

    Attributes
    ----------
    reduced : ReducedSystem
    constants : NewmarkConstants
    near_spans : int
    arrays : SpanModeArrays
        What both loops read of the design, with one configuration (the pantograph in the first span); a
        passage reads :meth:`arrays_for` each configuration it meets, while it is in it.
    builder : _ConfigurationBuilder
        Builds the configurations (:meth:`arrays_for`) when a passage first needs them: one that stops
        early, as ``evaluate``'s does, never builds those of the spans it does not reach.
    built : dict
        The configurations built so far, kept for the next passage (another speed) while they take at most
        :data:`KEPT_CONFIGURATION_BYTES` together (some 0.1 MB a configuration at 20 spans, growing with the
        section's length, and with it their number).
    """

    reduced: ReducedSystem
    constants: NewmarkConstants
    near_spans: int
    arrays: SpanModeArrays
    builder: _ConfigurationBuilder = field(repr=False, compare=False)
    built: dict[tuple[int, ...], dict[str, np.ndarray]] = field(
        default_factory=dict, repr=False, compare=False
    )

    def arrays_for(self, configuration: tuple[int, ...]) -> SpanModeArrays:
        """The design's arrays in one configuration, the spans the pantographs are in (-1: off the section),
        as configuration 0; built on its first use, and kept within :data:`KEPT_CONFIGURATION_BYTES`."""
        one = self.built.get(configuration)
        if one is None:
            one = self.builder.build(configuration)
            kept = sum(a.nbytes for built in self.built.values() for a in built.values())
            if kept + sum(a.nbytes for a in one.values()) <= KEPT_CONFIGURATION_BYTES:
                self.built[configuration] = one
        return self.arrays._replace(**as_configuration_zero(one))


KEPT_CONFIGURATION_BYTES = 64 * 2**20
"""The built configurations a prepared design keeps for its next passages, at most (bytes)."""


def prepare(system: LinearSystem, fidelity: DynamicsSettings) -> PreparedSpanModes:
    """The span modes below the fidelity's cut-offs (:func:`.reduction.reduce_system`) and, for its time
    step and near spans, what the Schur complements, dropper responses and residual compliances of each
    configuration are built from (:meth:`PreparedSpanModes.arrays_for`)."""
    if not system.rayleigh:
        raise ValueError(
            "the span-mode model integrates C = alpha M + beta K with slack droppers dropping their whole "
            "force only: use the exact model"
        )
    reduced = reduce_system(system, fidelity.near_cutoff, fidelity.far_cutoff)
    return prepare_reduced(reduced, fidelity.time_step, fidelity.near_spans)


def prepare_reduced(reduced: ReducedSystem, time_step: float, near_spans: int) -> PreparedSpanModes:
    """:func:`prepare` of a reduced system, for a time step (s) and the spans on each side of a
    pantograph's that keep the near cut-off."""
    system = reduced.system
    nm = NewmarkConstants.for_step(time_step)
    c_k = 1.0 + system.beta * nm.a1
    c_m = nm.a0 + system.alpha * nm.a1
    modes = _mode_arrays(reduced, c_k, c_m)
    droppers = _dropper_arrays(reduced, modes["inverse_diagonal"])
    residual = _Residuals(reduced, c_k, c_m, droppers["dropper_span"])
    builder = _ConfigurationBuilder(reduced, c_k, c_m, modes, droppers, residual, near_spans)
    first = builder.build((0,))  # every passage starts there
    elements = _element_arrays(reduced, droppers, residual)
    kh = system.static.layout.catenary.contact_stiffness
    arrays = SpanModeArrays(
        **modes,
        **droppers,
        interface_end=interface_end(reduced),
        block_start=builder.block_start,
        **as_configuration_zero(first),
        **elements,
        droppers=Droppers.for_step(system.dropper_rate, system.dropper_force, system.beta, nm.a1),
        support=residual.interface_position[system.support_z],
        coefficients=StepCoefficients.for_step(nm, system.alpha, system.beta, kh),
    )
    return PreparedSpanModes(reduced, nm, near_spans, arrays, builder, {(0,): first})


def interface_end(reduced: ReducedSystem) -> np.ndarray:
    """(S,): the interface DOFs below ``interface_end[s]`` belong to spans 0 .. s only (the interface runs in
    track order), so that a loop stepping those spans holds the rest, the next support's DOFs included."""
    first = np.array([c.min() if c.size else reduced.interface.size for c in reduced.coupled])
    later = np.minimum.accumulate(first[::-1])[::-1]  # the first DOF of spans s .. S - 1
    return np.r_[later[1:], reduced.interface.size].astype(np.int64)


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


def _dropper_arrays(reduced: ReducedSystem, inv_d: np.ndarray) -> dict[str, np.ndarray]:
    """Each dropper's row of B T, split into its span's modes (B_q) and coupled interface (B_c).

    A span stands for its type's representative (:class:`.reduction.ReducedSystem`), and so do its
    droppers: their rows are the representative's, the same for every span of the type, so that the
    compiled loop reads them once per type (``type_dropper_q``: some 25 kB a type, which stay in the
    cache, where a row per dropper of the section is half a megabyte at 20 spans and grows with it)."""
    system = reduced.system
    B = system.dropper_elongation.tocsr()
    d_span = system.static.layout.dropper_span.astype(np.int64)
    if np.any(np.diff(d_span) < 0):
        raise AssertionError("the droppers are not in order of span")  # a bug, never a user error
    start = np.searchsorted(d_span, np.arange(len(reduced.internal) + 1)).astype(np.int64)
    row_size = np.asarray(abs(B).sum(axis=1)).ravel()
    B_span = []  # each span's droppers' rows of B on its internal, then its coupled interface DOFs
    for s, dofs in enumerate(reduced.internal):
        q = np.arange(start[s], start[s + 1])
        B_span.append(submatrix(B, q, np.r_[dofs, reduced.interface[reduced.coupled[s]]]))
        inside = np.bincount(B_span[s].row, np.abs(B_span[s].data), minlength=q.size)
        if not np.allclose(inside, row_size[q], rtol=1e-12, atol=0.0):
            raise AssertionError("a dropper's row reaches outside its span")  # a bug, never a user error
    n_types, m_max = inv_d.shape
    type_q = np.zeros((n_types, int(np.diff(start).max(initial=0)), m_max))
    type_c = np.zeros((n_types, type_q.shape[1], max(c.size for c in reduced.coupled)))
    for t, r in enumerate(reduced.representative):
        # B T with T = [[Φ, Ψ], [0, I]]: B_i Φ on the modes, B_i Ψ + B_c on the coupled interface DOFs
        modes, n_c = reduced.types[t], reduced.coupled[r].size
        B_i, B_c = np.hsplit(B_span[r].toarray(), [modes.shapes.shape[0]])
        type_q[t, : B_i.shape[0], : modes.n_modes] = B_i @ modes.shapes
        type_c[t, : B_i.shape[0], :n_c] = B_i @ modes.constraint + B_c
    for s, t in enumerate(reduced.span_type):
        if not B_span[s].same(B_span[reduced.representative[t]]):
            raise AssertionError("a span's droppers differ from its type's")  # a bug, never a user error
    t_of, within = reduced.span_type[d_span], np.arange(d_span.size) - start[d_span]
    return dict(
        dropper_span=d_span,
        dropper_start=start,
        dropper_q=type_q[t_of, within] * inv_d[t_of],
        type_dropper_q=type_q * inv_d[:, None, :],
        dropper_q_plain=type_q[t_of, within],
        dropper_c=type_c[t_of, within],
    )


class _Residuals:
    """The truncated modes' one-step compliance R = K̂_ii⁻¹ - Φ D⁻¹ Φᵀ of each span type, with the near
    and with the far modes, on the internal DOFs where forces act ("selected": the contact wire's z
    DOFs and the droppers' ends), the near modes' own Φ D⁻¹ Φᵀ there, and each span's droppers as
    rows over those DOFs. R is the truncated eigenpairs' own sum Φ_t D_t⁻¹ Φ_tᵀ (the span's
    eigenvectors diagonalise K̂_ii), without a solve and without the cancellation of a difference.

    Each compliance is kept as its factor F (C = F Fᵀ, :data:`COMPLIANCES`), and only the entries that are
    used are formed: the droppers' blocks B C Bᵀ, C Bᵀ, and each contact-wire element's 4 × 4 block. The
    whole C over the selected DOFs (some 270 of a span's 410 DOFs) cost 270² multiply-adds a mode, a
    millisecond a span type (docs/performance.md, 'The span types' eigensolutions through the mass matrix's
    band')."""

    COMPLIANCES = ("near", "far", "modal")
    """R with the near modes (F = Φ_t D_t^-½), R with the far modes (the near modes above the far cut-off
    added to F), and the near modes' own Φ D⁻¹ Φᵀ (F = Φ D^-½)."""

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
        self.selected: list[np.ndarray] = []
        self.factors: dict[str, list[np.ndarray]] = {name: [] for name in self.COMPLIANCES}
        entry_row = np.repeat(np.arange(B.shape[0]), np.diff(B.indptr))  # each stored entry's dropper
        for t, modes in enumerate(reduced.types):
            spans_t = np.flatnonzero(reduced.span_type == t)
            dofs = np.r_[z_dofs, B.indices[np.isin(d_span, spans_t)[entry_row]]]  # B's rows' DOFs, in order
            sel = np.unique(self.local_of[dofs[np.isin(self.span_of[dofs], spans_t)]])
            phi = modes.shapes[sel]
            phi /= np.sqrt(c_k * modes.omega2 + c_m)  # in place, not a second (sel, m) array
            rest = modes.truncated_shapes[sel] / np.sqrt(c_k * modes.truncated_omega2 + c_m)
            self.selected.append(sel)
            self.factors["near"].append(rest)
            self.factors["far"].append(np.hstack([rest, phi[:, modes.far_modes :]]))  # what a far span drops
            self.factors["modal"].append(phi)
        # A span whose rows equal its type's first span's (every interior span: the same droppers on the
        # same DOFs) stands for it in the products with them, made once (``of_rows``): ``rows_of``.
        self.span_droppers, self.rows_of, first = [], np.arange(n_spans), {}
        for s in range(n_spans):
            t = reduced.span_type[s]
            sel = self.selected[t]
            position = np.full(reduced.internal[s].size, -1)
            position[sel] = np.arange(sel.size)
            B_s = submatrix(B, np.flatnonzero(d_span == s), reduced.internal[s])
            rows = np.zeros((B_s.shape[0], sel.size))
            np.add.at(rows, (B_s.row, position[B_s.col]), B_s.data)
            if t in first and np.array_equal(self.span_droppers[first[t]], rows):
                self.rows_of[s] = first[t]
            first.setdefault(t, s)
            self.span_droppers.append(rows)
        self._products: dict[tuple[str, int], np.ndarray] = {}
        self._element_blocks: dict[tuple[str, int, bytes], np.ndarray] = {}

    def of_rows(self, reduced: ReducedSystem, span: int, name: str, make) -> np.ndarray:  # noqa: ANN001
        """``make(rows, t)`` of the span's dropper rows and type t, made once for the spans whose rows are
        the same (``name`` tells the products apart)."""
        key = (name, int(self.rows_of[span]))
        if key not in self._products:
            self._products[key] = make(self.span_droppers[span], reduced.span_type[span])
        return self._products[key]

    def dropper_block(self, reduced: ReducedSystem, span: int, near: bool) -> np.ndarray:
        """The span's droppers' residual flexibility B R Bᵀ, m/N."""
        name = "near" if near else "far"

        def make(rows: np.ndarray, t: int) -> np.ndarray:
            rows_f = rows @ self.factors[name][t]
            return rows_f @ rows_f.T

        return self.of_rows(reduced, span, f"block {name}", make)

    def to_droppers(self, reduced: ReducedSystem, span: int, name: str) -> np.ndarray:
        """C Bᵀ (selected DOFs, the span's droppers) of the compliance ``name``, m/N."""
        return self.of_rows(
            reduced,
            span,
            f"to droppers {name}",
            lambda rows, t: self.factors[name][t] @ (rows @ self.factors[name][t]).T,
        )

    def element_blocks(self, t: int, positions: np.ndarray, name: str) -> np.ndarray:
        """(E, 4, 4): the compliance ``name`` of type t between each element's 4 DOFs, ``positions`` (E, 4)
        in the type's selected DOFs (-1: an interface DOF, whose entries are 0), made once for a type's
        spans whose elements lie alike."""
        key = (name, t, positions.tobytes())
        if key not in self._element_blocks:
            rows = self.factors[name][t][np.maximum(positions, 0)]  # (E, 4, r)
            inside = positions >= 0
            blocks = rows @ rows.transpose(0, 2, 1)
            self._element_blocks[key] = np.where(inside[:, :, None] & inside[:, None, :], blocks, 0.0)
        return self._element_blocks[key]


def kept_modes(reduced: ReducedSystem, near_spans: int, configuration: tuple[int, ...]) -> np.ndarray:
    """(S,): the modes each span keeps in a configuration, the spans the pantographs are in (-1: a
    pantograph off the section): those within ``near_spans`` of a pantograph keep their near modes, the
    others their far modes (docs/model.md, 'Several pantographs'). The configurations' arrays
    (:class:`_ConfigurationBuilder`) follow whatever this returns, as long as each count is one the span's
    blocks and residual compliances are prepared for (its near or far count: another, such as none for the
    spans far from every pantograph, needs its blocks in ``_ConfigurationBuilder.__init__`` and
    :class:`_Residuals`)."""
    n_spans = reduced.span_type.size
    far = np.array([t.far_modes for t in reduced.types])[reduced.span_type]
    full = np.array([t.n_modes for t in reduced.types])[reduced.span_type]
    spans = np.array([s for s in configuration if s >= 0], dtype=np.int64)
    distance = np.abs(np.arange(n_spans)[:, None] - spans[None, :]).min(axis=1, initial=n_spans)
    return np.where(distance <= near_spans, full, far).astype(np.int64)


CONFIGURATION_FIELDS = (
    "schur_band",
    "schur_columns",
    "schur_rows",
    "schur_inverse_diagonal",
    "interface_rhs_rows",
    "dropper_h",
    "dropper_interface_force",
    "dropper_blocks",
    "element_interface",
    "dropper_element_interface",
)
"""The fields of :class:`SpanModeArrays` with one entry per configuration (besides ``kept``)."""


class _ConfigurationBuilder:
    """Builds a configuration's arrays (:meth:`build`) from the blocks every configuration shares: each
    span's share of Σ M_cq D⁻¹ M_qc, of its droppers' H, G and residual, per mode count kept, and every span
    with its far modes."""

    def __init__(
        self,
        reduced: ReducedSystem,
        c_k: float,
        c_m: float,
        modes: dict[str, np.ndarray],
        droppers: dict[str, np.ndarray],
        residual: _Residuals,
        near_spans: int,
    ) -> None:
        types = reduced.types
        n_spans = reduced.span_type.size
        self.reduced, self.c_k, self.c_m, self.near_spans = reduced, c_k, c_m, near_spans
        d_span, d_q, d_qd, d_c = (
            droppers[k] for k in ("dropper_span", "dropper_q_plain", "dropper_q", "dropper_c")
        )
        self.d_c, self.d_span, self.n_coupled, self.coupled = (
            d_c,
            d_span,
            modes["n_coupled"],
            modes["coupled"],
        )
        n_drop, nc_max = d_c.shape
        inv_d, coupling = modes["inverse_diagonal"], modes["coupling"]
        self.width = max(
            max((int(np.ptp(c)) for c in reduced.coupled if c.size), default=0),
            band_width(reduced.interface_mass),
            band_width(reduced.interface_stiffness),
        )
        # A span's share of Σ M_cq D⁻¹ M_qc, of its droppers' H, G and residual, per mode count kept: the
        # first three its type's (the droppers' rows are the type's, _dropper_arrays), the residual its own.
        self.start = start = droppers["dropper_start"]
        self.span_sum, self.span_h, self.modal_block, self.residual_block = {}, {}, {}, {}
        of_type = {}
        for s in range(n_spans):
            t = reduced.span_type[s]
            q = slice(start[s], start[s + 1])
            for k in {types[t].far_modes, types[t].n_modes}:
                if (t, k) not in of_type:
                    mqc = types[t].mass_coupling[:k] * np.sqrt(inv_d[t, :k, None])
                    of_type[t, k] = (
                        mqc.T @ mqc,
                        d_qd[q, :k] @ coupling[t, :, :k].T,
                        (d_q[q, :k] * inv_d[t, :k]) @ d_q[q, :k].T,
                    )
                self.span_sum[s, k], self.span_h[s, k], self.modal_block[s, k] = of_type[t, k]
                self.residual_block[s, k] = residual.dropper_block(reduced, s, near=k == types[t].n_modes)
        # Every span with its far modes; a configuration adds its near spans' differences.
        self.far = far = np.array([types[t].far_modes for t in reduced.span_type])
        # Each dropper's span's coupled interface DOFs, and which of its n_c columns are some (the rest 0)
        self.dropper_coupled = self.coupled[d_span]
        self.dropper_valid = _coupled_columns(d_span, reduced.span_type, self.n_coupled, nc_max)
        n_b = reduced.interface.size
        self.far_sum = np.zeros((n_b, n_b))
        self.far_h = np.zeros((n_drop, nc_max))
        # The droppers' G within each span (of its modes, and with the residual), its (K_s, K_s) block row by
        # row from block_start[s]: G's other entries are the interface's alone (dropper_responses)
        self.block_start = np.r_[0, np.cumsum(np.diff(start) ** 2)].astype(np.int64)
        self.far_blocks = np.zeros((2, self.block_start[-1]))
        for s, c in enumerate(reduced.coupled):
            q = slice(start[s], start[s + 1])
            self.far_sum[np.ix_(c, c)] += self.span_sum[s, far[s]]
            self.far_h[q] = self.span_h[s, far[s]]
            self.far_blocks[:, self.block_start[s] : self.block_start[s + 1]] = self._blocks(s, far[s])
        diagonals = np.arange(n_b)[:, None] + np.arange(-self.width, self.width + 1)[None, :]
        self.inside = (diagonals >= 0) & (diagonals < n_b)  # Y[r, r + k] at [r, w + k]
        self.diagonals = np.clip(diagonals, 0, n_b - 1)

    def build(self, configuration: tuple[int, ...]) -> dict[str, np.ndarray]:
        """One configuration's arrays (:data:`CONFIGURATION_FIELDS` and ``kept``): S's banded factor, Y,
        H = B_q D⁻¹ M_qc, a unit dropper force's right-hand side on the interface, B_c - c_m H, and each
        span's droppers' flexibility block (of the kept modes, and with the residual); and for each
        pantograph's span, S⁻¹ at its coupled interface DOFs and the droppers' elongations there,
        (B_c - c_m H) S⁻¹.

        The droppers' interface responses S⁻¹ (B_c - c_m H)ᵀ and their flexibility G over the whole section
        are not built: dense, (D, n_b) and (D, D), their cost grew with the square of the section's length
        and a passage's configurations with its length. A loop takes a slack dropper's row of them when it
        first needs it (:func:`dropper_responses`; docs/performance.md, 'A slack dropper's responses when
        it first goes slack')."""
        reduced, c_k, c_m, width, start = self.reduced, self.c_k, self.c_m, self.width, self.start
        n_b = reduced.interface.size
        kept = kept_modes(reduced, self.near_spans, configuration)
        sum_coupling = self.far_sum.copy()
        dropper_h = self.far_h.copy()
        near = np.flatnonzero(kept != self.far)
        for s in near:
            c, q, k = reduced.coupled[s], slice(start[s], start[s + 1]), kept[s]
            sum_coupling[np.ix_(c, c)] += self.span_sum[s, k] - self.span_sum[s, self.far[s]]
            dropper_h[q] = self.span_h[s, k]
        schur = c_k * reduced.interface_stiffness + c_m * reduced.interface_mass - c_m**2 * sum_coupling
        factor = sla.cholesky_banded(band_storage(0.5 * (schur + schur.T), width), check_finite=False)
        out = dict(kept=kept, schur_band=factor, dropper_h=dropper_h)
        out["schur_columns"], out["schur_rows"], out["schur_inverse_diagonal"] = band_rows(factor)
        Y = reduced.interface_mass - c_m * sum_coupling
        out["interface_rhs_rows"] = np.where(self.inside, Y[np.arange(n_b)[:, None], self.diagonals], 0.0)
        # B_c - c_m H on the interface: a unit dropper force's right-hand side, ≤ n_c entries a row (sparse:
        # its products below then cost n_c, not n_b, multiply-adds an entry of theirs)
        out["dropper_interface_force"] = forces = self.d_c - c_m * dropper_h
        forces = np.where(self.dropper_valid, forces, 0.0)
        # Each pantograph's span: S⁻¹ at its coupled interface DOFs (a band solve of each unit force) and
        # the droppers' elongations under them, (B_c - c_m H) S⁻¹ a dropper's n_c entries at a time
        owns = [reduced.coupled[s] if s >= 0 else np.zeros(0, dtype=np.int64) for s in configuration]
        nc_max = self.d_c.shape[1]
        out["element_interface"] = np.zeros((len(owns), nc_max, n_b))
        out["dropper_element_interface"] = np.zeros((len(owns), nc_max, forces.shape[0]))
        for p, own in enumerate(owns):
            unit = np.zeros((n_b, own.size))
            unit[own, np.arange(own.size)] = 1.0
            columns = sla.cho_solve_banded((factor, False), unit, check_finite=False)
            out["element_interface"][p, : own.size] = columns.T
            out["dropper_element_interface"][p, : own.size] = np.einsum(
                "qj,qjk->kq", forces, columns[self.dropper_coupled]
            )
        # Each span's droppers' blocks of G (a near span's of its near modes)
        blocks = self.far_blocks.copy()
        for s in near:
            blocks[:, self.block_start[s] : self.block_start[s + 1]] = self._blocks(s, kept[s])
        out["dropper_blocks"] = blocks
        return out

    def _blocks(self, span: int, kept: int) -> np.ndarray:
        """(2, n²): the span's droppers' G within it, of its ``kept`` modes and with the residual, flat."""
        modal = self.modal_block[span, kept]
        return np.stack([modal.ravel(), (modal + self.residual_block[span, kept]).ravel()])


def as_configuration_zero(built: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """A configuration's arrays (:meth:`_ConfigurationBuilder.build`) as the loops read them, configuration
    0 of one (views, not copies)."""
    return {name: built[name][None] for name in ("kept", *CONFIGURATION_FIELDS)}


def _coupled_columns(
    dropper_span: np.ndarray, span_type: np.ndarray, n_coupled: np.ndarray, n_c: int
) -> np.ndarray:
    """(D, n_c) bool: which of a dropper's n_c columns are its span's coupled interface DOFs (the rest 0)."""
    return np.arange(n_c)[None, :] < n_coupled[span_type[dropper_span]][:, None]


def interface_forces(
    forces: np.ndarray,
    dropper_span: np.ndarray,
    span_type: np.ndarray,
    n_coupled: np.ndarray,
    coupled: np.ndarray,
    n_b: int,
) -> sp.csr_matrix:
    """B_c - c_m H (``forces``, (D, n_c) on each dropper's span's coupled interface DOFs ``coupled``) as a
    sparse (D, n_b) matrix over the interface: ≤ n_c entries a row, so that its products cost n_c, not n_b,
    multiply-adds an entry of theirs."""
    valid = _coupled_columns(dropper_span, span_type, n_coupled, forces.shape[1])
    pointers = np.r_[0, np.cumsum(valid.sum(axis=1))]
    return sp.csr_matrix((forces[valid], coupled[dropper_span][valid], pointers), (forces.shape[0], n_b))


def dropper_responses(d: SpanModeArrays, c: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The droppers' responses in configuration c, dense over the section: X = (B_c - c_m H) S⁻¹ (D, n_b),
    the interface's motion under a unit force at each dropper, and its flexibility G = (B_c - c_m H) S⁻¹
    (B_c - c_m H)ᵀ plus each span's own block, of the kept modes and with the residual (D, D): a dropper's
    elongations under a unit force at each. The numpy loop takes them whole as it enters a configuration;
    the compiled loop a slack dropper's row when it first needs it (its ``_dropper_row``, the same sums)."""
    n_b = d.schur_inverse_diagonal.shape[1]
    forces = interface_forces(
        d.dropper_interface_force[c], d.dropper_span, d.span_type, d.n_coupled, d.coupled, n_b
    )
    X = sla.cho_solve_banded((d.schur_band[c], False), forces.T.toarray(), check_finite=False)
    modal = np.asarray(forces @ X)
    full = modal.copy()
    for s in range(d.span_type.size):
        q = slice(d.dropper_start[s], d.dropper_start[s + 1])
        n = q.stop - q.start
        block = d.dropper_blocks[c, :, d.block_start[s] : d.block_start[s + 1]].reshape(2, n, n)
        modal[q, q] += block[0]
        full[q, q] += block[1]
    return X.T, modal, full


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
        loc = np.where(el_local[els] >= 0, where[np.maximum(el_local[els], 0)], -1)
        ok = loc >= 0
        safe = np.maximum(loc, 0)
        el_comp[els] = residual.element_blocks(t, loc, "near")
        el_modal[els] = residual.element_blocks(t, loc, "modal")
        drops = np.flatnonzero(d_span == s)
        el_droppers[els, : drops.size] = drops
        for out, name in ((el_res, "near"), (el_drop_modal, "modal")):
            out[els, :, : drops.size] = np.where(
                ok[:, :, None], residual.to_droppers(reduced, s, name)[safe], 0.0
            )
    return dict(
        element_span=el_span,
        element_local=el_local,
        element_compliance=el_comp,
        element_droppers=el_droppers,
        element_dropper_residual=el_res,
        element_modal_compliance=el_modal,
        element_dropper_modal=el_drop_modal,
    )


def initial_acceleration(reduced: ReducedSystem, kept: np.ndarray, load: np.ndarray) -> np.ndarray:
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
