"""The benchmark's parts (issue 26): constraint values beside σ, the store's schema upgrade, the best-known
designs, the fixed-target and rank views, the dataset export and the ioh wrapper."""

from __future__ import annotations

import math
import sqlite3

import gymnasium as gym
import numpy as np
import pytest

from catenary_env.pipeline import CONSTRAINTS
from catenary_env.problems import PROBLEMS, get_problem
from experiments import benchmark_views as bv
from experiments import best_known
from experiments.common import read_csv
from optimizers import RunStore, optimize
from optimizers.catenary_adapter import STATISTICS, simulate_catenary_design
from optimizers.store import SCHEMA_VERSION

# -- constraint values ----------------------------------------------------------------------------------


def test_constraint_values_say_what_feasibility_says():
    """On the test model: the level wire is feasible with every constraint <= 0; a wire raised by 20 mm
    at the supports compresses a dropper, which the first constraint measures in N (as the reason does);
    the env's info carries the same values by name."""
    problem = get_problem("B1")
    feasible = problem.evaluate([0.0] * 5, 300.0, "test")
    assert feasible.feasible and len(feasible.constraints) == len(CONSTRAINTS)
    assert all(value <= 0.0 for value in feasible.constraints)
    assert feasible.constraints[2] == feasible.statistics.contact_loss_percent == 0.0
    compressed = problem.evaluate([0.02, -0.02, 0.02, 0.0, 0.0], 300.0, "test")
    assert not compressed.feasible and "compression" in compressed.reason
    assert compressed.constraints[0] > 0.0 and math.isnan(compressed.constraints[2])  # no passage
    assert f"{-compressed.constraints[0]:.2f} N" in compressed.reason
    outcome = simulate_catenary_design("B1", (0.0,) * 5, 300.0, "test")  # what an optimiser's run stores
    assert outcome.constraints == feasible.constraints and len(outcome.statistics) == len(STATISTICS)
    assert outcome.statistics[STATISTICS.index("std")] == outcome.sigma == feasible.statistics.std
    env = gym.make("Catenary-B1-v0", fidelity="test", n_spans=5)
    env.reset(seed=0)
    info = env.step(np.zeros(5, np.float32))[4]
    assert set(info["constraints"]) == set(CONSTRAINTS)
    assert (max(info["constraints"].values()) <= 0.0) == info["feasible"]


def test_a_version_1_store_is_read_as_it_is_and_upgraded_for_writing(tmp_path):
    path = tmp_path / "runs.sqlite"
    with RunStore(path) as store:
        optimize("synthetic-quadratic", "random", budget=5, seed=0, fidelity="test", store=store)
    with sqlite3.connect(path) as connection:  # what a store of schema version 1 looked like
        connection.execute("ALTER TABLE evaluations DROP COLUMN constraints")
        connection.execute("ALTER TABLE evaluations DROP COLUMN statistics")
        connection.execute("PRAGMA user_version = 1")
    with RunStore(path, read_only=True) as store:
        assert store.schema_version == 1
        assert [row["constraints"] for row in store.all_evaluations()] == [()] * 5
    with RunStore(path) as store:
        assert store.schema_version == SCHEMA_VERSION == 2
        resumed = optimize("synthetic-quadratic", "random", budget=5, seed=0, fidelity="test", store=store,
                           resume=True)  # fmt: skip
        assert [record.constraints for record in resumed.history] == [()] * 5  # as stored, not re-simulated
        assert [record.statistics for record in resumed.history] == [()] * 5
    with sqlite3.connect(path) as connection:
        assert connection.execute("PRAGMA user_version").fetchone()[0] == 2


# -- best-known designs ---------------------------------------------------------------------------------


