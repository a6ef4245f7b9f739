"""The run store: an embedded SQLite file holding runs, their evaluations, and the evaluation cache.

Every evaluation is committed as it completes, so a killed process loses at most the evaluations in
flight (the file is in WAL mode; a commit survives the death of the process that made it). The same
rows are the cache: an evaluation is identified by (problem, design on its grid, speed, fidelity), the
design by the integers ``round(x / step)``, and a design evaluated once in a store is not simulated
again by any run in it. Runs made by the RL trainer (whose simulations belong to a Gymnasium env and
its reward convention) are stored with ``source = 'env'`` and are not served to the other optimisers;
they are served to RL runs on the same env (:meth:`RunStore.lookup_env`).

A run is identified by its configuration (:class:`RunConfig`); resuming a run replays its stored
evaluations one by one in place of simulating them (see :func:`optimizers.runner.optimize`).

The file carries a marker: SQLite's ``application_id`` header field is :data:`APPLICATION_ID` and its
``user_version`` is :data:`SCHEMA_VERSION`. A file that is not SQLite, or an SQLite database without
the marker (someone else's), or one of another schema version, is refused with :class:`StoreError`.

A catenary problem's name in the store carries the fingerprint of its model
(:attr:`~optimizers.problem.GridSpace.store_key`, ``B1@<fingerprint>``: the definitions, the named fidelities'
settings and what the simulator computes, :mod:`catenary_env.fingerprint`), so a store never serves σ of
another model: after a change of the physics the same file holds the new results beside the old ones. The
run table also records the package version, and resuming a run made by another version is refused.

Examples
--------
>>> store = RunStore(":memory:")
>>> config = RunConfig("ga", "synthetic-quadratic", 100, 1, 300.0, "test", "{}", "0.1.0")
>>> run_id = store.start_run(config)
>>> store.find_run(config) == run_id
True
"""

from __future__ import annotations

import contextlib
import datetime
import functools
import hashlib
import json
import os
import sqlite3
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import NamedTuple

from catenary_env.errors import CatenaryError

from .base import EvaluationRecord
from .problem import Outcome

try:  # the runs' claims (RunStore.claim) are file locks
    import fcntl
except ImportError:  # Windows: runs are not claimed
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "APPLICATION_ID",
    "EXPORT_SOURCE",
    "SCHEMA_VERSION",
    "RunConfig",
    "RunStore",
    "StoreError",
    "StoredEvaluation",
]

_CLAIMED: set[str] = set()
"""The claims' lock files this process holds (:meth:`RunStore.claim`): a second open file would not get the
lock the first holds, in the same process too."""

APPLICATION_ID = 0x43415445
"""SQLite ``application_id`` of a run store: the bytes ``CATE``."""

SCHEMA_VERSION = 2
"""SQLite ``user_version`` of the schema this code reads and writes. Version 2 added the evaluations'
``constraints`` and ``statistics`` (JSON lists of the problem's constraint values and contact-force
statistics); a version-1 store is upgraded in place when opened for writing (the columns added, its old rows
without those values) and read as it is when opened read-only."""

EXPORT_SOURCE = "export"
"""The ``source`` of evaluations rebuilt from a results export (the runs' ``evaluations.csv``) where the store
that made them was lost: each keeps its design, σ, feasibility, charge and times, but not its reason,
constraint values or statistics, so they are read back as their runs' history and never served as cache (a
constraint-aware optimiser served one would be told less than a simulation tells it)."""

_ADDED_IN_2 = ("constraints", "statistics")
"""The evaluations' columns that schema version 2 added."""

_UPGRADABLE = {1: [f"ALTER TABLE evaluations ADD COLUMN {column} TEXT" for column in _ADDED_IN_2]}
"""The statements that bring a store of an older schema version to :data:`SCHEMA_VERSION`."""

_SQLITE_HEADER = b"SQLite format 3\x00"

