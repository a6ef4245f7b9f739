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


def run_steps(  # noqa: C901
    prepared: PreparedExact, points: tuple[ContactPointArrays, ...], s: ExactState, first: int, stop: int
) -> None:
    """Steps ``first`` to ``stop - 1`` of the passage, updating the ExactState ``s`` in place."""
    system, nm, cf = prepared.system, prepared.constants, prepared.coefficients
    M, K, B = system.mass, system.stiffness, system.dropper_elongation
    W, G = prepared.dropper_response, prepared.dropper_flexibility
    n_c = len(points)
    heads = [point.y_star.size - 1 for point in points]
    c1, c2, c3 = cf.a0 + system.alpha * cf.a1, cf.a2 + system.alpha * cf.a4, cf.a3 + system.alpha * cf.a5
    d1, d2, d3 = cf.rayleigh_beta * cf.a1, cf.rayleigh_beta * cf.a4, cf.rayleigh_beta * cf.a5
    contact = np.array([bool(ps.contact[0]) for ps in s.pantographs])
    slack = s.slack.copy()
    current = [-1] * n_c
    responses: list = [None] * n_c
    for k in range(first, stop):
        u, v, a = s.u, s.v, s.a
        u_known = prepared.factor.solve(M @ (c1 * u + c2 * v + c3 * a) + K @ (d1 * u + d2 * v + d3 * a))
        on = [i for i, point in enumerate(points) if point.element[k] >= 0]
        for i in on:
            if points[i].element[k] != current[i]:
                current[i] = points[i].element[k]
                responses[i] = _element_responses(prepared, current[i])
        gap_known = np.full(n_c, -1.0)  # a point off the section stays out of contact
        c_cc = np.eye(n_c)
        g_dc = np.zeros((n_c, B.shape[0]))
        y_known = [None] * n_c
        for i in on:
            point, h = points[i], points[i].shape[k]
            zd, P, Pzz, Wz = responses[i]
            c_cc[i, i] = h @ Pzz @ h + point.y_star[heads[i]]
            for j in on:
                if j != i:
                    c_cc[i, j] = h @ responses[j][1][zd] @ points[j].shape[k]
            g_dc[i] = Wz.T @ h
            y_known[i] = known_response(point, cf, s.pantographs[i])
            gap_known[i] = float(y_known[i][heads[i]] - point.wire_z[k] - h @ u_known[zd])
        rate_term = cf.rayleigh_beta * prepared.droppers.rate * (B @ (cf.a1 * u + cf.a4 * v + cf.a5 * a))
        step = settle(
            contact, slack, gap_known, c_cc, g_dc, B @ u_known, rate_term, cf.contact_stiffness,
            prepared.droppers, G,
        )  # fmt: skip
        contact, slack, f, idx, lam, elastic = step[:6]
        u_new = u_known
        for i in on:
            u_new = u_new + (responses[i][1] @ points[i].shape[k]) * f[i]
        u_new = u_new + W[:, idx] @ lam
        v_new, a_new = nm.update(u, v, a, u_new)
        s.u[:], s.v[:], s.a[:] = u_new, v_new, a_new
        uplift = np.zeros(n_c)
        for i in on:
            advance_pantograph(points[i], cf, s.pantographs[i], y_known[i], f[i])
            uplift[i] = points[i].shape[k] @ s.u[responses[i][0]]
        heights = np.array([ps.y[head] for ps, head in zip(s.pantographs, heads, strict=True)])
        record(
            s.history, k, f, heights, uplift, s.u[system.support_z], elastic, slack, idx.size > 0,
            step.resolved,
        )  # fmt: skip
    for ps, touching in zip(s.pantographs, contact, strict=True):
        ps.contact[0] = int(touching)
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
