"""Studies 4 and 5 (docs/problems.md, 'Experiments') end to end: the files they write, their re-making from
the data alone, and their resumption from the run store without simulating again.

The optimiser comparison runs on the synthetic problem (optimizers/synthetic.py) in every run; the real
quick settings (the "test" fidelity, budgets of about ten simulations, PPO) are behind the ``slow`` marker
(``python -m pytest -m slow``): a smoke test of the machinery, not of the results.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
import sqlite3
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib", reason="the studies' figures need matplotlib")
pytest.importorskip("nevergrad", reason="the optimiser comparison runs nevergrad's optimisers")
pytest.importorskip("gymnasium", reason="PPO trains on the design environments")
pytest.importorskip("stable_baselines3", reason="PPO comes from stable-baselines3")

from catenary_env.problems.design_problem import DesignProblem  # noqa: E402
from experiments import optimizer_comparison, rl_studies  # noqa: E402
from experiments.common import config_from, read_csv, study_parser  # noqa: E402
from experiments.iohprofiler import INFEASIBLE_Y, IOHRun, evaluation_lines, read_dat  # noqa: E402
from optimizers import synthetic  # noqa: E402
from optimizers.store import RunStore, StoreError  # noqa: E402
from optimizers.synthetic import get_synthetic_problem  # noqa: E402

SYNTHETIC = "synthetic-quadratic"


def _columns(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines()[0].split(",")


def _no_simulation(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make any simulation of a design, catenary or synthetic, fail the test (calibrations of the uplift
    are not designs)."""

    def refuse(*args, **kwargs):
        raise AssertionError("a design was simulated")

    monkeypatch.setattr(DesignProblem, "evaluate", refuse)
    monkeypatch.setattr(DesignProblem, "evaluate_speeds", refuse)
    monkeypatch.setattr(synthetic, "simulate_quadratic", refuse)


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