_SCHEMA = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE runs (
    run_id INTEGER PRIMARY KEY AUTOINCREMENT,
    optimizer TEXT NOT NULL,
    problem TEXT NOT NULL,
    budget INTEGER NOT NULL,
    seed INTEGER NOT NULL,
    speed_kmh REAL,
    fidelity TEXT NOT NULL,
    options TEXT NOT NULL,
    package_version TEXT NOT NULL,
    created_at TEXT NOT NULL,
    finished_at TEXT,
    stop_reason TEXT
);
CREATE TABLE evaluations (
    run_id INTEGER NOT NULL REFERENCES runs (run_id),
    idx INTEGER NOT NULL,
    problem TEXT NOT NULL,
    design_key TEXT NOT NULL,
    speed_kmh REAL NOT NULL,
    fidelity TEXT NOT NULL,
    source TEXT NOT NULL,
    x TEXT NOT NULL,
    feasible INTEGER NOT NULL,
    sigma REAL,
    reason TEXT NOT NULL,
    wall_time REAL NOT NULL,
    cached INTEGER NOT NULL,
    charged INTEGER NOT NULL,
    reward REAL,
    created_at TEXT NOT NULL,
    constraints TEXT,
    statistics TEXT,
    PRIMARY KEY (run_id, idx)
);
CREATE INDEX evaluations_cache ON evaluations (problem, design_key, speed_kmh, fidelity, source);
"""


class StoreError(CatenaryError, RuntimeError):
    """The run store cannot be used: not a run store, another schema, or a run that cannot be resumed."""


class RunConfig(NamedTuple):
    """What identifies a run: resuming looks for a stored run with the same configuration.

    Attributes
    ----------
    optimizer : str
        Registry name of the optimiser.
    problem : str
        Problem id.
    budget : int
        Simulations allowed.
    seed : int
        Random seed.
    speed_kmh : float or None
        Design speed, km/h; None for a policy trained over a speed range.
    fidelity : str
        Model fidelity.
    options : str
        The optimiser's hyper-parameters as canonical JSON (sorted keys).
    package_version : str
        Version of catenary-env that made the run.
    """

    optimizer: str
    problem: str
    budget: int
    seed: int
    speed_kmh: float | None
    fidelity: str
    options: str
    package_version: str


@dataclass(frozen=True)
class StoredEvaluation:
    """An evaluation row of a run, as read back for a replay.

    Attributes
    ----------
    record : EvaluationRecord
        The evaluation.
    design_key : tuple of int
        Its design on the grid, ``round(x / step)``.
    reward : float or None
        The env's reward (RL runs only).
    """

    record: EvaluationRecord
    design_key: tuple[int, ...]
    reward: float | None


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds")


def _key_text(design_key: tuple[int, ...]) -> str:
    return ",".join(str(int(k)) for k in design_key)


class RunStore:
    """An open run store (a context manager; :meth:`close` when done).

    Parameters
    ----------
    path : str or path-like
        The SQLite file, created if absent; ``":memory:"`` for a store that lives as long as the object.
    read_only : bool
        Open an existing store without writing to it (a store that runs are writing into can be read).

    Raises
    ------
    StoreError
        The file is not SQLite, or an SQLite database that is not a run store of this schema version;
        read-only, a file that holds no store yet.
    """

    def __init__(self, path: str | os.PathLike[str], read_only: bool = False) -> None:
        self.path = str(path)
        self.read_only = read_only
        if self.path != ":memory:":
            _check_header(Path(self.path))
        try:
            if read_only:
                uri = f"{Path(self.path).resolve().as_uri()}?mode=ro"
                self._connection = sqlite3.connect(uri, uri=True, timeout=60.0)
            else:
                self._connection = sqlite3.connect(self.path, timeout=60.0)
            self._open()
        except sqlite3.DatabaseError as error:
            if hasattr(self, "_connection"):
                self._connection.close()
            raise StoreError(f"{self.path}: not a usable SQLite run store ({error})") from error

    def _open(self) -> None:
        connection = self._connection
        application_id = connection.execute("PRAGMA application_id").fetchone()[0]
        if application_id == 0 and not self.read_only:
            self._create()  # the schema, if the file is empty (another process may just have written it)
            application_id = connection.execute("PRAGMA application_id").fetchone()[0]
        n_tables = connection.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]
        if application_id == 0 and n_tables == 0:
            connection.close()
            raise StoreError(f"{self.path}: an empty file, not a run store (yet)")
        if application_id != APPLICATION_ID:
            connection.close()
            raise StoreError(
                f"{self.path}: an SQLite database that is not a catenary-env run store (application_id "
                f"{application_id:#x}, expected {APPLICATION_ID:#x}); refusing to write into it: "
                "give another --store path"
            )
        version = connection.execute("PRAGMA user_version").fetchone()[0]
        if version != SCHEMA_VERSION and version not in _UPGRADABLE:
            connection.close()
            raise StoreError(
                f"{self.path}: run store schema version {version}, this code reads versions "
                f"{', '.join(map(str, [*_UPGRADABLE, SCHEMA_VERSION]))}: use the catenary-env that made it"
            )
        if version != SCHEMA_VERSION and not self.read_only:
            with connection:
                for statement in _UPGRADABLE[version]:
                    connection.execute(statement)
                connection.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            version = SCHEMA_VERSION
        self.schema_version = int(version)
        self._check_integrity()
        if self.path != ":memory:" and not self.read_only:
            # WAL: a committed evaluation survives a SIGKILL; NORMAL sync is durable against a process
            # crash (only a power cut can lose the last commits).
            connection.execute("PRAGMA journal_mode=WAL")
            connection.execute("PRAGMA synchronous=NORMAL")

    def _check_integrity(self) -> None:
        """Refuse a damaged file (SQLite's own page checks) or one whose tables are not the schema's."""
        problems = [row[0] for row in self._connection.execute("PRAGMA quick_check(3)").fetchall()]
        if problems != ["ok"]:
            self._connection.close()
            raise StoreError(
                f"{self.path}: the run store is damaged ({'; '.join(problems)}); refusing to use it: "
                "restore it from a copy, or give another --store path"
            )
        for table, columns in _schema_columns().items():
            found = {row[1] for row in self._connection.execute(f"PRAGMA table_info({table})")}
            if self.schema_version == 1:  # read-only, not upgraded
                found |= set(_ADDED_IN_2) if table == "evaluations" and found else set()
            if not columns <= found:
                self._connection.close()
                missing = (
                    "the table is missing" if not found else f"columns missing: {sorted(columns - found)}"
                )
                raise StoreError(
                    f"{self.path}: table {table!r} of the run store is damaged ({missing}); refusing to use "
                    "it: restore it from a copy, or give another --store path"
                )

    def _create(self) -> None:
        """Write the schema into a new file, under an exclusive lock and only if no other process has
        written it meanwhile: the lanes of a study started together all open the same new store."""
        connection = self._connection
        connection.execute("BEGIN EXCLUSIVE")
        try:
            if connection.execute("SELECT count(*) FROM sqlite_master").fetchone()[0] == 0:
                for statement in filter(str.strip, _SCHEMA.split(";")):
                    connection.execute(statement)
                connection.execute(f"PRAGMA application_id = {APPLICATION_ID}")
                connection.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
                connection.execute(
                    "INSERT INTO meta (key, value) "
                    "VALUES ('format', 'catenary-env run store'), ('created_at', ?)",
                    (_now(),),
                )
            connection.commit()
        except BaseException:
            connection.rollback()
            raise

    # -- runs ----------------------------------------------------------------------------------------------

    def start_run(self, config: RunConfig) -> int:
        """Create a run; return its id."""
        with self._connection:
            cursor = self._connection.execute(
                "INSERT INTO runs (optimizer, problem, budget, seed, speed_kmh, fidelity, options, "
                "package_version, created_at) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (*config, _now()),
            )
        assert cursor.lastrowid is not None
        return int(cursor.lastrowid)

    def find_run(self, config: RunConfig) -> int | None:
        """The latest run with this configuration (any package version), or None.

        Raises
        ------
        StoreError
            That run was made by another package version (its physics may differ).
        """
        row = self._connection.execute(
            "SELECT run_id, package_version FROM runs WHERE optimizer = ? AND problem = ? AND budget = ? "
            "AND seed = ? AND speed_kmh IS ? AND fidelity = ? AND options = ? ORDER BY run_id DESC LIMIT 1",
            tuple(config[:7]),
        ).fetchone()
        if row is None:
            return None
        if row[1] != config.package_version:
            raise StoreError(
                f"{self.path}: run {row[0]} was made by catenary-env {row[1]}, this is "
                f"{config.package_version}; its results may differ: resume it with that version, "
                "or start the run in a new store"
            )
        return int(row[0])

    @contextlib.contextmanager
    def claim(self, config: RunConfig) -> Iterator[bool]:
        """Hold the run of ``config`` for this process while the block runs: yields True, or False when
        another process holds it (it is making that run now).

        The processes that share a study's runs (its lanes) each make only the runs they hold, so no run is
        made twice at once and a lane that has run out of its own runs can take the others' that nobody has
        started. The claim is a lock on a file in the folder ``<store>.claims`` beside the store, which the
        operating system releases when the process ends, however it ends. An in-memory store, or a system
        without ``fcntl`` (Windows), always holds it.
        """
        lock = self._claim_file(config)
        if lock is None or lock in _CLAIMED:  # held already by this process: the comparison holds a run,
            yield True  # then makes it
            return
        Path(lock).parent.mkdir(exist_ok=True)
        with open(lock, "a") as handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                yield False
                return
            _CLAIMED.add(lock)
            try:
                yield True
            finally:
                _CLAIMED.discard(lock)
                fcntl.flock(handle, fcntl.LOCK_UN)

    def being_made(self, config: RunConfig) -> bool:
        """Whether a process holds the run of ``config`` now (:meth:`claim`): it is making that run. Writes
        nothing, so a read-only store can watch the runs of others."""
        lock = self._claim_file(config)
        if lock is None:
            return False
        if lock in _CLAIMED:
            return True
        try:
            handle = open(lock, "rb")  # noqa: SIM115 (closed below)
        except FileNotFoundError:
            return False  # never claimed
        with handle:
            try:
                fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
            except BlockingIOError:
                return True
            fcntl.flock(handle, fcntl.LOCK_UN)
            return False

    def _claim_file(self, config: RunConfig) -> str | None:
        """The lock file of the run of ``config``; None where runs are not claimed (an in-memory store, a
        system without ``fcntl``)."""
        if fcntl is None or self.path == ":memory:":
            return None
        key = hashlib.sha256(json.dumps(list(config[:7])).encode()).hexdigest()[:16]
        return str(Path(self.path + ".claims", f"{key}.lock").resolve())

    def finish_run(self, run_id: int, stop_reason: str) -> None:
        """Record that a run ended, and why."""
        with self._connection:
            self._connection.execute(
                "UPDATE runs SET finished_at = ?, stop_reason = ? WHERE run_id = ?",
                (_now(), stop_reason, run_id),
            )

    def stop_reason(self, run_id: int) -> str | None:
        """Why a run ended (:meth:`finish_run`), or None while it has not ended (or there is no such run)."""
        row = self._connection.execute("SELECT stop_reason FROM runs WHERE run_id = ?", (run_id,)).fetchone()
        return None if row is None or row[0] is None else str(row[0])

    def runs(self) -> list[dict[str, object]]:
        """Every run as a dict of its columns, oldest first."""
        cursor = self._connection.execute("SELECT * FROM runs ORDER BY run_id")
        names = [column[0] for column in cursor.description]
        return [dict(zip(names, row, strict=True)) for row in cursor.fetchall()]

    def run_rows(self, run_id: int) -> tuple[dict[str, object], list[dict[str, object]]]:
        """A run's row (with its ``run_id``) and its evaluation rows in order (without it), every column as
        stored: what :meth:`add_run_rows` writes into another store."""
        cursor = self._connection.execute("SELECT * FROM runs WHERE run_id = ?", (run_id,))
        names = [column[0] for column in cursor.description]
        found = cursor.fetchone()
        if found is None:
            raise StoreError(f"{self.path}: no run {run_id}")
        run = dict(zip(names, found, strict=True))
        cursor = self._connection.execute(
            "SELECT * FROM evaluations WHERE run_id = ? ORDER BY idx", (run_id,)
        )
        names = [column[0] for column in cursor.description]
        rows = [
            {name: value for name, value in zip(names, row, strict=True) if name != "run_id"}
            for row in cursor.fetchall()
        ]
        return run, rows

    def add_run_rows(
        self, run: dict[str, object], rows: list[dict[str, object]], if_absent: bool = False
    ) -> int | None:
        """Write a run and its evaluations as :meth:`run_rows` gives them (from this store or another), in
        one transaction; return its id here: its ``run_id`` where that is free here (a store restored into
        a new file numbers its runs as the one it came from did), else a new one. ``if_absent``: where the
        store holds a run of the same configuration (checked in the same transaction, so that two processes
        restoring the same run into one store write it once), write nothing and return None, unless that
        run is unfinished, no process is making it now (:meth:`being_made`) and the given one carries it
        further (:meth:`_extend`): then write what it adds and return the stored run's id.

        Raises
        ------
        StoreError
            A column that is not the schema's (the rows come from a file); with ``if_absent``, the store's
            run of that configuration was made by another package version.
        """
        schema = _schema_columns()
        evaluation_columns = schema["evaluations"] - {"run_id"}
        unknown = set(run) - schema["runs"] | {c for row in rows for c in row} - evaluation_columns
        if unknown:
            raise StoreError(f"{self.path}: not columns of a run store to write: {sorted(unknown)}")
        connection = self._connection
        connection.execute("BEGIN IMMEDIATE")
        try:
            config = RunConfig(*(run[f] for f in RunConfig._fields)) if if_absent else None  # type: ignore[arg-type]
            stored = None if config is None else self.find_run(config)
            if stored is not None:
                # (not a run another process is making now: it would write the same evaluations)
                extended = not self.being_made(config) and self._extend(stored, run, rows)
                connection.commit() if extended else connection.rollback()
                return stored if extended else None
            taken = (
                "run_id" in run
                and connection.execute("SELECT 1 FROM runs WHERE run_id = ?", (run["run_id"],)).fetchone()
            )
            run_id = self._insert("runs", {k: v for k, v in run.items() if not (taken and k == "run_id")})
            for row in rows:
                self._insert("evaluations", {"run_id": run_id, **row})
            connection.commit()
        except BaseException:
            connection.rollback()
            raise
        return run_id

    def _extend(self, run_id: int, run: dict[str, object], rows: list[dict[str, object]]) -> bool:
        """Carry an unfinished stored run further with the evaluations of the same run made further
        elsewhere (another machine resumed it from the same snapshot): where every stored evaluation is in
        ``rows`` as the same design with the same result, add the rest and, where ``run`` finished, its end.
        Whether anything was written; a stored run that finished, holds an evaluation ``rows`` lacks or
        differs from them (a branch) is kept as it is. Inside :meth:`add_run_rows`'s transaction."""
        if self.stop_reason(run_id) is not None:
            return False
        given = {row["idx"]: row for row in rows}
        same = ("design_key", "x", "speed_kmh", "sigma", "feasible", "reason")
        cursor = self._connection.execute(
            f"SELECT idx, {', '.join(same)} FROM evaluations WHERE run_id = ?", (run_id,)
        )
        held = set()
        for idx, *values in cursor.fetchall():
            row = given.get(idx)
            if row is None or json.dumps([row[c] for c in same]) != json.dumps(values):  # NaN == NaN here
                return False
            held.add(idx)
        new = [row for row in rows if row["idx"] not in held]
        for row in new:
            self._insert("evaluations", {"run_id": run_id, **row})
        if run["stop_reason"] is not None:  # not finish_run: it would commit the transaction half-way
            self._connection.execute(
                "UPDATE runs SET finished_at = ?, stop_reason = ? WHERE run_id = ?",
                (run["finished_at"], run["stop_reason"], run_id),
            )
        return bool(new) or run["stop_reason"] is not None

    def _insert(self, table: str, row: dict[str, object]) -> int:
        """Insert a row of named columns (checked against the schema by the caller); its rowid."""
        columns = sorted(row)
        cursor = self._connection.execute(
            f"INSERT INTO {table} ({', '.join(columns)}) VALUES ({', '.join('?' * len(columns))})",
            [row[c] for c in columns],
        )
        assert cursor.lastrowid is not None
        return int(cursor.lastrowid)

    def run_progress(self) -> list[dict[str, object]]:
        """Every run's columns (:meth:`runs`) and its progress: ``evaluations`` stored, ``simulations``
        charged to its budget, ``best_sigma`` (N, its best feasible σ, or None) and ``last_evaluation_at``."""
        cursor = self._connection.execute(
            "SELECT r.*, count(e.idx) AS evaluations, coalesce(sum(e.charged), 0) AS simulations, "
            "min(CASE WHEN e.feasible THEN e.sigma END) AS best_sigma, "
            "max(e.created_at) AS last_evaluation_at "
            "FROM runs AS r LEFT JOIN evaluations AS e ON e.run_id = r.run_id "
            "GROUP BY r.run_id ORDER BY r.run_id"
        )
        names = [column[0] for column in cursor.description]
        return [dict(zip(names, row, strict=True)) for row in cursor.fetchall()]

    # -- evaluations ---------------------------------------------------------------------------------------

    def add_evaluation(
        self,
        run_id: int,
        problem: str,
        fidelity: str,
        design_key: tuple[int, ...],
        record: EvaluationRecord,
        source: str = "simulation",
        reward: float | None = None,
    ) -> None:
        """Write (and commit) one evaluation of a run."""
        with self._connection:
            self._connection.execute(
                "INSERT INTO evaluations (run_id, idx, problem, design_key, speed_kmh, fidelity, source, x, "
                "feasible, sigma, reason, wall_time, cached, charged, reward, created_at, constraints, "
                "statistics) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (
                    run_id, record.index, problem, _key_text(design_key), float(record.speed_kmh), fidelity,
                    source, json.dumps(list(record.x)), int(record.feasible), record.sigma, record.reason,
                    float(record.wall_time), int(record.cached), int(record.charged), reward, _now(),
                    json.dumps(list(record.constraints)), json.dumps(list(record.statistics)),
                ),
            )  # fmt: skip

    def drop_evaluations(self, run_id: int, first: int) -> int:
        """Delete a run's evaluations from index ``first`` on (a resumed run that branches off its stored
        history, :meth:`RunRecorder.stored <optimizers.recorder.RunRecorder.stored>`); how many."""
        with self._connection:
            cursor = self._connection.execute(
                "DELETE FROM evaluations WHERE run_id = ? AND idx >= ?", (run_id, first)
            )
        return int(cursor.rowcount)

    def evaluations(self, run_id: int) -> dict[int, StoredEvaluation]:
        """The stored evaluations of a run by index (gaps where evaluations were lost in flight)."""
        rows = self._connection.execute(
            "SELECT idx, x, feasible, sigma, reason, wall_time, cached, charged, speed_kmh, design_key, "
            f"reward, {self._added()} FROM evaluations WHERE run_id = ? ORDER BY idx",
            (run_id,),
        ).fetchall()
        stored: dict[int, StoredEvaluation] = {}
        for row in rows:
            try:
                stored[int(row[0])] = _stored_evaluation(*row)
            except (ValueError, TypeError) as error:  # json.JSONDecodeError is a ValueError
                raise StoreError(
                    f"{self.path}: run {run_id}, evaluation row {row[0]} is damaged ({error}); the run "
                    "cannot be resumed: start it anew without --resume, or in another --store"
                ) from None
        return stored

    def lookup(
        self,
        problem: str,
        design_key: tuple[int, ...],
        speed_kmh: float,
        fidelity: str,
        source: str = "simulation",
    ) -> Outcome | None:
        """The cached outcome of a design (any run of this store), or None if never simulated here;
        ``source="env"``: as an RL run's env step of any env (for its simulation's time, not its reward)."""
        row = self._connection.execute(
            f"SELECT feasible, sigma, reason, wall_time, {self._added()} FROM evaluations WHERE "
            "problem = ? AND design_key = ? AND speed_kmh = ? AND fidelity = ? AND source = ? "
            "ORDER BY cached LIMIT 1",
            (problem, _key_text(design_key), float(speed_kmh), fidelity, source),
        ).fetchone()
        if row is None:
            return None
        sigma = None if row[1] is None else float(row[1])
        return Outcome(bool(row[0]), sigma, str(row[2]), float(row[3]), _values(row[4]), _values(row[5]))

    def lookup_env(
        self, problem: str, design_key: tuple[int, ...], speed_kmh: float, fidelity: str, env: str
    ) -> tuple[Outcome, float] | None:
        """The outcome and reward of an env step an RL run made on the same env, or None.

        ``env`` is the env's settings as canonical JSON (sorted keys), as the run's options hold them under
        ``"env"``: the same env gives the same reward for the same design at the same speed.
        """
        row = self._connection.execute(
            "SELECT e.feasible, e.sigma, e.reason, e.wall_time, e.reward FROM evaluations AS e "
            "JOIN runs AS r ON r.run_id = e.run_id WHERE e.problem = ? AND e.design_key = ? "
            "AND e.speed_kmh = ? AND e.fidelity = ? AND e.source = 'env' AND e.cached = 0 "
            "AND e.reward IS NOT NULL AND json_extract(r.options, '$.env') = json(?) LIMIT 1",
            (problem, _key_text(design_key), float(speed_kmh), fidelity, env),
        ).fetchone()
        if row is None:
            return None
        sigma = None if row[1] is None else float(row[1])
        return Outcome(bool(row[0]), sigma, str(row[2]), float(row[3])), float(row[4])

    def count_evaluations(self, run_id: int | None = None) -> int:
        """Evaluations stored (of one run, or of all)."""
        if run_id is None:
            return int(self._connection.execute("SELECT count(*) FROM evaluations").fetchone()[0])
        query = "SELECT count(*) FROM evaluations WHERE run_id = ?"
        return int(self._connection.execute(query, (run_id,)).fetchone()[0])

    def _added(self, prefix: str = "") -> str:
        """The columns schema version 2 added, in a query (NULL in a version-1 store read as it is)."""
        return ", ".join(f"{prefix}{c}" if self.schema_version >= 2 else f"NULL AS {c}" for c in _ADDED_IN_2)

    def all_evaluations(self) -> list[dict[str, object]]:
        """Every evaluation of the store with its run's optimiser, seed and package version, oldest first:
        the columns of the evaluations table, ``x``, ``constraints`` and ``statistics`` decoded (the dataset
        export)."""
        cursor = self._connection.execute(
            f"SELECT e.run_id, r.optimizer, r.seed, r.package_version, e.idx, e.problem, e.design_key, "
            f"e.speed_kmh, e.fidelity, e.source, e.x, e.feasible, e.sigma, e.reason, e.wall_time, e.cached, "
            f"e.charged, e.reward, e.created_at, {self._added('e.')} "
            "FROM evaluations AS e JOIN runs AS r ON r.run_id = e.run_id "
            "ORDER BY e.run_id, e.idx"
        )
        names = [column[0] for column in cursor.description]
        rows = [dict(zip(names, row, strict=True)) for row in cursor.fetchall()]
        for row in rows:
            row["x"] = tuple(float(v) for v in json.loads(str(row["x"])))
            row["constraints"] = _values(row["constraints"])
            row["statistics"] = _values(row["statistics"])
        return rows

    # -- lifetime ------------------------------------------------------------------------------------------

    def close(self) -> None:
        """Close the connection (committed data is already on disk)."""
        self._connection.close()

    def __enter__(self) -> RunStore:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()