def test_every_problem_with_variables_has_a_confirmed_best_known_design():
    for name in ("B1", "B2", "B3", "SW1", "SW2", "SW3"):
        problem = PROBLEMS[name]
        best = problem.best_known
        assert best is not None and best.fidelity == "study" and best.speed_kmh == 300.0, name
        assert np.allclose(problem.snap(best.x), best.x) and not problem.out_of_bounds(best.x), name
        assert best.confirmed_fidelity == "reference"
        assert abs(best.confirmed_sigma_N / best.sigma_N - 1.0) < 0.005, name  # the span-mode contract
        assert best.gap(1.02 * best.sigma_N) == pytest.approx(0.02)
    assert PROBLEMS["BPresag"].best_known is None


def test_the_best_known_search_reads_the_design_study_and_both_comparisons(tmp_path):
    """The lowest feasible σ wins wherever it was found; an infeasible row never does."""
    results = tmp_path / "results"
    history = results / "design" / "SW1" / "history.csv"
    history.parent.mkdir(parents=True)
    history.write_text("index,feasible,sigma_N,dh_1,dh_2,dh_3,dh_4\n7,1,22.0,-0.01,0,0,0\n", encoding="utf-8")
    header = "run,optimizer,problem,seed,index,feasible,sigma_N,x_m\n"
    for folder, row in [
        ("optimizers", "3,cma,SW1,0,5,1,21.5,-0.01 0 0 -0.002\n"),
        ("full-protocol/optimizers", "9,tpe,SW1,4,12,1,21.2,-0.01 -0.001 0 0\n4,gp,SW1,1,2,0,1.0,0 0 0 0\n"),
    ]:
        (results / folder).mkdir(parents=True)
        (results / folder / "evaluations.csv").write_text(header + row, encoding="utf-8")
    found = sorted(best_known.candidates(results, "SW1"))
    assert [sigma for sigma, _, _ in found] == [21.2, 21.5, 22.0]
    assert found[0][1] == (-0.01, -0.001, 0.0, 0.0)
    assert "tpe seed 4 (results/full-protocol/optimizers, run 9, evaluation 12)" in found[0][2]
    assert best_known.candidates(results, "B1") == []


def test_the_best_known_design_is_served_only_for_its_model(monkeypatch):
    problem = get_problem("B1")
    monkeypatch.setattr(type(problem), "store_fingerprint", lambda self: "another-model")
    assert problem.best_known is None


# -- views ----------------------------------------------------------------------------------------------


def test_ert_is_all_simulations_over_the_successes():
    assert bv.expected_running_time([(10, True), (300, False), (40, True)]) == 175.0
    assert bv.expected_running_time([(300, False)]) == math.inf
    curves = np.array([[5.0, 3.0, 1.0, 1.0], [4.0, 4.0, 4.0, 4.0]])
    assert bv.runtimes(curves, [4, 3], 3.0) == [(2, True), (3, False)]


def test_holm_adjusts_step_down_and_keeps_the_order():
    assert bv.holm([0.01, 0.04, 0.03]) == pytest.approx([0.03, 0.06, 0.06])


def test_ranks_find_a_clear_winner_and_the_ecdf_counts_targets():
    blocks = [("P", seed) for seed in range(8)]
    finals = {"good": {b: 1.0 + 0.01 * b[1] for b in blocks}, "mid": {b: 2.0 for b in blocks},
              "bad": {b: math.inf for b in blocks}}  # fmt: skip
    friedman, pairs = bv.rank_tests(finals)
    assert friedman["mean_ranks"] == {"bad": 3.0, "good": 1.0, "mid": 2.0} and friedman["p_value"] < 0.01
    assert {(p["better"], p["significant"]) for p in pairs} == {("good", True), ("mid", True)}
    curves = {"P": {"a": np.array([[3.0, 1.0, 1.0]])}}
    shares = bv.ecdf(curves, {"P": {"a": [3]}}, {"P": 1.0}, 3)
    assert shares["a"].tolist() == [0.0, 1.0, 1.0]