def _check_comparison(config: optimizer_comparison.Config, tmp_path: Path, monkeypatch) -> None:
    """Run the comparison and check what it writes, its re-making from the data alone and its replay from
    the run store without simulating."""
    folder = optimizer_comparison.main(config)
    assert folder == tmp_path / "optimizers"
    assert _columns(folder / "evaluations.csv") == [
        "run", "optimizer", "problem", "seed", "index", "simulation", "sigma_N", "feasible", "charged",
        "cached", "wall_time_s", "simulation_time_s", "x_m",
    ]  # fmt: skip
    runs = read_csv(folder / "runs.csv")
    assert len(runs) == len(config.problems) * len(config.optimizers) * len(config.seeds)
    for run in runs:
        if run["status"] == "done":
            assert run["n_simulations"] <= config.budget
        else:  # only NGOpt may be refused here, with its reason
            assert run["optimizer"] == "ngopt" and run["note"]
    summary = read_csv(folder / "summary.csv")
    assert {(r["problem"], r["optimizer"]) for r in summary} <= {
        (p, o) for p in config.problems for o in config.optimizers
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


def test_the_comparison_machinery_on_a_synthetic_problem(tmp_path, monkeypatch):
    """Every optimiser but PPO (which needs a design env) on the synthetic problem: microseconds a
    simulation, the same runs, store, tables, figure and IOHprofiler files as on B1."""
    optimizers = tuple(o for o in optimizer_comparison.OPTIMIZERS if o != "ppo")
    config = optimizer_comparison.Config(out=tmp_path, problems=(SYNTHETIC,), optimizers=optimizers)
    _check_comparison(config, tmp_path, monkeypatch)
    reference = read_csv(tmp_path / "optimizers" / "reference.csv")
    level = get_synthetic_problem(SYNTHETIC).sigma(np.zeros(3))
    assert [(r["problem"], r["sigma_N"]) for r in reference] == [(SYNTHETIC, pytest.approx(float(level)))]


@pytest.mark.slow  # the real quick study: about 300 simulations on B1 and SW1, and PPO
def test_optimizer_comparison_quick(tmp_path, monkeypatch):
    _check_comparison(optimizer_comparison.Config(out=tmp_path), tmp_path, monkeypatch)


@pytest.mark.slow  # the real quick study: PPO, GA runs at four speeds and the mean-σ GA on B1
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


def test_the_committed_rl_data_remake_the_committed_report(tmp_path, monkeypatch):
    """The RL study's tables and figures come from its CSV files alone (PPO needs a design env, so its
    machinery has no synthetic stand-in: the real quick run is the slow test above)."""
    committed = Path(__file__).parents[1] / "results" / "rl"
    _no_simulation(monkeypatch)
    outputs = ["rl.md", "learning_curves.png", "speed_policy.png", "robust_design.png"]
    copy = _remake_from_data(committed, tmp_path, rl_studies, outputs)
    assert (copy / "rl.md").read_text(encoding="utf-8") == (committed / "rl.md").read_text(encoding="utf-8")
    for name in outputs[1:]:
        assert (copy / name).stat().st_size > 0


def test_policy_start_is_refused_where_the_bounds_are_not_centred_on_the_reference():
    rl_studies.check_starts_at_reference("B1")
    with pytest.raises(ValueError, match="B2"):
        rl_studies.check_starts_at_reference("B2")


def test_ioh_lines_are_every_evaluation_an_infeasible_one_at_the_penalty():
    run = IOHRun(0, ((1, 40.0, ()), (2, None, ()), (3, 38.0, ()), (4, 39.0, ()), (5, None, ())))
    assert evaluation_lines(run) == [(1, 40.0), (2, INFEASIBLE_Y), (3, 38.0), (4, 39.0), (5, INFEASIBLE_Y)]
    assert evaluation_lines(IOHRun(0, ((1, None, ()),))) == [(1, INFEASIBLE_Y)]


@pytest.mark.parametrize(("folder", "n_runs"), [("optimizers", 70), ("full-protocol/optimizers", None)])
def test_iohinspector_loads_every_committed_run_in_full(folder, n_runs):
    """IOH's own reader (iohinspector 0.0.8) finds every run of the committed comparisons (the five-seed one,
    70 runs, and the full protocol's finished runs), each with all its simulations from evaluation 1, and
    its best σ."""
    iohinspector = pytest.importorskip("iohinspector")
    import polars as pl

    root = Path(__file__).resolve().parents[1] / "results" / folder
    manager = iohinspector.DataManager()
    for path in sorted((root / "ioh").glob("*/IOHprofiler_f*_*.json")):
        manager.add_json(str(path))
    data = manager.load(monotonic=False, include_meta_data=True)
    runs = data.group_by(["algorithm_name", "function_name", "run_id"]).agg(
        pl.col("evaluations").min().alias("first"), pl.col("evaluations").max().alias("last"),
        pl.len().alias("lines"), pl.col("raw_y").min().alias("best"),
    )  # fmt: skip
    done = [r for r in read_csv(root / "runs.csv") if r["status"] == "done"]
    assert runs.height == len(done) == (n_runs or len(done)) > 0
    assert set(runs["first"]) == {1} and runs["lines"].to_list() == runs["last"].to_list()
    expected = sorted((r["optimizer"], r["problem"], r["n_simulations"], r["best_sigma_N"]) for r in done)
    found = sorted(
        zip(runs["algorithm_name"], runs["function_name"], runs["last"], runs["best"], strict=True)
    )
    for (o, p, n, best), (o2, p2, n2, best2) in zip(expected, found, strict=True):
        assert (o, p, n) == (o2, p2, n2) and best2 == pytest.approx(best, abs=1e-9)


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
        optimizer_comparison.Config(out=tmp_path, problems=(SYNTHETIC,), optimizers=("random",))
    )
    runs = read_csv(folder / "runs.csv")
    assert {(r["optimizer"], r["problem"], r["status"]) for r in runs} == {("random", SYNTHETIC, "done")}
    assert [r["seed"] for r in runs] == [0, 1]
    with pytest.raises(SystemExit):
        optimizer_comparison.cli(["--optimizers", "nelder-mead"])


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


# -- the results of a protocol still running, written from the store alone (--from-store) --------------------


def _store_counts(path: Path) -> tuple[int, int, int]:
    """Runs, evaluations and finished runs in a store file."""
    with sqlite3.connect(path) as connection:
        runs, finished = connection.execute("SELECT count(*), count(stop_reason) FROM runs").fetchone()
        (evaluations,) = connection.execute("SELECT count(*) FROM evaluations").fetchone()
    return runs, evaluations, finished


def _interrupt(path: Path, optimizer: str, seed: int, kept: int) -> None:
    """Make a finished run of the store look like one killed after ``kept`` evaluations."""
    with sqlite3.connect(path) as connection:
        (run_id,) = connection.execute(
            "SELECT run_id FROM runs WHERE optimizer = ? AND seed = ?", (optimizer, seed)
        ).fetchone()
        connection.execute(
            "UPDATE runs SET finished_at = NULL, stop_reason = NULL WHERE run_id = ?", (run_id,)
        )
        connection.execute("DELETE FROM evaluations WHERE run_id = ? AND idx >= ?", (run_id, kept))


