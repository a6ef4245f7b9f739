"""Dynamics (docs/model.md, 'Time integration and the fast method'): the fast method against the oracle, and
closed forms."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from catenary_env.dynamics import exact
from catenary_env.dynamics.linear_system import linearise
from catenary_env.dynamics.newmark import NewmarkConstants
from catenary_env.dynamics.protocol import Passage
from catenary_env.fem.layout import CONTACT, build_layout
from catenary_env.model.design import Design, level_design
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.pipeline import Fidelity
from catenary_env.statics.shape_finding import find_shape


def test_fast_method_equals_the_straightforward_method_with_contact_loss_and_slack_droppers():
    catenary = load_catenary("en50318-2002")
    pantograph = load_pantograph("en50318-2002")
    system = linearise(find_shape(build_layout(catenary, level_design(catenary), 3, 2.0, 4.0)))
    # A high uplift at 350 km/h: droppers go slack under the pantograph and the head leaves the wire.
    speed, dt, uplift, steps = 350 / 3.6, 2e-3, 200.0, 520
    prepared = exact.prepare(system, Fidelity(time_step=dt))
    oracle = exact.run(
        prepared, Passage.one_pantograph(pantograph, uplift, speed, n_steps=steps, backend="oracle")
    )
    fast = exact.run(prepared, Passage.one_pantograph(pantograph, uplift, speed, n_steps=steps))
    assert oracle.slack_steps > 50
    assert np.sum(oracle.contact_force == 0.0) >= 1
    assert oracle.unresolved_steps == 0 and fast.unresolved_steps == 0
    assert np.max(np.abs(fast.contact_force - oracle.contact_force)) < 1e-6
    assert np.max(np.abs(fast.support_uplift - oracle.support_uplift)) < 1e-9
    assert np.max(np.abs(fast.head_height - oracle.head_height)) < 1e-9
    assert np.allclose(fast.dropper_force_min, oracle.dropper_force_min, atol=1e-6)


def test_newmark_converges_at_second_order_on_a_linear_oscillator():
    mass, stiffness, damping = 2.0, 800.0, 1.5
    omega = np.sqrt(stiffness / mass)
    zeta = damping / (2 * np.sqrt(stiffness * mass))
    omega_d = omega * np.sqrt(1 - zeta**2)

    def exact(t):
        return np.exp(-zeta * omega * t) * (
            np.cos(omega_d * t) + zeta * omega / omega_d * np.sin(omega_d * t)
        )

    errors = []
    for dt in (4e-3, 2e-3, 1e-3, 5e-4):
        nm = NewmarkConstants.for_step(dt)
        k_hat = stiffness + nm.a1 * damping + nm.a0 * mass
        u, v, a = 1.0, 0.0, -stiffness / mass
        for _ in range(round(1.0 / dt)):
            rhs = mass * (nm.a0 * u + nm.a2 * v + nm.a3 * a) + damping * (nm.a1 * u + nm.a4 * v + nm.a5 * a)
            u_new = rhs / k_hat
            v, a = nm.update(np.array(u), np.array(v), np.array(a), np.array(u_new))
            u = u_new
        errors.append(abs(u - exact(1.0)))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - 2.0) < 0.1), rates


def _string(monkeypatch, span: float, support_stiffness: float, element: float):
    """A contact wire alone between two supports, with gravity off so that it is straight."""
    monkeypatch.setattr("catenary_env.fem.assembly.GRAVITY", 0.0)
    base = load_catenary("benchmark")
    catenary = dataclasses.replace(
        base,
        span_length=span,
        dropper_positions=(0.5 * span,),
        supports=dataclasses.replace(
            base.supports, steady_arm_stiffness=support_stiffness, steady_arm_mass=0.0
        ),
        damping=dataclasses.replace(base.damping, alpha=0.0, beta=0.0),
    )
    system = linearise(find_shape(build_layout(catenary, Design((), ()), 1, element, 4 * element)))
    return catenary, system


def test_a_force_moving_along_a_taut_string_lifts_it_as_the_wave_solution(monkeypatch):
    # String: T u_xx - rho u_tt = -P δ(x - x0 - v t). From rest, d'Alembert gives the displacement under
    # the load u = P t / (2 sqrt(T rho)) for any v < c, and a point ahead stays still until the front,
    # moving at c = sqrt(T / rho), reaches it.
    catenary, system = _string(monkeypatch, 200.0, 2673.58, 0.25)
    wire = catenary.contact_wire
    c = wire.wave_speed
    force, speed, start, dt = 100.0, 40.0, 60.0, 2.5e-4
    nm = NewmarkConstants.for_step(dt)
    M, K = system.mass.tocsc(), system.stiffness.tocsc()
    solver = spla.splu((K + nm.a0 * M).tocsc())
    n = system.n_dofs
    u, v, a = np.zeros(n), np.zeros(n), np.zeros(n)
    probe_x = start + 30.0
    _, probe_h, _ = system.contact_wire.locate(np.array([probe_x]))
    probe_dofs = system.contact_wire.z_dofs[system.contact_wire.locate(np.array([probe_x]))[0][0]]
    times = np.arange(1, round(0.3 / dt) + 1) * dt
    under, probe = [], []
    for t in times:
        e, h, _ = system.contact_wire.locate(np.array([start + speed * t]))
        zd = system.contact_wire.z_dofs[e[0]]
        rhs = M @ (nm.a0 * u + nm.a2 * v + nm.a3 * a)
        rhs[zd] += h[0] * force
        u_new = solver.solve(rhs)
        v, a = nm.update(u, v, a, u_new)
        u = u_new
        under.append(h[0] @ u[zd])
        probe.append(probe_h[0] @ u[probe_dofs])
    under, probe = np.array(under), np.array(probe)
    rate = force / (2.0 * np.sqrt(wire.tension * wire.linear_mass))
    late = times > 0.05
    slope, offset = np.polyfit(times[late], under[late], 1)
    assert slope == pytest.approx(rate, rel=5e-3)
    # The wire's bending stiffness rounds the kink under the load over sqrt(EI / T) ≈ 0.1 m, which
    # lowers the string's deflection by about P sqrt(EI / T) / (2 T): a constant offset, not a rate.
    bending_offset = force * np.sqrt(wire.bending_stiffness / wire.tension) / (2.0 * wire.tension)
    assert -2.0 * bending_offset < offset < 0.0
    # Ahead of the load, d'Alembert gives u(x, t) = P (c t - d) / (2 rho c (c - v)) once the front,
    # travelling at c from the load's start d behind, has arrived at t = d / c: fit that line.
    moving = probe > 0.2 * probe.max()
    slope, intercept = np.polyfit(times[moving], probe[moving], 1)
    assert -intercept / slope == pytest.approx(30.0 / c, rel=1e-2)
    assert slope == pytest.approx(force / (2.0 * wire.linear_mass * (c - speed)), rel=1e-2)


def test_natural_frequencies_of_a_tensioned_beam(monkeypatch):
    # Pinned-pinned beam under tension: f_n = n c / (2 L) sqrt(1 + (n π)² EI / (T L²)).
    span = 40.0
    catenary, system = _string(monkeypatch, span, 1e12, 0.5)
    wire = catenary.contact_wire
    lay = system.static.layout
    cw = np.isin(
        system.free,
        np.r_[[lay.node_dof[i] + k for i in np.flatnonzero(lay.node_kind == CONTACT) for k in (1, 3)]],
    )
    M = system.mass.toarray()[np.ix_(cw, cw)]
    K = system.stiffness.toarray()[np.ix_(cw, cw)]
    omega2 = sla.eigh(K, M, eigvals_only=True, subset_by_index=[0, 5])
    frequencies = np.sqrt(omega2) / (2 * np.pi)
    n = np.arange(1, 7)
    exact = (
        n
        * wire.wave_speed
        / (2 * span)
        * np.sqrt(1 + (n * np.pi) ** 2 * wire.bending_stiffness / (wire.tension * span**2))
    )
    assert np.allclose(frequencies, exact, rtol=1e-3), (frequencies, exact)
