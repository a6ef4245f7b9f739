"""The exact model's preparation: K̂ factorised once per design and time step, and the unit dropper responses
(docs/model.md, 'Time integration and the fast method').

K̂ = K + a1 C + a0 M does not change in time, so it is factorised once (banded Cholesky after a
reverse Cuthill–McKee ordering). The two nonlinearities, contact and slack droppers, are moved to
the right-hand side as unknown forces, and by superposition

    u₁ = u_known + u*_c f_c + Σ_d W_d λ_d,

with W_d = K̂⁻¹ B_dᵀ the responses to unit dropper force pairs (computed here, once per design) and
u*_c the response to a unit contact force (computed for the contact-wire element as the pantograph
reaches it). Each step then solves a small problem in f_c and the slack droppers' λ only
(:mod:`~catenary_env.dynamics.active_set`; Gregori et al. 2017, "An approach to geometric optimisation of
railway catenaries", Veh. Syst. Dyn. 56).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..active_set import Droppers
from ..linear_system import LinearSystem
from ..newmark import NewmarkConstants, StepCoefficients
from ..protocol import DynamicsSettings
from .kernel_preparation import CompiledArrays, compiled_arrays


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
class PreparedExact:
    """The design's part of the exact model, computed once per design and time step.

    Attributes
    ----------
    system : LinearSystem
    constants : NewmarkConstants
    coefficients : StepCoefficients
    droppers : Droppers
    factor : BandedCholesky or None
        Of K̂ = (1 + β a1) K + (a0 + α a1) M; None for a system the fast loops do not integrate
        (:attr:`LinearSystem.rayleigh` False: only the oracle runs it).
    dropper_response : ndarray (n, D) or None
        W = K̂⁻¹ Bᵀ, responses to unit dropper force pairs.
    dropper_flexibility : ndarray (D, D) or None
        G = B W, dropper elongations per unit dropper force.
    """

    system: LinearSystem
    constants: NewmarkConstants
    coefficients: StepCoefficients
    droppers: Droppers
    factor: BandedCholesky | None
    dropper_response: np.ndarray | None
    dropper_flexibility: np.ndarray | None

    @cached_property
    def compiled(self) -> CompiledArrays:
        """The compiled loop's arrays, built at its first passage (:mod:`.kernel_preparation`)."""
        assert self.factor is not None and self.dropper_response is not None  # run() checks
        assert self.dropper_flexibility is not None
        return compiled_arrays(
            self.system,
            self.coefficients,
            self.droppers,
            self.factor.factor,
            self.factor.perm,
            self.dropper_response,
            self.dropper_flexibility,
        )


def prepare(system: LinearSystem, fidelity: DynamicsSettings) -> PreparedExact:
    """Factorise K̂ for the fidelity's time step and compute the unit dropper responses (nothing of the kind
    for a system only the oracle integrates)."""
    nm = NewmarkConstants.for_step(fidelity.time_step)
    kh = system.static.layout.catenary.contact_stiffness
    coefficients = StepCoefficients.for_step(nm, system.alpha, system.beta, kh)
    droppers = Droppers.for_step(system.dropper_rate, system.dropper_force, system.beta, nm.a1)
    if not system.rayleigh:
        return PreparedExact(system, nm, coefficients, droppers, None, None, None)
    factor = BandedCholesky(
        (1.0 + system.beta * nm.a1) * system.stiffness + (nm.a0 + system.alpha * nm.a1) * system.mass
    )
    B = system.dropper_elongation
    W = factor.solve(B.T.toarray())
    return PreparedExact(system, nm, coefficients, droppers, factor, W, np.asarray(B @ W))
