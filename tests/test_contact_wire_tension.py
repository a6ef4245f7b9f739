"""A problem on its catenary with another contact-wire tension, and the envs and design policies conditioned
on the tension (docs/problems.md, 'Contact-wire tension')."""

from __future__ import annotations

import dataclasses
import json
import math
import sqlite3

import numpy as np
import pytest
from conftest import SHORT, horizontal_tension

from catenary_env.fem.layout import CONTACT, MESSENGER
from catenary_env.model.definition import DefinitionError
from catenary_env.model.design import level_design
from catenary_env.pipeline import solve_static
from catenary_env.problems import get_problem

gymnasium = pytest.importorskip("gymnasium")

from catenary_env.envs import register_envs  # noqa: E402

register_envs()

PRESET = 22000.0
"""The benchmark catenary's contact-wire tension, N."""


def test_a_problem_at_another_tension_is_another_model_whose_contact_wire_carries_it():
    b1 = get_problem("B1")
    low = b1.with_contact_wire_tension(18000.0)
    assert b1.catenary_definition.contact_wire.tension == PRESET
    assert b1.with_contact_wire_tension(PRESET) is b1  # the preset itself
    assert dataclasses.replace(b1, contact_wire_tension=PRESET).store_fingerprint() == b1.store_fingerprint()
    assert low.store_fingerprint() != b1.store_fingerprint()  # its results never mix with the preset's
    assert low.catenary_definition.wave_speed == pytest.approx(
        b1.catenary_definition.wave_speed * math.sqrt(18000.0 / PRESET), rel=1e-12
    )
    static = solve_static(low.catenary_definition, level_design(low.catenary_definition), SHORT)
    horizontal, wire = horizontal_tension(static), static.layout.cable_wire
    assert np.max(np.abs(horizontal[wire == CONTACT] / 18000.0 - 1.0)) < 1e-6
    messenger = b1.catenary_definition.messenger_wire.tension
    assert (
        np.max(np.abs(horizontal[wire == MESSENGER] / messenger - 1.0)) < 1e-6
    )  # the messenger keeps its own


def test_every_tension_is_simulated_under_the_presets_uplift_force():
    b1 = get_problem("B1")
    low = b1.with_contact_wire_tension(18000.0)
    assert low.uplift_force(300.0, "test") == b1.uplift_force(300.0, "test")
    reference, slack = b1.reference_evaluation(300.0, "test"), low.reference_evaluation(300.0, "test")
    assert reference.uplift_force == slack.uplift_force
    assert slack.statistics.std != reference.statistics.std  # another catenary: another contact force


@pytest.mark.parametrize("tension", [15000.0, 30000.0, math.nan])
def test_a_tension_out_of_range_is_refused_naming_the_range(tension):
    with pytest.raises(DefinitionError, match=r"contact_wire_tension = .* must be within \[15400, 28600\] N"):
        get_problem("B1").with_contact_wire_tension(tension)


def _tension_env(**kwargs):
    return gymnasium.make(
        "Catenary-B1-v0", speed_range=(200.0, 320.0), contact_wire_tension_range=(18000.0, 26000.0),
        excluded_tensions=((21000.0, 23000.0),), fidelity="test", **kwargs,
    )  # fmt: skip


def test_the_env_draws_tensions_on_their_grid_outside_the_held_out_band_and_observes_them():
    env = _tension_env()
    speed_only = gymnasium.make("Catenary-B1-v0", speed_range=(200.0, 320.0), fidelity="test")
    assert env.observation_space.shape == (3,) and speed_only.observation_space.shape == (2,)
    drawn = set()
    for seed in range(30):
        observation, info = env.reset(seed=seed)
        tension, speed = info["contact_wire_tension"], info["speed_kmh"]
        drawn.add(tension)
        assert 18000.0 <= tension <= 26000.0 and not 21000.0 <= tension <= 23000.0
        assert tension % 100.0 == 0.0
        wave_speed_kmh = env.unwrapped.problem.catenary_definition.wave_speed * 3.6
        np.testing.assert_allclose(observation, [speed / wave_speed_kmh] * 2 + [tension / PRESET], rtol=1e-6)
        assert speed == speed_only.reset(seed=seed)[1]["speed_kmh"]  # a speed-only env draws as it did
    assert len(drawn) > 20


def test_the_tension_conditioned_env_passes_the_environment_checkers():
    pytest.importorskip("matplotlib", reason="rendering needs matplotlib")
    import warnings

    from gymnasium.utils.env_checker import check_env

    checkers = [check_env]
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    checkers.append(sb3_checker.check_env)
    for checker in checkers:
        env = _tension_env(render_mode="rgb_array")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            checker(env.unwrapped)
        said = [
            str(w.message) for w in caught if "gymnasium" in w.filename or "stable_baselines3" in w.filename
        ]
        assert said == [], checker


