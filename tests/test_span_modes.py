"""The span-mode (reduced) model against the exact one (docs/performance.md, 'Model fidelities').

With every mode kept the reduction is a change of basis, so the reduced passage must equal the exact
one to rounding, slack droppers and contact loss included; with a cut-off it must approach it as the
cut-off rises.
"""

from __future__ import annotations

import collections
import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from conftest import assert_recorded
from scipy.sparse.csgraph import breadth_first_order

from catenary_env.dynamics import exact as exact_model
from catenary_env.dynamics import span_modes
from catenary_env.dynamics.contact_point import start_train
from catenary_env.dynamics.linear_system import linearise
from catenary_env.dynamics.protocol import Passage
from catenary_env.dynamics.span_modes import reduction
from catenary_env.dynamics.span_modes.reduction import reduce_system, reduced_matrices
from catenary_env.fem.layout import build_layout
from catenary_env.model.design import Design, DesignError, level_design
from catenary_env.model.options import FORMER_DEFAULTS, ModellingOptions
from catenary_env.pipeline import FIDELITIES, Fidelity, check_fidelity, evaluate
from catenary_env.statics.shape_finding import find_shape

SPEED = 300 / 3.6
DT = 2e-3


def simulate_exact(system, pantograph, uplift, speed, **options):
    """The exact passage of one pantograph, frame force ``uplift`` (N)."""
    return exact_model.run(
        exact_model.prepare(system, Fidelity(time_step=DT)),
        Passage.one_pantograph(pantograph, uplift, speed, **options),
    )


def simulate_reduced(prepared, pantograph, uplift, speed, **options):
    """The span-mode passage of one pantograph, frame force ``uplift`` (N)."""
    return span_modes.run(prepared, Passage.one_pantograph(pantograph, uplift, speed, **options))


@pytest.fixture(scope="module")
def system(benchmark_catenary):
    # The model of physics revision 2 (hinged messenger, extensible wires): its interior spans are identical
    # to round-off and it has modes between the cut-offs tried below. With the default continuous messenger
    # a span's shape departs from its neighbours' by 1e-6 one span from an end, 1e-9 two spans in, so each
    # of those spans is its own type; the reduction itself is the same.
    catenary = dataclasses.replace(benchmark_catenary, modelling=ModellingOptions(**FORMER_DEFAULTS))
    return linearise(find_shape(build_layout(catenary, level_design(catenary), 5, 1.0, 2.0)))


@pytest.fixture(scope="module")
def exact(system, benchmark_pantograph_definition):
    return simulate_exact(system, benchmark_pantograph_definition, 190.0, SPEED, backend="numpy")


@pytest.fixture(scope="module")
def full_basis(system):
    return span_modes.prepare_reduced(reduce_system(system, np.inf), DT, near_spans=1)


def test_interior_spans_share_one_eigensolution(system):
    reduced = reduce_system(system, 200.0)
    first, *interior, last = reduced.span_type.tolist()
    # first span, the interior ones, last span
    assert len(set(interior)) == 1 and len({first, interior[0], last}) == 3
    assert len(reduced.types) == 3


def test_a_type_s_spans_share_its_representative_s_droppers(system):
    """Every span of a type stands for the type's representative, its droppers too: the loops read one
    set of rows per type, and each span's own rows (its B on its own DOFs) are the representative's."""
    reduced = reduce_system(system, 200.0)
    assert np.array_equal(reduced.span_type[reduced.representative], np.arange(len(reduced.types)))
    d = span_modes.prepare_reduced(reduced, DT, near_spans=1).arrays
    B = system.dropper_elongation.toarray()
    for s, t in enumerate(reduced.span_type):
        q = np.arange(d.dropper_start[s], d.dropper_start[s + 1])
        m = reduced.types[t].n_modes
        np.testing.assert_array_equal(d.dropper_q[q], d.type_dropper_q[t, : q.size])
        own = B[np.ix_(q, reduced.internal[s])] @ reduced.types[t].shapes  # this span's own rows
        np.testing.assert_allclose(d.dropper_q_plain[q, :m], own, rtol=0, atol=1e-9 * np.abs(own).max())


