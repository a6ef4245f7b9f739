"""The fast pantograph passage: Newmark with a constant effective matrix and superposition
(docs/model.md, 'Time integration and the fast method').

K̂ = K + a1 C + a0 M does not change in time, so it is factorised once (banded Cholesky after a
reverse Cuthill–McKee ordering). The two nonlinearities, contact and slack droppers, are moved to
the right-hand side as unknown forces, and by superposition

    u₁ = u_known + u*_c f_c + Σ_d W_d λ_d,

with W_d = K̂⁻¹ B_dᵀ the responses to unit dropper force pairs (computed once per design) and
u*_c the response to a unit contact force (computed for the contact-wire element as the pantograph
reaches it). Each step then solves a small problem in f_c and the slack droppers' λ only, by
active-set iteration (Gregori et al. 2017, "An approach to geometric optimisation of railway
catenaries", Veh. Syst. Dyn. 56; the same method for slack droppers).

A slack dropper transmits nothing: λ_d cancels its whole linear force, spring and Rayleigh damping
share, N₀ + k (1 + β a1) Δl₁ - β k B (a1 u₀ + a4 v₀ + a5 a₀). A dropper is slack when that force
would be compressive: judging by the spring force alone while removing the damping share too
leaves droppers near zero force with no consistent state, whereas this rule makes each step a
linear complementarity problem with a unique solution.

The time loop has two backends with the same steps and arithmetic (:data:`BACKENDS`; docs/performance.md,
'Benchmark'): numpy, the reference, cut into the compiled loop's functions, and one compiled by numba
(:mod:`catenary_env.dynamics._kernels`, optional), which :func:`simulate_passage` takes when numba is
installed. Their contact forces agree to about 1e-9 N. Both follow the active-set rules of
:mod:`~catenary_env.dynamics.active_set` and record through
:class:`~catenary_env.dynamics.history.PassageHistory`; the span-mode model
(:mod:`~catenary_env.dynamics.reduced_passage`) plugs in beside them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import NamedTuple

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..model.definition import PantographDefinition
from .active_set import settle
from .history import PassageHistory
from .kernel_preparation import padded_width, response_windows, unit_factor, upper_rows
from .linear_system import LinearSystem
from .newmark import NewmarkConstants, Trajectory, passage_positions
from .pantograph import PantographMatrices, pantograph_matrices, static_contact


class BandedCholesky:
    """K̂ = Uᵀ U of a sparse SPD matrix in band storage; solves in the original order.

    The DOFs are numbered along the track already (:mod:`catenary_env.fem.layout`); reverse
    Cuthill–McKee is used instead only where it gives a narrower band.
    """

    def __init__(self, matrix: sp.spmatrix) -> None:
        A = sp.csr_matrix(matrix)
        coo = A.tocoo()
        natural = int(np.max(np.abs(coo.row - coo.col)))
        rcm = reverse_cuthill_mckee(A, symmetric_mode=True)
        Ar = A[rcm][:, rcm].tocoo()
        if int(np.max(np.abs(Ar.row - Ar.col))) < natural:
            self.perm: np.ndarray | None = rcm
            coo = Ar
        else:
            self.perm = None
        upper = coo.row <= coo.col
        rows, cols, vals = coo.row[upper], coo.col[upper], coo.data[upper]
        self.bandwidth = int(np.max(cols - rows))
        ab = np.zeros((self.bandwidth + 1, A.shape[0]))
        ab[self.bandwidth + rows - cols, cols] = vals
        self.factor = sla.cholesky_banded(ab, lower=False, check_finite=False)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        if self.perm is None:
            return sla.cho_solve_banded((self.factor, False), rhs, check_finite=False)
        out = np.empty_like(rhs)
        out[self.perm] = sla.cho_solve_banded((self.factor, False), rhs[self.perm], check_finite=False)
        return out


@dataclass(frozen=True)
class PreparedPassage:
    """The design's part of the fast method, computed once per design and time step.

    Attributes
    ----------
    system : LinearSystem
    constants : NewmarkConstants
    factor : BandedCholesky
        Of K̂ = (1 + β a1) K + (a0 + α a1) M.
    dropper_response : ndarray (n, D)
        W = K̂⁻¹ Bᵀ, responses to unit dropper force pairs.
    dropper_flexibility : ndarray (D, D)
        G = B W, dropper elongations per unit dropper force.
    """

    system: LinearSystem
    constants: NewmarkConstants
    factor: BandedCholesky
    dropper_response: np.ndarray
    dropper_flexibility: np.ndarray


def prepare_passage(system: LinearSystem, time_step: float) -> PreparedPassage:
    """Factorise K̂ and compute the unit dropper responses."""
    nm = NewmarkConstants.for_step(time_step)
    factor = BandedCholesky(
        (1.0 + system.beta * nm.a1) * system.stiffness + (nm.a0 + system.alpha * nm.a1) * system.mass
    )
    B = system.dropper_elongation
    W = factor.solve(B.T.toarray())
    return PreparedPassage(system, nm, factor, W, np.asarray(B @ W))


def _compiled_kernels() -> ModuleType | None:
    """:mod:`catenary_env.dynamics._kernels`, or None where numba is not installed."""
    try:
        from . import _kernels
    except ImportError:
        return None
    return _kernels


class _Passage(NamedTuple):
    """The pantograph and track part of a passage, and the initial state; shared by both backends."""

    time: np.ndarray
    position: np.ndarray
    element: np.ndarray
    shape: np.ndarray
    wire_z: np.ndarray
    pantograph: PantographMatrices
    pantograph_inverse: np.ndarray
    y_star: np.ndarray
    load_p: np.ndarray
    y0: np.ndarray
    force0: float
    acceleration0: np.ndarray


def _start_passage(
    system: LinearSystem,
    pantograph: PantographDefinition,
    uplift_force: float,
    speed: float,
    nm: NewmarkConstants,
    n_steps: int | None,
) -> _Passage:
    """Positions, contact-wire elements and heights along the passage, pantograph matrices, initial state."""
    lay = system.static.layout
    cat = lay.catenary
    pm = pantograph_matrices(pantograph)
    head = pm.head
    Kp_hat = pm.stiffness + nm.a1 * pm.damping + nm.a0 * pm.mass
    Kp_inv = np.linalg.inv(Kp_hat)
    load_p = np.zeros(pm.mass.shape[0])
    load_p[0] = uplift_force
    time, position = passage_positions(lay.n_spans * lay.span_length, speed, nm.dt)
    if n_steps is not None:
        time, position = time[:n_steps], position[:n_steps]
    element, shape, wire_z = system.contact_wire.locate(position)
    wire_z = wire_z - cat.contact_wire_height  # static height above nominal
    kh = cat.contact_stiffness
    y0 = static_contact(pm, uplift_force, kh, wire_z[0])[0]
    f0 = kh * max(0.0, y0[head] - wire_z[0])
    # Consistent initial acceleration: the catenary starts at rest under the initial contact force.
    load0 = np.zeros(system.n_dofs)
    np.add.at(load0, system.contact_wire.z_dofs[element[0]], shape[0] * f0)
    a = spla.spsolve(system.mass.tocsc(), load0)
    y_star = Kp_inv[:, head].copy()  # pantograph response to a unit downward head force (negated)
    return _Passage(time, position, element, shape, wire_z, pm, Kp_inv, y_star, load_p, y0, f0, a)


def simulate_passage(
    system: LinearSystem,
    pantograph: PantographDefinition,
    uplift_force: float,
    speed: float,
    time_step: float,
    n_steps: int | None = None,
    progress: Callable[[float], None] | None = None,
    prepared: PreparedPassage | None = None,
    backend: str = "auto",
) -> Trajectory:
    """Pantograph passage over the whole section at constant ``speed`` (m/s), fast method.

    Parameters
    ----------
    uplift_force : float
        Static uplift force on the pantograph's bottom mass, N.
    time_step : float
        Newmark step, s.
    n_steps : int, optional
        Stop after this many steps (the whole section by default).
    progress : callable, optional
        Called with the fraction done, about a hundred times.
    prepared : PreparedPassage, optional
        From :func:`prepare_passage` with the same system and time step, to reuse it.
    backend : {"auto", "numpy", "numba"}
        Where the time loop runs: ``"numba"`` compiles it (:mod:`catenary_env.dynamics._kernels`; about
        four to five times faster on the study mesh, compiled once per machine and band width, some ten
        seconds, then cached), ``"numpy"`` is the reference implementation, ``"auto"`` takes numba
        when it is installed. Both give the same results to rounding (1e-9 N on the contact force).

    Examples
    --------
    >>> from catenary_env.model.design import level_design
    >>> from catenary_env.fem.layout import build_layout
    >>> from catenary_env.dynamics.linear_system import linearise
    >>> from catenary_env.model.presets import load_catenary, load_pantograph
    >>> from catenary_env.statics.shape_finding import find_shape
    >>> catenary = load_catenary("benchmark")
    >>> system = linearise(find_shape(build_layout(catenary, level_design(catenary), 3, 2.0, 4.0)))
    >>> passage = simulate_passage(system, load_pantograph(catenary.pantograph), 150.0, 250 / 3.6, 2e-3)
    >>> bool(passage.contact_force.max() > 150.0)
    True
    """
    if backend not in ("auto", *BACKENDS):
        raise ValueError(f"backend = {backend!r}: one of auto, {', '.join(BACKENDS)}")
    if backend == "auto":
        backend = "numba" if _compiled_kernels() is not None else "numpy"
    if prepared is None:
        prepared = prepare_passage(system, time_step)
    if prepared.system is not system or prepared.constants.dt != time_step:
        raise ValueError("prepared: computed for another system or time step")
    passage = _start_passage(system, pantograph, uplift_force, speed, prepared.constants, n_steps)
    return BACKENDS[backend](prepared, passage, progress)


def _simulate_numpy(
    prepared: PreparedPassage, passage: _Passage, progress: Callable[[float], None] | None
) -> Trajectory:
    """The time loop in numpy: the reference implementation of the fast method, in the compiled loop's
    steps (:func:`catenary_env.dynamics._kernels.run_steps`)."""
    system = prepared.system
    nm = prepared.constants
    M, K = system.mass, system.stiffness
    alpha, beta = system.alpha, system.beta
    W, G = prepared.dropper_response, prepared.dropper_flexibility
    N0 = system.dropper_force
    kappa = system.dropper_rate * (1.0 + beta * nm.a1)
    kh = system.static.layout.catenary.contact_stiffness
    y_star, head = passage.y_star, passage.pantograph.head
    n_steps = passage.time.size

    u, v, a = np.zeros(system.n_dofs), np.zeros(system.n_dofs), passage.acceleration0
    y, yd, ydd = passage.y0, np.zeros(head + 1), np.zeros(head + 1)
    history = PassageHistory(n_steps, system.support_z.size, N0, passage.force0, y[head])
    contact = passage.force0 > 0.0
    slack = np.zeros(N0.size, dtype=bool)
    current_element = -1
    c1, c2, c3 = nm.a0 + alpha * nm.a1, nm.a2 + alpha * nm.a4, nm.a3 + alpha * nm.a5
    d1, d2, d3 = beta * nm.a1, beta * nm.a4, beta * nm.a5
    report_every = max(1, n_steps // 100)

    for k in range(1, n_steps):
        if progress is not None and k % report_every == 0:
            progress(k / n_steps)
        u_known = prepared.factor.solve(M @ (c1 * u + c2 * v + c3 * a) + K @ (d1 * u + d2 * v + d3 * a))
        if passage.element[k] != current_element:
            current_element = passage.element[k]
            zd, P, Pzz, Wz = _element_responses(prepared, current_element)
        h = passage.shape[k]
        c_cc = h @ Pzz @ h + y_star[head]
        g_dc = Wz.T @ h
        y_known, gap_known, dl_known, rate_term = _known_part(
            prepared, passage, k, h, zd, u_known, u, v, a, y, yd, ydd
        )
        step = settle(contact, slack, gap_known, c_cc, g_dc, dl_known, rate_term, kh, kappa, N0, G)
        contact, slack, f, idx, lam, elastic = step[:6]
        u_new = u_known + (P @ h) * f + W[:, idx] @ lam
        y_new = y_known - f * y_star
        v, a = nm.update(u, v, a, u_new)
        yd, ydd = nm.update(y, yd, ydd, y_new)
        u, y = u_new, y_new
        history.record(
            k, f, y[head], h @ u[zd], u[system.support_z], elastic, slack, idx.size > 0, step.resolved
        )

    if progress is not None:
        progress(1.0)
    return history.trajectory(passage.time, passage.position, system.static.layout.support_x)


def _element_responses(
    prepared: PreparedPassage, element: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The contact-wire element's z DOFs, the unit responses P = K̂⁻¹ E to forces there, P[zd] and W[zd]."""
    system = prepared.system
    zd = system.contact_wire.z_dofs[element]
    unit = np.zeros((system.n_dofs, 4))
    unit[zd, np.arange(4)] = 1.0
    P = prepared.factor.solve(unit)
    return zd, P, P[zd], prepared.dropper_response[zd]


