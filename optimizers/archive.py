"""A run archive: the finished runs of a run store kept as files, one per run, that rebuild the store.

A run store is a working file (SQLite, written as evaluations complete) and is not committed; a study that
runs for days across machines and checkouts commits its finished runs instead, as the runs finish, and a
fresh checkout restores them into its store before it goes on (:func:`restore_runs`). A finished run never
changes, so its file is written once and the archive only grows.

Each file is gzip-compressed JSON (written without a timestamp, so the same run gives the same bytes):
``{"format": "catenary-env run", "version": 1, "run": {...}, "columns": [...], "rows": [[...], ...]}``,
``run`` the run's row of the store (its ``run_id`` kept where the store restored into has it free) and
``rows`` its evaluations in order, every column as stored (floats as JSON writes them, exactly; NaN as
``NaN``).
Its path is ``<problem>/<optimizer>-seed<seed>-<digest>.json.gz``, where ``<problem>`` is the store's name
of the problem (with its model's fingerprint, ``B1@64e3ab672ccb``) and ``<digest>`` is a hash of the run's
whole configuration (:class:`~optimizers.store.RunConfig`, options and version included). Files of
other kinds in the folder (the study's ``model.json``) are left alone.

A run still going can be kept too, as a snapshot (:func:`snapshot_run`, ``...-<digest>.partial.json.gz``,
rewritten at each snapshot): restored into a store that lacks the run, it is an interrupted run, which its
study resumes from there (the snapshot's evaluations replayed, not simulated). A session that ends mid-run
then loses only what came after its last snapshot. When the run finishes, its file replaces the snapshot.
A run taken further elsewhere (another machine resumed it from the same snapshot and wrote a longer one)
is carried further in a store that holds it unfinished, when restored from there.

Examples
--------
>>> import tempfile
>>> from optimizers.store import RunConfig, RunStore
>>> store = RunStore(":memory:")
>>> config = RunConfig("ga", "synthetic-quadratic", 100, 1, 300.0, "test", "{}", "0.1.0")
>>> run_id = store.start_run(config)
>>> store.finish_run(run_id, "budget")
>>> folder = tempfile.mkdtemp()
>>> archive_run(store, run_id, folder).name.startswith("ga-seed1-")
True
>>> fresh = RunStore(":memory:")
>>> restore_runs(fresh, folder), restore_runs(fresh, folder)
(1, 0)
>>> fresh.find_run(config)
1
"""

from __future__ import annotations

import gzip
import hashlib
import json
from pathlib import Path
from typing import Any

from .store import RunConfig, RunStore, StoreError

__all__ = [
    "FORMAT",
    "PARTIAL",
    "archive_path",
    "archive_run",
    "finished_runs",
    "restore_runs",
    "snapshot_run",
    "write_run_file",
]

FORMAT = {"format": "catenary-env run", "version": 1}
"""The marker of a run file."""


PARTIAL = ".partial.json.gz"
"""The end of a snapshot's file name (a run not finished yet)."""


def archive_path(folder: str | Path, run: dict[str, Any], partial: bool = False) -> Path:
    """Where a run (its row of the store) is kept in an archive folder; ``partial``: its snapshot."""
    config = _config(run)
    digest = hashlib.sha256(json.dumps(list(config)).encode()).hexdigest()[:12]
    name = f"{config.optimizer}-seed{config.seed}-{digest}" + (PARTIAL if partial else ".json.gz")
    return Path(folder) / config.problem / name


def archive_run(store: RunStore, run_id: int, folder: str | Path) -> Path:
    """Write a finished run of the store into the archive folder (once: a file already there is kept), and
    remove its snapshot; return its path.

    Raises
    ------
    StoreError
        The run has not finished (:func:`snapshot_run` keeps such a run).
    """
    run, rows = store.run_rows(run_id)
    if run["stop_reason"] is None:
        raise StoreError(f"{store.path}: run {run_id} has not finished; only finished runs are archived")
    path = write_run_file(folder, run, rows)
    archive_path(folder, run, partial=True).unlink(missing_ok=True)
    return path


