"""The model's fingerprint: the one key of every stored and committed result (docs/model.md, 'Results and
the model that made them').

A result (σ in the run store, an uplift force in the calibration cache, a committed study's data) is reused
or trusted only under the fingerprint it was made with. The fingerprint names

- what the simulator computes, not its source: :func:`simulator_fingerprint` runs tiny canary passages
  (:data:`CANARIES`: each dynamic model, and the modelling choices off their defaults) and compares their
  contact forces and statistics with the canaries recorded for the current model (:data:`CANARY_RECORD`).
  Within :data:`FORCE_TOLERANCE` (rounding: another processor's BLAS kernels, the compiled or the numpy loop,
  a refactoring) the simulator is the recorded model and takes its fingerprint; beyond it (a change of the
  numbers) it is another model, whose fingerprint hashes its canaries rounded to :data:`FORCE_RESOLUTION`;
- the data the caller names (:func:`model_fingerprint`): the definitions (provenance notes excluded), a
  problem's variables, the fidelities' settings.

The canaries take a few seconds. They run once per process, on first use, and their fingerprint is remembered
on disk (in the cache folder, :mod:`~catenary_env.cache_folder`) under a digest of the simulator's source and
of numpy's, scipy's and numba's versions, so that later commands need not wait for them. The digest only
finds the memo; the key is the canaries' result. A deliberate change of the numbers is recorded with
``python -m catenary_env.fingerprint --record``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import hashlib
import importlib.metadata
import json
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .cache_folder import cache_folder
from .model.design import level_design
from .model.options import ModellingOptions
from .model.presets import load_catenary, load_pantograph

# Bound here, by name: a test that replaces the pipeline's functions does not reach the canaries.
from .pipeline import FIDELITIES, Fidelity, evaluate_unchecked, simulate

__all__ = [
    "CANARIES",
    "CANARY_RECORD",
    "FORCE_RESOLUTION",
    "FORCE_TOLERANCE",
    "STATISTICS_TOLERANCE",
    "Canary",
    "canaries_agree",
    "data_fingerprint",
    "model_fingerprint",
    "presets_fingerprint",
    "record_canaries",
    "simulator_fingerprint",
]

FORCE_TOLERANCE = 1e-3
"""N: the canaries' raw and filtered contact forces agree with the recorded ones within this when the
simulator is the recorded model. The same model differs from itself by rounding: up to 1.5e-5 N between
the BLAS kernels of different processors on the span-mode canary, whose contact losses amplify it, and
4e-8 N on the exact ones (docs/model.md, 'Results and the model that made them')."""
STATISTICS_TOLERANCE = 1e-6
"""Relative (with 1e-9 absolute): the canaries' statistics agree with the recorded ones within this (the same
model on different BLAS kernels: 3e-8)."""
FORCE_RESOLUTION = 1e-4
"""N: the forces of a simulator that is not the recorded model are hashed rounded to this. Such a fingerprint
names the numbers of one machine: rounding moves a force across a boundary of 1e-4 N on most other
processors, so a change of the numbers is recorded (:func:`record_canaries`) before results are made
with it."""
CANARY_RECORD = Path(__file__).with_name("canaries.json")
"""The current model's canaries and its fingerprint (written by :func:`record_canaries`)."""

CANARY_CATENARY = "en50318-2002"
"""The canaries' catenary preset (with its pantograph): the standard's data, which do not change."""
CANARY_SPEED = 300.0 / 3.6
"""m/s."""
CANARY_UPLIFT = 120.0
"""N."""

_SECTION = {
    "n_spans": 3,
    "analysis_spans": 1,
    "contact_wire_element": 3.0,
    "messenger_wire_element": 6.0,
    "time_step": 5e-3,
}


class Canary(NamedTuple):
    """One canary passage: the level design of :data:`CANARY_CATENARY` on a 3-span section.

    Attributes
    ----------
    name : str
        What it exercises.
    modelling : ModellingOptions
        The catenary's modelling choices.
    fidelity : Fidelity
        Its section, mesh, time step and dynamic model.
    """

    name: str
    modelling: ModellingOptions
    fidelity: Fidelity


CANARIES = (
    Canary("exact model", ModellingOptions(), Fidelity(**_SECTION, dynamics="exact")),
    # No near spans: the spans beside the pantograph's keep their modes below the far cut-off only.
    Canary(
        "span-mode model",
        ModellingOptions(),
        Fidelity(**_SECTION, dynamics="span-modes", near_spans=0),
    ),
    Canary(
        "exact model, the other modelling choices",
        ModellingOptions(
            uplift_definition="nominal-height",
            messenger_support="hinge",
            axial_restraint="every-support",
            linearisation="extensible",
            dropper_geometric_stiffness="included",
            clamp_masses="distributed",
        ),
        Fidelity(**_SECTION, dynamics="exact"),
    ),
    Canary(
        "exact model, damping other than Rayleigh's (the straightforward loop)",
        ModellingOptions(slack_dropper_damping="stiffness-proportional", rayleigh_damping_scope="wires-only"),
        Fidelity(**_SECTION, dynamics="exact"),
    ),
)
"""The canary passages, some 3 s together (most of it the straightforward loop's)."""