def _known_part(
    prepared: PreparedPassage,
    passage: _Passage,
    k: int,
    h: np.ndarray,
    zd: np.ndarray,
    u_known: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    a: np.ndarray,
    y: np.ndarray,
    yd: np.ndarray,
    ydd: np.ndarray,
) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """The pantograph without contact (y_known), the contact gap without contact force (m), the dropper
    elongations B u_known (m) and damping shares β k B (a1 u₀ + a4 v₀ + a5 a₀) (N)."""
    system, nm, pm = prepared.system, prepared.constants, passage.pantograph
    B = system.dropper_elongation
    rhs_p = pm.mass @ (nm.a0 * y + nm.a2 * yd + nm.a3 * ydd) + pm.damping @ (
        nm.a1 * y + nm.a4 * yd + nm.a5 * ydd
    )
    y_known = passage.pantograph_inverse @ (rhs_p + passage.load_p)
    gap_known = y_known[pm.head] - passage.wire_z[k] - h @ u_known[zd]
    rate_term = system.beta * system.dropper_rate * (B @ (nm.a1 * u + nm.a4 * v + nm.a5 * a))
    return y_known, float(gap_known), B @ u_known, rate_term


def _simulate_compiled(
    prepared: PreparedPassage, passage: _Passage, progress: Callable[[float], None] | None
) -> Trajectory:
    """The time loop compiled by numba (:mod:`catenary_env.dynamics._kernels`), in chunks for ``progress``."""
    kernels = _compiled_kernels()
    if kernels is None:
        raise ImportError("backend='numba' needs numba: pip install numba")
    system = prepared.system
    data, width, order = _kernel_arrays(kernels, prepared, passage)
    n, n_steps, head, w = system.n_dofs, passage.time.size, passage.pantograph.head, len(width)
    N0 = system.dropper_force
    state = kernels.PassageState(
        u=np.zeros(n),
        v=np.zeros(n),
        a=passage.acceleration0[order],
        x=np.zeros(n),
        y=np.zeros(n),
        work=np.zeros(n + w),
        sweep=np.zeros(n + w),
        unit=np.zeros((n + w, 4)),
        y_p=passage.y0.copy(),
        yd_p=np.zeros(head + 1),
        ydd_p=np.zeros(head + 1),
        slack=np.zeros(N0.size, dtype=np.bool_),
        flags=np.array([passage.force0 > 0.0, -1, 0, 0, 0, -1], dtype=np.int64),
        force=np.zeros(n_steps),
        head_height=np.zeros(n_steps),
        wire_uplift=np.zeros(n_steps),
        support_uplift=np.zeros((n_steps, system.support_z.size)),
        dropper_min=N0.copy(),
        dropper_max=N0.copy(),
    )
    state.force[0] = passage.force0
    state.head_height[0] = passage.y0[head]
    bounds = np.unique(np.linspace(1, n_steps, 101 if progress is not None else 2).round().astype(int))
    for first, stop in zip(bounds[:-1], bounds[1:], strict=True):
        kernels.run_steps(data, state, int(first), int(stop), width)
        if progress is not None:
            progress(stop / n_steps)
    history = PassageHistory.from_arrays(
        state, state.flags[kernels.SLACK_STEPS], state.flags[kernels.UNRESOLVED]
    )
    return history.trajectory(passage.time, passage.position, system.static.layout.support_x)


