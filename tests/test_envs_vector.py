"""``gymnasium.make_vec`` on the design envs: same-step autoreset, so that no step is spent on a reset."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from gymnasium.vector import AsyncVectorEnv, AutoresetMode, SyncVectorEnv  # noqa: E402

from catenary_env.envs import BUILTIN_PROBLEMS, make_vector_env, register_envs  # noqa: E402
from catenary_env.problems import PROBLEMS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FAST = {"fidelity": "test", "n_spans": 3}


def test_the_builtin_names_are_the_problems():
    assert list(BUILTIN_PROBLEMS) == list(PROBLEMS)


def _two_steps_simulate_twice(envs) -> None:
    """Two steps of a 2-env vector: each env simulates a design at both, every reward is a real −σ."""
    assert envs.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    observation, _ = envs.reset(seed=0)
    for step in range(2):
        actions = np.full((2, 5), -0.5 + 0.5 * step, dtype=np.float32)
        actions[1, 0] = 0.25  # two designs per step
        after, reward, terminated, truncated, info = envs.step(actions)
        assert terminated.all() and not truncated.any()
        assert np.all(np.isfinite(reward)) and np.all(reward < 0.0)  # next-step autoreset: 0 at step 2
        assert "final_obs" in info  # the episode's end, reset within the step
        np.testing.assert_array_equal(after, observation)  # one speed: the reset observation
    assert envs.get_attr("evaluation_count") == (2, 2)


@pytest.mark.parametrize(
    ("mode", "vector_class"), [(None, SyncVectorEnv), ("sync", SyncVectorEnv), ("async", AsyncVectorEnv)]
)
def test_make_vec_resets_in_the_same_step_in_every_mode(mode, vector_class):
    register_envs()
    envs = gym.make_vec("Catenary-B1-v0", 2, vectorization_mode=mode, **FAST)
    try:
        assert isinstance(envs, vector_class)
        _two_steps_simulate_twice(envs)
    finally:
        envs.close()


def test_make_vec_passes_the_envs_arguments():
    register_envs()
    envs = gym.make_vec("Catenary-SW2-v0", 2, vectorization_mode="async", speed_kmh=250.0, **FAST)
    try:
        assert envs.get_attr("fidelity")[0].n_spans == 3
        _, info = envs.reset(seed=0)
        np.testing.assert_array_equal(info["speed_kmh"], [250.0, 250.0])
    finally:
        envs.close()


def test_make_vector_env_is_make_vec_with_more_vector_options():
    register_envs()
    envs = make_vector_env(2, problem="B1", asynchronous=True, vector_kwargs={"shared_memory": False}, **FAST)
    try:
        assert isinstance(envs, AsyncVectorEnv) and envs.shared_memory is False
        _two_steps_simulate_twice(envs)
    finally:
        envs.close()
    with pytest.raises(ValueError, match="num_envs"):
        make_vector_env(0, problem="B1", **FAST)


def test_a_single_env_refuses_other_vector_options():
    register_envs()
    gym.make("Catenary-B1-v0", **FAST).close()  # the registered vector_kwargs pass
    with pytest.raises(ValueError, match="vector_kwargs.*gymnasium.make_vec"):
        gym.make("Catenary-B1-v0", vector_kwargs={"autoreset_mode": "NextStep"}, **FAST)


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
