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
so one eigensolution serves all of them: a section has a few span types (the interior one, and a
span or two next to each end, where the end effects exceed :data:`SAME_SPAN_TOLERANCE`).
Mirror images save two more: a span whose matrices are another type's mirrored about mid-span (the
last span of a symmetric section is the first one's) takes that type's modes mirrored, and a span
that is its own mirror image (the interior span of a symmetric design) solves its symmetric and
antisymmetric modes apart, two problems of half the size. Both are exact equivalences, used only
where the matrices agree to :data:`MIRROR_TOLERANCE`; otherwise the span is solved as it is.
With every mode kept the reduction is only a change of basis and the reduced model equals the
exact one; the cut-off is the only approximation.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.linalg import lapack
from scipy.sparse.csgraph import breadth_first_order

from ..linear_system import LinearSystem

SAME_SPAN_TOLERANCE = 1e-7
"""Largest relative difference of two spans' matrices for them to share their modes. Interior
spans of a section differ by rounding only (about 1e-11); the section's end effects decay by a factor
of 100 to 1000 a span (1e-6 and 1e-9 in the second and third spans of the benchmark catenary, 1e-4,
1e-6 and 2e-8 in the stitched one's), and a span within 1e-7 of another perturbs the dynamics by that
order, 10⁵ times below the accuracy contract."""

MIRROR_TOLERANCE = 1e-10
"""Largest relative difference between a span's matrices and the mirror image of another's (or of
its own) for their eigensolutions to be mirror images. Mirror-image spans of a symmetric design
differ by rounding only (about 1e-12)."""


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
        K_ii and M_ii.
    far_modes : int
        How many of the modes lie below the far-field cut-off.
    truncated_omega2 : ndarray (n_i - m,)
    truncated_shapes : ndarray (n_i, n_i - m)
        The span's other eigenpairs, above the cut-off: the residual flexibility of the truncated
        modes is theirs, Φ_t (c_k ω_t² + c_m)⁻¹ Φ_tᵀ.
    """

    omega2: np.ndarray
    shapes: np.ndarray
    constraint: np.ndarray
    mass_coupling: np.ndarray
    stiffness_internal: np.ndarray
    mass_internal: np.ndarray
    far_modes: int
    truncated_omega2: np.ndarray
    truncated_shapes: np.ndarray

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
    representative : ndarray (T,)
        Each type's representative: the span whose matrices its modes are, and that every span of the
        type stands for.
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
    representative: np.ndarray
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

    A DOF belongs to the span its node stands in; nodes at a support are interface DOFs, and so are
    both DOFs of any coupling between two spans (a stitch wire's middle bar crosses the support), so
    that spans couple only through the interface and a section symmetric about mid-span splits into
    spans that are each other's mirror images.
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
        interface[i[across]] = interface[j[across]] = True
    b = np.flatnonzero(interface)
    position = np.full(x.size, -1)
    position[b] = np.arange(b.size)
    internal = tuple(np.flatnonzero((span == s) & ~interface) for s in range(lay.n_spans))
    csr = pattern.tocsr()
    columns = (csr.indices[_row_entries(csr, dofs)[0]] for dofs in internal)
    coupled = tuple(np.unique(position[cols[interface[cols]]]) for cols in columns)
    return internal, b, coupled


def _row_entries(matrix: sp.csr_matrix, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions in ``matrix.data`` of the entries of ``rows``, row by row, and their row in ``rows``."""
    starts = matrix.indptr[rows]
    lengths = matrix.indptr[rows + 1] - starts
    first = np.cumsum(lengths) - lengths
    row = np.repeat(np.arange(rows.size), lengths)
    return np.repeat(starts - first, lengths) + np.arange(lengths.sum()), row


@dataclass(frozen=True)
class SparseRows:
    """Some rows of a sparse matrix on chosen columns, as coordinates (row, column, value) in row order:
    what a span's comparison and its dense blocks need, without scipy's checks on each new matrix."""

    row: np.ndarray
    col: np.ndarray
    data: np.ndarray
    shape: tuple[int, int]

    def toarray(self) -> np.ndarray:
        dense = np.zeros(self.shape)
        dense[self.row, self.col] = self.data
        return dense

    def same(self, other: SparseRows) -> bool:
        """Equal to :data:`SAME_SPAN_TOLERANCE` (an entry that rounds to zero in one may be stored)."""
        if self.shape != other.shape:
            return False
        scale = SAME_SPAN_TOLERANCE * np.abs(other.data).max(initial=0.0)
        if np.array_equal(self.row, other.row) and np.array_equal(self.col, other.col):
            return bool(np.abs(self.data - other.data).max(initial=0.0) <= scale)
        return bool(np.abs(self.toarray() - other.toarray()).max() <= scale)


