"""Studies 4 and 5 (docs/problems.md, 'Experiments') end to end in their quick setting: the files they write,
their re-making from the data alone, and their resumption from the run store without simulating again.

The quick settings simulate on the "test" fidelity with budgets of about ten simulations: a smoke test of
the machinery, not of the results.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

pytest.importorskip("matplotlib", reason="the studies' figures need matplotlib")
pytest.importorskip("nevergrad", reason="the optimiser comparison runs nevergrad's optimisers")
pytest.importorskip("gymnasium", reason="PPO trains on the design environments")
pytest.importorskip("stable_baselines3", reason="PPO comes from stable-baselines3")

from catenary_env.problems.design_problem import DesignProblem  # noqa: E402
from experiments import optimizer_comparison, rl_studies  # noqa: E402
from experiments.common import read_csv  # noqa: E402
from experiments.iohprofiler import IOHRun, improvement_lines, read_dat  # noqa: E402


def _columns(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines()[0].split(",")


def _no_simulation(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make any simulation of a design fail the test (calibrations of the uplift are not designs)."""

    def refuse(*args, **kwargs):
        raise AssertionError("a design was simulated")

    monkeypatch.setattr(DesignProblem, "evaluate", refuse)


def _remake_from_data(folder: Path, tmp_path: Path, module, outputs: list[str]) -> Path:
    """Copy only the CSV data to a new folder (no run store) and re-make the outputs there."""
    copy = tmp_path / "data_only"
    copy.mkdir()
    for csv in folder.glob("*.csv"):
        shutil.copy(csv, copy)
    for name in outputs:
        (copy / name).unlink(missing_ok=True)
    module.report(copy)
    return copy


def _check_ioh(root: Path, problems: tuple[str, ...], budget: int) -> int:
    """Every IOHprofiler JSON parses, points to a .dat file with one block per run; return the runs."""
    n_runs = 0
    for meta_path in sorted(root.glob("*/IOHprofiler_f*_*.json")):
        meta = json.loads(meta_path.read_text(encoding="utf-8"))
        assert meta["function_name"] in problems and meta["maximization"] is False
        assert meta["attributes"] == ["evaluations", "raw_y"]
        (scenario,) = meta["scenarios"]
        blocks = read_dat(meta_path.parent / scenario["path"])
        assert len(blocks) == len(scenario["runs"]) >= 1
        for run, block in zip(scenario["runs"], blocks, strict=True):
            evaluations = [e for e, _ in block]
            assert evaluations == sorted(set(evaluations))
            assert 1 <= evaluations[0] and evaluations[-1] <= budget
            assert run["evals"] == evaluations[-1]
            assert run["best"]["y"] == pytest.approx(min(y for _, y in block), rel=1e-9)
            assert len(run["best"]["x"]) == scenario["dimension"]
        n_runs += len(blocks)
    return n_runs


def test_optimizer_comparison_quick(tmp_path, monkeypatch):
    config = optimizer_comparison.Config(out=tmp_path)
    folder = optimizer_comparison.main(config)
    assert folder == tmp_path / "optimizers"
    assert _columns(folder / "evaluations.csv") == [
        "run", "optimizer", "problem", "seed", "index", "simulation", "sigma_N", "feasible", "charged",
        "cached", "wall_time_s", "simulation_time_s", "x_m",
    ]  # fmt: skip
    runs = read_csv(folder / "runs.csv")
    expected = len(config.problems) * len(optimizer_comparison.OPTIMIZERS) * len(config.seeds)
    assert len(runs) == expected
    for run in runs:
        if run["status"] == "done":
            assert run["n_simulations"] <= config.budget
        else:  # only NGOpt may be refused here, with its reason
            assert run["optimizer"] == "ngopt" and run["note"]
    summary = read_csv(folder / "summary.csv")
    assert {(r["problem"], r["optimizer"]) for r in summary} <= {
        (p, o) for p in config.problems for o in optimizer_comparison.OPTIMIZERS
    }
    assert (folder / "convergence.png").stat().st_size > 0
    assert "final σ (N): median [IQR]" in (folder / "optimizers.md").read_text(encoding="utf-8")
    assert _check_ioh(folder / "ioh", config.problems, config.budget) >= 1

    # the data alone re-make the table, the figure and the IOHprofiler files
    _no_simulation(monkeypatch)
    copy = _remake_from_data(folder, tmp_path, optimizer_comparison, ["summary.csv"])
    assert (copy / "convergence.png").stat().st_size > 0
    assert (copy / "summary.csv").read_text() == (folder / "summary.csv").read_text()
    assert _check_ioh(copy / "ioh", config.problems, config.budget) == _check_ioh(
        folder / "ioh", config.problems, config.budget
    )

    # run again on the same store: every run is replayed, nothing is simulated
    optimizer_comparison.main(config)
    assert (folder / "evaluations.csv").read_text() == (copy / "evaluations.csv").read_text()


