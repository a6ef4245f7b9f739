"""The lumped-mass pantograph: a chain of masses, springs and dampers from the roof to the head.

Coordinates y are the masses' heights above the contact wire's nominal height at the supports
(``catenary.contact_wire_height``), and the passages relax the bottom (frame) spring there. The static
uplift force F₀ is, by default, the static contact force (``uplift_definition = "static-contact"``;
docs/model.md, 'Modelling choices'): :func:`frame_force` gives the force on the frame that relaxes the
frame spring where the pantograph stands at static equilibrium on the wire, so that the static contact
force averaged over a span is F₀. With ``"nominal-height"`` F₀ itself acts on the frame, and the frame
spring takes part of it as the pantograph rises. The masses' own weight is carried by the static uplift
force, as in EN 50318's reference model, and does not appear.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..fem.track_order import compliances
from ..model.definition import PantographDefinition
from .linear_system import LinearSystem


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


STATIC_POINTS = 24
"""Equally spaced pantograph positions over a span at which the static contact force is averaged."""


def frame_force(system: LinearSystem, pantograph: PantographDefinition, uplift_force: float) -> float:
    """The force on the frame (N), spring relaxed at the nominal height, that realises ``uplift_force`` (N).

    With ``uplift_definition = "nominal-height"`` that is ``uplift_force`` itself. With ``"static-contact"``
    it is the force for which the static contact force, averaged over the positions of the central span,
    equals ``uplift_force``: the frame spring is then relaxed at the frame's mean static height y_r, and
    F₀ + k₀ y_r is applied. At position x the static contact force is

        f(x) = (F - k₀ z₀(x)) / (1 + k₀ s(x)),    s(x) = c(x) + 1/k_h + Σ_{i>0} 1/k_i,

    with F the force on the frame, z₀ the static contact-wire height above nominal, c the catenary's static
    compliance under the pantograph (every dropper taut) and k_i the chain's upper springs; F follows from
    mean f = ``uplift_force``.
    """
    options = system.static.layout.catenary.modelling
    k0 = pantograph.stiffnesses[0]
    if options.uplift_definition == "nominal-height" or k0 == 0.0:
        return uplift_force
    lay = system.static.layout
    span = lay.n_spans // 2
    x = lay.span_length * (span + np.arange(STATIC_POINTS) / STATIC_POINTS)
    element, shape, height = system.contact_wire.locate(x)
    dofs = system.contact_wire.z_dofs[element]  # (P, 4): the contact wire's vertical coordinates are free
    compliance = compliances(system.stiffness, dofs, shape)
    series = (
        compliance + 1.0 / lay.catenary.contact_stiffness + sum(1.0 / k for k in pantograph.stiffnesses[1:])
    )
    z0 = height - lay.catenary.contact_wire_height
    share = 1.0 / (1.0 + k0 * series)
    return float((uplift_force + k0 * np.mean(z0 * share)) / np.mean(share))
