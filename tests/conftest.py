"""Shared fixtures: short sections and coarse meshes, so that the physics tests stay fast.

Tests of an optional extra skip where it is not installed (:func:`requires`, ``pytest.importorskip``), so
that ``pip install -e . pytest`` runs the core.
"""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from catenary_env.blas_threads import limit_process
from catenary_env.model.design import level_design
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.pipeline import Fidelity, solve_static
from catenary_env.statics.shape_finding import StaticSolution

# No uplift calibration is read from or written to the user's disk cache: tests that replace the simulator
# must not leave their fake forces there (tests/test_calibration_cache.py sets a folder of its own).
os.environ["CATENARY_ENV_CACHE"] = "off"
# The tests run on one BLAS thread, as evaluations do (docs/performance.md, 'Threads'): tests that call the
# dynamics below the pipeline compare contact forces with recorded ones to 1e-9 N, and a BLAS reduction
# split over two threads adds in another order (the span modes then differ by some 1e-7 N).
limit_process()


def requires(module: str) -> pytest.MarkDecorator:
    """Skip a test, or a parameter, where the optional dependency ``module`` is not installed."""
    missing = importlib.util.find_spec(module) is None
    return pytest.mark.skipif(missing, reason=f"needs {module} (an optional extra)")


SHORT = Fidelity(
    n_spans=5, analysis_spans=1, contact_wire_element=1.0, messenger_wire_element=2.0, time_step=2e-3
)


@pytest.fixture(scope="session")
def benchmark_catenary():
    return load_catenary("benchmark")


@pytest.fixture(scope="session")
def stitched_catenary():
    return load_catenary("stitched")


@pytest.fixture(scope="session")
def benchmark_pantograph_definition():
    return load_pantograph("benchmark")


@pytest.fixture(scope="session")
def benchmark_static(benchmark_catenary) -> StaticSolution:
    return solve_static(benchmark_catenary, level_design(benchmark_catenary), SHORT)


@pytest.fixture(scope="session")
def stitched_static(stitched_catenary) -> StaticSolution:
    return solve_static(stitched_catenary, level_design(stitched_catenary), SHORT)


RECORDED_PASSAGES = Path(__file__).parent / "data" / "recorded_passages.npz"
"""Contact forces (N), slack steps and σ (N) of a few passages, recorded before the passage protocol
(commit 1d5cdd7): a refactoring of the time loops must reproduce them (:func:`assert_recorded`)."""

RECORDED_TOLERANCE = 1e-5
"""N: the same code's rounding across processors. Recorded on one machine; on another, with OpenBLAS's
kernels forced to three processor types (Haswell, Sandybridge, Nehalem), the passages differ from the record
by up to 5e-8 N (the exact model), 1.7e-7 N (the span-mode loop) and 2.1e-6 N (the span-mode passage of the
pipeline, whose contact losses amplify rounding), with the same slack steps (2026-12-02; the compiled loop
of one commit against another's on one machine: 7.5e-10 N). A change of the physics moves them by far more
(docs/model.md, 'Results and the model that made them')."""


@pytest.fixture(scope="session")
def recorded_passages() -> dict[str, np.ndarray]:
    with np.load(RECORDED_PASSAGES) as data:
        return dict(data)


def assert_recorded(
    recorded: dict[str, np.ndarray], case: str, trajectory, sigma: float | None = None
) -> None:
    """``trajectory`` (and its σ, N) equal the recorded ``case`` to :data:`RECORDED_TOLERANCE`."""
    force = recorded[f"{case}/contact_force"]
    assert trajectory.contact_force.shape == force.shape, case
    assert np.max(np.abs(trajectory.contact_force - force)) < RECORDED_TOLERANCE, case
    assert trajectory.slack_steps == int(recorded[f"{case}/slack_steps"]), case
    if sigma is not None:
        assert sigma == pytest.approx(float(recorded[f"{case}/sigma"]), rel=0.0, abs=RECORDED_TOLERANCE), case


_HOLDER = """
import json, sys
from optimizers.store import RunConfig, RunStore
with RunStore(sys.argv[1]) as store, store.claim(RunConfig(*json.loads(sys.argv[2]))) as held:
    print(held, flush=True)
    sys.stdin.read()
"""


@pytest.fixture
def claimed_elsewhere():
    """``claimed_elsewhere(store_path, config)``: a context in which another process holds the run of
    ``config`` in the store (:meth:`optimizers.store.RunStore.claim`), released on leaving it."""

    @contextlib.contextmanager
    def hold(store_path, config):
        holder = subprocess.Popen(
            [sys.executable, "-c", _HOLDER, str(store_path), json.dumps(list(config))],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=Path(__file__).resolve().parents[1],
        )
        try:
            assert holder.stdout.readline().strip() == "True"
            yield
        finally:
            holder.communicate("")

    return hold


def horizontal_tension(static: StaticSolution) -> np.ndarray:
    """Horizontal component of the force each cable element carries, N (x-force at its far node)."""
    from catenary_env.fem.ancf import cable_state

    lay = static.layout
    n_c = lay.cable_nodes.shape[0]
    q = static.positions[lay.cable_dofs()]
    state = cable_state(
        q, static.lengths[:n_c], lay.cable_axial_stiffness, lay.cable_bending_stiffness, False
    )
    return state.force[:, 4]
