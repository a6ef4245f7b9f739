"""Mesh and time-step convergence of σ on the benchmark preset (docs/model.md, 'Verification').

A short section keeps the test quick; the 20-span table is in experiments/convergence.py.
"""

from __future__ import annotations

import pytest

from catenary_env.model.design import level_design
from catenary_env.pipeline import Fidelity, simulate


@pytest.fixture(scope="module")
def sigmas(benchmark_catenary, benchmark_pantograph_definition):
    out = []
    for element, dt in ((1.0, 2e-3), (0.5, 1e-3), (0.25, 5e-4)):
        fidelity = Fidelity(
            n_spans=5,
            analysis_spans=1,
            contact_wire_element=element,
            messenger_wire_element=2 * element,
            time_step=dt,
            dynamics="exact",  # the reference model's discretisation
        )
        sim = simulate(
            benchmark_catenary,
            benchmark_pantograph_definition,
            level_design(benchmark_catenary),
            300 / 3.6,
            fidelity,
            uplift_force=170.0,
        )
        out.append(sim.statistics.std)
    return out


def test_halving_the_study_mesh_and_step_changes_sigma_by_less_than_one_percent(sigmas):
    coarse, study, fine = sigmas
    assert abs(fine - study) < 0.01 * fine


def test_sigma_converges_as_mesh_and_step_are_refined(sigmas):
    coarse, study, fine = sigmas
    # Each halving shrinks the change at least twofold (a convergent, better than first-order sequence).
    assert abs(fine - study) < 0.5 * abs(study - coarse)