def test_rl_studies_quick(tmp_path, monkeypatch):
    config = rl_studies.Config(out=tmp_path)
    folder = rl_studies.main(config)
    assert _columns(folder / "steps.csv") == [
        "part", "problem", "seed", "rollout_steps", "step", "speed_kmh", "feasible", "sigma_N", "reward",
        "x_m",
    ]  # fmt: skip
    steps_text = (folder / "steps.csv").read_text(encoding="utf-8")
    steps = read_csv(folder / "steps.csv")
    learning = [s for s in steps if s["part"] == "learning"]
    assert len(learning) == len(config.problems) * len(config.seeds) * config.learning_budget
    policy = [s for s in steps if s["part"] == "speed_policy"]
    assert len(policy) == len(config.problems) * config.policy_budget
    assert all(200.0 <= s["speed_kmh"] <= 320.0 for s in policy)
    for s in steps:  # reward −σ of a feasible design, else the −Fm penalty (below −σ of any feasible one)
        assert s["reward"] == pytest.approx(-s["sigma_N"]) if s["feasible"] else s["reward"] < -100.0
    speed = read_csv(folder / "speed_policy.csv")
    assert {r["speed_kmh"] for r in speed if r["design"] == "policy"} == set(config.sweep_kmh)
    robust = read_csv(folder / "robust.csv")
    assert {r["design"] for r in robust} >= {"reference", "mean_sigma"}
    for name in ("learning_curves.png", "speed_policy.png", "robust_design.png"):
        assert (folder / name).stat().st_size > 0
    text = (folder / "rl.md").read_text(encoding="utf-8")
    assert "### Speed-conditioned policy against GA optima" in text

    _no_simulation(monkeypatch)
    outputs = ["rl.md", "learning_curves.png", "speed_policy.png", "robust_design.png"]
    copy = _remake_from_data(folder, tmp_path, rl_studies, outputs)
    for name in outputs:
        assert (copy / name).stat().st_size > 0
    assert (copy / "rl.md").read_text() == text

    rl_studies.main(config)  # replayed from the store: nothing simulated
    assert (folder / "steps.csv").read_text(encoding="utf-8") == steps_text


def test_policy_start_is_refused_where_the_bounds_are_not_centred_on_the_reference():
    rl_studies.check_starts_at_reference("B1")
    with pytest.raises(ValueError, match="B2"):
        rl_studies.check_starts_at_reference("B2")


def test_ioh_lines_are_improvements_and_the_last_evaluation():
    run = IOHRun(0, ((1, 40.0, ()), (2, None, ()), (3, 38.0, ()), (4, 39.0, ()), (5, None, ())))
    # the last evaluation is infeasible: its line carries the best σ so far
    assert improvement_lines(run) == [(1, 40.0), (3, 38.0), (5, 38.0)]
    assert improvement_lines(IOHRun(0, ((1, None, ()),))) == []


def test_ioh_reader_refuses_a_foreign_header(tmp_path):
    path = tmp_path / "IOHprofiler_f2_DIM5.dat"
    path.write_text("evaluations raw_y\n1 40.0\n3 38.5\nevaluations raw_y\n2 41.0\n")
    assert read_dat(path) == [[(1, 40.0), (3, 38.5)], [(2, 41.0)]]
    path.write_text('"function evaluation" "current f(x)"\n1 40.0\n')
    with pytest.raises(ValueError, match="evaluations raw_y"):
        read_dat(path)


def test_a_lane_of_the_full_studies_names_its_problems():
    """experiments/full_studies.sh runs each study on one problem at a time (``--problems``) in two lanes,
    then both studies on both problems."""
    assert rl_studies.Config(full=True).problems == ("B1", "SW1")
    assert rl_studies.Config().problems == ("B1",)
    assert rl_studies.Config(full=True, problems=("SW1",)).problems == ("SW1",)
    with pytest.raises(SystemExit):  # argparse refuses a name that is no design problem
        rl_studies.cli(["--problems", "X9"])
    with pytest.raises(SystemExit):
        optimizer_comparison.cli(["--problems", "X9"])


def test_the_comparison_runs_the_optimisers_it_is_given(tmp_path):
    """``--optimizers``: two processes with disjoint sets share a problem's runs (full_studies.sh)."""
    folder = optimizer_comparison.main(
        optimizer_comparison.Config(out=tmp_path, problems=("B1",), optimizers=("random",))
    )
    runs = read_csv(folder / "runs.csv")
    assert {(r["optimizer"], r["problem"], r["status"]) for r in runs} == {("random", "B1", "done")}
    assert [r["seed"] for r in runs] == [0, 1]
    with pytest.raises(SystemExit):
        optimizer_comparison.cli(["--optimizers", "nelder-mead"])


