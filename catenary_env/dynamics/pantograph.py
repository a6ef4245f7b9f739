"""The lumped-mass pantograph: a chain of masses, springs and dampers from the roof to the head.

Coordinates y are the masses' heights above the contact wire's nominal height at the supports
(``catenary.contact_wire_height``), where the bottom (frame) spring is relaxed: as the pantograph rises, that
spring takes part of the uplift force, so the mean contact force is the uplift less k₀ times the mean frame
height (docs/model.md, 'Pantograph and contact'). The masses' own weight is carried by the static uplift
force, as in EN 50318's reference model, and does not appear.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..model.definition import PantographDefinition


class PantographMatrices(NamedTuple):
    """Mass (kg), damping (N·s/m) and stiffness (N/m) of the chain; the head is the last coordinate."""

    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray

    @property
    def head(self) -> int:
        return self.mass.shape[0] - 1


def pantograph_matrices(pantograph: PantographDefinition) -> PantographMatrices:
    """Matrices of the chain: spring and damper ``i`` join mass ``i`` to mass ``i - 1`` (0 to the ground)."""
    n = len(pantograph.masses)
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    for i, (k, c) in enumerate(zip(pantograph.stiffnesses, pantograph.dampings, strict=True)):
        e = np.zeros(n)
        e[i] = 1.0
        if i > 0:
            e[i - 1] = -1.0
        K += k * np.outer(e, e)
        C += c * np.outer(e, e)
    return PantographMatrices(np.diag(pantograph.masses), C, K)


def static_contact(
    matrices: PantographMatrices, uplift_force: float, contact_stiffness: float, wire_height: float
) -> tuple[np.ndarray, float]:
    """Static pantograph pressed against a rigid wire at ``wire_height`` (m above nominal).

    Returns the coordinates y (m) and the contact force (N).
    """
    n = matrices.mass.shape[0]
    h = matrices.head
    A = matrices.stiffness.copy()
    A[h, h] += contact_stiffness
    rhs = np.zeros(n)
    rhs[0] = uplift_force
    rhs[h] += contact_stiffness * wire_height
    y = np.linalg.solve(A, rhs)
    return y, contact_stiffness * (y[h] - wire_height)