BACKENDS = {"numpy": _simulate_numpy, "numba": _simulate_compiled}
"""The exact passage's time loops by name; ``"auto"`` takes numba where it is installed."""


def _kernel_arrays(
    kernels: ModuleType, prepared: PreparedPassage, passage: _Passage
) -> tuple[NamedTuple, tuple[int, ...], np.ndarray]:
    """The compiled loop's data in the factor's DOF order, the band-width tuple, that order (index -> DOF).

    The loop works in the factor's order throughout: it reads the state only at the contact
    wire, the supports and the droppers, whose indices are mapped once here.
    """
    system, nm, factor = prepared.system, prepared.constants, prepared.factor
    M, W = system.mass, prepared.dropper_response
    B = sp.csr_matrix(system.dropper_elongation)
    order = np.arange(system.n_dofs)
    if factor.perm is not None:
        order = factor.perm
        M, B, W = M[order][:, order], B[:, order], W[order]
    index = np.empty_like(order)  # DOF -> position in the factor's order
    index[order] = np.arange(order.size)
    width = padded_width(factor.bandwidth)
    unit = unit_factor(factor.factor, width)
    m_ptr, m_offset, m_values = upper_rows(M)
    B.sort_indices()
    alpha, beta = system.alpha, system.beta
    kh = system.static.layout.catenary.contact_stiffness
    # K̂ = c_k K + c_m M, so M x + K y = M (x - (c_m / c_k) y) + K̂ y / c_k (see _kernels): the
    # right-hand side's M and K parts, c and d, become e = c - (c_m / c_k) d and g = d / c_k.
    c = np.array([nm.a0 + alpha * nm.a1, nm.a2 + alpha * nm.a4, nm.a3 + alpha * nm.a5])
    d = beta * np.array([nm.a1, nm.a4, nm.a5])
    c_k, c_m = 1.0 + beta * nm.a1, nm.a0 + alpha * nm.a1
    coefficients = np.concatenate(
        [c - (c_m / c_k) * d, d / c_k, [nm.a0, nm.a1, nm.a2, nm.a3, nm.a4, nm.a5, kh, beta, 0.0, 0.0]]
    )
    pm = passage.pantograph
    data = kernels.PassageArrays(
        upper=unit.upper,
        lower=unit.lower,
        scale=unit.scale,
        m_ptr=m_ptr,
        m_offset=m_offset,
        m_values=m_values,
        b_ptr=B.indptr.astype(np.int64),
        b_index=B.indices.astype(np.int64),
        b_values=B.data.astype(float),
        dropper_response_t=np.ascontiguousarray(W.T),
        dropper_window=response_windows(W),
        dropper_flexibility=np.ascontiguousarray(prepared.dropper_flexibility, dtype=float),
        dropper_rate=system.dropper_rate.astype(float),
        dropper_force=system.dropper_force.astype(float),
        dropper_kappa=system.dropper_rate * (1.0 + beta * nm.a1),
        z_dofs=index[system.contact_wire.z_dofs].astype(np.int64),
        support_z=index[system.support_z].astype(np.int64),
        element=passage.element.astype(np.int64),
        shape=np.ascontiguousarray(passage.shape, dtype=float),
        wire_z=passage.wire_z.astype(float),
        pantograph_inverse=passage.pantograph_inverse,
        pantograph_mass=np.ascontiguousarray(pm.mass, dtype=float),
        pantograph_damping=np.ascontiguousarray(pm.damping, dtype=float),
        y_star=passage.y_star,
        load_p=passage.load_p,
        coefficients=coefficients,
    )
    return data, (0,) * width, order
