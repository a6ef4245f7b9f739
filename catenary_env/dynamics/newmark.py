"""Newmark time integration: its constants, the step coefficients both dynamic models' loops read, the
compiled update, and the passage's output record (docs/model.md, 'Time integration and the fast method')."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from .compilable import compilable

GAMMA = 0.5
BETA = 0.25
"""Newmark's average-acceleration parameters (docs/model.md, 'Time integration and the fast method'):
unconditionally stable, second order."""


@dataclass(frozen=True)
class NewmarkConstants:
    """Coefficients of the displacement form of Newmark's method for a time step ``dt`` (s).

    K̂ u₁ = F₁ + M (a0 u₀ + a2 v₀ + a3 a₀) + C (a1 u₀ + a4 v₀ + a5 a₀), K̂ = K + a1 C + a0 M;
    a₁ = a0 (u₁ - u₀) - a2 v₀ - a3 a₀; v₁ = a1 (u₁ - u₀) - a4 v₀ - a5 a₀.
    """

    dt: float
    a0: float
    a1: float
    a2: float
    a3: float
    a4: float
    a5: float

    @classmethod
    def for_step(cls, dt: float, gamma: float = GAMMA, beta: float = BETA) -> NewmarkConstants:
        return cls(
            dt=dt,
            a0=1.0 / (beta * dt**2),
            a1=gamma / (beta * dt),
            a2=1.0 / (beta * dt),
            a3=1.0 / (2.0 * beta) - 1.0,
            a4=gamma / beta - 1.0,
            a5=0.5 * dt * (gamma / beta - 2.0),
        )

    def update(
        self, u0: np.ndarray, v0: np.ndarray, acc0: np.ndarray, u1: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Velocity and acceleration at the end of the step."""
        acc1 = self.a0 * (u1 - u0) - self.a2 * v0 - self.a3 * acc0
        v1 = self.a1 * (u1 - u0) - self.a4 * v0 - self.a5 * acc0
        return v1, acc1


class StepCoefficients(NamedTuple):
    """The scalars of one time step, by name, for every loop (numba reads a NamedTuple of floats).

    With Rayleigh damping K̂ = c_k K + c_m M (c_k = 1 + β a1, c_m = a0 + α a1), so the right-hand side
    M x + K z of :class:`NewmarkConstants` gives K̂⁻¹ (M x + K z) = K̂⁻¹ M (x - (c_m / c_k) z) + z / c_k:
    no product with K. The next step's u_known is then K̂⁻¹ M e + y with e = e1 u + e2 v + e3 a and
    y = g1 u + g2 v + g3 a.

    Attributes
    ----------
    e1, e2, e3, g1, g2, g3 : float
        As above.
    a0, a1, a2, a3, a4, a5 : float
        :class:`NewmarkConstants`'.
    contact_stiffness : float
        k_h, N/m.
    rayleigh_beta : float
        β, s.
    mass_factor : float
        c_m, 1/s².
    inverse_stiffness_factor : float
        1 / c_k.
    """

    e1: float
    e2: float
    e3: float
    g1: float
    g2: float
    g3: float
    a0: float
    a1: float
    a2: float
    a3: float
    a4: float
    a5: float
    contact_stiffness: float
    rayleigh_beta: float
    mass_factor: float
    inverse_stiffness_factor: float

    @classmethod
    def for_step(
        cls, nm: NewmarkConstants, alpha: float, beta: float, contact_stiffness: float
    ) -> StepCoefficients:
        """For Rayleigh damping C = ``alpha`` M + ``beta`` K and the contact stiffness (N/m)."""
        c_k, c_m = 1.0 + beta * nm.a1, nm.a0 + alpha * nm.a1
        x = (nm.a0 + alpha * nm.a1, nm.a2 + alpha * nm.a4, nm.a3 + alpha * nm.a5)  # M's part
        z = (beta * nm.a1, beta * nm.a4, beta * nm.a5)  # K's part
        e = [xi - (c_m / c_k) * zi for xi, zi in zip(x, z, strict=True)]
        g = [zi / c_k for zi in z]
        newmark = (nm.a0, nm.a1, nm.a2, nm.a3, nm.a4, nm.a5)
        return cls(*e, *g, *newmark, contact_stiffness, beta, c_m, 1.0 / c_k)