SIMULATOR_PARTS = (
    "model",
    "fem",
    "statics",
    "dynamics",
    "analysis",
    "pipeline.py",
    "fingerprint.py",
    CANARY_RECORD.name,
)
"""The package's parts whose source (and preset data) find the memo of the simulator's fingerprint."""

MEMO_FILE = "simulator.json"
MEMO_ENTRIES = 16
"""Fingerprints remembered (one per simulator source, e.g. of several checkouts)."""


def data_fingerprint(*records: object) -> str:
    """A short hash of the records' data: dataclasses by their fields, ``provenance`` excluded, a catenary's
    modelling choices only where they depart from the defaults (whose physics the canaries hash)."""
    default_modelling = dataclasses.asdict(ModellingOptions())

    def plain(record: object) -> object:
        if dataclasses.is_dataclass(record) and not isinstance(record, type):
            data = dataclasses.asdict(record)
            data.pop("provenance", None)
            if data.get("modelling") == default_modelling:
                data.pop("modelling")
            return data
        return record

    text = json.dumps([plain(record) for record in records], sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def model_fingerprint(*records: object) -> str:
    """The fingerprint of results computed from the records (definitions, a problem's variables, fidelity
    settings) by this simulator: :func:`data_fingerprint` with :func:`simulator_fingerprint`.

    Two results may stand for each other only when their fingerprints agree: an edited copy of a preset that
    keeps its name, or a simulator that computes other numbers, gets a new fingerprint.
    """
    return data_fingerprint(simulator_fingerprint(), *records)


def presets_fingerprint(catenaries: Sequence[str]) -> str:
    """The fingerprint of results computed on catenary presets (with their pantographs) at the named
    fidelities (:data:`~catenary_env.pipeline.FIDELITIES`): what a committed study records."""
    definitions: list[object] = []
    for name in catenaries:
        catenary = load_catenary(name)
        definitions += [catenary, load_pantograph(catenary.pantograph)]
    fidelities = {name: dataclasses.asdict(f) for name, f in FIDELITIES.items()}
    return model_fingerprint(*definitions, fidelities)


CanaryValues = dict[str, list[float]]
"""A canary's results: ``contact_force`` and ``filtered_force`` (N, one a step), ``statistics`` (those of
:class:`~catenary_env.analysis.statistics.ContactForceStatistics`, in its order) and, for the span-mode model,
``evaluation`` (the statistics ``evaluate`` gives)."""


@functools.lru_cache(maxsize=1)
def simulator_fingerprint() -> str:
    """The name of what the simulator computes: the recorded model's fingerprint where the canaries agree
    with its record (:func:`canaries_agree`), else a short hash of the canaries' rounded results.

    Computed once per process; remembered on disk under :func:`source_digest` (see the module's notes).
    """
    key = source_digest()
    memo = _memo_file()
    known = _read_memo(memo).get(key)
    if isinstance(known, str):
        return known
    values = [canary_values(canary) for canary in CANARIES]
    record = _read_record(CANARY_RECORD)
    if record is not None and canaries_agree(values, record[1]):
        fingerprint = record[0]
    else:
        fingerprint = _hashed(values)
    _write_memo(memo, key, fingerprint)
    return fingerprint


def canary_values(canary: Canary) -> CanaryValues:
    """The canary's results (:data:`CanaryValues`)."""
    catenary = dataclasses.replace(load_catenary(CANARY_CATENARY), modelling=canary.modelling)
    pantograph = load_pantograph(catenary.pantograph)
    design = level_design(catenary)
    arguments = (catenary, pantograph, design, CANARY_SPEED, canary.fidelity, CANARY_UPLIFT)
    simulation = simulate(*arguments)
    values = {
        "contact_force": np.asarray(simulation.trajectory.contact_force, dtype=float).tolist(),
        "filtered_force": np.asarray(simulation.filtered_force, dtype=float).tolist(),
        "statistics": [float(v) for v in dataclasses.astuple(simulation.statistics)],
    }
    if canary.fidelity.dynamics == "span-modes":
        statistics = evaluate_unchecked(*arguments).statistics  # the input checked by simulate
        values["evaluation"] = [float(v) for v in dataclasses.astuple(statistics)] if statistics else []
    return values


def canaries_agree(values: Sequence[CanaryValues], recorded: Sequence[CanaryValues]) -> bool:
    """Whether two sets of canary results are the same model's: the same quantities and lengths, non-finite
    values in the same places, forces within :data:`FORCE_TOLERANCE` and statistics within
    :data:`STATISTICS_TOLERANCE`."""
    if len(values) != len(recorded):
        return False
    for mine, theirs in zip(values, recorded, strict=True):
        if mine.keys() != theirs.keys():
            return False
        for name, value in mine.items():
            a, b = np.asarray(value, dtype=float), np.asarray(theirs[name], dtype=float)
            if a.shape != b.shape or not np.array_equal(np.isfinite(a), np.isfinite(b)):
                return False
            forces = name.endswith("force")
            tolerance = (0.0, FORCE_TOLERANCE) if forces else (STATISTICS_TOLERANCE, 1e-9)
            if not np.allclose(a, b, rtol=tolerance[0], atol=tolerance[1], equal_nan=True):
                return False
    return True


def record_canaries(path: Path = CANARY_RECORD, fingerprint: str | None = None) -> str:
    """Record the canaries this simulator computes as the current model's, under ``fingerprint`` (default:
    their hash, :data:`FORCE_RESOLUTION`); returns the fingerprint. Run it once when a change of the numbers
    is meant (results made before it no longer stand for the model)."""
    values = [canary_values(canary) for canary in CANARIES]
    name = _hashed(values) if fingerprint is None else fingerprint
    canaries = [
        {"name": canary.name, **{k: [float(f"{v:.12g}") for v in vs] for k, vs in value.items()}}
        for canary, value in zip(CANARIES, values, strict=True)
    ]
    text = json.dumps({"fingerprint": name, "canaries": canaries}, separators=(",", ":"))
    Path(path).write_text(text + "\n", encoding="utf-8")
    return name


def _read_record(path: Path) -> tuple[str, list[CanaryValues]] | None:
    """The recorded model's fingerprint and canaries; None where there is no readable record."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        canaries = [{k: v for k, v in canary.items() if k != "name"} for canary in data["canaries"]]
        return str(data["fingerprint"]), canaries
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def _hashed(values: Sequence[CanaryValues]) -> str:
    """The fingerprint of an unrecorded simulator: forces in :data:`FORCE_RESOLUTION`, statistics to 7
    significant digits."""
    return data_fingerprint(
        [
            {
                k: _in_resolution(np.asarray(v, dtype=float)) if k.endswith("force") else _significant(v)
                for k, v in value.items()
            }
            for value in values
        ]
    )


def _in_resolution(force: NDArray[np.float64]) -> list[int]:
    """Forces as whole multiples of :data:`FORCE_RESOLUTION` (a non-finite force as an extreme one)."""
    largest = 2.0**62
    steps = np.nan_to_num(np.asarray(force) / FORCE_RESOLUTION, nan=-largest, posinf=largest, neginf=-largest)
    return np.rint(np.clip(steps, -largest, largest)).astype(np.int64).tolist()


def _significant(values: Sequence[float]) -> list[str]:
    return [f"{float(v):.6e}" for v in values]


@functools.lru_cache(maxsize=1)
def source_digest() -> str:
    """A hash of the simulator's source and preset files and of the numerical libraries' versions: finds the
    memo of :func:`simulator_fingerprint` (a changed file or library runs the canaries again)."""
    root = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for part in SIMULATOR_PARTS:
        path = root / part
        files = (
            [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.suffix in (".py", ".toml"))
        )
        for file in files:
            digest.update(file.relative_to(root).as_posix().encode())
            digest.update(file.read_bytes())
    for library in ("numpy", "scipy", "numba"):
        try:
            digest.update(f"{library} {importlib.metadata.version(library)}".encode())
        except importlib.metadata.PackageNotFoundError:
            digest.update(f"{library} none".encode())
    return digest.hexdigest()[:16]


def _memo_file() -> Path | None:
    folder = cache_folder()
    return None if folder is None else folder / MEMO_FILE


def _read_memo(path: Path | None) -> dict[str, object]:
    """The remembered fingerprints by source digest; empty when there is none or it cannot be read."""
    if path is None:
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _write_memo(path: Path | None, key: str, fingerprint: str) -> None:
    """Remember the fingerprint (atomically; the latest :data:`MEMO_ENTRIES`); a memo that cannot be written
    is no loss: the canaries run again next time."""
    if path is None:
        return
    memo = {k: v for k, v in _read_memo(path).items() if k != key}
    memo[key] = fingerprint
    text = json.dumps(dict(list(memo.items())[-MEMO_ENTRIES:]), indent=1)
    temporary: str | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(
            "w", encoding="utf-8", dir=path.parent, prefix=".simulator-", suffix=".tmp", delete=False
        ) as handle:
            temporary = handle.name
            handle.write(text)
        os.replace(temporary, path)
    except OSError:
        if temporary is not None:
            with contextlib.suppress(OSError):
                os.unlink(temporary)


if __name__ == "__main__":
    import sys

    if sys.argv[1:] != ["--record"]:
        sys.exit(
            "usage: python -m catenary_env.fingerprint --record (this simulator's canaries as the model's)"
        )
    print(f"recorded the canaries of model {record_canaries()} in {CANARY_RECORD}")