def test_reduced_matrices_are_the_projection(system):
    reduced = reduce_system(system, 150.0)
    T = reduced.rows(np.arange(system.n_dofs))
    M, K = reduced_matrices(reduced)
    assert np.abs(T.T @ system.mass @ T - M).max() < 1e-9 * abs(M).max()
    assert np.abs(T.T @ system.stiffness @ T - K).max() < 1e-9 * abs(K).max()
    # fixed-interface modes: mass-normalised, no stiffness coupling to the interface
    n_q = reduced.n_modal
    assert np.allclose(M[:n_q, :n_q].diagonal(), 1.0)
    assert abs(K[:n_q, n_q:]).max() < 1e-6 * abs(K).max()


def test_every_mode_kept_equals_the_exact_passage(full_basis, exact, benchmark_pantograph_definition):
    reduced = simulate_reduced(full_basis, benchmark_pantograph_definition, 190.0, SPEED, backend="numpy")
    assert exact.slack_steps > 50  # the case exercises slack droppers
    assert reduced.slack_steps == exact.slack_steps
    assert np.abs(reduced.contact_force - exact.contact_force).max() < 1e-5
    assert np.abs(reduced.support_uplift - exact.support_uplift).max() < 1e-9
    assert np.abs(reduced.dropper_force_min - exact.dropper_force_min).max() < 1e-5


def test_contact_loss_is_handled_as_in_the_exact_passage(system, full_basis, benchmark_pantograph_definition):
    # A weak uplift at 350 km/h: the pantograph leaves the wire.
    pantograph = benchmark_pantograph_definition
    exact = simulate_exact(system, pantograph, 60.0, 350 / 3.6, backend="numpy")
    reduced = simulate_reduced(full_basis, pantograph, 60.0, 350 / 3.6, backend="numpy")
    lost = exact.contact_force == 0.0
    assert lost.sum() > 10
    assert np.array_equal(reduced.contact_force == 0.0, lost)
    assert np.abs(reduced.contact_force - exact.contact_force).max() < 1e-5