def test_a_design_at_two_tensions_is_two_simulations_and_the_presets_tension_is_the_preset():
    env = _tension_env()
    design = np.zeros(5, dtype=np.float32)
    env.reset(options={"speed_kmh": 300.0, "contact_wire_tension": PRESET})  # held out: set, not drawn
    _, at_preset, _, _, info = env.step(design)
    env.reset(options={"speed_kmh": 300.0, "contact_wire_tension": 19000.0})
    _, at_low, _, _, low_info = env.step(design)
    assert env.unwrapped.evaluation_count == 2 and low_info["contact_wire_tension"] == 19000.0
    preset = gymnasium.make("Catenary-B1-v0", speed_kmh=300.0, fidelity="test")
    preset.reset()
    _, reward, _, _, preset_info = preset.step(design)
    assert at_preset == reward and info["std"] == preset_info["std"]
    assert at_low != at_preset and preset_info["contact_wire_tension"] == PRESET


@pytest.mark.parametrize(
    ("kwargs", "says"),
    [
        ({"contact_wire_tension_range": (12000.0, 26000.0)}, r"must be within \[15400, 28600\] N"),
        ({"contact_wire_tension": 20000.0, "contact_wire_tension_range": (18000.0, 26000.0)}, "give one"),
        ({"excluded_tensions": ((18000.0, 19000.0),)}, "only with contact_wire_tension_range"),
        (
            {"contact_wire_tension_range": (18000.0, 19000.0), "excluded_tensions": ((18000.0, 19000.0),)},
            "no tension of",
        ),
        ({"contact_wire_tension_range": (18050.0, 18090.0)}, "100 N grid"),
    ],
)
def test_bad_tension_arguments_are_refused_naming_the_field(kwargs, says):
    with pytest.raises(ValueError, match=says):
        speed = None if "contact_wire_tension_range" in kwargs else 300.0
        gymnasium.make("Catenary-B1-v0", speed_kmh=speed, fidelity="test", **kwargs)


def test_an_env_without_a_tension_range_refuses_a_tension_at_reset():
    env = gymnasium.make("Catenary-B1-v0", speed_kmh=300.0, fidelity="test")
    with pytest.raises(ValueError, match="only for an env with a contact_wire_tension_range"):
        env.reset(options={"contact_wire_tension": 20000.0})


