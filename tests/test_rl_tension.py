"""Study 5c (docs/problems.md, 'Experiments'): design policies conditioned on the contact-wire tension as well
as the speed, against a GA run per tension. The quick study (B1, the "test" fidelity) is behind the ``slow``
marker; its ledger's bookkeeping is checked here on made-up rows."""

from __future__ import annotations

import math
import sqlite3

import pytest

pytest.importorskip("matplotlib", reason="the study's figures need matplotlib")
pytest.importorskip("gymnasium", reason="the policies train on design environments")
pytest.importorskip("stable_baselines3", reason="SAC comes from stable-baselines3")

from catenary_env.problems.design_problem import DesignProblem  # noqa: E402
from experiments import rl_amortised, rl_analysis, rl_tension  # noqa: E402
from experiments.common import read_csv  # noqa: E402
from optimizers.catenary_adapter import catenary_problem  # noqa: E402
from optimizers.problem import GridSpace  # noqa: E402
from optimizers.rl import load_policy  # noqa: E402
from optimizers.store import RunStore  # noqa: E402


def test_the_ledger_counts_one_policy_against_a_ga_run_per_tension():
    low, high = rl_tension.label(20000.0), rl_tension.label(24000.0)
    assert (low, rl_tension.trained_on(low)) == ("B1 at 20 kN", "B1")
    curves = [
        {"problem": low, "speed_kmh": 300.0, "simulations": 30.0, "best_sigma_N": 30.0},
        {"problem": high, "speed_kmh": 300.0, "simulations": 50.0, "best_sigma_N": 25.0},
    ]
    designs = [
        {"problem": name, "design": design, "seed": seed, "speed_kmh": 300.0, "held_out": 0, "sigma_N": sigma}
        for name, design, seed, sigma in [
            (low, "reference", -1, math.nan), (low, "ga", 0, 24.0), (low, "sac", 0, 30.0),
            (high, "reference", -1, 40.0), (high, "ga", 0, 20.0), (high, "sac", 0, 25.0),
        ]
    ]  # fmt: skip
    ga_runs = [{"problem": name, "speed_kmh": 300.0, "n_simulations": 1000} for name in (low, high)]
    steps = [{"problem": "B1", "learner": "sac", "seed": 0}] * 600
    (row,) = rl_analysis.amortisation_ledger(
        designs, curves, ga_runs, steps, n_speeds=(1,), trained_on=rl_tension.trained_on
    )
    assert (row["problem"], row["training_simulations"]) == ("B1", 600.0)  # one policy, both tensions
    assert row["gap_percent"] == pytest.approx(25.0)  # +25 % at both
    assert row["ga_per_speed_to_policy_sigma"] == 40.0  # the mean of 30 and 50
    assert row["break_even_same_sigma"] == 16.0  # 16 x 40 = 640 >= 600 + 16


@pytest.mark.slow  # the quick studies: 5b's SAC on B1, then SAC on B1 over tensions, GA runs at 22 and 24 kN
def test_rl_tension_quick(tmp_path, monkeypatch):
    rl_amortised.main(rl_amortised.Config(out=tmp_path, learners=("sac",)))  # its speed-only policy
    config = rl_tension.Config(out=tmp_path)
    folder = rl_tension.main(config)
    assert folder == tmp_path / "rl" / "tension"
    steps = read_csv(folder / "steps.csv")
    assert len(steps) == config.policy_budget and all(200.0 <= s["speed_kmh"] <= 320.0 for s in steps)
    policy, record = load_policy(folder / "policies" / "sac-B1-tension-seed0.zip")
    assert record.env_spec.contact_wire_tension_range == rl_tension.TENSION_RANGE
    assert record.env_spec.excluded_tensions == rl_tension.HELD_OUT_TENSIONS
    # every step is stored under the model of a tension drawn in training, never a held-out one
    problem = catenary_problem("B1")
    drawn = {
        GridSpace.from_problem(problem.with_contact_wire_tension(100.0 * t)).store_key
        for t in range(200, 281)
        if not any(a <= 100.0 * t <= b for a, b in rl_tension.HELD_OUT_TENSIONS)
    }
    with sqlite3.connect(tmp_path / "runs.sqlite") as connection:
        (run_id,) = connection.execute(
            "SELECT run_id FROM runs WHERE optimizer = 'sac' AND options LIKE '%tension_range%'"
        ).fetchone()
        keys = {
            k for (k,) in connection.execute("SELECT problem FROM evaluations WHERE run_id = ?", (run_id,))
        }
    assert keys <= drawn and len(keys) > 1
    designs = read_csv(folder / "designs.csv")
    assert {(r["tension_N"], bool(r["held_out"])) for r in designs if r["design"] == "sac"} == set(
        config.tensions
    )
    text = (folder / "tension.md").read_text(encoding="utf-8")
    assert "### Policies against a GA run per tension at 300 km/h (GA: 12 simulations" in text
    assert "| 22 | yes | sac |" in text and "### Amortisation ledger" in text
    # study 5b's policy (trained at the preset's tension alone) beside it; not in the ledger
    speed_only = [r for r in designs if r["design"] == "sac speed only"]
    assert {r["tension_N"] for r in speed_only} == {t for t, _ in config.tensions}
    assert len({r["x_m"] for r in speed_only}) == 1  # one design, whatever the tension
    assert "| 22 | yes | sac speed only |" in text
    assert {r["learner"] for r in read_csv(folder / "ledger.csv")} == {"sac"}
    with RunStore(tmp_path / "runs.sqlite") as store:  # the runs its lanes (--lane) would make
        assert all(store.stop_reason(store.find_run(r.identity)) for r in rl_tension.study_runs(config))

    def refuse(*args, **kwargs):
        raise AssertionError("a design was simulated")

    monkeypatch.setattr(DesignProblem, "evaluate_speeds", refuse)
    rl_tension.main(config)  # replayed from the store: nothing simulated
    assert (folder / "tension.md").read_text(encoding="utf-8") == text


def test_a_full_run_is_reproduced_by_the_catenary_optimize_command_beside_its_policy(tmp_path):
    import argparse
    import shlex

    from optimizers.cli.optimize import add_arguments, rl_env_spec

    config = rl_tension.Config(full=True, out=tmp_path)
    store, policy = tmp_path / "runs.sqlite", tmp_path / "sac.zip"
    words = shlex.split(rl_tension.reproduce_command(config, store, "sac", 1, policy))
    assert words[:2] == ["catenary", "optimize"]
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    args = parser.parse_args(words[2:])
    assert (args.optimizer, args.budget, args.seed, args.save_policy) == ("sac", 10_000, 1, str(policy))
    assert rl_env_spec("B1", args) == rl_tension.env_spec(config)
    quick = shlex.split(
        rl_tension.reproduce_command(rl_tension.Config(out=tmp_path), store, "sac", 0, policy)
    )
    assert quick[:3] == ["catenary", "experiment", "rl-tension"]
