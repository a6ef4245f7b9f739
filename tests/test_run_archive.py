"""The run archive (optimizers/archive.py): the committed form of a run store, which a fresh checkout restores
and resumes from; the archive rebuilt from a results export (experiments/archive_from_export.py); a new store
opened by several processes at once."""

from __future__ import annotations

import gzip
import json
import shutil
import sqlite3
import threading
from pathlib import Path

import pytest

pytest.importorskip("nevergrad", reason="the comparison runs nevergrad's optimisers")
pytest.importorskip("matplotlib", reason="the comparison draws its figures")

from experiments import optimizer_comparison  # noqa: E402
from experiments.archive_from_export import archive_from_export  # noqa: E402
from experiments.common import read_csv  # noqa: E402
from optimizers import synthetic  # noqa: E402
from optimizers.archive import archive_path, archive_run, restore_runs, snapshot_run  # noqa: E402
from optimizers.problem import GridSpace  # noqa: E402
from optimizers.problem_registry import resolve_problem  # noqa: E402
from optimizers.store import EXPORT_SOURCE, RunConfig, RunStore, StoreError  # noqa: E402

SYNTHETIC = "synthetic-quadratic"
SIMULATE = synthetic.simulate_quadratic  # as imported, whatever a test patches


def _comparison(out: Path, **options) -> Path:
    config = optimizer_comparison.Config(
        out=out, problems=(SYNTHETIC,), optimizers=("random", "cma"), **options
    )
    return optimizer_comparison.main(config)


def _untimed(path: Path) -> list[list[str]]:
    """The rows of an evaluations.csv, as written, without the seconds they took."""
    rows = [line.split(",") for line in path.read_text(encoding="utf-8").splitlines()]
    kept = [i for i, name in enumerate(rows[0]) if not name.endswith("time_s")]
    return [[row[i] for i in kept] for row in rows]