def test_ranks_of_an_unequal_set_are_those_of_the_blocks_every_optimiser_has():
    """A partial set of runs (a protocol still running): an optimiser with fewer runs, one problem that only
    some optimisers reached. The tests are made on the common blocks and are the same as on those alone;
    with fewer than MIN_BLOCKS of them, none are made."""
    blocks = [("P", seed) for seed in range(6)]
    full = {"good": {b: 1.0 + 0.01 * b[1] for b in blocks}, "mid": {b: 2.0 + 0.02 * b[1] for b in blocks},
            "bad": {b: 3.0 - 0.01 * b[1] for b in blocks}}  # fmt: skip
    unequal = {name: dict(by_block) for name, by_block in full.items()}
    for seed in (4, 5):  # "mid" has not finished these runs yet
        del unequal["mid"][("P", seed)]
    unequal["good"][("Q", 0)] = unequal["bad"][("Q", 0)] = 0.5  # a second problem reached by two of the three
    common = [("P", seed) for seed in range(4)]
    assert bv.common_blocks(unequal) == common
    restricted = {name: {b: by_block[b] for b in common} for name, by_block in unequal.items()}
    assert bv.rank_tests(unequal) == bv.rank_tests(restricted)
    assert bv.rank_tests(unequal)[0]["blocks"] == 4
    del unequal["mid"][("P", 1)], unequal["mid"][("P", 2)], unequal["mid"][("P", 3)]
    assert bv.common_blocks(unequal) == [("P", 0)] and bv.common_blocks({}) == []
    with pytest.raises(ValueError, match="1 block"):
        bv.rank_tests(unequal)


def test_an_optimiser_not_run_on_every_problem_gets_ranks_with_and_without_it(tmp_path):
    """As PPO, which runs on B1 and SW1 only: the ranks with it are over the problems it runs on; a second
    section ranks the others over every problem's blocks."""
    from experiments.benchmark_report import DONE, NOT_RUN, views

    finals = {"good": 1.0, "mid": 2.0, "bad": 3.0, "narrow": 2.5}
    curves, runs = {}, []
    for problem in ("P", "Q"):
        for optimizer, final in finals.items():
            if optimizer == "narrow" and problem == "Q":
                runs.append({"status": NOT_RUN, "problem": problem, "optimizer": optimizer})
                continue
            curves.setdefault(problem, {})[optimizer] = np.array([[5.0, final + 0.01 * s] for s in range(4)])
            run = {"status": DONE, "problem": problem, "optimizer": optimizer, "n_simulations": 2}
            runs += [{**run, "seed": s, "budget": 2, "fidelity": "test"} for s in range(4)]
    text = views(tmp_path, curves, runs)
    assert "### Ranks over 4 blocks (problem, seed) by final best σ\n" in text
    assert "mean rank (1 = best): good 1.00, mid 2.00, narrow 3.00, bad 4.00" in text
    assert (
        "### Ranks over 8 blocks (problem, seed) by final best σ, without narrow (not run on every problem)"
        in text
    )
    assert "mean rank (1 = best): good 1.00, mid 2.00, bad 3.00" in text
    assert {r["a"] for r in read_csv(tmp_path / "ranks_every_problem.csv")} == {"bad", "good"}


def test_the_fixed_budget_and_target_views_read_each_optimisers_own_runs():
    """Unequal numbers of runs and lengths (a partial set): each row counts its own runs, an ERT its own."""
    curves = {"P": {"a": np.array([[3.0, 1.0, 1.0], [4.0, 4.0, 2.0]]), "b": np.array([[2.0, 2.0, 2.0]])}}
    lengths = {"P": {"a": [3, 3], "b": [3]}}
    assert [(r["optimizer"], r["runs"]) for r in bv.fixed_budget_rows(curves)] == [("a", 2), ("b", 1)]
    rows = {r["optimizer"]: r for r in bv.fixed_target_rows(curves, lengths, {"P": 1.0})}
    assert (rows["a"]["reached_10"], rows["a"]["ert_10"]) == ("1/2", 5.0)  # 2 + 3 simulations over 1 success
    assert (rows["b"]["reached_10"], rows["b"]["ert_10"]) == ("0/1", math.inf)