def snapshot_run(store: RunStore, run_id: int, folder: str | Path) -> Path:
    """Write what the store holds of a run not finished yet into the archive folder, replacing its earlier
    snapshot; return its path.

    Raises
    ------
    StoreError
        The run has finished (:func:`archive_run` keeps it).
    """
    run, rows = store.run_rows(run_id)
    if run["stop_reason"] is not None:
        raise StoreError(f"{store.path}: run {run_id} has finished: archive it, not a snapshot of it")
    return _write(archive_path(folder, run, partial=True), run, rows)


def write_run_file(folder: str | Path, run: dict[str, Any], rows: list[dict[str, Any]]) -> Path:
    """Write a finished run (its row and its evaluation rows, as :meth:`RunStore.run_rows` gives them) into
    the archive folder, once: a file already there is kept; return its path."""
    path = archive_path(folder, run)
    return path if path.is_file() else _write(path, run, rows)


def _write(path: Path, run: dict[str, Any], rows: list[dict[str, Any]]) -> Path:
    columns = sorted(rows[0]) if rows else []
    content = {**FORMAT, "run": run, "columns": columns, "rows": [[row[c] for c in columns] for row in rows]}
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(path.name + ".part")
    with gzip.GzipFile(temporary, "wb", mtime=0) as file:  # mtime 0: the same run, the same bytes
        file.write(json.dumps(content, sort_keys=True).encode())
    temporary.replace(path)  # a file in the archive is whole: an interrupted write leaves only the .part
    return path


def restore_runs(store: RunStore, folder: str | Path) -> int:
    """Write into the store every archived run it does not hold, finished or (from its snapshot) not, and
    carry further each unfinished run it holds that the archive has further (a run resumed from the same
    snapshot on another machine; :meth:`RunStore.add_run_rows`); a run of the same configuration in the
    store is otherwise kept as it is. Return how many runs were written or carried further. Nothing
    happens for a missing folder.

    Raises
    ------
    StoreError
        A file of the folder is not a run file (its path names it), or the store holds the run as made by
        another package version.
    """
    finished, snapshots = _run_files(folder)
    done = set(finished)
    unfinished = [p for p in snapshots if _finished_path(p) not in done]
    restored = 0
    for path in finished + unfinished:  # a run's file, else its snapshot
        run, rows = _read(path)
        restored += store.add_run_rows(run, rows, if_absent=True) is not None
    return restored


def finished_runs(folder: str | Path) -> list[tuple[dict[str, Any], list[dict[str, Any]]]]:
    """The archive's finished runs (snapshots left out), each as its run row and its evaluations' rows in
    order, in path order; none for a missing folder.

    Raises
    ------
    StoreError
        A file of the folder is not a run file (its path names it).
    """
    return [_read(path) for path in _run_files(folder)[0]]


def _run_files(folder: str | Path) -> tuple[list[Path], list[Path]]:
    """The archive's finished runs' files and its snapshots, each in path order."""
    paths = sorted(Path(folder).glob("*/*.json.gz"))
    return [p for p in paths if not p.name.endswith(PARTIAL)], [p for p in paths if p.name.endswith(PARTIAL)]


def _read(path: Path) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    try:
        with gzip.open(path, "rb") as file:
            content = json.loads(file.read())
        if {k: content.get(k) for k in FORMAT} != FORMAT:
            raise ValueError(f"not a run file of this format ({FORMAT})")
        run, columns = content["run"], content["columns"]
        rows = [dict(zip(columns, row, strict=True)) for row in content["rows"]]
        _config(run)
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise StoreError(f"{path}: not a readable run file of a run archive ({error})") from None
    return run, rows


def _finished_path(snapshot: Path) -> Path:
    return snapshot.with_name(snapshot.name.removesuffix(PARTIAL) + ".json.gz")


def _config(run: dict[str, Any]) -> RunConfig:
    return RunConfig(*(run[field] for field in RunConfig._fields))