@functools.cache
def _schema_columns() -> dict[str, frozenset[str]]:
    """The columns of each table of the schema, read from a database made with it."""
    connection = sqlite3.connect(":memory:")
    try:
        connection.executescript(_SCHEMA)
        query = "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'"
        tables = [row[0] for row in connection.execute(query)]
        return {t: frozenset(row[1] for row in connection.execute(f"PRAGMA table_info({t})")) for t in tables}
    finally:
        connection.close()


def _stored_evaluation(
    idx: int, x: str, feasible: int, sigma: float | None, reason: str, wall_time: float, cached: int,
    charged: int, speed: float, key: str, reward: float | None, constraints: str | None,
    statistics: str | None,
) -> StoredEvaluation:  # fmt: skip
    """An evaluation row read back; ValueError or TypeError when a field is not what was written."""
    values = json.loads(x)
    if not isinstance(values, list):
        raise ValueError(f"x = {x!r} is not a list of numbers")
    record = EvaluationRecord(
        int(idx), tuple(float(v) for v in values), bool(feasible), None if sigma is None else float(sigma),
        str(reason), float(wall_time), bool(cached), bool(charged), float(speed),
        _values(constraints), _values(statistics),
    )  # fmt: skip
    design_key = tuple(int(k) for k in key.split(",")) if key else ()
    return StoredEvaluation(record, design_key, None if reward is None else float(reward))


def _values(text: str | None) -> tuple[float, ...]:
    """Constraint values or statistics read back (empty where none were stored; NaN as JSON's NaN)."""
    if text is None:
        return ()
    values = json.loads(text)
    if not isinstance(values, list):
        raise ValueError(f"{text!r} is not a list of numbers")
    return tuple(float(v) for v in values)


def _check_header(path: Path) -> None:
    """Refuse a non-empty file that does not start with the SQLite header (before SQLite touches it)."""
    if not path.exists() or path.stat().st_size == 0:
        return
    if path.is_dir():
        raise StoreError(f"{path}: is a directory, not a run store file")
    with path.open("rb") as file:
        header = file.read(len(_SQLITE_HEADER))
    if header != _SQLITE_HEADER:
        raise StoreError(
            f"{path}: not a catenary-env run store (not an SQLite database: the file is corrupt or something "
            "else); refusing to touch it: give another --store path"
        )
