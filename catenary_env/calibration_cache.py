"""The pantograph uplift calibration, kept on disk: computed once per model, speed and fidelity.

Calibrating the uplift force (:func:`~catenary_env.pipeline.calibrate_uplift`) takes a few passages of the
reference design, some 15 s at the study fidelity: every ``catenary evaluate``, ``simulate`` and optimiser
worker would pay it again. :func:`cached_uplift` keeps each result in one small JSON file,
``uplift.json`` in the cache folder (:func:`cache_folder`), keyed by

- the model: the catenary's and pantograph's data, the design calibrated on and the fidelity, with the
  simulator's fingerprint (:func:`~catenary_env.fingerprint.model_fingerprint`: an edited copy of a preset
  that keeps its name, or a simulator that computes other numbers, is a new key);
- the speed (km/h) and the target mean contact force (N).

The file is replaced atomically (written beside it, then renamed), so a reader never sees half of it; a
calibration in progress holds the cache's lock, so that parallel workers wait for the first one's result
instead of repeating it. A file that cannot be read is ignored with a :class:`CacheWarning` and rewritten;
a folder that cannot be written leaves the result in this process only. Neither is ever fatal.

``CATENARY_ENV_CACHE`` sets the folder (:mod:`~catenary_env.cache_folder`); ``CATENARY_ENV_CACHE=off`` keeps
nothing on disk (the tests run so).
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import json
import math
import os
import sys
import tempfile
import time
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from . import pipeline
from .cache_folder import CACHE_ENV, cache_folder
from .fingerprint import model_fingerprint
from .model.definition import CatenaryDefinition, PantographDefinition
from .model.design import Design

__all__ = ["CACHE_ENV", "CacheWarning", "cache_file", "cache_folder", "cached_uplift", "quiet_calibrations"]

FILE_NAME = "uplift.json"
FORMAT = 1
"""Version of the file's layout; a file of another version is ignored (and rewritten)."""


_ANNOUNCE = contextvars.ContextVar("catenary_env_announce_calibrations", default=True)


@contextlib.contextmanager
def quiet_calibrations() -> Iterator[None]:
    """Announce no calibration on stderr within the block (the design envs step in it: a training loop
    meets many speeds, each with its calibration)."""
    token = _ANNOUNCE.set(False)
    try:
        yield
    finally:
        _ANNOUNCE.reset(token)


class CacheWarning(UserWarning):
    """The uplift cache could not be read or written: the calibration runs (or is kept) in this process."""


def cache_file() -> Path | None:
    """The uplift cache file, or None when there is no cache on disk."""
    folder = cache_folder()
    return None if folder is None else folder / FILE_NAME


def calibration_key(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    speed_kmh: float,
    fidelity: pipeline.Fidelity,
    target_mean: float,
) -> str:
    """The cache key of a calibration: the model's fingerprint of the definitions, design, fidelity, speed
    and target."""
    return model_fingerprint(
        catenary,
        pantograph,
        design,
        fidelity,
        {"speed_kmh": float(speed_kmh), "target_mean": float(target_mean)},
    )


def cached_uplift(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    design: Design,
    speed_kmh: float,
    fidelity: pipeline.Fidelity,
    target_mean: float,
    *,
    announce: bool = True,
) -> float:
    """The uplift force (N) that gives ``design`` the mean contact force ``target_mean`` (N) at ``speed_kmh``.

    Read from the cache file when it holds this calibration, else computed with
    :func:`~catenary_env.pipeline.calibrate_uplift` (announced on stderr) and stored.

    Parameters
    ----------
    catenary, pantograph : CatenaryDefinition, PantographDefinition
        The model.
    design : Design
        The design calibrated on (a problem's reference design, the level contact wire).
    speed_kmh : float
        Train speed, km/h.
    fidelity : Fidelity
        Model size and resolution.
    target_mean : float
        Mean contact force to reach, N.
    announce : bool
        Say on stderr when the calibration runs, and how long it took (not within
        :func:`quiet_calibrations`).

    Returns
    -------
    float
        Uplift force, N.
    """
    announce = announce and _ANNOUNCE.get()
    key = calibration_key(catenary, pantograph, design, speed_kmh, fidelity, target_mean)
    path = cache_file()
    if path is not None:
        stored = _read(path).get(key)
        if stored is not None:
            return stored
    with _locked(path):
        if path is not None:  # another process may have computed it while this one waited
            stored = _read(path, warn=False).get(key)
            if stored is not None:
                return stored
        if announce:
            print(
                f"calibrating the pantograph uplift on the reference design at {speed_kmh:g} km/h (once per "
                "catenary, speed and fidelity) ...",
                file=sys.stderr,
                flush=True,
            )
        start = time.perf_counter()
        force = float(
            pipeline.calibrate_uplift(
                catenary, pantograph, design, float(speed_kmh) / 3.6, fidelity, target_mean=target_mean
            )
        )
        elapsed = time.perf_counter() - start
        where = _write(path, key, _entry(catenary, pantograph, speed_kmh, fidelity, target_mean, force))
        if announce:
            kept = f", kept in {where}" if where else ""
            print(f"uplift force {force:.2f} N ({elapsed:.1f} s{kept})", file=sys.stderr, flush=True)
    return force


