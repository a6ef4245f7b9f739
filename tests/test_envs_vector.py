"""``gymnasium.make_vec`` on the design envs: same-step autoreset, so that no step is spent on a reset."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from gymnasium.vector import AsyncVectorEnv, AutoresetMode, SyncVectorEnv  # noqa: E402

from catenary_env.envs import BUILTIN_PROBLEMS, register_envs  # noqa: E402
from catenary_env.problems import PROBLEMS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FAST = {"fidelity": "test", "n_spans": 3}


def test_the_builtin_names_are_the_problems():
    assert list(BUILTIN_PROBLEMS) == list(PROBLEMS)


def test_make_vec_resets_in_the_same_step_and_simulates_at_every_step():
    register_envs()
    envs = gym.make_vec("Catenary-B1-v0", 2, **FAST)
    try:
        assert isinstance(envs, SyncVectorEnv)
        assert envs.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
        observation, _ = envs.reset(seed=0)
        for step in range(2):
            actions = np.full((2, 5), -0.5 + 0.5 * step, dtype=np.float32)
            actions[1, 0] = 0.25  # two designs per step
            after, reward, terminated, truncated, info = envs.step(actions)
            assert terminated.all() and not truncated.any()
            assert np.all(np.isfinite(reward)) and np.all(reward < 0.0)
            assert "final_obs" in info  # the episode's end, reset within the step
            np.testing.assert_array_equal(after, observation)  # one speed: the reset observation
        # Next-step autoreset would have spent the second step on resets: here each env simulated twice.
        assert envs.get_attr("evaluation_count") == (2, 2)
    finally:
        envs.close()


def test_make_vec_passes_the_envs_arguments_and_can_run_envs_in_processes():
    register_envs()
    envs = gym.make_vec("Catenary-SW2-v0", 2, speed_kmh=250.0, asynchronous=True, **FAST)
    try:
        assert isinstance(envs, AsyncVectorEnv)
        assert envs.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
        assert envs.get_attr("fidelity")[0].n_spans == 3
    finally:
        envs.close()
    with pytest.raises(ValueError, match="num_envs"):
        gym.make_vec("Catenary-B1-v0", 0, **FAST)


def test_make_vec_in_the_other_modes_is_gymnasiums_own():
    register_envs()
    envs = gym.make_vec("Catenary-B1-v0", 2, vectorization_mode="sync", **FAST)
    try:
        assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP  # Gymnasium's default, asked for
    finally:
        envs.close()


@pytest.mark.parametrize(
    "code",
    [
        "import catenary_env.envs",
        "import catenary_env; import gymnasium",
        "import gymnasium; import catenary_env",
        "import catenary_env; import gymnasium.envs.registration",
    ],
)
def test_the_envs_are_registered_whatever_the_import_order(code):
    check = (
        f"{code}; import gymnasium; print(sorted(k for k in gymnasium.registry if k.startswith('Catenary')))"
    )
    out = subprocess.run([sys.executable, "-c", check], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == str(sorted(f"Catenary-{name}-v0" for name in BUILTIN_PROBLEMS))


def test_importing_the_package_imports_neither_gymnasium_nor_the_simulator():
    loaded = "sorted(m for m in ('gymnasium', 'numpy', 'scipy') if m in sys.modules)"
    code = f"import sys, catenary_env; print({loaded})"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"