def test_the_reduced_model_approaches_the_exact_one_as_the_cutoff_rises(
    system, exact, benchmark_pantograph_definition
):
    window = slice(exact.time.size // 3, 2 * exact.time.size // 3)
    errors = []
    for cutoff in (100.0, 200.0, 400.0):
        prepared = span_modes.prepare_reduced(reduce_system(system, cutoff), DT, near_spans=1)
        reduced = simulate_reduced(prepared, benchmark_pantograph_definition, 190.0, SPEED, backend="numpy")
        difference = reduced.contact_force[window] - exact.contact_force[window]
        errors.append(np.sqrt(np.mean(difference**2)) / np.std(exact.contact_force[window]))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.05


def test_compiled_loop_equals_the_numpy_loop(system, benchmark_pantograph_definition, recorded_passages):
    pytest.importorskip("numba")
    prepared = span_modes.prepare_reduced(reduce_system(system, 300.0, 50.0), DT, near_spans=1)
    a = simulate_reduced(prepared, benchmark_pantograph_definition, 190.0, SPEED, backend="numpy")
    b = simulate_reduced(prepared, benchmark_pantograph_definition, 190.0, SPEED, backend="numba")
    assert np.abs(a.contact_force - b.contact_force).max() < 1e-9
    assert np.abs(a.wire_uplift - b.wire_uplift).max() < 1e-10
    assert a.slack_steps == b.slack_steps
    assert_recorded(recorded_passages, "span_modes_300_numpy", a)
    assert_recorded(recorded_passages, "span_modes_300_numba", b)


def test_the_compiled_loop_pairs_spans_of_one_type_and_kept_modes():
    pytest.importorskip("numba")
    from catenary_env.dynamics.span_modes import kernels

    Arrays = collections.namedtuple("Arrays", "span_type kept")
    span_type = np.array([3, 1, 0, 0, 0, 0, 0, 2, 0, 4])
    kept = np.array([[81, 356, 356, 356, 81, 81, 81, 81, 81, 81]])
    partner = np.zeros(span_type.size, dtype=np.int64)
    kernels._span_pairs(Arrays(span_type, kept), 0, partner, span_type.size)
    assert partner.tolist() == [-1, -1, 3, -2, 5, -2, 8, -1, -2, -1]
    # pairs share a type and a number of kept modes, every span is in one pair or alone
    for s, z in enumerate(partner):
        if z >= 0:
            assert span_type[s] == span_type[z] and kept[0, s] == kept[0, z] and partner[z] == -2
    assert np.sum(partner >= 0) == np.sum(partner == -2)
    # with the first 5 spans stepped (the others held ahead of the wave front), only they are paired
    kernels._span_pairs(Arrays(span_type, kept), 0, partner, 5)
    assert partner.tolist() == [-1, -1, 3, -2, -1, -1, -1, -1, -1, -1]


@pytest.mark.parametrize("count", [1, 3, 4, 7, 9])
def test_the_paired_row_products_are_the_row_products(count):
    pytest.importorskip("numba")
    from catenary_env.dynamics.span_modes import kernels

    rng = np.random.default_rng(count)
    rows, x, z = rng.standard_normal((count, 83)), rng.standard_normal(90), rng.standard_normal(90)
    out_x, out_z = np.full(count + 2, 7.0), np.full(count + 2, 7.0)
    kernels._rows_dot_pair(rows, count, x, z, 83, out_x, out_z)
    np.testing.assert_allclose(out_x[:count], rows @ x[:83], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(out_z[:count], rows @ z[:83], rtol=1e-13, atol=1e-13)
    assert np.all(out_x[count:] == 7.0) and np.all(out_z[count:] == 7.0)


def test_fidelities_name_both_models():
    assert FIDELITIES["study"].dynamics == "span-modes"
    assert FIDELITIES["reference"].dynamics == "exact"
    assert dataclasses.replace(FIDELITIES["study"], dynamics="exact") == FIDELITIES["reference"]


def test_bad_reduced_fidelity_is_refused(benchmark_catenary):
    with pytest.raises(DesignError, match="fidelity.dynamics"):
        check_fidelity(benchmark_catenary, Fidelity(dynamics="modal"))
    with pytest.raises(DesignError, match="fidelity.far_cutoff"):
        check_fidelity(benchmark_catenary, Fidelity(near_cutoff=100.0, far_cutoff=200.0))


def test_pipeline_runs_the_span_mode_model(benchmark_catenary, benchmark_pantograph_definition):
    fidelity = Fidelity(
        n_spans=4, analysis_spans=2, contact_wire_element=1.0, messenger_wire_element=2.0, time_step=2e-3
    )
    design = level_design(benchmark_catenary)
    study = evaluate(benchmark_catenary, benchmark_pantograph_definition, design, SPEED, fidelity, 190.0)
    exact = evaluate(
        benchmark_catenary,
        benchmark_pantograph_definition,
        design,
        SPEED,
        dataclasses.replace(fidelity, dynamics="exact"),
        190.0,
    )
    assert study.feasible == exact.feasible
    assert study.statistics.std == pytest.approx(exact.statistics.std, rel=0.02)
    assert study.statistics.mean == pytest.approx(exact.statistics.mean, rel=0.005)


def test_evaluation_stops_one_span_after_the_analysis_section_without_changing_it(
    benchmark_catenary, benchmark_pantograph_definition
):
    from catenary_env.pipeline import run_passage, solve_static

    fidelity = Fidelity(
        n_spans=7, analysis_spans=3, contact_wire_element=1.0, messenger_wire_element=2.0, time_step=2e-3
    )
    static = solve_static(benchmark_catenary, level_design(benchmark_catenary), fidelity)
    args = (static, benchmark_pantograph_definition, SPEED, fidelity, 190.0)
    whole = run_passage(*args)
    short = run_passage(*args, statistics_only=True)
    assert short.trajectory.position[-1] == pytest.approx(6 * benchmark_catenary.span_length, abs=1.0)
    for name, value in whole.statistics.as_dict().items():
        assert getattr(short.statistics, name) == pytest.approx(value, rel=1e-6, abs=1e-9), name


# Speed-ups that must not change the model (docs/performance.md, 'Speed'): mirror images of spans,
# the residual from the truncated eigenpairs, sparse blocks gathered by hand.


def test_a_passage_without_kept_configurations_is_the_one_with_them(
    system, benchmark_pantograph_definition, monkeypatch
):
    """A passage holds one configuration's arrays at a time, built as it enters it or taken from those the
    design keeps (within a memory budget): rebuilt or kept, the passage is the same, number for number."""
    from catenary_env.dynamics.span_modes import preparation

    def passage(budget, repeat=1):
        monkeypatch.setattr(preparation, "KEPT_CONFIGURATION_BYTES", budget)
        prepared = span_modes.prepare_reduced(reduce_system(system, 200.0), DT, near_spans=1)
        for _ in range(repeat):
            trajectory = simulate_reduced(prepared, benchmark_pantograph_definition, 190.0, SPEED)
        return trajectory, prepared

    kept, prepared = passage(2**40, repeat=2)  # the second passage runs on the kept configurations
    rebuilt, unkept = passage(0)
    assert len(prepared.built) == system.static.layout.n_spans and set(unkept.built) == {(0,)}
    np.testing.assert_array_equal(kept.contact_force, rebuilt.contact_force)
    np.testing.assert_array_equal(kept.dropper_force_max, rebuilt.dropper_force_max)


def test_progress_reports_do_not_change_the_span_mode_passage(system, benchmark_pantograph_definition):
    # With progress the loop runs in a hundred calls, which split the configurations' stretches of steps.
    prepared = span_modes.prepare_reduced(reduce_system(system, 200.0), DT, near_spans=1)
    fractions: list[float] = []
    chunked = simulate_reduced(
        prepared, benchmark_pantograph_definition, 190.0, SPEED, progress=fractions.append
    )
    whole = simulate_reduced(prepared, benchmark_pantograph_definition, 190.0, SPEED)
    assert len(fractions) > 50 and fractions[-1] == 1.0
    np.testing.assert_array_equal(chunked.contact_force, whole.contact_force)
    np.testing.assert_array_equal(chunked.support_uplift, whole.support_uplift)


def test_the_passage_does_not_depend_on_where_its_arrays_lie(system, benchmark_pantograph_definition):
    """The same passage, its loop's work arrays allocated anew in each of a hundred calls (progress) and the
    allocator's free memory shuffled between passages, gives the same forces to the last bit: no loop's
    rounding may depend on the addresses of its arrays (docs/model.md, 'Results and the model that made
    them')."""
    prepared = span_modes.prepare_reduced(reduce_system(system, 200.0), DT, near_spans=1)
    rng = np.random.default_rng(3)
    forces, held = set(), []
    for _ in range(40):
        held.append([np.empty(int(n)) for n in rng.integers(1, 600, size=20)])  # move later allocations
        passage = simulate_reduced(prepared, benchmark_pantograph_definition, 190.0, SPEED, progress=_ignore)
        forces.add(passage.contact_force.tobytes())
    assert len(forces) == 1


def _ignore(fraction: float) -> None:
    """A progress report that does nothing (with one, the loop runs in a hundred calls)."""


def _plain(monkeypatch, system, *args):
    """reduce_system with every span's eigenproblem solved as it is (no mirror images)."""
    with monkeypatch.context() as patch:
        patch.setattr(reduction, "find_mirror", lambda *a, **k: None)
        return reduce_system(system, *args)


def test_mirror_images_give_the_same_modes(system, monkeypatch):
    mirrors = []
    found = reduction.find_mirror

    def spy(*args):
        mirrors.append((args[1] is args[2], found(*args) is not None))
        return found(*args)

    monkeypatch.setattr(reduction, "find_mirror", spy)
    mirrored = reduce_system(system, 300.0, 50.0)
    monkeypatch.undo()
    # the interior span is its own mirror image, the last span the first one's
    assert (True, True) in mirrors and (False, True) in mirrors
    plain = _plain(monkeypatch, system, 300.0, 50.0)
    assert mirrored.span_type.tolist() == plain.span_type.tolist()
    for a, b in zip(plain.types, mirrored.types, strict=True):
        assert a.n_modes == b.n_modes and a.far_modes == b.far_modes
        # the mirror images agree to MIRROR_TOLERANCE of the largest entry: the low modes to about 1e-10
        assert np.allclose(a.omega2, b.omega2, rtol=1e-8, atol=0.0)
        # the same subspace: Φ_aᵀ M Φ_b is orthogonal
        overlap = np.linalg.svd(a.shapes.T @ a.mass_internal @ b.shapes, compute_uv=False)
        assert np.allclose(overlap, 1.0, atol=1e-9)
        assert np.allclose(b.shapes.T @ b.mass_internal @ b.shapes, np.eye(b.n_modes), atol=1e-9)
        assert np.allclose(a.truncated_omega2, b.truncated_omega2, rtol=1e-8, atol=0.0)


def test_the_passage_with_mirrored_modes_equals_the_plain_one(
    system, monkeypatch, benchmark_pantograph_definition
):
    runs = []
    for reduced in (reduce_system(system, 300.0, 50.0), _plain(monkeypatch, system, 300.0, 50.0)):
        prepared = span_modes.prepare_reduced(reduced, DT, near_spans=1)
        runs.append(
            simulate_reduced(prepared, benchmark_pantograph_definition, 190.0, SPEED, backend="numpy")
        )
    a, b = runs
    assert a.slack_steps == b.slack_steps > 50
    # rounding only: the numpy and the compiled loops differ by as much
    assert np.abs(a.contact_force - b.contact_force).max() < 1e-6
    assert np.std(a.contact_force) == pytest.approx(np.std(b.contact_force), rel=1e-9)


def _own_mirror(system, span):
    internal, b, coupled = reduction.split_spans(system)
    dofs = internal[span]
    rows = tuple(
        reduction.submatrix(x.tocsr(), dofs, np.r_[dofs, b[coupled[span]]])
        for x in (system.stiffness, system.mass)
    )
    dense = tuple(x.toarray()[:, : dofs.size] for x in rows)
    axis = (span + 0.5) * system.static.layout.span_length
    return reduction.find_mirror(system, dofs, dofs, axis, dense, rows)


def test_a_span_that_is_not_symmetric_is_not_mirrored(system, benchmark_catenary):
    assert _own_mirror(system, 2) is not None  # the level design's interior span is symmetric
    design = level_design(benchmark_catenary)
    shifted = np.array(design.dropper_positions) + np.linspace(0.0, 0.5, design.n_droppers)
    layout = build_layout(
        benchmark_catenary, Design(tuple(shifted), design.contact_wire_offsets), 5, 1.0, 2.0
    )
    assert _own_mirror(linearise(find_shape(layout)), 2) is None


def test_residual_from_the_truncated_eigenpairs_is_the_inverse_less_the_kept_modes(system):
    reduced = reduce_system(system, 300.0, 50.0)
    modes = reduced.types[1]
    c_k, c_m = 1.3, 4.0e6
    effective = c_k * modes.stiffness_internal + c_m * modes.mass_internal
    phi = modes.shapes / np.sqrt(c_k * modes.omega2 + c_m)
    rest = modes.truncated_shapes / np.sqrt(c_k * modes.truncated_omega2 + c_m)
    inverse = np.linalg.inv(effective)
    assert np.abs(rest @ rest.T - (inverse - phi @ phi.T)).max() < 1e-9 * np.abs(inverse).max()


def test_submatrix_equals_scipy_indexing(system):
    K = system.stiffness.tocsr()
    rng = np.random.default_rng(3)
    rows = np.sort(rng.choice(system.n_dofs, 40, replace=False))
    cols = rng.permutation(system.n_dofs)[:300]
    assert np.array_equal(reduction.submatrix(K, rows, cols).toarray(), K[rows][:, cols].toarray())


def test_band_width_of_a_dense_matrix_is_that_of_its_non_zero_entries():
    rng = np.random.default_rng(7)
    for _ in range(500):
        shape = rng.integers(1, 9, size=2)
        A = np.where(rng.random(shape) < 0.3, rng.standard_normal(shape), 0.0)
        i, j = np.nonzero(A)
        expected = int(np.max(np.abs(i - j), initial=0))
        assert reduction.band_width(A) == expected == reduction.band_width(sp.csr_matrix(A))


def test_the_parity_basis_products_are_the_sparse_basis_ones(system):
    """Qᵀ X and Q v by gathering rows are a sparse Q's products, to the last bit."""
    mirror = _own_mirror(system, 2)
    internal, _, _ = reduction.split_spans(system)
    dofs = internal[2]
    K = system.stiffness.tocsr()[dofs][:, dofs].toarray()
    n = dofs.size
    index = np.arange(n)
    pairs, half = index[index < mirror.source], np.sqrt(0.5)
    for parity in (1.0, -1.0):
        on_plane = index[(mirror.source == index) & (mirror.sign == parity)]
        rows = np.r_[pairs, mirror.source[pairs], on_plane]
        cols = np.r_[np.arange(pairs.size), np.arange(pairs.size), pairs.size + np.arange(on_plane.size)]
        values = np.r_[np.full(pairs.size, half), parity * half * mirror.sign[pairs], np.ones(on_plane.size)]
        Q = sp.csr_matrix((values, (rows, cols)), shape=(n, pairs.size + on_plane.size))
        Qt = Q.T.tocsr()
        basis = reduction._ParityBasis.of(mirror, parity)
        assert np.array_equal(basis.project(basis.project(K).T), Qt @ (Qt @ K).T)
        v = np.random.default_rng(4).standard_normal((Q.shape[1], Q.shape[1]))
        assert np.array_equal(basis.expand(v), Q @ v)


@pytest.mark.parametrize("span", [0, 2])
@pytest.mark.parametrize("compiled", [True, False])
def test_the_eigensolution_through_the_mass_band_is_lapack_s_generalised_one(
    system, span, compiled, monkeypatch
):
    """M's Cholesky factor kept banded, then the standard eigensolution (docs/performance.md, 'The span types'
    eigensolutions through the mass matrix's band'): the eigenvalues of dsygvd, every residual and the
    M-orthonormality at rounding, with the band solves compiled or LAPACK's."""
    if compiled:
        pytest.importorskip("numba")
    else:
        monkeypatch.setattr(reduction, "_band_kernels", lambda: None)
    dofs = reduction.split_spans(system)[0][span]
    K, M = (x.tocsr()[dofs][:, dofs].toarray() for x in (system.stiffness, system.mass))
    omega2, shapes = reduction.generalised_eigh(K, M)
    expected = sla.eigh(K, M, eigvals_only=True)
    np.testing.assert_allclose(omega2, expected, rtol=0, atol=1e-13 * expected.max())
    assert np.abs(K @ shapes - (M @ shapes) * omega2).max() < 1e-12 * np.abs(K).max()
    np.testing.assert_allclose(shapes.T @ M @ shapes, np.eye(dofs.size), rtol=0, atol=1e-13)


@pytest.mark.parametrize("transposed", [True, False])
def test_the_compiled_band_solves_are_lapack_s(transposed, monkeypatch):
    """The row-wise substitutions (numba) solve U x = b or Uᵀ x = b as LAPACK's dtbtrs does, and leave the
    right-hand sides as they were."""
    pytest.importorskip("numba")
    rng = np.random.default_rng(6)
    n, width = 50, 4
    M = sum(np.diag(rng.uniform(-1.0, 1.0, n - k), k) for k in range(1, width + 1))
    M = M + M.T + np.diag(rng.uniform(2.0 * width, 3.0 * width, n))  # diagonally dominant: SPD
    factor = reduction.upper_band(M)
    U = np.triu(sla.cholesky(M))
    rows = rng.standard_normal((n, 13))
    given = rows.copy()
    compiled = reduction._solve_factor(factor, rows, transposed)
    monkeypatch.setattr(reduction, "_band_kernels", lambda: None)
    lapack_s = reduction._solve_factor(factor, rows, transposed)
    np.testing.assert_allclose(compiled, lapack_s, rtol=0, atol=1e-14 * np.abs(lapack_s).max())
    np.testing.assert_allclose((U.T if transposed else U) @ compiled, rows, rtol=0, atol=1e-13)
    assert np.array_equal(rows, given)


def _tree_walk_signs(i, j, a, b, n):
    """reduction._mirror_signs as a walk down each breadth-first tree, one DOF at a time."""
    diagonal = np.zeros(n)
    diagonal[i[i == j]] = np.sqrt(np.abs(a[i == j]))
    strong = np.abs(a) > 1e-6 * diagonal[i] * diagonal[j]
    graph = sp.csr_matrix((np.sign(a * b)[strong], (i[strong], j[strong])), shape=(n, n))
    sign = np.zeros(n)
    for root in range(n):
        if sign[root]:
            continue
        order, parent = breadth_first_order(graph, root, directed=False)
        child = order[1:]
        ratio = np.asarray(graph[parent[child], child]).ravel()
        if np.any(ratio == 0.0):
            return None
        sign[root] = 1.0
        for v, r in zip(child, ratio, strict=True):
            sign[v] = sign[parent[v]] * r
    return sign


def test_mirror_signs_are_those_of_the_walk_down_the_tree(system):
    internal, _, _ = reduction.split_spans(system)
    dofs = internal[2]
    rows = reduction.submatrix(system.stiffness.tocsr(), dofs, dofs)
    i, j, a, n = rows.row, rows.col, rows.data, dofs.size
    flip = np.random.default_rng(5).choice([-1.0, 1.0], n)
    apart = (i < n // 3) == (j < n // 3)  # two components: the first third and the rest
    for keep in (np.ones(i.size, dtype=bool), apart):
        args = (i[keep], j[keep], a[keep], (flip[i] * flip[j] * a)[keep], n)
        signs = reduction._mirror_signs(*args)
        assert np.array_equal(signs, _tree_walk_signs(*args))
        assert np.array_equal((signs[i] * signs[j])[keep], (flip[i] * flip[j])[keep])
    assert signs[0] == signs[n // 3] == 1.0  # each component's first DOF
    alone = ((i != n // 2) & (j != n // 2)) | (i == j)  # a DOF without couplings: a component of its own
    args = (i[alone], j[alone], a[alone], (flip[i] * flip[j] * a)[alone], n)
    signs = reduction._mirror_signs(*args)
    assert signs[n // 2] == 1.0
    assert np.array_equal((signs[i] * signs[j])[alone], (flip[i] * flip[j])[alone])


def test_a_configuration_s_interface_responses_are_the_band_solves(system):
    """A configuration's S⁻¹ columns are the band solves of the pantograph's unit forces to the last bit; the
    droppers' responses there, and the dense X and G of dropper_responses, are those of their right-hand
    sides to rounding."""
    reduced = reduce_system(system, 300.0, 50.0)
    prepared = span_modes.prepare_reduced(reduced, DT, near_spans=1)
    builder = prepared.builder
    for configuration in ((1,), (0, 3), (-1,)):
        out = builder.build(configuration)
        factor = (out["schur_band"], False)
        n_drop, n_b = builder.d_c.shape[0], reduced.interface.size
        H = np.zeros((n_drop, n_b))  # each dropper's row on its span's coupled interface DOFs
        for q, span in enumerate(builder.d_span):
            own = reduced.coupled[span]
            H[q, own] = (builder.d_c - builder.c_m * out["dropper_h"])[q, : own.size]
        X = sla.cho_solve_banded(factor, H.T)
        scale = np.abs(X).max()
        for p, span in enumerate(configuration):
            own = reduced.coupled[span] if span >= 0 else np.zeros(0, dtype=np.int64)
            unit = np.zeros((n_b, own.size))
            unit[own, np.arange(own.size)] = 1.0
            assert np.array_equal(
                out["element_interface"][p, : own.size], sla.cho_solve_banded(factor, unit).T
            )
            np.testing.assert_allclose(
                out["dropper_element_interface"][p, : own.size], X[own], rtol=0.0, atol=1e-13 * scale
            )
        # G: each span's droppers' own block (its kept modes; and with the residual), and H X
        G, G_full = H @ X, H @ X
        for span, k in enumerate(out["kept"]):
            q = slice(builder.start[span], builder.start[span + 1])
            G[q, q] += builder.modal_block[span, k]
            G_full[q, q] += builder.modal_block[span, k] + builder.residual_block[span, k]
        arrays = prepared.arrays._replace(**span_modes.preparation.as_configuration_zero(out))
        responses = span_modes.preparation.dropper_responses(arrays)
        np.testing.assert_allclose(responses[0], X.T, rtol=0.0, atol=1e-13 * scale)
        for got, expected in zip(responses[1:], (G, G_full), strict=True):
            np.testing.assert_allclose(got, expected, rtol=0.0, atol=1e-13 * np.abs(expected).max())


def test_the_compiled_loop_s_dropper_rows_are_those_of_the_dense_responses(system):
    """The compiled loop takes a slack dropper's row of X and G when it first needs it (kernels._dropper_row):
    each row equals the dense dropper_responses' to rounding, in every configuration."""
    kernels = pytest.importorskip("catenary_env.dynamics.span_modes.kernels")
    reduced = reduce_system(system, 300.0, 50.0)
    prepared = span_modes.prepare_reduced(reduced, DT, near_spans=1)
    for configuration in ((1,), (0, 3), (-1,)):
        arrays = prepared.arrays_for(configuration)
        X, G, G_full = span_modes.preparation.dropper_responses(arrays)
        n_drop, n_b = X.shape
        x, modal, full = np.zeros(n_b), np.zeros(n_drop), np.zeros(n_drop)
        for q in range(n_drop):
            kernels._dropper_row(arrays, 0, q, np.zeros(n_b), x, modal, full)
            np.testing.assert_allclose(x, X[q], rtol=0.0, atol=1e-13 * np.abs(X).max())
            np.testing.assert_allclose(modal, G[q], rtol=0.0, atol=1e-13 * np.abs(G).max())
            np.testing.assert_allclose(full, G_full[q], rtol=0.0, atol=1e-13 * np.abs(G_full).max())


# The spans ahead of the wave front (docs/performance.md, 'The spans ahead of the wave front'): held at rest,
# they change the passage by rounding only.


@pytest.fixture(scope="module")
def long_system(benchmark_catenary):
    """Ten spans of the default model (transverse-only wires) on a coarse mesh: as the pantograph starts,
    the six spans more than 200 m ahead of the front (460 km/h) are held."""
    layout = build_layout(benchmark_catenary, level_design(benchmark_catenary), 10, 1.5, 3.0)
    return linearise(find_shape(layout))


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_holding_the_spans_ahead_of_the_front_changes_the_passage_by_rounding_only(
    long_system, benchmark_pantograph_definition, backend
):
    if backend == "numba":
        pytest.importorskip("numba")
    from catenary_env.dynamics.span_modes.passage import FRONT_MARGIN, _stepped_spans

    prepared = span_modes.prepare_reduced(reduce_system(long_system, 200.0), DT, near_spans=1)
    passage = Passage.one_pantograph(benchmark_pantograph_definition, 190.0, SPEED, backend=backend)
    held = span_modes.run(prepared, passage)
    every = span_modes.run(prepared, passage, front_margin=None)
    started = start_train(long_system, passage, prepared.constants)
    stepped = _stepped_spans(long_system, started, 10, FRONT_MARGIN)
    assert stepped[0] == 4 and stepped[-1] == 10 and np.all(np.diff(stepped) >= 0)  # the case holds spans
    assert every.slack_steps > 0 and held.slack_steps == every.slack_steps
    assert np.abs(held.contact_force - every.contact_force).max() < 1e-7
    assert np.abs(held.support_uplift - every.support_uplift).max() < 1e-12
    assert np.abs(held.dropper_force_min - every.dropper_force_min).max() < 1e-7
    # too close to the front the held spans do change it: the margin is not idle
    near = span_modes.run(prepared, passage, front_margin=0.0)
    assert np.abs(near.contact_force - every.contact_force).max() > 1e-3


def test_extensible_wires_step_every_span(system, benchmark_pantograph_definition):
    from catenary_env.dynamics.span_modes.passage import FRONT_MARGIN, _stepped_spans, front_speed

    catenary = system.static.layout.catenary
    assert catenary.modelling.linearisation == "extensible"
    assert front_speed(catenary) == pytest.approx(catenary.contact_wire.wave_speed)
    prepared = span_modes.prepare_reduced(reduce_system(system, 200.0), DT, near_spans=1)
    passage = Passage.one_pantograph(benchmark_pantograph_definition, 190.0, SPEED)
    started = start_train(system, passage, prepared.constants)
    assert np.all(_stepped_spans(system, started, 5, FRONT_MARGIN) == 5)


def test_the_interface_a_span_reaches_runs_in_track_order(long_system):
    reduced = reduce_system(long_system, 200.0)
    end = span_modes.preparation.interface_end(reduced)
    assert end[-1] == reduced.interface.size and np.all(np.diff(end) > 0)
    for s in range(end.size - 1):  # what spans 0 .. s hold is theirs alone; the next support is not
        later = np.concatenate(reduced.coupled[s + 1 :])
        assert later.min() == end[s]
        assert np.isin(reduced.coupled[s], np.arange(end[s])).any()
