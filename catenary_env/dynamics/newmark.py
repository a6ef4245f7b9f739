"""Newmark time integration constants and the records shared by the two dynamic solvers."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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


@dataclass(frozen=True)
class Trajectory:
    """Time histories of a pantograph passage.

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


def passage_positions(
    section_length: float, speed: float, dt: float, start: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and pantograph positions (m) of a passage from ``start`` to the section's end."""
    n = int(np.floor((section_length - start) / (speed * dt) + 1e-9)) + 1
    time = np.arange(n) * dt
    return time, start + speed * time
