"""The Gymnasium environments (docs/problems.md, 'Environments').

Two groups. Tests of the environment's mechanics (spaces, the action mapping, clipping, bad actions,
seeding, rewards, vector envs and how many simulations they run) replace the simulator with a fast,
deterministic fake (``fake_simulator``), so that they test the env and not the physics. The API checkers
(Gymnasium's and stable-baselines3's), the reference σ and a vector env run the real simulator.
Every env uses the test fidelity (5 spans, coarse mesh).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium", reason="the environments need gymnasium: pip install -e .[gym]")

import catenary_env.envs  # noqa: E402
from catenary_env import pipeline  # noqa: E402
from catenary_env.analysis.statistics import ContactStatistics  # noqa: E402
from catenary_env.envs import CatenaryDesignEnv, env_ids, register_envs  # noqa: E402
from catenary_env.envs.design_env import INFEASIBLE_SIGMA_OVER_MEAN  # noqa: E402
from catenary_env.model.design import Design, level_design  # noqa: E402
from catenary_env.pipeline import Evaluation, en50367_mean_force  # noqa: E402
from catenary_env.problems import PROBLEMS, clear_caches, resolve_fidelity  # noqa: E402

register_envs()

FAST = {"fidelity": "test", "n_spans": 5}
"""Keyword arguments of every env made here: the short, coarse model."""

IDS = env_ids()


# ---------------------------------------------------------------------------------------------------------
# A fake simulator for the mechanics tests


@dataclass
class FakeSimulator:
    """Deterministic stand-in: σ grows with |Δh| and uneven dropper spacing; deep sag loses contact."""

    calls: list[tuple[Design, float]] = field(default_factory=list)
    calibrations: int = 0
    batches: list[int] = field(default_factory=list)  # the evaluations of each call at several speeds

    def evaluate(
        self, catenary, pantograph, design, speed, fidelity, uplift_force=None, *options, train=None
    ):  # type: ignore[no-untyped-def]
        self.calls.append((design, speed))
        offsets = np.asarray(design.contact_wire_offsets)
        spacing = np.diff(np.concatenate([[0.0], design.dropper_positions, [catenary.span_length]]))
        sigma = 20.0 + 2e4 * float(np.mean(offsets**2)) + 0.5 * float(np.std(spacing)) + 0.05 * speed
        mean = float(uplift_force) - 4.0
        lost = float(np.mean(offsets)) < -0.015
        statistics = ContactStatistics(
            mean,
            sigma,
            sigma / mean,
            mean + 3 * sigma,
            mean - 3 * sigma,
            mean + 2 * sigma,
            mean - 2 * sigma,
            1.5 if lost else 0.0,
            0.05,
        )
        return Evaluation(
            not lost,
            "dynamic: contact lost" if lost else "",
            statistics,
            (1.0,) * design.n_droppers,
            (150.0,) * design.n_droppers,
            float(uplift_force),
            0.25,
        )

    def evaluate_speeds(self, catenary, pantograph, design, passages, fidelity, *options, train=None):  # type: ignore[no-untyped-def]
        out = []
        for speed, force in passages:
            out.append(self.evaluate(catenary, pantograph, design, speed, fidelity, force))
            if not out[-1].feasible:
                break
        self.batches.append(len(out))
        return out

    def calibrate_uplift(self, catenary, pantograph, design, speed, fidelity, target_mean):  # type: ignore[no-untyped-def]
        self.calibrations += 1
        return target_mean + 4.0


@pytest.fixture
def fake_simulator(monkeypatch: pytest.MonkeyPatch) -> Iterator[FakeSimulator]:
    # Calibrations are cached per process: keep the real ones out of a fake test and the fake ones out of
    # the real tests (which share theirs, as a process would).
    fake = FakeSimulator()
    clear_caches()
    monkeypatch.setattr(pipeline, "evaluate", fake.evaluate)
    monkeypatch.setattr(pipeline, "evaluate_unchecked", fake.evaluate)
    monkeypatch.setattr(pipeline, "evaluate_speeds_unchecked", fake.evaluate_speeds)
    monkeypatch.setattr(pipeline, "calibrate_uplift", fake.calibrate_uplift)
    yield fake
    clear_caches()


def make(env_id: str = "Catenary-B1-v0", **kwargs: object) -> gym.Env:
    return gym.make(env_id, **{**FAST, **kwargs})


# ---------------------------------------------------------------------------------------------------------
# Registration and spaces


def test_every_problem_has_an_env_and_registration_is_idempotent() -> None:
    assert IDS == [f"Catenary-{name}-v0" for name in PROBLEMS]
    register_envs()  # again: no error, nothing replaced
    for env_id, name in zip(IDS, PROBLEMS, strict=True):
        spec = gym.spec(env_id)
        assert spec.entry_point == "catenary_env.envs.design_env:CatenaryDesignEnv"
        assert spec.kwargs == {"problem": name, "vector_kwargs": {"autoreset_mode": "SameStep"}}
    assert catenary_env.envs.CatenaryDesignEnv is CatenaryDesignEnv


@pytest.mark.parametrize("env_id", IDS)
def test_spaces(env_id: str) -> None:
    env = make(env_id)
    problem = env.unwrapped.problem
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (problem.n_variables,), np.float32)
    assert env.observation_space == gym.spaces.Box(0.0, 1.0, (2,), np.float32)


@pytest.mark.parametrize("env_id", IDS)
def test_action_maps_affinely_onto_the_bounds_and_the_grid(env_id: str) -> None:
    env = make(env_id).unwrapped
    problem = env.problem
    n = problem.n_variables
    np.testing.assert_array_equal(env.action_to_x(-np.ones(n, np.float32)), problem.lower)
    np.testing.assert_array_equal(env.action_to_x(np.ones(n, np.float32)), problem.upper)
    np.testing.assert_array_equal(
        env.action_to_x(np.zeros(n, np.float32)), problem.snap(0.5 * (problem.lower + problem.upper))
    )
    reference = problem.reference_x()
    if reference is not None:
        np.testing.assert_array_equal(env.action_to_x(env.x_to_action(reference)), reference)


def test_level_wire_is_action_zero_for_the_height_problems() -> None:
    for name in ("B1", "SW1"):
        env = make(f"Catenary-{name}-v0").unwrapped
        x = env.action_to_x(np.zeros(env.problem.n_variables, np.float32))
        assert env.problem.design(x) == env.problem.reference_design()


def test_observation_is_the_speed_over_the_wave_speed(fake_simulator: FakeSimulator) -> None:
    env = make("Catenary-B1-v0", speed_kmh=250.0)
    obs, info = env.reset(seed=0)
    wave_speed_kmh = env.unwrapped.problem.catenary_definition.wave_speed * 3.6
    np.testing.assert_allclose(obs, [250.0 / wave_speed_kmh] * 2, rtol=1e-6)
    assert obs.dtype == np.float32 and info == {"speed_kmh": 250.0}


# ---------------------------------------------------------------------------------------------------------
# Steps, rewards, info


def test_one_step_episode_reward_and_info(fake_simulator: FakeSimulator) -> None:
    env = make("Catenary-B1-v0")
    env.reset(seed=0)
    action = np.array([0.5, 0.0, -0.25, 0.0, 0.1], np.float32)
    obs, reward, terminated, truncated, info = env.step(action)
    assert (terminated, truncated) == (True, False)
    assert info["feasible"] is True and info["reason"] == ""
    assert reward == -info["std"] == -info["objective"]
    assert info["variables"] == {"dh_1": 0.01, "dh_2": 0.0, "dh_3": -0.005, "dh_4": 0.0, "dh_5": 0.002}
    assert info["design"] == env.unwrapped.problem.design(list(info["variables"].values()))
    assert set(ContactStatistics.__dataclass_fields__) <= set(info)
    assert info["uplift_force"] == pytest.approx(en50367_mean_force(300 / 3.6) + 4.0)
    assert info["wall_time"] == 0.25 and info["clipped"] is False and info["speed_kmh"] == 300.0
    assert len(info["dropper_lengths"]) == len(info["dropper_forces"]) == 9
    ((design, speed),) = fake_simulator.calls
    assert speed == pytest.approx(300 / 3.6) and design == info["design"]


def test_out_of_range_actions_are_clipped_and_reported(fake_simulator: FakeSimulator) -> None:
    env = make("Catenary-B2-v0")
    env.reset(seed=0)
    *_, info = env.step(np.array([3.0, -1.5, 1.0, -1.0], np.float32))
    assert info["clipped"] is True
    assert list(info["variables"].values()) == [7.4, 7.5, 18.8, 18.9]
    *_, info = env.step(np.array([1.0, -1.0, 1.0, -1.0], np.float32))
    assert info["clipped"] is False


@pytest.mark.parametrize(
    ("action", "match"),
    [
        ([np.nan, 0, 0, 0, 0], "finite"),
        ([0, np.inf, 0, 0, 0], "finite"),
        ([0, 0, 0, 0], r"shape \(5,\)"),
        ([[0, 0, 0, 0, 0]], r"shape \(5,\)"),
        (0.0, r"shape \(5,\)"),
        (["up"] * 5, "numbers"),
    ],
)
def test_bad_actions_raise(fake_simulator: FakeSimulator, action: object, match: str) -> None:
    env = make("Catenary-B1-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=match):
        env.step(action)
    assert fake_simulator.calls == []


def test_infeasible_design_scores_the_documented_penalty(fake_simulator: FakeSimulator) -> None:
    env = make("Catenary-B1-v0")
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(
        -np.ones(5, np.float32)
    )  # wire 20 mm low everywhere: the fake loses contact
    assert terminated is True
    assert info["feasible"] is False and info["reason"] == "dynamic: contact lost"
    assert reward == pytest.approx(-INFEASIBLE_SIGMA_OVER_MEAN * en50367_mean_force(300 / 3.6))
    assert info["std"] < -reward  # the statistics of the run are still reported


def test_design_the_catenary_cannot_build_is_infeasible(fake_simulator: FakeSimulator) -> None:
    env = make("Catenary-SW3-v0")
    env.reset(seed=0)
    _, reward, _, _, info = env.step(
        np.array([1.0, 0.0, 0.0, 0.0, 0.0], np.float32)
    )  # d_1 = 9 m: stitch-wire end
    assert info["feasible"] is False and info["reason"].startswith("design:")
    assert reward == pytest.approx(-en50367_mean_force(300 / 3.6))
    assert "std" not in info and fake_simulator.calls == []


def test_normalized_reward_divides_by_the_reference_sigma(fake_simulator: FakeSimulator) -> None:
    env = make("Catenary-B2-v0", normalize_reward=True)
    env.reset(seed=0)
    reference = env.unwrapped.problem.reference_x()
    _, reward, _, _, info = env.step(env.unwrapped.x_to_action(reference))
    assert reward == pytest.approx(-1.0)
    _, reward, _, _, info = env.step(np.array([1.0, 1.0, -1.0, -1.0], np.float32))
    reference_sigma = env.unwrapped.problem.reference_evaluation(
        300.0, resolve_fidelity("test")
    ).statistics.std
    assert reward == pytest.approx(-info["std"] / reference_sigma)


@pytest.mark.parametrize(
    ("objective", "aggregate"), [("mean_sigma_over_speeds", np.mean), ("worst_sigma_over_speeds", np.max)]
)
def test_multi_speed_objectives(fake_simulator: FakeSimulator, objective: str, aggregate: object) -> None:
    speeds = (200.0, 250.0, 320.0)
    env = make("Catenary-B1-v0", objective=objective, speeds_kmh=speeds)
    obs, _ = env.reset(seed=0)
    wave_speed_kmh = env.unwrapped.problem.catenary_definition.wave_speed * 3.6
    np.testing.assert_allclose(obs, [200.0 / wave_speed_kmh, 320.0 / wave_speed_kmh], rtol=1e-6)
    _, reward, _, _, info = env.step(np.zeros(5, np.float32))
    assert info["std"].shape == (3,) and info["uplift_force"].shape == (3,)
    np.testing.assert_array_equal(info["speed_kmh"], speeds)
    assert reward == pytest.approx(-aggregate(info["std"]))  # type: ignore[operator]
    assert [s * 3.6 for _, s in fake_simulator.calls] == pytest.approx(list(speeds))
    assert fake_simulator.calibrations == 3  # one pantograph setting per speed


def test_the_env_and_the_studies_share_the_mean_sigma_objective(fake_simulator: FakeSimulator) -> None:
    from experiments.design_evaluations import simulate_mean_sigma

    speeds = (200.0, 250.0, 320.0)
    env = make("Catenary-B1-v0", objective="mean_sigma_over_speeds", speeds_kmh=speeds)
    env.reset(seed=0)
    action = np.array([0.2, -0.1, 0.0, 0.3, -0.2], np.float32)
    _, reward, _, _, info = env.step(action)
    x = tuple(info["variables"].values())
    outcome = simulate_mean_sigma("B1", speeds, x, 300.0, resolve_fidelity("test", 5))
    assert outcome.feasible and reward == pytest.approx(-outcome.sigma, rel=1e-12)


def test_speeds_near_the_wave_speed_are_warned_about(fake_simulator: FakeSimulator) -> None:
    with pytest.warns(UserWarning, match="wave speed"):  # 0.94 of the benchmark's 459.6 km/h
        make("Catenary-B1-v0", speed_kmh=430.0)
    with pytest.warns(UserWarning, match="wave speed"):
        make("Catenary-B1-v0", speed_range=(300.0, 430.0))
    env = make("Catenary-B1-v0", speed_kmh=300.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # 300 km/h: no warning
        env.reset(seed=0)
    with pytest.warns(UserWarning, match="430.0 km/h is 0.936 of the contact wire's wave speed"):
        env.reset(options={"speed_kmh": 430.0})


def test_calibrations_are_not_announced_inside_the_env(fake_simulator: FakeSimulator, capsys) -> None:
    env = make("Catenary-SW1-v0", speed_range=(200.0, 320.0))
    for speed in (210.0, 250.0, 290.0):  # three speeds, three calibrations, silent
        env.reset(seed=0, options={"speed_kmh": speed})
        env.step(np.zeros(4, np.float32))
    assert fake_simulator.calibrations == 3 and "calibrating" not in capsys.readouterr().err
    PROBLEMS["SW1"].uplift_force(300.0, "test")  # outside an env (the command line): announced
    assert "calibrating the pantograph uplift" in capsys.readouterr().err


def test_a_repeated_design_is_not_simulated_again(fake_simulator: FakeSimulator) -> None:
    env = make("Catenary-B1-v0")
    env.reset(seed=0)
    first = env.step(np.full(5, 0.3, np.float32))
    second = env.step(np.full(5, 0.3001, np.float32))  # the same grid point
    assert len(fake_simulator.calls) == 1 and env.unwrapped.evaluation_count == 1
    assert first[1] == second[1] and first[4]["wall_time"] == second[4]["wall_time"]


def test_a_design_is_simulated_at_all_its_speeds_at_once_and_remembered_at_each(
    fake_simulator: FakeSimulator,
) -> None:
    env = make("Catenary-B1-v0", objective="mean_sigma_over_speeds", speeds_kmh=(200.0, 250.0, 300.0))
    env.reset(seed=0)
    env.step(np.full(5, 0.3, np.float32))
    assert (
        fake_simulator.batches == [3] and env.unwrapped.evaluation_count == 3
    )  # one statics, three passages
    env.step(np.full(5, 0.3001, np.float32))  # the same grid point: from the memo
    assert fake_simulator.batches == [3] and env.unwrapped.evaluation_count == 3
    lost = np.full(5, -1.0, np.float32)  # the wire 20 mm low everywhere: contact lost at the first speed
    _, _, _, _, info = env.step(lost)
    assert fake_simulator.batches == [3, 1] and not info["feasible"]
    env.step(lost)
    assert fake_simulator.batches == [3, 1] and env.unwrapped.evaluation_count == 4


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"problem": "B4"}, "unknown design problem"),
        ({"objective": "sigma_max"}, "objective"),
        ({"speeds_kmh": (200.0, 300.0)}, "speeds_kmh"),
        ({"objective": "worst_sigma_over_speeds"}, "speeds_kmh"),
        (
            {"objective": "mean_sigma_over_speeds", "speeds_kmh": (250.0,), "speed_range": (200.0, 300.0)},
            "speed_range",
        ),
        ({"speed_kmh": 250.0, "speed_range": (200.0, 300.0)}, "speed_kmh = 250.0 and speed_range"),
        ({"objective": "mean_sigma_over_speeds", "speeds_kmh": (250.0,), "speed_kmh": 250.0}, "speed_kmh"),
        ({"speed_kmh": 480.0}, "wave speed"),
        ({"speed_kmh": -5.0}, "km/h"),
        ({"speed_range": (300.0, 200.0)}, "speed_range"),
        ({"n_spans": 2}, "n_spans"),
        ({"fidelity": "coarse"}, "fidelity"),
        ({"render_mode": "human"}, "render_mode"),
    ],
)
def test_bad_arguments_raise(kwargs: dict, match: str) -> None:
    arguments = {"problem": "B1", **FAST, **kwargs}
    with pytest.raises((ValueError, KeyError), match=match):
        CatenaryDesignEnv(**arguments)


# ---------------------------------------------------------------------------------------------------------
# Seeding and the speed range


def test_same_seed_same_speed_observation_and_reward(fake_simulator: FakeSimulator) -> None:
    def episode(seed: int) -> tuple[np.ndarray, float, float]:
        env = make("Catenary-SW1-v0", speed_range=(200.0, 320.0))
        obs, info = env.reset(seed=seed)
        action = np.array([0.1, -0.2, 0.3, 0.0], np.float32)
        _, reward, _, _, _ = env.step(action)
        return obs, reward, info["speed_kmh"]

    obs_a, reward_a, speed_a = episode(7)
    obs_b, reward_b, speed_b = episode(7)
    np.testing.assert_array_equal(obs_a, obs_b)
    assert (reward_a, speed_a) == (reward_b, speed_b)
    speeds = {episode(seed)[2] for seed in range(8)}
    assert len(speeds) > 1 and all(200 <= v <= 320 and v == int(v) for v in speeds)


def test_speed_range_draws_a_new_speed_each_reset_and_options_set_it(fake_simulator: FakeSimulator) -> None:
    env = make("Catenary-B1-v0", speed_range=(200.0, 320.0))
    env.reset(seed=3)
    speeds = [env.reset()[1]["speed_kmh"] for _ in range(10)]
    assert len(set(speeds)) > 1
    obs, info = env.reset(options={"speed_kmh": 275.0})
    assert info["speed_kmh"] == 275.0
    _, _, _, _, info = env.step(np.zeros(5, np.float32))
    assert info["speed_kmh"] == 275.0 and fake_simulator.calls[-1][1] == pytest.approx(275.0 / 3.6)


def test_excluded_speed_bands_are_never_drawn_but_can_be_set(fake_simulator: FakeSimulator) -> None:
    bands = ((225.0, 235.0), (285.0, 295.0))
    env = make("Catenary-B1-v0", speed_range=(200.0, 320.0), excluded_speeds=bands)
    env.reset(seed=5)
    speeds = {env.reset()[1]["speed_kmh"] for _ in range(400)}
    assert speeds <= set(range(200, 225)) | set(range(236, 285)) | set(range(296, 321))
    assert min(speeds) < 225 and 236 <= max(s for s in speeds if s < 285) and max(speeds) > 295
    assert env.reset(options={"speed_kmh": 230.0})[1]["speed_kmh"] == 230.0  # held out, not forbidden


@pytest.mark.parametrize(
    ("bands", "match"),
    [
        (((190.0, 210.0),), r"within speed_range"),
        (((240.0, 230.0),), r"a <= b"),
        (((220.0, 240.0), (235.0, 250.0)), "overlap"),
        (((200.0, 320.0),), r"no speed of \(200, 320\) km/h on the 1 km/h grid"),
    ],
)
def test_excluded_speed_bands_that_make_no_sense_are_refused(bands, match) -> None:
    with pytest.raises(ValueError, match=match):
        CatenaryDesignEnv("B1", speed_range=(200.0, 320.0), excluded_speeds=bands, **FAST)
    with pytest.raises(ValueError, match="only with speed_range"):
        CatenaryDesignEnv("B1", speed_kmh=300.0, excluded_speeds=((225.0, 235.0),), **FAST)


def test_step_before_reset_with_a_speed_range_is_refused() -> None:
    env = CatenaryDesignEnv("B1", speed_range=(200.0, 300.0), **FAST)
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(5, np.float32))


# ---------------------------------------------------------------------------------------------------------
# Vector envs: one-step episodes must not waste a step on the reset


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_vector_env_simulates_every_step(fake_simulator: FakeSimulator, mode: str) -> None:
    n_envs, n_steps = 3, 4
    envs = catenary_env.envs.make_vector_env(
        n_envs,
        problem="B1",
        asynchronous=mode == "async",
        vector_kwargs={"context": "fork"} if mode == "async" else None,  # workers inherit the fake
        speed_range=(250.0, 300.0),
        **FAST,
    )
    try:
        obs, _ = envs.reset(seed=11)
        rng = np.random.default_rng(0)
        for _ in range(n_steps):
            actions = rng.uniform(-0.9, 0.9, size=(n_envs, 5)).astype(np.float32)
            obs, rewards, terminated, truncated, infos = envs.step(actions)
            assert terminated.all() and not truncated.any()
            assert np.all(rewards < -20.0)  # every reward comes from a simulation, none from a reset
            np.testing.assert_allclose(rewards, -infos["final_info"]["std"])
            assert obs.shape == (n_envs, 2) and np.all((obs > 0) & (obs < 1))
        counts = envs.get_attr("evaluation_count")
    finally:
        envs.close()
    assert sum(counts) == n_envs * n_steps


# ---------------------------------------------------------------------------------------------------------
# Rendering


def test_render_works_right_after_reset_and_after_a_step(fake_simulator: FakeSimulator) -> None:
    pytest.importorskip("matplotlib", reason="rendering needs matplotlib")
    env = make("Catenary-SW3-v0", render_mode="rgb_array")
    env.reset(seed=0)
    before = env.render()
    assert before.dtype == np.uint8 and before.ndim == 3 and before.shape[2] == 3
    env.step(np.array([-0.5, 0.2, 0.1, 0.0, -0.3], np.float32))
    after = env.render()
    assert after.shape == before.shape and not np.array_equal(after, before)


def test_render_without_a_mode_returns_none() -> None:
    env = CatenaryDesignEnv("B1", **FAST)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


# ---------------------------------------------------------------------------------------------------------
# The real simulator


def _checker_warnings(caught: list[warnings.WarningMessage]) -> list[str]:
    return [str(w.message) for w in caught if "gymnasium" in w.filename or "stable_baselines3" in w.filename]


@pytest.mark.parametrize("env_id", IDS)
def test_gymnasium_check_env(env_id: str) -> None:
    pytest.importorskip("matplotlib", reason="rendering needs matplotlib")
    from gymnasium.utils.env_checker import check_env

    env = make(env_id, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    assert _checker_warnings(caught) == []


@pytest.mark.parametrize(
    "env_id",
    # One env in every run; the others behind the slow marker (each calibrates its catenary: 10-50 s).
    [
        env_id if env_id == "Catenary-B1-v0" else pytest.param(env_id, marks=pytest.mark.slow)
        for env_id in IDS
    ],
)
def test_stable_baselines3_check_env(env_id: str) -> None:
    env_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    sb3_check_env = env_checker.check_env
    env = make(env_id)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sb3_check_env(env)
    assert _checker_warnings(caught) == []


@pytest.mark.parametrize("name", [name for name, p in PROBLEMS.items() if p.reference_x() is not None])
def test_reference_design_as_an_action_reproduces_the_reference_sigma(name: str) -> None:
    env = make(f"Catenary-{name}-v0", speed_kmh=300.0)
    problem = env.unwrapped.problem
    env.reset(seed=0)
    _, reward, _, _, info = env.step(env.unwrapped.x_to_action(problem.reference_x()))

    # The same run, straight from the simulator: level wire, pantograph set on it for EN 50367's mean.
    catenary, pantograph, fidelity = (
        problem.catenary_definition,
        problem.pantograph_definition,
        resolve_fidelity("test"),
    )
    speed = 300.0 / 3.6
    design = level_design(catenary)
    uplift = pipeline.calibrate_uplift(
        catenary, pantograph, design, speed, fidelity, target_mean=en50367_mean_force(speed)
    )
    direct = pipeline.evaluate(catenary, pantograph, design, speed, fidelity, uplift_force=uplift)
    assert info["design"] == design and info["feasible"] and direct.feasible
    assert info["uplift_force"] == pytest.approx(uplift, rel=1e-9)
    assert reward == pytest.approx(-direct.statistics.std, rel=1e-9)
    assert direct.statistics.mean == pytest.approx(en50367_mean_force(speed), rel=0.01)


def test_real_async_vector_env() -> None:
    envs = gym.make_vec(
        "Catenary-B1-v0",
        num_envs=2,
        vectorization_mode="async",
        **FAST,
    )
    try:
        envs.reset(seed=0)
        actions = np.array([[0.0] * 5, [0.2, -0.2, 0.1, 0.0, -0.1]], np.float32)
        _, rewards, terminated, _, infos = envs.step(actions)
        counts = envs.get_attr("evaluation_count")
    finally:
        envs.close()
    assert terminated.all() and list(counts) == [1, 1]
    np.testing.assert_allclose(rewards, -infos["final_info"]["std"])