def submatrix(matrix: sp.csr_matrix, rows: np.ndarray, columns: np.ndarray) -> SparseRows:
    """``matrix[rows][:, columns]``, gathered through the row pointers and a column lookup instead of
    scipy's fancy indexing (about a millisecond a call)."""
    lookup = np.full(matrix.shape[1], -1)
    lookup[columns] = np.arange(columns.size)
    at, row = _row_entries(matrix, rows)
    col = lookup[matrix.indices[at]]
    keep = col >= 0
    return SparseRows(row[keep], col[keep], matrix.data[at][keep], (rows.size, columns.size))


def band_width(matrix: np.ndarray | sp.spmatrix | SparseRows) -> int:
    """The largest distance of a non-zero entry from the diagonal."""
    if isinstance(matrix, SparseRows) or sp.issparse(matrix):
        coo = matrix if isinstance(matrix, SparseRows) else matrix.tocoo()
        rows, cols = coo.row[coo.data != 0.0], coo.col[coo.data != 0.0]
        return int(np.max(np.abs(rows - cols), initial=0))
    # Dense: each row's first and last non-zero column (argmax finds the first True), without listing every
    # non-zero entry as np.nonzero does (a third of a millisecond for a span's 356 × 356).
    nonzero = matrix != 0.0
    rows = np.flatnonzero(nonzero.any(axis=1))
    first = np.argmax(nonzero[rows], axis=1)
    last = matrix.shape[1] - 1 - np.argmax(nonzero[rows, ::-1], axis=1)
    return int(max(np.max(rows - first, initial=0), np.max(last - rows, initial=0)))


def band_storage(matrix: np.ndarray, width: int | None = None) -> np.ndarray:
    """The upper band of a symmetric matrix in LAPACK storage, (width + 1, n); width: its own by default."""
    width = band_width(matrix) if width is None else width
    ab = np.zeros((width + 1, matrix.shape[0]))
    for k in range(width + 1):
        ab[width - k, k:] = np.diagonal(matrix, k)
    return ab


def upper_band(matrix: np.ndarray, width: int | None = None) -> np.ndarray:
    """The upper Cholesky factor of a banded SPD matrix, in LAPACK band storage; width: its own by
    default (at least the matrix's)."""
    return sla.cholesky_banded(band_storage(matrix, width), check_finite=False)


