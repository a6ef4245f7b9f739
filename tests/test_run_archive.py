"""The run archive (optimizers/archive.py): the committed form of a run store, which a fresh checkout restores
and resumes from; the archive rebuilt from a results export (experiments/archive_from_export.py); a new store
opened by several processes at once."""

from __future__ import annotations

import gzip
import json
import threading
from pathlib import Path

import pytest

pytest.importorskip("nevergrad", reason="the comparison runs nevergrad's optimisers")
pytest.importorskip("matplotlib", reason="the comparison draws its figures")

from experiments import optimizer_comparison  # noqa: E402
from experiments.archive_from_export import archive_from_export  # noqa: E402
from experiments.common import read_csv  # noqa: E402
from optimizers import synthetic  # noqa: E402
from optimizers.archive import archive_run, restore_runs  # noqa: E402
from optimizers.problem import GridSpace  # noqa: E402
from optimizers.problem_registry import resolve_problem  # noqa: E402
from optimizers.store import EXPORT_SOURCE, RunConfig, RunStore, StoreError  # noqa: E402

SYNTHETIC = "synthetic-quadratic"


def _comparison(out: Path, **options) -> Path:
    config = optimizer_comparison.Config(
        out=out, problems=(SYNTHETIC,), optimizers=("random", "cma"), **options
    )
    return optimizer_comparison.main(config)


def _refuse_simulations(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(
        synthetic, "simulate_quadratic", lambda *a, **k: pytest.fail("a design was simulated")
    )


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