def test_from_store_writes_the_finished_runs_and_simulates_nothing(tmp_path, monkeypatch):
    """A store with finished runs, a run killed part-way and runs never started: ``--from-store`` writes
    the finished runs' rows as the full study writes them, lists the others as not run yet with the
    simulations the store holds, and neither simulates nor starts nor resumes a run."""
    from experiments.cli.report import build_report

    made = optimizer_comparison.Config(
        out=tmp_path, problems=(SYNTHETIC,), optimizers=("random", "cma", "de", "ga")
    )
    folder = optimizer_comparison.main(made)
    full_rows = (folder / "evaluations.csv").read_text(encoding="utf-8").splitlines()
    store = tmp_path / "runs.sqlite"
    _interrupt(store, "cma", 1, kept=5)
    before = _store_counts(store)

    _no_simulation(monkeypatch)
    for name in ("optimize", "train_policy"):  # a resumed run would replay without simulating: refuse it too
        monkeypatch.setattr(optimizer_comparison, name, lambda *a, **k: pytest.fail("a run was made"))
    args = "--optimizers random cma de ga pso --from-store --out".split() + [str(tmp_path)]
    config = config_from(
        optimizer_comparison.Config, study_parser(optimizer_comparison, "x").parse_args(args)
    )
    assert config.from_store  # the option, declared once, as `catenary experiment optimizers` takes it too
    optimizer_comparison.main(dataclasses.replace(config, problems=(SYNTHETIC,)))  # (--problems: catalogue)
    assert _store_counts(store) == before  # nothing written to the store: no run started or resumed

    runs = {(r["optimizer"], int(r["seed"])): r for r in read_csv(folder / "runs.csv")}
    done = {key for key, r in runs.items() if r["status"] == "done"}
    assert done == {("random", 0), ("random", 1), ("cma", 0), ("de", 0), ("de", 1), ("ga", 0), ("ga", 1)}
    killed = runs[("cma", 1)]
    assert (killed["status"], killed["n_simulations"]) == ("not run yet", 5)  # CMA-ES charges each design
    assert "5 of its 12 simulations in the store" in killed["note"]
    for seed in (0, 1):
        assert (runs[("pso", seed)]["status"], runs[("pso", seed)]["n_simulations"]) == ("not run yet", 0)
    written = (folder / "evaluations.csv").read_text(encoding="utf-8").splitlines()
    kept = [full_rows[0]] + [
        r for r in full_rows[1:] if r.split(",")[1:4:2] != ["cma", "1"]
    ]  # optimizer, seed
    assert written == kept  # the finished runs' rows, as the study wrote them when it made the runs

    text = (folder / "optimizers.md").read_text(encoding="utf-8")
    assert text.startswith("Partial: 7 of 10 runs of the protocol finished")
    assert (
        f"- not run yet on {SYNTHETIC} (runs of each optimiser): cma 1 (5 simulations in the store), pso 2"
        in text
    )
    summary = {r["optimizer"]: r["runs"] for r in read_csv(folder / "summary.csv")}
    assert summary == {"random": 2, "cma": 1, "de": 2, "ga": 2}
    # CMA-ES, one run finished of its two, would leave the ranks one block: they are made without it
    assert (
        "### Ranks over 2 blocks (problem, seed) by final best σ (partial: 7 of 10 runs); left out until "
        "they have finished 2 runs (one problem's seeds): cma (1 finished)" in text
    )
    assert {p["a"] for p in read_csv(folder / "ranks.csv")} | {
        p["b"] for p in read_csv(folder / "ranks.csv")
    } == {"random", "de", "ga"}
    assert _check_ioh(folder / "ioh", (SYNTHETIC,), made.budget) == 7
    assert "Partial: 7 of 10 runs" in build_report(tmp_path).read_text(encoding="utf-8")  # catenary report
    shutil.copytree(folder, tmp_path / "full-protocol" / "optimizers")  # experiments/full_protocol.sh's
    report = build_report(tmp_path).read_text(encoding="utf-8")
    assert "\n## optimizers (full-protocol): " in report and report.count("Partial: 7 of 10 runs") == 2


def test_from_store_on_a_protocol_not_started_yet(tmp_path, monkeypatch):
    """Before the first run finishes: every run of the protocol not run yet (PPO not run on a problem whose
    bounds are not centred on its reference design), empty tables, and the model's stamp as for a full run."""
    from experiments.model_stamp import ModelStamp

    _no_simulation(monkeypatch)
    with pytest.raises(StoreError, match="no run store here"):
        optimizer_comparison.main(optimizer_comparison.Config(out=tmp_path, from_store=True))
    RunStore(tmp_path / "runs.sqlite").close()
    config = optimizer_comparison.Config(out=tmp_path, problems=("B1", "B2"), from_store=True)
    folder = optimizer_comparison.main(config)
    runs = read_csv(folder / "runs.csv")
    statuses = {(r["problem"], r["optimizer"], r["status"]) for r in runs}
    assert ("B2", "ppo", "not run") in statuses and ("B1", "ppo", "not run yet") in statuses
    assert {r["n_simulations"] for r in runs} == {0}
    assert read_csv(folder / "evaluations.csv") == [] and read_csv(folder / "summary.csv") == []
    assert not (folder / "convergence.png").exists()
    pending = sum(r["status"] == "not run yet" for r in runs)
    assert (folder / "optimizers.md").read_text(encoding="utf-8").startswith(f"Partial: 0 of {pending} runs")
    assert ModelStamp.read(folder) == ModelStamp.now(("benchmark",))