# -- the dataset export and the ioh wrapper -------------------------------------------------------------


def test_export_writes_every_evaluation_with_its_constraints(tmp_path, capsys):
    pq = pytest.importorskip("pyarrow.parquet")
    from catenary_env.cli import main

    store = tmp_path / "runs.sqlite"
    with RunStore(store) as opened:
        result = optimize("synthetic-quadratic", "random", budget=12, seed=0, fidelity="test", store=opened)
    assert main(["export", str(store), str(tmp_path / "data")]) == 0
    table = pq.read_table(tmp_path / "data" / "synthetic-quadratic.parquet").to_pylist()
    assert len(table) == len(result.history)
    for row, record in zip(table, result.history, strict=True):
        assert (row["dh_1"], row["dh_2"], row["dh_3"]) == record.x and row["feasible"] == record.feasible
        assert row["sigma_N"] == record.sigma and row["constraint_excess_m"] == record.constraints[0]
    assert "How to cite" in (tmp_path / "data" / "DATASHEET.md").read_text(encoding="utf-8")
    assert main(["export", str(tmp_path / "none.sqlite"), str(tmp_path / "data")]) == 2


def test_the_ioh_wrapper_maps_the_unit_box_to_the_grid():
    pytest.importorskip("ioh")
    from optimizers.ioh_problem import INFEASIBLE_Y, ioh_problem
    from optimizers.synthetic import get_synthetic_problem

    problem = ioh_problem("synthetic-quadratic", fidelity="test")
    synthetic = get_synthetic_problem("synthetic-quadratic")
    assert problem([0.5, 0.5, 0.5]) == pytest.approx(float(synthetic.sigma(np.zeros(3))))
    assert problem([1.0, 1.0, 1.0]) == INFEASIBLE_Y  # x_1 + x_3 = 40 mm > 12 mm
    assert problem.meta_data.n_variables == 3 and problem.state.evaluations == 2


def test_the_comparison_takes_any_registered_optimizer_with_its_own_options(capsys):
    from experiments import optimizer_comparison
    from experiments.common import study_parser
    from optimizers.optuna_adapters import OptunaOptions

    assert isinstance(optimizer_comparison.Config().options("tpe"), OptunaOptions)  # was: NevergradOptions
    parser = study_parser(optimizer_comparison, "catenary experiment optimizers")
    assert parser.parse_args(["--optimizers", "gp", "ppo"]).optimizers == ["gp", "ppo"]
    with pytest.raises(SystemExit):
        parser.parse_args(["--optimizers", "nosuch"])
    assert "unknown optimizer 'nosuch'" in capsys.readouterr().err


def test_the_broad_ranks_leave_out_an_optimiser_that_would_narrow_them_to_a_few_blocks():
    """While runs are missing, an optimiser finished on one problem only would cut the ranks over every
    problem to that problem's blocks: it waits, named, and the others are ranked over all theirs."""
    from experiments.benchmark_views import broadest, common_blocks

    everywhere = {(p, s): 1.0 for p in ("B1", "B2", "B3") for s in range(10)}
    finals = {
        "ga": everywhere,
        "cma": dict(everywhere),
        "tpe": {k: v for k, v in everywhere.items() if k[0] != "B3"},
    }
    finals["gp"] = {("B1", s): 1.0 for s in range(5)}  # 5 blocks: fewer than half the others' 20
    kept, left = broadest(finals)
    assert sorted(kept) == ["cma", "ga", "tpe"] and left == {"gp": 5}
    assert len(common_blocks(kept)) == 20  # B1 and B2: TPE's 20 of 30 is more than half
    kept, left = broadest({"ga": everywhere, "cma": dict(everywhere), "gp": dict(everywhere)})
    assert sorted(kept) == ["cma", "ga", "gp"] and left == {}  # every run there: nobody waits
