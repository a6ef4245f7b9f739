"""Study 5b (docs/problems.md, 'Experiments'): speed-conditioned policies against a GA run per speed, and the
amortisation ledger. The whole study runs in seconds on the synthetic problem whose optimum moves with the
speed; the real quick setting (B1, the "test" fidelity) is behind the ``slow`` marker."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib", reason="the study's figures need matplotlib")
pytest.importorskip("gymnasium", reason="the policies train on design environments")
pytest.importorskip("stable_baselines3", reason="PPO and SAC come from stable-baselines3")

from catenary_env.problems.design_problem import DesignProblem  # noqa: E402
from experiments import rl_amortised, rl_analysis  # noqa: E402
from experiments.common import markdown_table, read_csv  # noqa: E402
from optimizers import synthetic  # noqa: E402
from optimizers.rl import load_policy  # noqa: E402

OUTPUTS = ["amortised.md", "ledger.csv", "learning_curves.png", "ledger.png"]


def _no_simulation(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(*args, **kwargs):
        raise AssertionError("a design was simulated")

    monkeypatch.setattr(DesignProblem, "evaluate", refuse)
    monkeypatch.setattr(DesignProblem, "evaluate_speeds", refuse)
    monkeypatch.setattr(synthetic, "simulate_quadratic", refuse)


def _check_study(config: rl_amortised.Config, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    folder = rl_amortised.main(config)
    assert folder == tmp_path / "rl" / "amortised"
    steps = read_csv(folder / "steps.csv")
    runs = len(config.problems) * len(config.learners) * len(config.seeds)
    assert len(steps) == runs * config.policy_budget
    for s in steps:  # trained on 200-320 km/h, never in a held-out band
        assert 200.0 <= s["speed_kmh"] <= 320.0
        assert not any(a <= s["speed_kmh"] <= b for a, b in rl_amortised.HELD_OUT)
    designs = read_csv(folder / "designs.csv")
    for problem in config.problems:
        for learner in config.learners:
            chosen = [r for r in designs if r["problem"] == problem and r["design"] == learner]
            assert {(r["speed_kmh"], bool(r["held_out"])) for r in chosen} == set(config.speeds)
            for seed in config.seeds:
                path = folder / "policies" / f"{learner}-{problem}-seed{seed}.zip"
                _, record = load_policy(path)
                assert record.learner == learner and record.problem == problem
                assert record.env_spec.excluded_speeds == rl_amortised.HELD_OUT
                assert record.command == path.with_suffix(".txt").read_text(encoding="utf-8").strip()
    ga = read_csv(folder / "ga_runs.csv")
    assert {r["speed_kmh"] for r in ga} == {v for v, _ in config.speeds}
    assert all(r["n_simulations"] == config.ga_budget for r in ga)
    text = (folder / "amortised.md").read_text(encoding="utf-8")
    assert f"### Policies against a GA run per speed (GA: {config.ga_budget} simulations" in text
    assert "### Where the policies' designs went" in text
    assert "### Amortisation ledger" in text
    for name in OUTPUTS:
        assert (folder / name).stat().st_size > 0

    steps_text = (folder / "steps.csv").read_text(encoding="utf-8")
    _no_simulation(monkeypatch)
    copy = tmp_path / "data_only"
    copy.mkdir()
    for csv in folder.glob("*.csv"):
        shutil.copy(csv, copy)
    (copy / "ledger.csv").unlink()
    rl_amortised.report(copy)  # from the data alone
    assert (copy / "amortised.md").read_text(encoding="utf-8") == text
    rl_amortised.main(config)  # replayed from the store: nothing simulated
    assert (folder / "steps.csv").read_text(encoding="utf-8") == steps_text


def test_the_study_runs_on_the_synthetic_problem_and_replays(tmp_path, monkeypatch):
    config = rl_amortised.Config(
        out=tmp_path, problems=("synthetic-speed-quadratic",), envs=1, workers=1, seeds=(0, 1)
    )
    _check_study(config, tmp_path, monkeypatch)

    # catenary report finds the study in rl/amortised, and does not take it for study 5 (rl/)
    from experiments.cli.report import build_report

    report = build_report(tmp_path).read_text(encoding="utf-8")
    assert "## rl-amortised: speed-conditioned PPO and SAC policies" in report
    assert "![learning_curves](rl/amortised/learning_curves.png)" in report
    assert "## rl:" not in report and "`catenary experiment rl`," in report  # not run yet


def test_lanes_over_one_store_make_each_run_once_and_leave_the_tables_to_the_study(tmp_path, monkeypatch):
    """``--lane``: a run another process is making (its claim held here through a file of its own) is left
    to it, and so is a run finished already; each run is made by one lane, and the study afterwards writes
    the tables of every run, replaying them."""
    import fcntl

    from experiments.common import run_study
    from optimizers.store import RunStore

    config = rl_amortised.Config(
        out=tmp_path, problems=("synthetic-speed-quadratic",), envs=1, workers=1, seeds=(0, 1), lane=True
    )
    runs = rl_amortised.study_runs(config)
    assert [r.name for r in runs] == [
        "ga on synthetic-speed-quadratic at 230 km/h", "ga on synthetic-speed-quadratic at 260 km/h",
        *(f"{name} on synthetic-speed-quadratic seed {seed}" for name in ("ppo", "sac") for seed in (0, 1)),
    ]  # fmt: skip
    store = RunStore(tmp_path / "runs.sqlite")
    claim = Path(store._claim_file(runs[3].identity))
    claim.parent.mkdir()
    held = claim.open("a")  # noqa: SIM115 (closed below)
    fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)  # another lane is making PPO's seed 1
    text = rl_amortised.lane(config)
    assert text.startswith("This lane made 5 run(s)") and "1 were made, or are being made, by other" in text
    assert store.find_run(runs[3].identity) is None
    held.close()
    assert rl_amortised.lane(config).startswith(
        "This lane made 1 run(s): ppo on synthetic-speed-quadratic seed 1."
    )
    assert all(store.stop_reason(store.find_run(r.identity)) == "budget" for r in runs)
    assert not (tmp_path / "rl" / "amortised" / "steps.csv").exists()  # a lane writes no table

    def progress() -> list[dict[str, object]]:  # (a replayed run is marked finished again: its time moves)
        return [{k: v for k, v in run.items() if k != "finished_at"} for run in store.run_progress()]

    made = progress()
    argv = ["--problems", "synthetic-speed-quadratic", "--envs", "1", "--workers", "1", "--seeds", "0", "1"]
    assert run_study(rl_amortised, [*argv, "--out", str(tmp_path)], "rl-amortised") == 0
    assert len(read_csv(tmp_path / "rl" / "amortised" / "steps.csv")) == 4 * config.policy_budget
    now = progress()
    assert now[: len(made)] == made  # every run replayed, none made again
    assert all(run["budget"] == 0 for run in now[len(made) :])  # only the table's designs simulated
    store.close()


@pytest.mark.slow  # the real quick study: PPO and SAC on B1 on two envs, GA runs at 230 and 260 km/h
def test_rl_amortised_quick(tmp_path, monkeypatch):
    _check_study(rl_amortised.Config(out=tmp_path), tmp_path, monkeypatch)


def test_break_even_counts_the_policys_simulation_per_speed():
    assert rl_analysis.break_even(1000.0, 101.0) == 10.0  # 10 x 101 = 1010 >= 1000 + 10
    assert rl_analysis.break_even(1000.0, 100.0) == 11.0  # 10 x 100 < 1010; 11 x 100 >= 1011
    assert rl_analysis.break_even(1000.0, 1.0) == math.inf


def test_the_ledger_charges_the_ga_what_it_needed_to_reach_the_policys_sigma():
    curves = [
        {"problem": "P", "speed_kmh": 230.0, "simulations": 1.0, "best_sigma_N": 30.0},
        {"problem": "P", "speed_kmh": 230.0, "simulations": 40.0, "best_sigma_N": 25.0},
        {"problem": "P", "speed_kmh": 230.0, "simulations": 300.0, "best_sigma_N": 20.0},
    ]
    assert rl_analysis.ga_simulations_to(curves, "P", 230.0, 26.0) == 40.0
    assert rl_analysis.ga_simulations_to(curves, "P", 230.0, 19.0) == math.inf
    designs = [
        {
            "problem": "P",
            "design": "reference",
            "seed": -1,
            "speed_kmh": 230.0,
            "held_out": 1,
            "sigma_N": 32.0,
        },
        {"problem": "P", "design": "ga", "seed": 0, "speed_kmh": 230.0, "held_out": 1, "sigma_N": 20.0},
        {"problem": "P", "design": "sac", "seed": 0, "speed_kmh": 230.0, "held_out": 1, "sigma_N": 26.0},
    ]
    ga_runs = [{"problem": "P", "speed_kmh": 230.0, "n_simulations": 1000}]
    steps = [{"problem": "P", "learner": "sac", "seed": 0}] * 500
    ledger = rl_analysis.amortisation_ledger(designs, curves, ga_runs, steps, n_speeds=(1, 10))
    first, tenth = ledger
    assert first["gap_percent"] == pytest.approx(30.0)
    costs = ("training_simulations", "ga_per_speed", "ga_per_speed_to_policy_sigma")
    assert [first[k] for k in costs] == [500.0, 1000.0, 40.0]
    assert first["break_even_full"] == 1.0  # one GA run of 1000 costs more than 500 + 1
    assert first["break_even_same_sigma"] == 13.0  # 13 x 40 = 520 >= 500 + 13
    totals = ("policy_simulations", "ga_simulations", "ga_simulations_to_policy_sigma")
    assert [tenth[k] for k in totals] == [510.0, 10000.0, 400.0]


def test_the_speeds_share_of_sigma_is_all_of_it_for_a_cubic_and_none_for_noise():
    rng = np.random.default_rng(0)
    speeds = rng.uniform(200.0, 320.0, 400)
    cubic = [
        {"feasible": 1, "speed_kmh": v, "sigma_N": 20.0 + 1e-5 * (v - 200.0) ** 3 - 0.1 * v} for v in speeds
    ]
    assert rl_analysis.speed_share(cubic) == pytest.approx(1.0, abs=1e-12)
    sigmas = rng.normal(30.0, 2.0, speeds.size)
    noise = [{"feasible": 1, "speed_kmh": v, "sigma_N": s} for v, s in zip(speeds, sigmas, strict=True)]
    assert rl_analysis.speed_share(noise) < 0.03  # four parameters fitted to 400 points of pure noise
    infeasible = [{**row, "feasible": 0, "sigma_N": math.nan} for row in cubic[:395]]
    assert math.isnan(rl_analysis.speed_share(infeasible + cubic[395:]))  # five feasible: too few to say


def test_the_drift_measures_the_way_from_the_first_designs_to_the_ga_optima():
    # The GA optima at two speeds average to (-10, -20) mm; a policy's designs move in a straight line from
    # the reference, (0, 0), to half-way, (-5, -10) mm, in pairs 1 mm either side of the line's point.
    designs = [
        {"problem": "P", "design": "ga", "x_m": "-0.008 -0.02"},
        {"problem": "P", "design": "ga", "x_m": "-0.012 -0.02"},
        {"problem": "P", "design": "reference", "x_m": "0 0"},
    ]
    direction = np.array([-0.010, -0.020])
    steps = []
    for step in range(100):
        x = 0.5 * (step // 2) / 49 * direction + (1e-3 if step % 2 else -1e-3)
        steps.append(
            {"problem": "P", "learner": "ppo", "seed": 0, "step": step, "speed_kmh": 200.0 + step,
             "feasible": 1, "sigma_N": 30.0, "x_m": " ".join(f"{v:.9g}" for v in x)}
        )  # fmt: skip
    (row,) = rl_analysis.design_drift(steps[::-1], designs, window=10)  # any order of the steps
    full = 1e3 * math.hypot(*direction)
    first, last = 0.5 * 2 / 49, 0.5 * 47 / 49  # the windows' mean pairs: 0-4 and 45-49
    assert row["to_ga_first_mm"] == pytest.approx((1.0 - first) * full)
    assert row["to_ga_last_mm"] == pytest.approx((1.0 - last) * full)
    assert row["covered_percent"] == pytest.approx(100.0 * (last - first) / (1.0 - first))
    # a variable's variance over a window: 1 mm² from the pairs, and its pairs' points' spread along the line
    variances = [1.0 + (0.5 * d / 49) ** 2 * np.var(range(5)) for d in 1e3 * direction]
    assert row["spread_first_mm"] == pytest.approx(math.sqrt(np.mean(variances)))
    assert row["spread_last_mm"] == pytest.approx(row["spread_first_mm"])
    assert math.isnan(row["speed_share_percent"])  # σ does not vary


def test_a_missing_value_reads_as_the_tables_word_for_it():
    rows = [{"a": math.nan, "b": 1.0}]
    table = markdown_table(rows, [("a", "A", ".2f"), ("b", "B", ".1f")])
    assert table == "| A | B |\n|---|---|\n| nan | 1.0 |"
    assert markdown_table(rows, [("a", "A", ".2f")], missing="–").endswith("| – |")


def test_a_problem_whose_reference_is_not_action_0_is_refused():
    rl_amortised.check_starts_at_reference("B1")
    rl_amortised.check_starts_at_reference("synthetic-speed-quadratic")
    with pytest.raises(ValueError, match="B2"):
        rl_amortised.check_starts_at_reference("B2")


def test_a_full_run_is_reproduced_by_the_catenary_optimize_command_beside_its_policy(tmp_path):
    """The full setting trains with the learners' defaults, so the command written beside each policy is a
    ``catenary optimize`` that makes the same run (the same env, options and budget: it resumes it)."""
    import argparse
    import dataclasses
    import shlex

    from optimizers.cli.optimize import add_arguments, rl_env_spec
    from optimizers.rl import LEARNERS, EnvSpec

    config = rl_amortised.Config(full=True, out=tmp_path)
    store, policy = tmp_path / "runs.sqlite", tmp_path / "sac.zip"
    command = rl_amortised.reproduce_command(config, store, "B1", "sac", 2, policy)
    words = shlex.split(command)
    assert words[:2] == ["catenary", "optimize"]
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    args = parser.parse_args(words[2:])
    assert (args.optimizer, args.budget, args.seed, args.store) == ("sac", 10_000, 2, str(store))
    expected = EnvSpec("Catenary-B1-v0", None, rl_amortised.SPEED_RANGE, "study", rl_amortised.HELD_OUT)
    assert rl_env_spec("B1", args) == expected
    assert dataclasses.replace(LEARNERS["sac"](), n_envs=args.workers) == config.learner_options("sac")


def test_the_study_resumes_from_its_run_archive_on_a_fresh_checkout(tmp_path, monkeypatch):
    """With ``archive``, each GA run and policy is archived as it finishes; another checkout (another out
    folder, no store) restores them and writes the same steps, its policies replayed, not trained anew: it
    simulates only the designs the study evaluates outside its runs (the policies' and GA's designs at
    each speed)."""
    archive = tmp_path / "archive"
    simulate, calls = synthetic.simulate_quadratic, []
    monkeypatch.setattr(
        synthetic, "simulate_quadratic", lambda p, x, *a: calls.append(x) or simulate(p, x, *a)
    )

    def study(out: Path) -> Path:
        config = rl_amortised.Config(
            out=out, problems=("synthetic-speed-quadratic",), envs=1, workers=1, seeds=(0,), archive=archive
        )
        return rl_amortised.main(config)

    first = study(tmp_path / "a")
    made, calls[:] = len(calls), []
    files = sorted(p.name.split("-seed")[0] for p in archive.glob("*/*.json.gz"))
    config = rl_amortised.Config(problems=("synthetic-speed-quadratic",))
    assert files == sorted(["ga"] * len(config.speeds) + list(config.learners))
    second = study(tmp_path / "b")
    runs = (
        sum(r["n_simulations"] for r in read_csv(first / "ga_runs.csv"))
        + len(config.learners) * config.policy_budget
    )
    assert len(calls) == made - runs
    n_runs = len(config.speeds) + len(config.learners)  # what the archive's runs cost, written beside
    cost = (first / "cost.md").read_text(encoding="utf-8")
    assert f"| all | {n_runs} | {int(runs):,} | {int(runs):,} |" in cost
    assert (second / "steps.csv").read_text(encoding="utf-8") == (first / "steps.csv").read_text(
        encoding="utf-8"
    )
    assert (second / "ga_runs.csv").read_text(encoding="utf-8") == (first / "ga_runs.csv").read_text(
        encoding="utf-8"
    )


def test_a_negative_seed_is_refused_before_anything_runs():
    with pytest.raises(ValueError, match=r"seeds = \(0, -1\): each must lie in \[0, 2\*\*32 - 1\]"):
        rl_amortised.Config(seeds=(0, -1))