@compilable(fastmath={"contract"}, inline="always")  # inlined into the loops (docs/performance.md, 'Speed')
def advance(u, v, acc, x, y, b, cf):  # noqa: ANN001, ANN201 - compilable
    """Newmark update to u₁ = b + y (n,), then the next step's x = e1 u + e2 v + e3 a and y = g1 u + g2 v
    + g3 a (:class:`StepCoefficients` ``cf``), in place: the compiled loops' update."""
    for i in range(u.size):
        u_new = b[i] + y[i]
        du = u_new - u[i]
        acc_new = cf.a0 * du - cf.a2 * v[i] - cf.a3 * acc[i]
        v_new = cf.a1 * du - cf.a4 * v[i] - cf.a5 * acc[i]
        u[i] = u_new
        v[i] = v_new
        acc[i] = acc_new
        x[i] = cf.e1 * u_new + cf.e2 * v_new + cf.e3 * acc_new
        y[i] = cf.g1 * u_new + cf.g2 * v_new + cf.g3 * acc_new


class PantographTrace(NamedTuple):
    """One pantograph's histories in a passage (see :class:`Trajectory`): position (m), raw contact force
    (N), head height and contact-wire uplift under it (m), each (n,)."""

    position: np.ndarray
    contact_force: np.ndarray
    head_height: np.ndarray
    wire_uplift: np.ndarray


@dataclass(frozen=True)
class Trajectory:
    """Time histories of a pantograph passage; with several pantographs, the single fields are the first
    (leading) pantograph's and :attr:`pantographs` has each one's.

    Attributes
    ----------
    time : ndarray (n,)
        s.
    position : ndarray (n,)
        Pantograph position along the track, m.
    contact_force : ndarray (n,)
        Raw contact force, N (zero when contact is lost).
    head_height : ndarray (n,)
        Pantograph head height above the nominal contact-wire height, m.
    wire_uplift : ndarray (n,)
        Dynamic uplift of the contact wire at the pantograph, m.
    support_x : ndarray (s,)
        Support positions, m.
    support_uplift : ndarray (n, s)
        Dynamic uplift of the contact wire at each support, m.
    dropper_force_min, dropper_force_max : ndarray (D,)
        Extremes of each dropper's force over the passage, N (zero while slack).
    slack_steps : int
        Time steps with at least one slack dropper.
    unresolved_steps : int
        Time steps whose contact / slack state did not settle within the iteration limit.
    pantographs : tuple of PantographTrace
        Every pantograph's histories, the leading one first (docs/model.md, 'Several pantographs').
    """

    time: np.ndarray
    position: np.ndarray
    contact_force: np.ndarray
    head_height: np.ndarray
    wire_uplift: np.ndarray
    support_x: np.ndarray
    support_uplift: np.ndarray
    dropper_force_min: np.ndarray
    dropper_force_max: np.ndarray
    slack_steps: int
    unresolved_steps: int
    pantographs: tuple[PantographTrace, ...] = ()

    def of_pantograph(self, index: int) -> Trajectory:
        """The passage as pantograph ``index`` saw it: its histories in the single fields."""
        trace = self.pantographs[index]
        return replace(
            self,
            position=trace.position,
            contact_force=trace.contact_force,
            head_height=trace.head_height,
            wire_uplift=trace.wire_uplift,
        )


def passage_positions(
    section_length: float, speed: float, dt: float, start: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and pantograph positions (m) of a passage from ``start`` to the section's end."""
    n = int(np.floor((section_length - start) / (speed * dt) + 1e-9)) + 1
    time = np.arange(n) * dt
    return time, start + speed * time
