"""A trained PPO design policy is saved as one file, reloads, and proposes the same designs; ``catenary
propose`` reads it, and a speed-range run reports its best σ with the speed it was met at."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from catenary_env.calibration_cache import CACHE_ENV  # noqa: E402
from catenary_env.cli import main  # noqa: E402
from optimizers.catenary_adapter import catenary_problem  # noqa: E402
from optimizers.rl import (  # noqa: E402
    POLICY_MEMBER,
    EnvSpec,
    PolicyFileError,
    PPOOptions,
    design_for_speed,
    load_policy,
    save_policy,
    train_design_policy,
)
from optimizers.synthetic import get_synthetic_problem  # noqa: E402

PROBLEM = get_synthetic_problem("synthetic-quadratic")
ENV_ID = "TestPolicyFileDesign-v0"
SPEEDS = (250.0, 275.0, 300.0)


class ShiftingOptimumEnv(gymnasium.Env):
    """One step: the action is a design of the synthetic problem; σ grows away from a point that moves
    with the speed."""

    def __init__(
        self, speed_kmh: float | None = 300.0, speed_range: Any = None, fidelity: str = "test"
    ) -> None:
        self.speed_kmh = 300.0 if speed_kmh is None else float(speed_kmh)
        self.speed_range = speed_range
        self.action_space = gymnasium.spaces.Box(-1.0, 1.0, (len(PROBLEM.variable_names),), np.float32)
        self.observation_space = gymnasium.spaces.Box(0.0, 1.0, (1,), np.float32)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        super().reset(seed=seed)
        if options and "speed_kmh" in options:
            self.speed_kmh = float(options["speed_kmh"])
        elif self.speed_range is not None:
            self.speed_kmh = float(self.np_random.integers(*self.speed_range))
        return np.array([self.speed_kmh / 500.0], np.float32), {"speed_kmh": self.speed_kmh}

    def step(self, action: Any) -> Any:
        optimum = (self.speed_kmh - 275.0) / 2500.0  # m: -0.01 at 250 km/h, 0.01 at 300 km/h
        sigma = 20.0 + float(np.sum(((np.clip(action, -1, 1) * 0.02 - optimum) / 0.01) ** 2))
        info = {"feasible": True, "speed_kmh": self.speed_kmh, "objective": sigma}
        return np.array([self.speed_kmh / 500.0], np.float32), -sigma, True, False, info


if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point=ShiftingOptimumEnv)

SPEC = EnvSpec(ENV_ID, speed_kmh=None, speed_range=(250.0, 300.0), fidelity="test")
OPTIONS = PPOOptions(n_steps=16, batch_size=16, n_epochs=4, learning_rate=1e-2)


@pytest.fixture(scope="module")
def trained() -> Any:
    return train_design_policy(SPEC, PROBLEM, budget=32, seed=3, options=OPTIONS)


def test_a_saved_policy_reloads_and_proposes_the_same_designs(trained, tmp_path):
    policy, result = trained
    path = save_policy(policy, tmp_path / "policy.zip", PROBLEM, result)
    assert [p.name for p in tmp_path.iterdir()] == ["policy.zip"]  # no temporary file left
    loaded, record = load_policy(path)
    before = [design_for_speed(policy, PROBLEM, v) for v in SPEEDS]
    after = [design_for_speed(loaded, PROBLEM, v) for v in SPEEDS]
    for a, b in zip(before, after, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(before[0], before[-1])  # a speed-conditioned policy: designs differ
    assert record.problem == PROBLEM.name and record.env_spec == SPEC
    assert (record.budget, record.seed, record.run_id) == (32, 3, result.run_id)
    assert record.best_sigma == result.best_sigma and record.best_speed_kmh == result.best_speed_kmh
    assert record.speeds == "250-300 km/h"


def test_a_speed_range_run_reports_the_speed_of_its_best_sigma(trained):
    _, result = trained
    assert result.speed_kmh is None  # a range
    best = min((r for r in result.history if r.feasible), key=lambda r: (r.sigma, r.index))
    assert (result.best_sigma, result.best_speed_kmh) == (best.sigma, best.speed_kmh)
    assert 250.0 <= result.best_speed_kmh <= 300.0


def _zip_with(member: str, text: str) -> Any:
    def make(path: Path) -> None:
        with zipfile.ZipFile(path, "w") as archive:
            archive.writestr(member, text)

    return make


@pytest.mark.parametrize(
    ("make", "says"),
    [
        (lambda path: path.write_text("not a zip"), "not a zip archive"),
        (_zip_with("data", "{}"), f"without {POLICY_MEMBER}"),
        (_zip_with(POLICY_MEMBER, "{broken"), f"{POLICY_MEMBER} is damaged"),
        (_zip_with(POLICY_MEMBER, '{"format": 1, "problem": "B1"}'), "env_spec"),
    ],
)
def test_a_file_that_is_no_policy_is_refused_naming_it(tmp_path, make, says):
    path = tmp_path / "policy.zip"
    make(path)
    with pytest.raises(ValueError, match=says) as caught:
        load_policy(path)
    assert str(path) in str(caught.value)


def test_a_file_with_other_members_is_refused_before_stable_baselines3_reads_it(
    trained, tmp_path, monkeypatch
):
    # A genuine policy file with one more member (a pickle, say): refused on its layout, and
    # stable-baselines3's loader (which unpickles) is never reached.
    policy, result = trained
    path = save_policy(policy, tmp_path / "policy.zip", PROBLEM, result)
    with zipfile.ZipFile(path, "a") as archive:
        archive.writestr("payload.pkl", b"\x80\x04N.")
    import optimizers.rl.policy_files

    monkeypatch.setattr(
        optimizers.rl.policy_files, "import_stable_baselines3", lambda: pytest.fail("the loader was reached")
    )
    with pytest.raises(PolicyFileError, match="other members: payload.pkl") as caught:
        load_policy(path)
    assert str(path) in str(caught.value)


def test_catenary_optimize_saves_the_policy_and_propose_reads_it(tmp_path, monkeypatch, capsys):
    # The real B1 env on the coarse "test" model, four simulations: the subject is the files and commands.
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))  # optimize and propose share calibrations
    monkeypatch.chdir(tmp_path)
    argv = ["optimize", "B1", "--optimizer", "ppo", "--budget", "4", "--fidelity", "test", "--quiet"]
    assert main([*argv, "--speed-range", "250", "300", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    policy = tmp_path / out["policy"]
    assert policy.name == "catenary-runs.ppo-B1-run1.zip" and policy.is_file()  # beside the default store
    assert out["units"]["best_sigma, history.sigma"] == "N"
    assert out["best_speed_kmh"] is None or 250.0 <= out["best_speed_kmh"] <= 300.0

    assert main(["propose", str(policy), "--speed", "260", "290", "--no-evaluate", "--json"]) == 0
    proposed = json.loads(capsys.readouterr().out)["proposals"]
    loaded, _ = load_policy(policy)
    for entry in proposed:
        expected = design_for_speed(loaded, catenary_problem("B1"), entry["speed_kmh"])
        np.testing.assert_array_equal(list(entry["design"].values()), expected)

    assert main(["propose", str(policy), "--speed", "260"]) == 0
    text = capsys.readouterr().out
    assert "at 260 km/h:" in text and "dh_5 = " in text and ("sigma = " in text or "infeasible" in text)

    mine = tmp_path / "mine.zip"
    assert main([*argv, "--speed", "280", "--save-policy", str(mine), "--store", ":memory:"]) == 0
    assert f"policy saved to {mine}" in capsys.readouterr().out and mine.is_file()


def test_a_sac_policy_with_held_out_speeds_is_saved_with_its_record_and_command(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    argv = ["optimize", "B1", "--optimizer", "sac", "--budget", "2", "--fidelity", "test", "--quiet"]
    bands = ["--speed-range", "200", "320", "--held-out-speeds", "225", "235", "285", "295"]
    assert main([*argv, *bands, "--json"]) == 0
    policy = tmp_path / json.loads(capsys.readouterr().out)["policy"]
    assert policy.name == "catenary-runs.sac-B1-run1.zip"
    loaded, record = load_policy(policy)
    assert type(loaded.model).__name__ == "SAC" and record.learner == "sac"
    assert record.env_spec.excluded_speeds == ((225.0, 235.0), (285.0, 295.0))
    assert record.speeds == "200-320 km/h except 225-235 and 285-295"
    assert record.model_fingerprint == catenary_problem("B1").model_fingerprint
    assert record.command.startswith("catenary optimize B1 --optimizer sac --budget 2 --seed 0")
    assert "--held-out-speeds 225 235 285 295" in record.command and policy.name in record.command

    assert main(["propose", str(policy), "--speed", "230", "--no-evaluate"]) == 0
    captured = capsys.readouterr()
    assert "sac policy for B1" in captured.out and f"reproduce: {record.command}" in captured.out
    assert "230 km/h is outside the policy's training speeds" in captured.err


@pytest.mark.parametrize(
    ("options", "says"),
    [
        (["--held-out-speeds", "225", "235"], "with --speed-range"),
        (["--speed-range", "200", "320", "--held-out-speeds", "225"], "pairs of km/h"),
        (["--speed-range", "200", "320", "--held-out-speeds", "190", "235"], "--held-out-speeds: excluded"),
        (["--speed-range", "320", "200"], "--speed-range: speed_range = (320.0, 200.0): need lo <= hi"),
        (["--speed-range", "200", "320", "--workers", "2"], "multiple"),
        (["--contact-wire-tension", "20000"], "give --contact-wire-tension-range LO HI"),
        (
            ["--contact-wire-tension-range", "12000", "26000"],
            "--contact-wire-tension-range: contact_wire_tension_range = (12000.0, 26000.0): "
            "contact_wire_tension = 12000.0 N: must be within [15400, 28600] N",
        ),
        (["--contact-wire-tension-range", "20000", "28000", "--held-out-tensions", "21500"], "pairs of N"),
        (["--held-out-tensions", "21500", "22500"], "with --contact-wire-tension-range"),
    ],
)
def test_bad_rl_options_end_in_one_line(tmp_path, capsys, options, says):
    argv = [
        "optimize",
        "B1",
        "--optimizer",
        "sac",
        "--budget",
        "3",
        "--fidelity",
        "test",
        "--store",
        ":memory:",
    ]
    assert main([*argv, *options]) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and "\n" not in err