def generalised_eigh(K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All eigenpairs (ω² ascending, M-normalised Φ) of K φ = ω² M φ, K symmetric, M banded SPD.

    LAPACK's generalised solver (``dsygvd``) in three steps, with M's Cholesky factor M = Uᵀ U kept banded:
    C = U⁻ᵀ K U⁻¹, the standard eigensolution C = Y Λ Yᵀ (``dsyevd``), Φ = U⁻¹ Y. ``dsygvd`` factors M
    densely and forms C and Φ with dense triangular products, a third of its time at a span's size; the
    banded solves cost n² w (docs/performance.md, 'The span types' eigensolutions through the mass matrix's
    band').
    """
    factor = upper_band(M)
    C = _solve_factor(factor, _solve_factor(factor, K, transposed=True).T, transposed=True)
    omega2, Y = sla.eigh(C, driver="evd", overwrite_a=True, check_finite=False)
    return omega2, _solve_factor(factor, Y, transposed=False)


def _solve_factor(factor: np.ndarray, rows: np.ndarray, transposed: bool) -> np.ndarray:
    """U⁻ᵀ rows (``transposed``) or U⁻¹ rows, for U in LAPACK's upper band storage (:func:`upper_band`):
    by rows where numba is installed, else a column at a time (``dtbtrs``)."""
    kernels = _band_kernels()
    if kernels is None:
        return lapack.dtbtrs(factor, rows, uplo="U", trans="T" if transposed else "N")[0]
    solved = np.array(rows, order="C")
    kernels.solve_upper_in_place(factor, solved, transposed)
    return solved


def _band_kernels() -> ModuleType | None:
    """:mod:`catenary_env.dynamics.span_modes.band_kernels`, or None where numba is not installed."""
    try:
        from . import band_kernels
    except ImportError:
        return None
    return band_kernels


@dataclass(frozen=True)
class Mirror:
    """A signed permutation P between two spans' internal DOFs: the mirror image on span b of a vector
    v on span a is (P v)_i = sign_i v[source_i]. Span b's matrices are P (span a's) Pᵀ to
    :data:`MIRROR_TOLERANCE`, so P maps span a's eigenvectors onto span b's."""

    source: np.ndarray
    sign: np.ndarray

    def apply(self, vectors: np.ndarray) -> np.ndarray:
        mirrored = vectors[self.source]
        mirrored *= self.sign[:, None]  # in place: a span's eigenvectors are a megabyte
        return mirrored


def _dof_codes(system: LinearSystem) -> tuple[np.ndarray, np.ndarray]:
    """Each free DOF's node kind and coordinate within its node (one integer), and its design x, m."""
    lay = system.static.layout
    nodes = np.arange(lay.node_x.size)
    node = np.repeat(nodes, lay.node_size(nodes))
    coordinate = np.arange(lay.n_dofs) - lay.node_dof[node]
    kind = lay.node_kind[node] * (coordinate.max() + 1) + coordinate
    return kind[system.free], lay.node_x[node][system.free]


def find_mirror(
    system: LinearSystem,
    a: np.ndarray,
    b: np.ndarray,
    axis: float,
    dense_a: tuple[np.ndarray, np.ndarray],
    rows_b: tuple[SparseRows, SparseRows],
    codes: tuple[np.ndarray, np.ndarray] | None = None,
    nonzeros_a: tuple[int, int] | None = None,
) -> Mirror | None:
    """The mirror image x → 2 axis - x from span a's internal DOFs onto span b's, if span b's stiffness
    and mass are span a's mirrored; None otherwise.

    DOFs match by node kind, coordinate within the node and design x; the signs (a coordinate along
    the track changes sign, and so does a slope) follow from the stiffness, along its strong entries,
    and both matrices are then checked entry by entry. ``dense_a`` holds K_aa and M_aa, ``rows_b``
    span b's rows of K and M (its internal DOFs first); ``codes``, the system's :func:`_dof_codes`, and
    ``nonzeros_a``, the counts of non-zero entries of ``dense_a``, where the caller has them (a section of
    distinct spans compares each with every type).
    """
    kind, x = _dof_codes(system) if codes is None else codes
    if nonzeros_a is None:
        nonzeros_a = tuple(np.count_nonzero(dense) for dense in dense_a)
    if a.size != b.size:
        return None
    microns = np.rint(np.r_[x[a], 2.0 * axis - x[b]] * 1e6).astype(np.int64)
    width = int(kind.max()) + 1
    code_a, code_b = microns[: a.size] * width + kind[a], microns[a.size :] * width + kind[b]
    order = np.argsort(code_a)
    source = order[np.minimum(np.searchsorted(code_a[order], code_b), a.size - 1)]
    if not np.array_equal(code_a[source], code_b):
        return None
    entries = []
    for dense, rows, nonzeros in zip(dense_a, rows_b, nonzeros_a, strict=True):
        inside = rows.col < b.size
        i, j, value = rows.row[inside], rows.col[inside], rows.data[inside]
        mirrored = dense[source[i], source[j]]
        if np.count_nonzero(value) != nonzeros or not np.allclose(
            np.abs(mirrored), np.abs(value), rtol=0.0, atol=MIRROR_TOLERANCE * np.abs(value).max()
        ):
            return None
        entries.append((i, j, value, mirrored))
    sign = _mirror_signs(*entries[0], b.size)
    if sign is None:
        return None
    for i, j, value, mirrored in entries:
        if np.abs(value - sign[i] * sign[j] * mirrored).max() > MIRROR_TOLERANCE * np.abs(value).max():
            return None
    return Mirror(source, sign)


def _mirror_signs(i: np.ndarray, j: np.ndarray, a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray | None:
    """Signs σ with σ_i σ_j b = a over the entries (i, j, a, b) of two matrices of size n, found along a
    spanning tree of the strong entries (above 1e-6 of their diagonal's geometric mean)."""
    diagonal = np.zeros(n)
    diagonal[i[i == j]] = np.sqrt(np.abs(a[i == j]))
    strong = np.abs(a) > 1e-6 * diagonal[i] * diagonal[j]
    graph = sp.csr_matrix((np.sign(a * b)[strong], (i[strong], j[strong])), shape=(n, n))
    sign = np.zeros(n)
    root = 0  # each component's first DOF
    while root < n:
        order, parent = breadth_first_order(graph, root, directed=False)
        child = order[1:]
        # (a DOF without strong entries is a component of its own, without children: scipy gives an empty
        # sparse matrix, not an array, for an empty index)
        ratio = np.asarray(graph[parent[child], child]).ravel() if child.size else np.zeros(0)
        if np.any(ratio == 0.0):
            return None
        # σ_v = σ_parent(v) r_v is the product of the ratios (±1, so exact in any order) on the path from v
        # to the root: by pointer jumping, over positions in ``order`` (the root's 0, its own step), each
        # pass doubling the stretch of path that ``above`` holds and ``step`` skips.
        position = np.empty(n, dtype=np.int64)
        position[order] = np.arange(order.size)
        above, step = np.r_[1.0, ratio], np.r_[0, position[parent[child]]]
        while step.any():
            above, step = above * above[step], step[step]
        sign[order] = above
        unsigned = np.flatnonzero(sign == 0.0)
        root = unsigned[0] if unsigned.size else n
    return sign


def _eigensolution(
    K_ii: np.ndarray, M_ii: np.ndarray, mirror: Mirror | None
) -> tuple[np.ndarray, np.ndarray]:
    """All eigenpairs (ω², mass-normalised Φ) of K_ii φ = ω² M_ii φ, in ascending order.

    With a span's own mirror image P (P K Pᵀ = K, P M Pᵀ = M, P² = I), the symmetric and the
    antisymmetric modes (P φ = ±φ) are solved apart, each in an orthonormal basis of its subspace:
    pairs of mirror DOFs (e_i ± σ_i e_j) / √2, and the DOFs on the mirror plane alone.
    """
    if mirror is None or np.any(mirror.sign * mirror.sign[mirror.source] != 1.0):  # P² = I
        return generalised_eigh(K_ii, M_ii)
    omega2, shapes = [], []
    for parity in (1.0, -1.0):
        basis = _ParityBasis.of(mirror, parity)
        K_pp, M_pp = (basis.project(basis.project(x).T) for x in (K_ii, M_ii))
        w, v = generalised_eigh(K_pp, M_pp)
        omega2.append(w)
        shapes.append(basis.expand(v))
    order = np.argsort(np.concatenate(omega2), kind="stable")
    return np.concatenate(omega2)[order], np.hstack(shapes)[:, order]


@dataclass(frozen=True)
class _ParityBasis:
    """The orthonormal basis Q of a span's symmetric (parity 1) or antisymmetric (-1) vectors under its own
    mirror image (:func:`_eigensolution`): a column (e_i + c_i e_j) / √2, c_i = ±σ_i, for each pair of mirror
    DOFs i < j, then e_k for each DOF k on the mirror plane whose sign is the parity. Qᵀ X and Q v gather and
    scatter rows: a sparse Q's products, term for term, without building it (a millisecond a span)."""

    n: int
    pairs: np.ndarray
    partner: np.ndarray
    coefficient: np.ndarray  # c_i / √2
    on_plane: np.ndarray

    HALF = np.sqrt(0.5)

    @classmethod
    def of(cls, mirror: Mirror, parity: float) -> _ParityBasis:
        index = np.arange(mirror.source.size)
        pairs = index[index < mirror.source]
        on_plane = index[(mirror.source == index) & (mirror.sign == parity)]
        return cls(index.size, pairs, mirror.source[pairs], parity * cls.HALF * mirror.sign[pairs], on_plane)

    def project(self, X: np.ndarray) -> np.ndarray:
        """Qᵀ X."""
        paired = self.HALF * X[self.pairs] + self.coefficient[:, None] * X[self.partner]
        return np.concatenate([paired, X[self.on_plane]])

    def expand(self, v: np.ndarray) -> np.ndarray:
        """Q v."""
        out = np.zeros((self.n, v.shape[1]))
        out[self.pairs] = self.HALF * v[: self.pairs.size]
        out[self.partner] = self.coefficient[:, None] * v[: self.pairs.size]
        out[self.on_plane] = v[self.pairs.size :]
        return out


def _span_modes(
    K_ii, M_ii, K_ic, M_ic, cutoff: float, far_cutoff: float, eigen: tuple[np.ndarray, np.ndarray], width: int
) -> SpanModes:
    """Fixed-interface modes below ``cutoff`` Hz (from all the span's eigenpairs) and constraint modes;
    ``width``: K_ii's band width."""
    omega2, shapes = eigen
    keep = int(np.searchsorted(omega2, (2.0 * np.pi * cutoff) ** 2, side="right"))
    truncated = omega2[keep:], shapes[:, keep:]
    omega2, shapes = omega2[:keep], shapes[:, :keep]
    far = int(np.searchsorted(omega2, (2.0 * np.pi * far_cutoff) ** 2, side="right"))
    constraint = -sla.cho_solve_banded((upper_band(K_ii, width), False), K_ic, check_finite=False)
    coupling = shapes.T @ (M_ii @ constraint + M_ic)
    return SpanModes(omega2, shapes, constraint, coupling, K_ii, M_ii, far, *truncated)


def reduce_system(system: LinearSystem, cutoff: float, far_cutoff: float | None = None) -> ReducedSystem:
    """Reduce ``system`` to span modes below ``cutoff`` Hz (``inf`` keeps every mode: exact).

    ``far_cutoff`` (Hz, default ``cutoff``) marks the modes that spans far from the pantograph keep.
    """
    far_cutoff = cutoff if far_cutoff is None else far_cutoff
    internal, b, coupled = split_spans(system)
    K = system.stiffness.tocsr()
    M = system.mass.tocsr()
    span_length = system.static.layout.span_length
    types: list[SpanModes] = []
    # Per type: its first span, its rows of K and M (sparse, for comparison), all its eigenpairs, the
    # counts of non-zero entries of its K_ii and M_ii (for find_mirror) and the interface matrices a span of
    # it adds.
    representatives: list[
        tuple[int, tuple[SparseRows, ...], tuple[np.ndarray, np.ndarray], tuple[int, int]]
    ] = []
    added: list[tuple[np.ndarray, np.ndarray]] = []
    span_type = np.zeros(len(internal), dtype=np.int64)
    # From the centre outwards: the interior type's representative is then a central span, the one
    # furthest from the end effects, and its own mirror image where the design is symmetric.
    centre = 0.5 * (len(internal) - 1)
    codes = _dof_codes(system)
    for s in sorted(range(len(internal)), key=lambda span: abs(span - centre)):
        dofs = internal[s]
        columns = np.r_[dofs, b[coupled[s]]]  # internal, then coupled interface
        rows = (submatrix(K, dofs, columns), submatrix(M, dofs, columns))
        for t, (_, rep, _, _) in enumerate(representatives):
            if all(x.same(r) for x, r in zip(rows, rep, strict=True)):
                span_type[s] = t
                break
        else:
            span_type[s] = len(types)
            (K_ii, K_ic), (M_ii, M_ic) = (np.hsplit(x.toarray(), [dofs.size]) for x in rows)
            # K_ii's and M_ii's non-zero entries, counted in the rows (each entry once, as in toarray)
            nonzeros = tuple(int(np.count_nonzero(x.data[x.col < dofs.size])) for x in rows)
            eigen = None
            for r, _, rep_eigen, rep_nonzeros in representatives:  # another type's mirror image?
                rep = types[span_type[r]]
                axis = 0.5 * (r + s + 1) * span_length
                dense = (rep.stiffness_internal, rep.mass_internal)
                mirror = find_mirror(system, internal[r], dofs, axis, dense, rows, codes, rep_nonzeros)
                if mirror is not None:
                    eigen = (rep_eigen[0], mirror.apply(rep_eigen[1]))
                    break
            if eigen is None:  # its own mirror image?
                axis = (s + 0.5) * span_length
                mirror = find_mirror(system, dofs, dofs, axis, (K_ii, M_ii), rows, codes, nonzeros)
                eigen = _eigensolution(K_ii, M_ii, mirror)
            representatives.append((s, rows, eigen, nonzeros))
            stiffness = rows[0]
            inside = (stiffness.col < dofs.size) & (stiffness.data != 0.0)
            width = int(np.abs(stiffness.row - stiffness.col)[inside].max(initial=0))
            modes = _span_modes(K_ii, M_ii, K_ic, M_ic, cutoff, far_cutoff, eigen, width)
            types.append(modes)
            # Ψᵀ M_ii Ψ + Ψᵀ M_ic + M_ci Ψ on the coupled interface DOFs; for K the same sum, K_ci Ψ.
            Psi = modes.constraint
            cross = Psi.T @ M_ic
            added.append((Psi.T @ M_ii @ Psi + cross + cross.T, K_ic.T @ Psi))
    interface_mass = submatrix(M, b, b).toarray()
    interface_stiffness = submatrix(K, b, b).toarray()
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
        representative=np.array([r for r, *_ in representatives], dtype=np.int64),
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
