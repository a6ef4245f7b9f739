"""Component modes per span: the reduced ("study") model of the linearised catenary.

Craig–Bampton reduction with one component per span (docs/performance.md, 'Model fidelities').
The DOFs are split into *interface* DOFs, at the supports (and any DOF coupled to two spans, such
as a stitch wire's bar across a support), and each span's *internal* DOFs. A span's internal motion
is written as

    u_i = Φ q + Ψ u_c,

with Φ the span's fixed-interface modes below the cut-off frequency (mass-normalised, so that the
modal mass is the identity and the modal stiffness diag(ω²)) and Ψ = -K_ii⁻¹ K_ic its constraint
modes (the static shape of the span when an interface DOF moves). Both matrices of the reduced
system are then block-arrow shaped: diagonal in each span's modal coordinates, coupled only through
the interface DOFs, and the stiffness has no modal-interface coupling at all. Rayleigh damping
C = αM + βK carries over exactly.

Away from the section's ends every span of a design is the same (the same matrices to rounding),
so one eigensolution serves all of them: a section has three span types (first, interior, last).
With every mode kept the reduction is only a change of basis and the reduced model equals the
exact one; the cut-off is the only approximation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .linear_system import LinearSystem

SAME_SPAN_TOLERANCE = 1e-9
"""Largest relative difference of two spans' matrices for them to share their modes. Interior
spans of a section differ by rounding only (about 1e-12)."""


@dataclass(frozen=True)
class SpanModes:
    """The fixed-interface modes of one span type, in its internal DOFs' local order.

    Attributes
    ----------
    omega2 : ndarray (m,)
        Squared circular frequencies ω², (rad/s)².
    shapes : ndarray (n_i, m)
        Φ, mass-normalised mode shapes.
    constraint : ndarray (n_i, n_c)
        Ψ, the internal DOFs' static response to a unit motion of each coupled interface DOF.
    mass_coupling : ndarray (m, n_c)
        Φᵀ (M_ii Ψ + M_ic): the only coupling of the modes to the interface, kg.
    stiffness_internal, mass_internal : ndarray (n_i, n_i)
        K_ii and M_ii, for the residual flexibility of the truncated modes.
    far_modes : int
        How many of the modes lie below the far-field cut-off.
    """

    omega2: np.ndarray
    shapes: np.ndarray
    constraint: np.ndarray
    mass_coupling: np.ndarray
    stiffness_internal: np.ndarray
    mass_internal: np.ndarray
    far_modes: int

    @property
    def n_modes(self) -> int:
        return int(self.omega2.size)


@dataclass(frozen=True)
class ReducedSystem:
    """A :class:`LinearSystem` in span-mode coordinates u_r = (q_0, ..., q_{S-1}, u_b).

    Attributes
    ----------
    system : LinearSystem
        The exact system that was reduced.
    cutoff : float
        Highest frequency of the kept modes, Hz.
    span_type : ndarray (S,)
        Index into ``types`` of each span.
    types : tuple of SpanModes
    internal : tuple of ndarray
        Each span's internal DOFs (free-DOF indices, in track order).
    coupled : tuple of ndarray
        Each span's coupled interface DOFs, as positions in ``interface``.
    modal_offset : ndarray (S + 1,)
        Span s's modal coordinates are u_r[modal_offset[s]:modal_offset[s + 1]].
    interface : ndarray (n_b,)
        Free-DOF index of each interface DOF; they follow the modal coordinates in u_r.
    interface_mass, interface_stiffness : ndarray (n_b, n_b)
        The interface blocks of the reduced mass (kg) and stiffness (N/m).
    """

    system: LinearSystem
    cutoff: float
    span_type: np.ndarray
    types: tuple[SpanModes, ...]
    internal: tuple[np.ndarray, ...]
    coupled: tuple[np.ndarray, ...]
    modal_offset: np.ndarray
    interface: np.ndarray
    interface_mass: np.ndarray
    interface_stiffness: np.ndarray

    @property
    def n_modal(self) -> int:
        return int(self.modal_offset[-1])

    @property
    def n_dofs(self) -> int:
        return self.n_modal + int(self.interface.size)

    def modes_of(self, span: int) -> SpanModes:
        return self.types[int(self.span_type[span])]

    def rows(self, dofs: np.ndarray) -> np.ndarray:
        """The rows of the transformation u = T u_r for the free DOFs ``dofs``; shape (len(dofs), n_r)."""
        dofs = np.asarray(dofs)
        out = np.zeros((dofs.size, self.n_dofs))
        where = _locate(self)
        for row, dof in enumerate(dofs):
            kind, span, local = where[dof]
            if kind < 0:
                out[row, self.n_modal + local] = 1.0
            else:
                modes = self.modes_of(span)
                out[row, self.modal_offset[span] : self.modal_offset[span + 1]] = modes.shapes[local]
                out[row, self.n_modal + self.coupled[span]] = modes.constraint[local]
        return out


def _locate(reduced: ReducedSystem) -> np.ndarray:
    """(kind, span, local index) of every free DOF: kind -1 for interface DOFs (local = position)."""
    n = reduced.system.n_dofs
    where = np.zeros((n, 3), dtype=np.int64)
    where[reduced.interface] = np.c_[
        -np.ones(reduced.interface.size), np.zeros(reduced.interface.size), np.arange(reduced.interface.size)
    ]
    for s, dofs in enumerate(reduced.internal):
        where[dofs] = np.c_[np.zeros(dofs.size), np.full(dofs.size, s), np.arange(dofs.size)]
    return where


def split_spans(system: LinearSystem) -> tuple[tuple[np.ndarray, ...], np.ndarray, tuple[np.ndarray, ...]]:
    """Internal DOFs of each span, the interface DOFs, and each span's coupled interface positions.

    A DOF belongs to the span its node stands in; nodes at a support are interface DOFs, and so is
    any DOF that the matrices couple to another span's DOF (a stitch wire's middle bar crosses the
    support), so that spans couple only through the interface.
    """
    lay = system.static.layout
    sizes = lay.node_size(np.arange(lay.node_x.size))
    x = lay.node_x[np.repeat(np.arange(lay.node_x.size), sizes)[system.free]] / lay.span_length
    span = np.clip(np.floor(x).astype(int), 0, lay.n_spans - 1)
    interface = np.abs(x - np.round(x)) < 1e-9
    pattern = (abs(system.stiffness) + abs(system.mass)).tocoo()
    i, j = pattern.row, pattern.col
    while True:
        across = ~interface[i] & ~interface[j] & (span[i] != span[j])
        if not across.any():
            break
        interface[np.where(span[i[across]] > span[j[across]], i[across], j[across])] = True
    b = np.flatnonzero(interface)
    position = np.full(x.size, -1)
    position[b] = np.arange(b.size)
    internal = tuple(np.flatnonzero((span == s) & ~interface) for s in range(lay.n_spans))
    csr = pattern.tocsr()
    coupled = tuple(np.unique(position[csr[dofs].indices[interface[csr[dofs].indices]]]) for dofs in internal)
    return internal, b, coupled


def band_width(matrix: np.ndarray) -> int:
    """The largest distance of a non-zero entry from the diagonal."""
    rows, cols = np.nonzero(matrix)
    return int(np.max(np.abs(rows - cols), initial=0))


def band_storage(matrix: np.ndarray, width: int | None = None) -> np.ndarray:
    """The upper band of a symmetric matrix in LAPACK storage, (width + 1, n); width: its own by default."""
    width = band_width(matrix) if width is None else width
    ab = np.zeros((width + 1, matrix.shape[0]))
    for k in range(width + 1):
        ab[width - k, k:] = np.diagonal(matrix, k)
    return ab


def upper_band(matrix: np.ndarray) -> np.ndarray:
    """The upper Cholesky factor of a banded SPD matrix, in LAPACK band storage."""
    return sla.cholesky_banded(band_storage(matrix), check_finite=False)


def _span_modes(K_ii, M_ii, K_ic, M_ic, cutoff: float, far_cutoff: float) -> SpanModes:
    """Fixed-interface modes below ``cutoff`` Hz and constraint modes of one span."""
    omega2, shapes = sla.eigh(K_ii, M_ii, driver="gvd", check_finite=False)
    keep = int(np.searchsorted(omega2, (2.0 * np.pi * cutoff) ** 2, side="right"))
    omega2, shapes = omega2[:keep], shapes[:, :keep]
    far = int(np.searchsorted(omega2, (2.0 * np.pi * far_cutoff) ** 2, side="right"))
    constraint = -sla.cho_solve_banded((upper_band(K_ii), False), K_ic, check_finite=False)
    coupling = shapes.T @ (M_ii @ constraint + M_ic)
    return SpanModes(omega2, shapes, constraint, coupling, K_ii, M_ii, far)


def _same_sparse(a: sp.csr_matrix, b: sp.csr_matrix) -> bool:
    """Equal to :data:`SAME_SPAN_TOLERANCE` (an entry that rounds to zero in one span may be stored)."""
    if a.shape != b.shape:
        return False
    scale = SAME_SPAN_TOLERANCE * np.abs(b.data).max(initial=0.0)
    if np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices):
        return bool(np.abs(a.data - b.data).max(initial=0.0) <= scale)
    return bool(abs(a - b).max() <= scale)


def reduce_system(system: LinearSystem, cutoff: float, far_cutoff: float | None = None) -> ReducedSystem:
    """Reduce ``system`` to span modes below ``cutoff`` Hz (``inf`` keeps every mode: exact).

    ``far_cutoff`` (Hz, default ``cutoff``) marks the modes that spans far from the pantograph keep.
    """
    far_cutoff = cutoff if far_cutoff is None else far_cutoff
    internal, b, coupled = split_spans(system)
    K = system.stiffness.tocsr()
    M = system.mass.tocsr()
    types: list[SpanModes] = []
    # Per type: its blocks (sparse, for comparison) and the interface matrices a span of it adds.
    representatives: list[tuple[sp.csr_matrix, ...]] = []
    added: list[tuple[np.ndarray, np.ndarray]] = []
    span_type = np.zeros(len(internal), dtype=np.int64)
    for s, dofs in enumerate(internal):
        cols = b[coupled[s]]
        K_s, M_s = K[dofs], M[dofs]
        blocks = (K_s[:, dofs], M_s[:, dofs], K_s[:, cols], M_s[:, cols])
        for t, rep in enumerate(representatives):
            if all(_same_sparse(x, r) for x, r in zip(blocks, rep, strict=True)):
                span_type[s] = t
                break
        else:
            span_type[s] = len(types)
            representatives.append(blocks)
            K_ii, M_ii, K_ic, M_ic = (x.toarray() for x in blocks)
            modes = _span_modes(K_ii, M_ii, K_ic, M_ic, cutoff, far_cutoff)
            types.append(modes)
            # Ψᵀ M_ii Ψ + Ψᵀ M_ic + M_ci Ψ on the coupled interface DOFs; for K the same sum, K_ci Ψ.
            Psi = modes.constraint
            cross = Psi.T @ M_ic
            added.append((Psi.T @ M_ii @ Psi + cross + cross.T, K_ic.T @ Psi))
    interface_mass = M[b][:, b].toarray()
    interface_stiffness = K[b][:, b].toarray()
    for s, c in enumerate(coupled):
        mass, stiffness = added[span_type[s]]
        interface_mass[np.ix_(c, c)] += mass
        interface_stiffness[np.ix_(c, c)] += stiffness
    interface_stiffness = 0.5 * (interface_stiffness + interface_stiffness.T)
    counts = np.array([types[t].n_modes for t in span_type])
    return ReducedSystem(
        system=system,
        cutoff=float(cutoff),
        span_type=span_type,
        types=tuple(types),
        internal=internal,
        coupled=coupled,
        modal_offset=np.r_[0, np.cumsum(counts)],
        interface=b,
        interface_mass=interface_mass,
        interface_stiffness=interface_stiffness,
    )


def reduced_matrices(reduced: ReducedSystem) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The reduced mass and stiffness as sparse matrices of size n_r (for tests and checks)."""
    n_q = reduced.n_modal
    n = reduced.n_dofs
    M = sp.lil_matrix((n, n))
    K = sp.lil_matrix((n, n))
    for s in range(len(reduced.internal)):
        modes = reduced.modes_of(s)
        q = np.arange(reduced.modal_offset[s], reduced.modal_offset[s + 1])
        c = n_q + reduced.coupled[s]
        M[q, q] = 1.0
        K[q, q] = modes.omega2
        M[np.ix_(q, c)] = modes.mass_coupling
        M[np.ix_(c, q)] = modes.mass_coupling.T
    M[n_q:, n_q:] = reduced.interface_mass
    K[n_q:, n_q:] = reduced.interface_stiffness
    return M.tocsr(), K.tocsr()
