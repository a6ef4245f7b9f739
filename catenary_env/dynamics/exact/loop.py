"""The exact model's time loop in numpy: the compiled loop's steps
(:mod:`~catenary_env.dynamics.exact.kernels`), with scipy's banded solve (docs/model.md, 'Time integration
and the fast method').

Each step solves K̂ u_known = M (c1 u + c2 v + c3 a) + K (d1 u + d2 v + d3 a) for the motion without the
step's contact and slack-dropper forces, then those forces by the active-set rules
(:func:`~catenary_env.dynamics.active_set.settle`), and superposes their unit responses. It reads the same
named records as the compiled loop: the contact point's
:class:`~catenary_env.dynamics.contact_point.ContactPointArrays`, the
:class:`~catenary_env.dynamics.newmark.StepCoefficients`, the
:class:`~catenary_env.dynamics.active_set.Droppers`, and updates an
:class:`~catenary_env.dynamics.exact.state.ExactState` (in the DOFs' own order).
"""

from __future__ import annotations

import numpy as np

from ..active_set import settle
from ..contact_point import ContactPointArrays, advance_pantograph, known_response
from ..history import record
from .preparation import PreparedExact
from .state import ExactState


def run_steps(
    prepared: PreparedExact, points: tuple[ContactPointArrays, ...], s: ExactState, first: int, stop: int
) -> None:
    """Steps ``first`` to ``stop - 1`` of the passage, updating the ExactState ``s`` in place."""
    (point,) = points
    system, nm, cf = prepared.system, prepared.constants, prepared.coefficients
    M, K, B = system.mass, system.stiffness, system.dropper_elongation
    W, G = prepared.dropper_response, prepared.dropper_flexibility
    head = point.y_star.size - 1
    c1, c2, c3 = cf.a0 + system.alpha * cf.a1, cf.a2 + system.alpha * cf.a4, cf.a3 + system.alpha * cf.a5
    d1, d2, d3 = cf.rayleigh_beta * cf.a1, cf.rayleigh_beta * cf.a4, cf.rayleigh_beta * cf.a5
    contact, slack = bool(s.pantograph.contact[0]), s.slack.copy()
    current_element = -1
    for k in range(first, stop):
        u, v, a = s.u, s.v, s.a
        u_known = prepared.factor.solve(M @ (c1 * u + c2 * v + c3 * a) + K @ (d1 * u + d2 * v + d3 * a))
        if point.element[k] != current_element:
            current_element = point.element[k]
            zd, P, Pzz, Wz = _element_responses(prepared, current_element)
        h = point.shape[k]
        c_cc = h @ Pzz @ h + point.y_star[head]
        g_dc = Wz.T @ h
        y_known = known_response(point, cf, s.pantograph)
        gap_known = float(y_known[head] - point.wire_z[k] - h @ u_known[zd])
        rate_term = cf.rayleigh_beta * prepared.droppers.rate * (B @ (cf.a1 * u + cf.a4 * v + cf.a5 * a))
        step = settle(
            contact, slack, gap_known, c_cc, g_dc, B @ u_known, rate_term, cf.contact_stiffness,
            prepared.droppers, G,
        )  # fmt: skip
        contact, slack, f, idx, lam, elastic = step[:6]
        u_new = u_known + (P @ h) * f + W[:, idx] @ lam
        v_new, a_new = nm.update(u, v, a, u_new)
        s.u[:], s.v[:], s.a[:] = u_new, v_new, a_new
        advance_pantograph(point, cf, s.pantograph, y_known, f)
        record(
            s.history, k, f, s.pantograph.y[head], h @ s.u[zd], s.u[system.support_z], elastic, slack,
            idx.size > 0, step.resolved,
        )  # fmt: skip
    s.pantograph.contact[0] = int(contact)
    s.slack[:] = slack


def _element_responses(
    prepared: PreparedExact, element: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The contact-wire element's z DOFs, the unit responses P = K̂⁻¹ E to forces there, P[zd] and W[zd]."""
    system = prepared.system
    zd = system.contact_wire.z_dofs[element]
    unit = np.zeros((system.n_dofs, 4))
    unit[zd, np.arange(4)] = 1.0
    P = prepared.factor.solve(unit)
    return zd, P, P[zd], prepared.dropper_response[zd]