def _run_full_studies(tmp_path: Path, fail: str = "") -> tuple[subprocess.CompletedProcess, list[str]]:
    """experiments/full_studies.sh with a stand-in ``python`` that logs its arguments (and fails on
    those containing ``fail``): the commands it runs, each study's in the order it runs them. The
    stand-in also logs each command with its parent's process id to ``lanes.txt``: one id per lane."""
    bin_dir, log = tmp_path / "bin", tmp_path / "calls.txt"
    bin_dir.mkdir()
    stub = bin_dir / "python"
    failing = f'case "$*" in *"{fail}"*) exit 3;; esac\n' if fail else ""
    lanes = f'echo "$PPID $*" >> {tmp_path / "lanes.txt"}\n'
    stub.write_text(f'#!/bin/sh\necho "$*" >> {log}\n{lanes}{failing}')
    stub.chmod(0o755)
    script = Path(__file__).parents[1] / "experiments" / "full_studies.sh"
    run = subprocess.run(
        ["bash", str(script), str(tmp_path / "out"), "2"],
        env={"PATH": f"{bin_dir}:/usr/bin:/bin"}, capture_output=True, text=True, check=False,
    )  # fmt: skip
    return run, log.read_text().splitlines() if log.exists() else []


def test_the_full_studies_script_runs_every_study_in_its_order(tmp_path):
    run, calls = _run_full_studies(tmp_path)
    assert run.returncode == 0, run.stderr
    assert run.stderr == ""
    out = f"--out {tmp_path / 'out'}"
    assert calls[:2] == [
        f"-m experiments.design_studies --full --problems B1 SW1 --workers 2 {out}",
        f"-m experiments.design_studies --full --problems B2 SW2 B3 SW3 --workers 2 {out}",
    ]
    compared = []  # (problem, optimiser) of every comparison command
    for call in (c.split() for c in calls[2:7] if "optimizer_comparison" in c):
        named = (
            call[call.index("--optimizers") + 1 : call.index("--workers")] if "--optimizers" in call else None
        )
        compared += [
            (call[call.index("--problems") + 1], o) for o in named or optimizer_comparison.OPTIMIZERS
        ]
    assert sorted(compared) == sorted(
        (p, o) for p in ("B1", "SW1") for o in optimizer_comparison.OPTIMIZERS
    )  # each run once
    lanes: dict[str, list[str]] = {}  # the lanes' commands by the lane's process id, in order
    for line in (tmp_path / "lanes.txt").read_text().splitlines()[2:7]:
        pid, command = line.split(" ", 1)
        lanes.setdefault(pid, []).append(command.split()[1])
    assert len(lanes) == 2
    for studies in lanes.values():  # each lane: its share of the comparison, the headline, then RL
        assert studies[-1] == "experiments.rl_studies"
        assert set(studies[:-1]) == {"experiments.optimizer_comparison"}
    assert calls[7:] == [
        f"-m experiments.optimizer_comparison --full --workers 2 {out}",
        f"-m experiments.rl_studies --full --workers 2 {out}",
        f"-m catenary_env.cli report --out {tmp_path / 'out'}",
    ]


def test_the_full_studies_script_stops_when_a_lane_fails(tmp_path):
    run, calls = _run_full_studies(tmp_path, fail="experiments.optimizer_comparison --full --problems B1")
    assert run.returncode == 1
    assert run.stderr.strip().startswith("a lane failed")
    assert not any("rl_studies --full --problems B1" in c for c in calls)  # the rest of its lane
    assert any("rl_studies --full --problems SW1" in c for c in calls)  # the other lane ran
    assert len(calls) == 5  # and nothing after the lanes


def test_an_interrupted_study_entry_point_ends_in_one_line(capsys):
    """``python -m experiments.X`` (the lanes of full_studies.sh) ends on Ctrl-C as ``catenary`` does."""
    from experiments.common import run_cli

    def interrupted() -> int:
        raise KeyboardInterrupt

    assert run_cli(interrupted, "experiments.x") == 130
    assert capsys.readouterr().err.strip() == "experiments.x: interrupted; run it again to resume"


def test_the_full_mean_sigma_ga_makes_ten_generations_within_its_budget():
    config = rl_studies.Config(full=True)
    options = config.mean_ga_options
    children = options.population_size - options.elite_count  # evaluated per generation
    assert (config.mean_budget - options.population_size) / children >= 10
