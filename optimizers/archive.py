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
of the problem (with its model's fingerprint, ``B1@362f3bf2265f``) and ``<digest>`` is a hash of the run's
whole configuration (:class:`~optimizers.store.RunConfig`, options and version included). Files of
other kinds in the folder (the study's ``model.json``) are left alone.

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

__all__ = ["FORMAT", "archive_path", "archive_run", "restore_runs", "write_run_file"]

FORMAT = {"format": "catenary-env run", "version": 1}
"""The marker of a run file."""


def archive_path(folder: str | Path, run: dict[str, Any]) -> Path:
    """Where a run (its row of the store) is kept in an archive folder."""
    config = _config(run)
    digest = hashlib.sha256(json.dumps(list(config)).encode()).hexdigest()[:12]
    return Path(folder) / config.problem / f"{config.optimizer}-seed{config.seed}-{digest}.json.gz"


def archive_run(store: RunStore, run_id: int, folder: str | Path) -> Path:
    """Write a finished run of the store into the archive folder (once: a file already there is kept);
    return its path.

    Raises
    ------
    StoreError
        The run has not finished.
    """
    run, rows = store.run_rows(run_id)
    if run["stop_reason"] is None:
        raise StoreError(f"{store.path}: run {run_id} has not finished; only finished runs are archived")
    return write_run_file(folder, run, rows)


def write_run_file(folder: str | Path, run: dict[str, Any], rows: list[dict[str, Any]]) -> Path:
    """Write a finished run (its row and its evaluation rows, as :meth:`RunStore.run_rows` gives them) into
    the archive folder, once: a file already there is kept; return its path."""
    path = archive_path(folder, run)
    if path.is_file():
        return path
    columns = sorted(rows[0]) if rows else []
    content = {**FORMAT, "run": run, "columns": columns, "rows": [[row[c] for c in columns] for row in rows]}
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".part")
    with gzip.GzipFile(partial, "wb", mtime=0) as file:  # mtime 0: the same run, the same bytes
        file.write(json.dumps(content, sort_keys=True).encode())
    partial.replace(path)  # a file in the archive is whole: an interrupted write leaves only the .part
    return path


def restore_runs(store: RunStore, folder: str | Path) -> int:
    """Write into the store every archived run it does not hold (a run of the same configuration, finished
    or not, is kept as it is); return how many were written. Nothing happens for a missing folder.

    Raises
    ------
    StoreError
        A file of the folder is not a run file (its path names it), or the store holds the run as made by
        another package version.
    """
    restored = 0
    for path in sorted(Path(folder).glob("*/*.json.gz")):
        run, rows = _read(path)
        if store.find_run(_config(run)) is None:
            store.add_run_rows(run, rows)
            restored += 1
    return restored


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


def _config(run: dict[str, Any]) -> RunConfig:
    return RunConfig(*(run[field] for field in RunConfig._fields))
