"""A run killed with SIGKILL in the middle resumes to the result of an uninterrupted run; the command line."""

from __future__ import annotations

import argparse
import dataclasses
import json
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import requires

from catenary_env.cli import main
from optimizers import EvaluationRecord, optimize
from optimizers.cli.optimize import add_arguments, add_parser, run

REPO = Path(__file__).resolve().parents[1]
PROBLEM = "synthetic-quadratic-slow"  # 5 ms an evaluation: a run lasts long enough to be killed
BUDGET = 300


def _count(store: Path) -> int:
    if not store.exists():
        return 0
    try:
        with sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=5.0) as connection:
            return int(connection.execute("SELECT count(*) FROM evaluations").fetchone()[0])
    except sqlite3.OperationalError:  # the schema is not created yet
        return 0


def _command(store: Path, optimizer: str) -> list[str]:
    return [
        sys.executable, "-m", "optimizers", PROBLEM, "--optimizer", optimizer, "--budget", str(BUDGET),
        "--seed", "3", "--fidelity", "test", "--store", str(store), "--workers", "1", "--quiet", "--json",
        "--resume-or-start",
    ]  # fmt: skip


def _comparable(records):
    return [dataclasses.replace(record, wall_time=0.0) for record in records]


@pytest.mark.parametrize(
    "optimizer", ["ga"]
)  # nevergrad's resume is tested in-process (its import takes 6 s)
def test_killed_run_resumes_to_the_uninterrupted_result(tmp_path, optimizer):
    store = tmp_path / "runs.sqlite"
    process = subprocess.Popen(
        _command(store, optimizer), cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    deadline = time.monotonic() + 60.0
    while _count(store) < 60 and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    process.send_signal(signal.SIGKILL)
    process.communicate()
    assert process.returncode == -signal.SIGKILL, "the run ended before it could be killed"
    stored_at_kill = _count(store)
    assert stored_at_kill >= 60

    resumed = subprocess.run(
        _command(store, optimizer), cwd=REPO, capture_output=True, text=True, timeout=120
    )
    assert resumed.returncode == 0, resumed.stderr
    result = json.loads(resumed.stdout)
    history = [
        EvaluationRecord(
            **{
                **entry,
                "x": tuple(entry["x"]),
                "constraints": tuple(entry["constraints"]),
                "statistics": tuple(entry["statistics"]),
            }
        )
        for entry in result["history"]
    ]

    # the same σ without the 5 ms sleep (only wall times differ, and those are not compared)
    uninterrupted = optimize("synthetic-quadratic", optimizer, budget=BUDGET, seed=3, fidelity="test")
    assert len(history) > stored_at_kill
    assert _comparable(history) == _comparable(uninterrupted.history)
    assert result["best_sigma"] == uninterrupted.best_sigma
    assert tuple(result["best_x"]) == uninterrupted.best_x
    assert result["stop_reason"] == uninterrupted.stop_reason
    assert _count(store) == len(history)  # one run in the store, each evaluation once


# -- the command line -------------------------------------------------------------------------------------


def _parse(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    return parser.parse_args(argv)


@requires("nevergrad")  # the run uses differential evolution
def test_cli_runs_and_prints_json(tmp_path, capsys):
    store = tmp_path / "runs.sqlite"
    argv = ["synthetic-quadratic", "--optimizer", "de", "--budget", "20", "--seed", "1",
            "--store", str(store), "--workers", "1", "--json", "--quiet"]  # fmt: skip
    assert run(_parse(argv)) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["n_simulations"] == 20 and result["optimizer"] == "de" and len(result["history"]) >= 20
    assert run(_parse(argv[:-2] + ["--quiet"])) == 0
    assert "best sigma" in capsys.readouterr().out


def test_cli_refuses_a_corrupt_store(tmp_path, capsys):
    store = tmp_path / "runs.sqlite"
    store.write_bytes(b"\x89PNG not a database at all" * 100)
    assert (
        main(["optimize", "synthetic-quadratic", "--budget", "5", "--store", str(store), "--workers", "1"])
        == 2
    )
    assert "not an SQLite database" in capsys.readouterr().err


def test_cli_reports_unknown_problem(capsys):
    assert (
        main(["optimize", "no-such-problem", "--budget", "5", "--store", ":memory:", "--workers", "1"]) == 2
    )
    assert "no-such-problem" in capsys.readouterr().err


def test_cli_help_explains_every_option_with_units():
    parser = argparse.ArgumentParser(prog="catenary")
    sub = parser.add_subparsers(dest="command")
    optimize_parser = add_parser(sub)
    text = optimize_parser.format_help()
    options = ("--optimizer", "--budget", "--seed", "--speed", "--fidelity", "--store", "--resume",
               "--workers", "--scheduler", "--json")  # fmt: skip
    for option in options:
        assert option in text
    assert "km/h" in text and "simulations" in text
    for action in optimize_parser._actions:
        assert action.help, f"{action.option_strings or action.dest} has no help"


def test_module_entry_point_help():
    completed = subprocess.run([sys.executable, "-m", "optimizers", "--help"], cwd=REPO, capture_output=True,
                               text=True, timeout=60)  # fmt: skip
    assert completed.returncode == 0 and "--budget" in completed.stdout


def test_catenary_runs_lists_each_runs_progress(tmp_path, capsys, claimed_elsewhere):
    """Finished runs with their progress, and of the others which a process is making now and which were
    interrupted; a study's collection of given designs (budget 0) is neither."""
    from catenary_env.cli import main
    from optimizers.ga import GAOptions
    from optimizers.store import RunConfig, RunStore

    store = tmp_path / "runs.sqlite"
    done = optimize(
        "synthetic-quadratic", "ga", 24, seed=1, options=GAOptions(population_size=8), store=store
    )
    interrupted = RunConfig("ga", "synthetic-quadratic", 50, 2, None, "test", "{}", "0.1.0")
    going = interrupted._replace(seed=3)
    given = interrupted._replace(optimizer="given-designs", budget=0, seed=0)
    with RunStore(store) as runs:  # runs before their first evaluation
        runs.start_run(interrupted)
        runs.start_run(going)
        runs.start_run(given)
    with claimed_elsewhere(store, going):
        assert main(["runs", "--store", str(store)]) == 0
        lines = capsys.readouterr().out.splitlines()
        assert main(["runs", "--store", str(store), "--json"]) == 0
        first, second, third, _ = json.loads(capsys.readouterr().out)
    expected = f"1 ga synthetic-quadratic 1 300 km/h study {done.n_simulations}/24"
    assert " ".join(lines[1].split()[:8]) == expected
    assert lines[1].split()[8:10] == [f"{done.best_sigma:.3f}", f"{done.stop_reason},"]
    assert lines[2].split()[4] == "range" and lines[2].endswith("interrupted, no evaluation")
    assert lines[3].split()[3] == "3" and lines[3].endswith("running now, no evaluation")
    assert lines[4].split()[6] == "0" and lines[4].endswith("designs a study gave, no budget")
    assert lines[-1] == (
        f"4 run(s) in {store}: 1 running now, 1 interrupted (they resume with --resume, or when their study "
        "runs again)"
    )
    assert first["simulations"] == done.n_simulations and first["best_sigma"] == done.best_sigma
    assert first["evaluations"] == len(done.history) and first["stop_reason"] == done.stop_reason
    assert second["simulations"] == 0 and second["best_sigma"] is None and second["finished_at"] is None
    assert [r["running"] for r in (first, second, third)] == [False, False, True]


def test_catenary_runs_refuses_a_missing_or_empty_store_without_writing(tmp_path, capsys):
    from catenary_env.cli import main

    missing = tmp_path / "none.sqlite"
    assert main(["runs", "--store", str(missing)]) == 2
    assert f"--store {missing}: no such file" in capsys.readouterr().err
    assert not missing.exists()
    empty = tmp_path / "empty.sqlite"
    empty.touch()
    assert main(["runs", "--store", str(empty)]) == 2
    assert "an empty file, not a run store" in capsys.readouterr().err
    assert empty.stat().st_size == 0  # read only: no schema written into it


def test_a_finished_run_reads_back_as_its_resumption_returns_it(tmp_path):
    """``finished_result`` (the comparison's ``--from-store``) gives, without its optimiser, the result a
    resumption of the finished run returns; an unfinished run is refused."""
    from optimizers.plugins import get_optimizer
    from optimizers.problem import GridSpace
    from optimizers.problem_registry import resolve_problem
    from optimizers.recorder import finished_result
    from optimizers.runner import run_config
    from optimizers.store import RunStore, StoreError

    store = tmp_path / "runs.sqlite"
    problem = "synthetic-quadratic"
    made = optimize(problem, "cma", 20, 2, fidelity="test", store=store)
    space = GridSpace.from_problem(resolve_problem(problem))
    with RunStore(store, read_only=True) as opened:
        config = run_config("cma", space, 20, 2, 300.0, "test", get_optimizer("cma").options_class())
        assert opened.find_run(config) == made.run_id
        read = finished_result(opened, made.run_id, config, space)
    resumed = optimize(problem, "cma", 20, 2, fidelity="test", store=store, resume=True)
    assert read == resumed == made
    with sqlite3.connect(store) as connection:
        connection.execute("UPDATE runs SET stop_reason = NULL WHERE run_id = ?", (made.run_id,))
    with RunStore(store, read_only=True) as opened, pytest.raises(StoreError, match="has not finished"):
        finished_result(opened, made.run_id, config, space)


def test_a_run_another_process_is_making_is_not_resumed_here(tmp_path, claimed_elsewhere):
    """Two processes resuming one run would interleave their evaluations in it: while another process holds
    the run (a second terminal, a lane), ``--resume`` is refused with a message that says so; a new run
    (without ``--resume``) is another run and goes ahead."""
    from optimizers.plugins import get_optimizer
    from optimizers.problem import GridSpace
    from optimizers.problem_registry import resolve_problem
    from optimizers.runner import run_config
    from optimizers.store import StoreError

    store = tmp_path / "runs.sqlite"
    problem = "synthetic-quadratic"
    space = GridSpace.from_problem(resolve_problem(problem))
    config = run_config("cma", space, 20, 2, 300.0, "test", get_optimizer("cma").options_class())
    first = optimize(problem, "cma", 20, 2, fidelity="test", store=store)
    with claimed_elsewhere(store, config):
        with pytest.raises(StoreError, match="being made by another process now; wait for it to end"):
            optimize(problem, "cma", 20, 2, fidelity="test", store=store, resume=True)
        assert optimize(problem, "cma", 20, 2, fidelity="test", store=store).run_id == first.run_id + 1
    resumed = optimize(problem, "cma", 20, 2, fidelity="test", store=store, resume=True)
    assert resumed.run_id == first.run_id + 1  # released: the latest run of the configuration