def _entry(
    catenary: CatenaryDefinition,
    pantograph: PantographDefinition,
    speed_kmh: float,
    fidelity: pipeline.Fidelity,
    target_mean: float,
    force: float,
) -> dict[str, Any]:
    """What a reader of the file needs to recognise a calibration (the key alone decides reuse)."""
    return {
        "uplift_force_n": force,
        "catenary": catenary.name,
        "pantograph": pantograph.name,
        "model_fingerprint": model_fingerprint(catenary, pantograph),
        "speed_kmh": float(speed_kmh),
        "target_mean_n": float(target_mean),
        "fidelity": dataclasses.asdict(fidelity),
        "computed": time.strftime("%Y-%m-%dT%H:%M:%S"),
    }


def _read(path: Path, warn: bool = True) -> dict[str, float]:
    """The file's calibrations, key to force; empty when absent; an unreadable file warns, once per read."""
    try:
        text = path.read_text(encoding="utf-8")
    except (
        FileNotFoundError,
        NotADirectoryError,
    ):  # none yet (a bad folder warns on writing)
        return {}
    except (OSError, UnicodeDecodeError) as error:
        return _unreadable(path, error, warn)
    try:
        data = json.loads(text)
        if not (isinstance(data, dict) and data.get("format") == FORMAT):
            raise ValueError(f"not a format-{FORMAT} uplift cache")
        entries = data["entries"]
        if not isinstance(entries, dict):
            raise ValueError("'entries' is not a table")
    except (ValueError, KeyError) as error:
        return _unreadable(path, error, warn)
    forces = {}
    for key, entry in entries.items():
        force = entry.get("uplift_force_n") if isinstance(entry, dict) else None
        # A tampered entry is skipped (and recomputed), never used.
        if isinstance(force, float | int) and math.isfinite(force) and force > 0.0:
            forces[key] = float(force)
    return forces


def _unreadable(path: Path, error: Exception, warn: bool) -> dict[str, float]:
    if warn:
        warnings.warn(
            f"the uplift cache {path} is unreadable ({' '.join(str(error).split())}): ignored; "
            "the calibration runs again and the file is rewritten",
            CacheWarning,
            stacklevel=4,
        )
    return {}


def _write(path: Path | None, key: str, entry: dict[str, Any]) -> Path | None:
    """Add the entry to the file, atomically; the file's path, or None where it could not be written."""
    if path is None:
        return None
    temporary: str | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        entries = _raw_entries(path)
        entries[key] = entry
        text = json.dumps({"format": FORMAT, "entries": entries}, indent=1, sort_keys=True)
        with tempfile.NamedTemporaryFile(
            "w", encoding="utf-8", dir=path.parent, prefix=".uplift-", suffix=".tmp", delete=False
        ) as handle:
            temporary = handle.name
            handle.write(text)
        os.replace(temporary, path)
    except OSError as error:
        if temporary is not None:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
        warnings.warn(
            f"the uplift cache {path} cannot be written ({error.strerror or error}): the calibration is kept "
            f"in this process only; set {CACHE_ENV} to a writable folder (or to 'off')",
            CacheWarning,
            stacklevel=4,
        )
        return None
    return path


def _raw_entries(path: Path) -> dict[str, Any]:
    """The entries as stored (to keep the other calibrations); none from an unreadable file."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        entries = data["entries"] if isinstance(data, dict) and data.get("format") == FORMAT else {}
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError):
        return {}
    return dict(entries) if isinstance(entries, dict) else {}


@contextlib.contextmanager
def _locked(path: Path | None) -> Iterator[None]:
    """Hold the cache's lock while calibrating (POSIX), so that parallel workers that need the same
    calibration compute it once: the others wait, then read it."""
    try:
        import fcntl
    except ImportError:  # Windows: no lock; two processes may both calibrate, harmlessly
        yield
        return
    if path is None:
        yield
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle = open(path.parent / ".uplift.lock", "a")  # noqa: SIM115 (closed below)
    except OSError:
        yield  # _write says that the folder cannot be written
        return
    try:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield
    finally:
        fcntl.flock(handle, fcntl.LOCK_UN)
        handle.close()