def test_from_store_finds_a_ppo_run_where_the_study_stores_it(tmp_path, monkeypatch):
    """The identity ``--from-store`` looks a PPO run up by is the one its training stores it under."""
    import optimizers.rl.training

    class Opened(Exception):
        pass

    def capture(store, config, resume, start_if_none=True):
        raise Opened(config)

    monkeypatch.setattr(optimizers.rl.training, "open_run", capture)
    config = optimizer_comparison.Config(out=tmp_path)
    with RunStore(":memory:") as store, pytest.raises(Opened) as opened:
        optimizer_comparison._run(store, config, "ppo", "B1", 1, "")
    assert optimizer_comparison._prepare(config, "ppo", "B1", 1).identity == opened.value.args[0]


def test_a_problem_without_a_reference_design_has_no_reference_row(tmp_path, monkeypatch):
    """B3 and SW3 cannot express the reference design (their droppers are variables): the comparison simulates
    no reference there (it asked for a design of NaN before, and stopped at B3)."""
    _no_simulation(monkeypatch)
    folder = optimizer_comparison.main(
        optimizer_comparison.Config(out=tmp_path, problems=("B3",), optimizers=())
    )
    assert read_csv(folder / "reference.csv") == []


def test_the_lanes_of_the_full_protocol_make_every_run_and_both_end_on_the_whole_protocol():
    """experiments/full_protocol.sh: between them the lanes' own parts make every run of the protocol, and
    each lane ends on the whole protocol, so that a lane done with its part takes the runs of the other's
    that nobody has started (a run the other lane is making is left to it: next test) instead of idling."""
    script = (Path(__file__).resolve().parents[1] / "experiments" / "full_protocol.sh").read_text(
        encoding="utf-8"
    )
    lanes: dict[str, list[set[tuple[str, str]]]] = {}
    for line in script.splitlines():
        words = line.split("#")[0].split()
        if words[:1] != ["comparison"] or not words[1].startswith('"$OUT/lanes/'):
            continue
        options = " ".join(words[2:]).split("--")[1:]
        given = {o.split()[0]: o.split()[1:] for o in options}
        problems = given.get("problems", list(optimizer_comparison.FULL_PROBLEMS))
        optimizers = given.get("optimizers", list(optimizer_comparison.OPTIMIZERS))
        lanes.setdefault(words[1], []).append({(p, o) for p in problems for o in optimizers})
    protocol = {(p, o) for p in optimizer_comparison.FULL_PROBLEMS for o in optimizer_comparison.OPTIMIZERS}
    assert len(lanes) == 2
    made = set().union(*(stage for stages in lanes.values() for stage in stages[:-1]))
    # PPO only where its start is the reference design (B1 and SW1)
    assert {r for r in protocol if r[1] != "ppo"} | {("B1", "ppo"), ("SW1", "ppo")} <= made
    assert all(stages[-1] == protocol for stages in lanes.values())


def test_a_run_another_process_is_making_is_left_to_it(tmp_path, claimed_elsewhere):
    """Two lanes sharing one store: a run that another process holds (:meth:`RunStore.claim`) is a line "not
    run yet" in this one's table, neither made nor read here; once released, this one makes it."""
    comparison = optimizer_comparison
    config = comparison.Config(out=tmp_path, problems=(SYNTHETIC,), optimizers=("random",))
    identity = comparison._prepare(config, "random", SYNTHETIC, 0).identity
    with RunStore(tmp_path / "runs.sqlite") as store:
        with claimed_elsewhere(store.path, identity):
            with store.claim(identity) as held:
                assert not held
            row, rows = comparison._protocol_run(store, config, "random", SYNTHETIC, 0)
            assert (row["status"], row["note"], rows) == ("not run yet", comparison.ANOTHER_PROCESS, [])
            assert store.find_run(identity) is None
        row, rows = comparison._protocol_run(store, config, "random", SYNTHETIC, 0)  # held, then made, here
        assert row["status"] == "done" and len(rows) == config.budget
