"""The time-step study's exact modal integration (experiments/time_step.py; docs/performance.md, 'Speed'):
the first-order hold against closed-form responses, and the passage against the project's Newmark
integration of the same linear catenary as both steps shrink."""

from __future__ import annotations

import numpy as np
import pytest

from catenary_env.analysis.statistics import filtered_contact_force, passage_statistics
from catenary_env.dynamics.exact import prepare, run
from catenary_env.dynamics.linear_system import linearise
from catenary_env.dynamics.pantograph import frame_force
from catenary_env.dynamics.protocol import ContactPoint, Passage
from catenary_env.model.design import level_design
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.pipeline import Fidelity, analysis_window, solve_static
from experiments.time_step import Modes, first_order_hold, modal_passage


def _oscillator(omega: float, zeta: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    a = np.array([[0.0, 1.0], [-(omega**2), -2.0 * zeta * omega]])
    return a, np.array([[0.0], [1.0]])


@pytest.mark.parametrize("omega", [3.0, 300.0, 3.0e4])
def test_first_order_hold_is_the_closed_form_response_of_an_undamped_oscillator(omega):
    dt = 2e-3
    F, G0, G1 = first_order_hold(*_oscillator(omega), dt)
    c, s = np.cos(omega * dt), np.sin(omega * dt)
    np.testing.assert_allclose(F, [[c, s / omega], [-omega * s, c]], rtol=1e-9, atol=1e-12)
    # q̈ + ω² q = u(t) from rest: a ramp u = t / dt, and a constant u = 1.
    ramp = [(dt - s / omega) / (omega**2 * dt), (1.0 - c) / (omega**2 * dt)]
    step = [(1.0 - c) / omega**2, s / omega]
    np.testing.assert_allclose(G1[:, 0], ramp, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(G0[:, 0] + G1[:, 0], step, rtol=1e-9, atol=1e-15)


def test_first_order_hold_keeps_a_damped_mode_at_rest_under_its_static_load():
    """A constant force ω² q on a mode at rest at q: no motion, for any step and damping (batched)."""
    omega = np.array([1.0, 50.0, 2e3, 1e5])
    a = np.stack([_oscillator(w, z)[0] for w, z in zip(omega, [0.01, 0.5, 1.0, 40.0], strict=True)])
    b = np.broadcast_to(np.array([[0.0], [1.0]]), (4, 2, 1))
    F, G0, G1 = first_order_hold(a, b, 1e-3)
    x1 = F[:, :, 0] + omega[:, None] ** 2 * (G0[:, :, 0] + G1[:, :, 0])
    np.testing.assert_allclose(x1, np.column_stack([np.ones(4), np.zeros(4)]), atol=1e-9)


def test_modal_passage_and_newmark_converge_to_one_answer():
    """Two independent integrations of the same catenary and pantograph: σ within 0.1 % as the steps shrink,
    and the modal one closer at 1 ms than at 2 ms."""
    catenary = load_catenary("benchmark")
    pantograph = load_pantograph(catenary.pantograph)
    fidelity = Fidelity(n_spans=4, analysis_spans=1, dynamics="exact")
    system = linearise(solve_static(catenary, level_design(catenary), fidelity))
    window = analysis_window(catenary, fidelity)
    passage = Passage(300 / 3.6, (ContactPoint(pantograph, frame_force(system, pantograph, 170.4)),))

    def sigma(trajectory):  # noqa: ANN001, ANN202
        return passage_statistics(trajectory, window, filtered_contact_force(trajectory)).std

    newmark = sigma(run(prepare(system, Fidelity(time_step=2.5e-4, dynamics="exact")), passage))
    modes = Modes.of(system)
    modal = {dt: sigma(modal_passage(system, modes, dt, passage)) for dt in (2e-3, 1e-3, 5e-4)}
    assert modal[5e-4] == pytest.approx(newmark, rel=1e-3)
    assert abs(modal[1e-3] - newmark) < abs(modal[2e-3] - newmark)