def test_a_tension_conditioned_policy_stores_each_step_under_its_tensions_model_and_resumes(
    tmp_path, monkeypatch, capsys
):
    pytest.importorskip("stable_baselines3")
    from catenary_env.calibration_cache import CACHE_ENV
    from catenary_env.cli import main
    from optimizers.catenary_adapter import catenary_problem
    from optimizers.problem import GridSpace
    from optimizers.rl import EnvSpec, PPOOptions, design_for_speed, save_policy, train_design_policy

    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))

    spec = EnvSpec(
        "Catenary-B1-v0", speed_kmh=None, speed_range=(250.0, 300.0), fidelity="test",
        contact_wire_tension_range=(18000.0, 26000.0), excluded_tensions=((21000.0, 23000.0),),
    )  # fmt: skip
    problem, store = catenary_problem("B1"), tmp_path / "runs.sqlite"
    options = PPOOptions(n_steps=64, batch_size=64, n_epochs=1, net_arch=(8,))
    policy, full = train_design_policy(spec, problem, budget=8, seed=0, options=options, store=store)
    with sqlite3.connect(store) as connection:
        ((run_problem, run_options),) = connection.execute("SELECT problem, options FROM runs").fetchall()
        stored = [row[0] for row in connection.execute("SELECT problem FROM evaluations ORDER BY idx")]
    assert run_problem == GridSpace.from_problem(problem).store_key
    assert json.loads(run_options)["env"]["contact_wire_tension_range"] == [18000.0, 26000.0]
    keys = {
        GridSpace.from_problem(problem.with_contact_wire_tension(t)).store_key: t
        for t in np.arange(18000.0, 26001.0, 100.0)
        if not 21000.0 <= t <= 23000.0
    }
    assert len(stored) == 8 and set(stored) <= set(keys) and len(set(stored)) > 1

    with sqlite3.connect(store) as connection:
        connection.execute("DELETE FROM evaluations WHERE idx >= 5")
    _, resumed = train_design_policy(
        spec, problem, budget=8, seed=0, options=options, store=store, resume=True
    )
    assert [(r.x, r.sigma, r.speed_kmh) for r in resumed.history] == [
        (r.x, r.sigma, r.speed_kmh) for r in full.history
    ]

    x = design_for_speed(policy, problem, 280.0, 22000.0)  # a held-out tension
    assert x.shape == (5,)
    with pytest.raises(ValueError, match="give the tension"):
        design_for_speed(policy, problem, 280.0)

    saved = save_policy(policy, tmp_path / "policy.zip", problem, full)
    assert main(["propose", str(saved), "--speed", "280", "--no-evaluate"]) == 2
    assert (
        "--contact-wire-tension: required, N: the policy was trained on 250-300 km/h, contact wire at "
        "18-26 kN except 21-23" in capsys.readouterr().err
    )
    argv = ["propose", str(saved), "--speed", "280", "--contact-wire-tension", "22000", "--json"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    (entry,) = json.loads(captured.out)["proposals"]
    assert entry["contact_wire_tension"] == 22000.0 and list(entry["design"].values()) == x.tolist()
    assert entry["reference_sigma"] == get_problem("B1").reference_evaluation(280.0, "test").statistics.std
    assert (
        "280 km/h with the contact wire at 22 kN is outside the policy's training conditions" in captured.err
    )


@pytest.mark.parametrize(
    ("options", "says"),
    [
        (
            ["--contact-wire-tension", "40000"],
            "contact_wire_tension = 40000.0 N: must be within [15400, 28600] N",
        ),
        (["--contact-wire-tension-range", "20000", "28000"], "ppo and sac only, not random"),
    ],
)
def test_bad_tension_options_of_catenary_optimize_end_in_one_line(capsys, options, says):
    from catenary_env.cli import main

    argv = [
        "optimize",
        "B1",
        "--optimizer",
        "random",
        "--budget",
        "2",
        "--fidelity",
        "test",
        "--store",
        ":memory:",
    ]
    assert main([*argv, *options]) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and "\n" not in err


def test_catenary_optimize_runs_a_problem_at_another_tension_and_a_policy_over_tensions(
    tmp_path, monkeypatch, capsys
):
    pytest.importorskip("stable_baselines3")
    from catenary_env.calibration_cache import CACHE_ENV
    from catenary_env.cli import main
    from optimizers.catenary_adapter import catenary_problem
    from optimizers.problem import GridSpace
    from optimizers.rl import load_policy

    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    store = tmp_path / "runs.sqlite"
    argv = ["optimize", "B1", "--budget", "2", "--fidelity", "test", "--store", str(store), "--quiet"]
    assert main([*argv, "--optimizer", "random", "--contact-wire-tension", "20000"]) == 0
    with sqlite3.connect(store) as connection:
        (key,) = connection.execute("SELECT DISTINCT problem FROM evaluations").fetchone()
    at_20 = catenary_problem("B1", contact_wire_tension=20000.0)
    assert key == GridSpace.from_problem(at_20).store_key and key.startswith("B1-T20kN@")  # says its tension
    assert at_20.simulate.args == ("B1",) and at_20.with_contact_wire_tension(None).name == "B1"
    policy = tmp_path / "policy.zip"
    tensions = ["--contact-wire-tension-range", "20000", "28000", "--held-out-tensions", "21500", "22500"]
    rl = ["--optimizer", "sac", "--speed-range", "250", "300", *tensions, "--save-policy", str(policy)]
    assert main([*argv, *rl]) == 0
    _, record = load_policy(policy)
    assert record.env_spec.contact_wire_tension_range == (20000.0, 28000.0)
    assert record.env_spec.excluded_tensions == ((21500.0, 22500.0),)
    assert " ".join(tensions) in record.command


def test_catenary_evaluate_simulates_a_design_at_another_tension(capsys):
    from catenary_env.cli import main

    command = ["evaluate", "B1", "--x", "0", "0", "0", "0", "0", "--fidelity", "test", "--speed", "300"]
    assert main([*command, "--contact-wire-tension", "24000", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    expected = get_problem("B1").with_contact_wire_tension(24000.0).evaluate(np.zeros(5), 300.0, "test")
    assert (
        record["contact_wire_tension"] == 24000.0 and record["statistics"]["std"] == expected.statistics.std
    )
    assert main(command) == 0
    assert "problem B1 at 300 km/h, contact wire at 22 kN (test fidelity)" in capsys.readouterr().out
    assert main([*command, "--contact-wire-tension", "12000"]) == 2
    assert "contact_wire_tension = 12000.0 N: must be within [15400, 28600] N" in capsys.readouterr().err