def _refuse_simulations(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(
        synthetic, "simulate_quadratic", lambda *a, **k: pytest.fail("a design was simulated")
    )


def _interrupt_after(monkeypatch: pytest.MonkeyPatch, n: int) -> list[object]:
    """Ctrl-C on the synthetic problem's simulation after ``n`` simulations; the designs it was asked."""
    calls: list[object] = []

    def interrupted(problem, x, *args):
        calls.append(x)
        if len(calls) > n:
            raise KeyboardInterrupt
        return SIMULATE(problem, x, *args)

    monkeypatch.setattr(synthetic, "simulate_quadratic", interrupted)
    return calls


def test_a_fresh_store_restored_from_the_archive_resumes_without_simulating(tmp_path, monkeypatch):
    """A study with ``archive`` writes each finished run once; on a fresh checkout (no store) the same study
    restores every run from it and replays them all, simulating no design of theirs, and writes the same
    results."""
    archive = tmp_path / "archive"
    first = _comparison(tmp_path / "a", archive=archive)
    files = sorted(archive.glob("*/*.json.gz"))
    assert len(files) == 4 and all(f.parent.name == SYNTHETIC for f in files)  # 2 optimisers, 2 seeds
    content = {f: f.read_bytes() for f in files}

    simulated = []
    simulate = synthetic.simulate_quadratic
    monkeypatch.setattr(
        synthetic, "simulate_quadratic", lambda p, x, *a: simulated.append(x) or simulate(p, x, *a)
    )
    second = _comparison(tmp_path / "b", archive=archive)
    assert simulated == [(0.0, 0.0, 0.0)]  # the reference design's row only: it belongs to no run
    assert (second / "evaluations.csv").read_text() == (first / "evaluations.csv").read_text()
    assert {f: f.read_bytes() for f in sorted(archive.glob("*/*.json.gz"))} == content  # written once
    with RunStore(tmp_path / "b" / "runs.sqlite") as store:
        assert restore_runs(store, archive) == 0  # each run restored once


def test_a_run_file_holds_every_column_of_the_store(tmp_path):
    """Restored, a run's rows are its rows in the store, every column (constraints and statistics too), so
    that its designs are served as cache as the original ones are."""
    _comparison(tmp_path, archive=tmp_path / "archive")
    with RunStore(tmp_path / "runs.sqlite") as original, RunStore(":memory:") as fresh:
        assert restore_runs(fresh, tmp_path / "archive") == 4
        for run in (r for r in original.runs() if r["stop_reason"]):  # not the reference design's evaluations
            config = RunConfig(*(run[f] for f in RunConfig._fields))
            assert original.run_rows(int(run["run_id"])) == fresh.run_rows(fresh.find_run(config))


def test_only_finished_runs_are_archived_and_foreign_files_are_refused(tmp_path):
    store = RunStore(":memory:")
    run_id = store.start_run(RunConfig("random", SYNTHETIC, 10, 0, 300.0, "test", "{}", "0.1.0"))
    with pytest.raises(StoreError, match="has not finished"):
        archive_run(store, run_id, tmp_path)
    damaged = tmp_path / SYNTHETIC / "random-seed0-0.json.gz"
    damaged.parent.mkdir()
    damaged.write_bytes(b"not gzip")
    with pytest.raises(StoreError, match="random-seed0-0.json.gz: not a readable run file"):
        restore_runs(store, tmp_path)
    with gzip.open(damaged, "wb") as file:
        file.write(json.dumps({"format": "something else", "version": 1}).encode())
    with pytest.raises(StoreError, match="not a run file of this format"):
        restore_runs(store, tmp_path)
    with pytest.raises(StoreError, match=r"not columns of a run store to write: \['bobby'\]"):
        store.add_run_rows({"bobby": "tables"}, [])


def test_an_export_rebuilds_its_finished_runs_which_are_never_served_as_cache(tmp_path, monkeypatch):
    """A store lost, its export kept: the rebuilt archive restores the finished runs, written again from the
    new store they give the same rows, and their designs (whose constraint values the export did not keep)
    are not served to other runs."""
    config = optimizer_comparison.Config(
        out=tmp_path / "a", problems=(SYNTHETIC,), optimizers=("random", "cma")
    )
    export = optimizer_comparison.main(config)
    paths = archive_from_export(export, tmp_path / "archive", "2026-12-02T00:00:00+00:00", config)
    assert len(paths) == 4

    _refuse_simulations(monkeypatch)
    rebuilt = tmp_path / "b"
    rebuilt.mkdir()
    with RunStore(rebuilt / "runs.sqlite") as store:
        assert restore_runs(store, tmp_path / "archive") == 4
        space = GridSpace.from_problem(resolve_problem(SYNTHETIC))
        (first, *_) = read_csv(export / "evaluations.csv")
        x = [float(v) for v in first["x_m"].split()]
        assert store.lookup(space.store_key, space.design_key(x), 300.0, "test") is None
        assert store.lookup(space.store_key, space.design_key(x), 300.0, "test", EXPORT_SOURCE) is not None
    again = optimizer_comparison.main(
        optimizer_comparison.Config(
            out=rebuilt, problems=(SYNTHETIC,), optimizers=("random", "cma"), from_store=True
        )
    )
    assert (again / "evaluations.csv").read_text() == (export / "evaluations.csv").read_text()
    assert read_csv(again / "runs.csv") == read_csv(export / "runs.csv")

    pq = pytest.importorskip("pyarrow.parquet")  # the dataset export says which rows were rebuilt
    from optimizers.dataset import export_store

    (table,) = [
        pq.read_table(path)
        for path in export_store(rebuilt / "runs.sqlite", tmp_path / "dataset")
        if path.suffix == ".parquet"
    ]
    rebuilt_rows = [r for r in table.to_pylist() if r["source"] == EXPORT_SOURCE]
    assert len(rebuilt_rows) == len(read_csv(export / "evaluations.csv"))
    assert all(r.get("constraint_excess_m") is None for r in rebuilt_rows)  # not kept: not invented


def test_processes_opening_a_new_store_together_all_get_it(tmp_path):
    """The lanes of a study started together open the same new file: one creates the schema, none fails."""
    path = tmp_path / "runs.sqlite"
    errors: list[BaseException] = []
    barrier = threading.Barrier(8)

    def open_store() -> None:
        barrier.wait()
        try:
            RunStore(path).close()
        except BaseException as error:  # noqa: BLE001 - collected, asserted below
            errors.append(error)

    threads = [threading.Thread(target=open_store) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    with RunStore(path, read_only=True) as store:
        assert store.runs() == []


def test_the_committed_archive_holds_every_finished_run_of_the_committed_export():
    """Each run the full protocol's export counts as finished is in the committed archive, with the same
    simulations and best σ: a fresh checkout resumes the protocol from it."""
    root = Path(__file__).resolve().parents[1] / "results" / "full-protocol"
    done = [r for r in read_csv(root / "optimizers" / "runs.csv") if r["status"] == "done"]
    assert done
    for line in done:
        (path,) = root.glob(
            f"archive/{line['problem']}@*/{line['optimizer']}-seed{int(line['seed'])}-*.json.gz"
        )
        with gzip.open(path, "rb") as file:
            content = json.loads(file.read())
        rows = [dict(zip(content["columns"], row, strict=True)) for row in content["rows"]]
        assert content["run"]["stop_reason"] == line["stop_reason"]
        assert sum(r["charged"] for r in rows) == line["n_simulations"]
        assert min(r["sigma"] for r in rows if r["feasible"]) == pytest.approx(
            line["best_sigma_N"], rel=1e-12
        )


def test_a_run_going_on_is_kept_as_a_snapshot_and_resumed_from_it(tmp_path, monkeypatch):
    """``--from-store`` with an archive keeps a run not finished as a snapshot; a fresh checkout restores it
    as an interrupted run and its study finishes it, replaying the snapshot's evaluations (not simulating
    them); the finished run's file then replaces the snapshot."""
    archive = tmp_path / "archive"
    made = tmp_path / "made.csv"
    shutil.copy(_comparison(tmp_path / "a", archive=archive) / "evaluations.csv", made)
    store_path = tmp_path / "a" / "runs.sqlite"
    with RunStore(store_path) as store:
        (cma,) = [r for r in store.runs() if r["optimizer"] == "cma" and r["seed"] == 1]
        config = RunConfig(*(cma[f] for f in RunConfig._fields))
        finished = archive_path(archive, cma)
    finished.unlink()  # as if the run had been killed after 5 evaluations, and never archived
    with sqlite3.connect(store_path) as connection:
        connection.execute(
            "UPDATE runs SET finished_at = NULL, stop_reason = NULL WHERE run_id = ?", (cma["run_id"],)
        )
        connection.execute("DELETE FROM evaluations WHERE run_id = ? AND idx >= 5", (cma["run_id"],))
    _comparison(tmp_path / "a", archive=archive, from_store=True)
    snapshot = archive_path(archive, cma, partial=True)
    assert snapshot.is_file() and not finished.exists()

    simulated = []
    simulate = synthetic.simulate_quadratic
    monkeypatch.setattr(
        synthetic, "simulate_quadratic", lambda p, x, *a: simulated.append(x) or simulate(p, x, *a)
    )
    second = _comparison(tmp_path / "b", archive=archive)
    assert (
        len(simulated) == 1 + 12 - 5
    )  # the reference design, and the run's evaluations after the snapshot's
    assert _untimed(second / "evaluations.csv") == _untimed(made)  # the new simulations took their own time
    assert finished.is_file() and not snapshot.exists()
    with RunStore(tmp_path / "b" / "runs.sqlite") as store, pytest.raises(StoreError, match="has finished"):
        snapshot_run(store, store.find_run(config), archive)


def test_a_run_killed_with_its_store_resumes_from_its_last_snapshot(tmp_path, monkeypatch):
    """A run with an archive keeps a snapshot as it goes (here after every evaluation); killed, and its store
    lost, it is restored from the snapshot into a new store and resumed to the same history as a run never
    interrupted, simulating only what came after the snapshot."""
    from optimizers import recorder
    from optimizers.runner import optimize

    monkeypatch.setattr(recorder, "SNAPSHOT_EVERY_S", 0.0)
    whole = optimize(SYNTHETIC, "cma", 24, seed=3, fidelity="test")
    simulate = synthetic.simulate_quadratic
    calls = _interrupt_after(monkeypatch, 10)
    archive = tmp_path / "archive"
    with pytest.raises(KeyboardInterrupt):
        optimize(
            SYNTHETIC, "cma", 24, seed=3, fidelity="test", store=tmp_path / "lost.sqlite", archive=archive
        )
    (snapshot,) = archive.glob("*/*.partial.json.gz")

    calls.clear()
    monkeypatch.setattr(
        synthetic, "simulate_quadratic", lambda p, x, *a: calls.append(x) or simulate(p, x, *a)
    )
    with RunStore(tmp_path / "new.sqlite") as store:
        assert restore_runs(store, archive) == 1
        resumed = optimize(
            SYNTHETIC, "cma", 24, seed=3, fidelity="test", store=store, resume=True, archive=archive
        )
    assert [(r.x, r.sigma) for r in resumed.history] == [(r.x, r.sigma) for r in whole.history]
    assert len(calls) == 24 - 10  # the ten in the snapshot were replayed
    assert not snapshot.exists() and len(list(archive.glob("*/*.json.gz"))) == 1


def test_a_run_interrupted_leaves_its_last_snapshot_in_the_archive(tmp_path, monkeypatch):
    """Ctrl-C (or SIGTERM, which unwinds the same way) between two periodic snapshots: the run's way out
    writes a last one, holding every evaluation the store has, and a finished run leaves no snapshot."""
    from optimizers.runner import optimize

    simulate = synthetic.simulate_quadratic
    _interrupt_after(monkeypatch, 7)
    archive = tmp_path / "archive"
    run = {"problem": SYNTHETIC, "optimizer": "cma", "budget": 24, "seed": 3, "fidelity": "test"}
    with pytest.raises(KeyboardInterrupt):  # the periodic snapshot (every ten minutes) never came
        optimize(**run, store=tmp_path / "runs.sqlite", archive=archive)
    (snapshot,) = archive.glob("*/*.partial.json.gz")
    with RunStore(tmp_path / "runs.sqlite") as store:
        (kept,) = store.runs()
        rows = store.run_rows(kept["run_id"])[1]
        assert len(rows) == 7
        fresh = RunStore(":memory:")
        restore_runs(fresh, archive)
        assert fresh.run_rows(fresh.runs()[0]["run_id"])[1] == rows

        monkeypatch.setattr(synthetic, "simulate_quadratic", simulate)
        optimize(**run, store=store, resume=True, archive=archive)
    assert not snapshot.exists() and len(list(archive.glob("*/*.json.gz"))) == 1


def test_a_run_taken_further_on_another_machine_is_carried_further_where_it_stopped(tmp_path, monkeypatch):
    """A snapshot of 10 evaluations is restored here and on another machine; that one resumes the run to 17
    and writes its longer snapshot: restored here, it carries the run here to 17 (the same rows as there),
    once; when that machine finishes the run, its file finishes the run here. A run here that went its own
    way (an evaluation the other lacks or holds otherwise) is kept as it is."""
    import fcntl

    from optimizers import recorder
    from optimizers.runner import optimize

    monkeypatch.setattr(recorder, "SNAPSHOT_EVERY_S", 0.0)
    simulate = synthetic.simulate_quadratic

    archive, elsewhere = tmp_path / "archive", tmp_path / "elsewhere"
    run = {"problem": SYNTHETIC, "optimizer": "cma", "budget": 24, "seed": 3, "fidelity": "test"}
    _interrupt_after(monkeypatch, 10)
    with pytest.raises(KeyboardInterrupt):
        optimize(**run, store=tmp_path / "lost.sqlite", archive=archive)
    shutil.copytree(archive, elsewhere)
    here, there = RunStore(tmp_path / "here.sqlite"), RunStore(tmp_path / "there.sqlite")
    assert restore_runs(here, archive) == restore_runs(there, elsewhere) == 1
    _interrupt_after(monkeypatch, 7)
    with pytest.raises(KeyboardInterrupt):
        optimize(**run, store=there, resume=True, archive=elsewhere)
    (run_there,), (run_here,) = (store.runs() for store in (there, here))
    assert len(there.run_rows(run_there["run_id"])[1]) == 17

    claim = Path(here._claim_file(RunConfig(*(run_here[f] for f in RunConfig._fields))))
    claim.parent.mkdir(exist_ok=True)
    with claim.open("a") as held:  # a process making the run here now: it is left to that process
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        assert restore_runs(here, elsewhere) == 0
    assert restore_runs(here, elsewhere) == 1
    assert here.run_rows(run_here["run_id"])[1] == there.run_rows(run_there["run_id"])[1]
    assert restore_runs(here, elsewhere) == 0  # carried once
    monkeypatch.setattr(synthetic, "simulate_quadratic", simulate)
    optimize(**run, store=there, resume=True, archive=elsewhere)
    assert restore_runs(here, elsewhere) == 1
    assert here.run_rows(run_here["run_id"]) == (
        {**there.run_rows(run_there["run_id"])[0], "run_id": run_here["run_id"]},
        there.run_rows(run_there["run_id"])[1],
    )

    branched = RunStore(tmp_path / "branched.sqlite")
    restore_runs(branched, archive)
    (kept,) = branched.runs()
    with branched._connection:  # the other machine's 5th design, held otherwise here
        branched._connection.execute("UPDATE evaluations SET sigma = 1.0 WHERE idx = 4")
    before = branched.run_rows(kept["run_id"])
    assert restore_runs(branched, elsewhere) == 0
    assert branched.run_rows(kept["run_id"]) == before
    for store in (here, there, branched):
        store.close()


def test_two_lanes_restoring_one_archive_into_one_store_write_each_run_once(tmp_path):
    """The lanes of a protocol started together on a fresh checkout restore the same archive into the same
    new store: each run is written once."""
    _comparison(tmp_path / "a", archive=tmp_path / "archive")
    path = tmp_path / "b.sqlite"
    counts: list[int] = []
    errors: list[BaseException] = []
    # A lane that fails must break the barrier for the others (a deadlock guard, not a time limit).
    barrier = threading.Barrier(4, timeout=300)

    def lane() -> None:
        try:
            with RunStore(path) as store:
                barrier.wait()
                counts.append(restore_runs(store, tmp_path / "archive"))
        except BaseException as error:
            errors.append(error)
            barrier.abort()

    threads = [threading.Thread(target=lane) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors, errors
    assert sum(counts) == 4
    with RunStore(path, read_only=True) as store:
        assert len(store.runs()) == 4


def test_catenary_optimize_keeps_its_run_in_an_archive_and_resumes_it_elsewhere(
    tmp_path, monkeypatch, capsys
):
    """``catenary optimize --archive``: the run goes into the archive; another machine (here a store in
    memory) resumes it from there with --resume, replaying it without simulating."""
    from catenary_env.cli import main

    command = ["optimize", SYNTHETIC, "--optimizer", "cma", "--budget", "12", "--workers", "1", "--quiet"]
    command += ["--json", "--archive", str(tmp_path / "archive")]
    assert main([*command, "--store", str(tmp_path / "a.sqlite")]) == 0
    made = json.loads(capsys.readouterr().out)
    assert len(list((tmp_path / "archive").glob("*/*.json.gz"))) == 1
    _refuse_simulations(monkeypatch)
    assert main([*command, "--store", ":memory:", "--resume"]) == 0
    resumed = json.loads(capsys.readouterr().out)
    assert (resumed["best_sigma"], resumed["history"]) == (made["best_sigma"], made["history"])
