"""The model's fingerprint: the one key of every stored and committed result (docs/model.md, 'Results and
the model that made them').

A result (σ in the run store, an uplift force in the calibration cache, a committed study's data) is reused
or trusted only under the fingerprint it was made with. The fingerprint hashes

- what the simulator computes, not its source: :func:`simulator_fingerprint` runs tiny canary passages
  (:data:`CANARIES`: each dynamic model, and the modelling choices off their defaults) and hashes their
  contact-force histories rounded to :data:`FORCE_RESOLUTION`, so that a refactoring that keeps the numbers
  keeps the key, and any change of the numbers changes it;
- the data the caller names (:func:`model_fingerprint`): the definitions (provenance notes excluded), a
  problem's variables, the fidelities' settings.

The canaries take a few seconds. They run once per process, on first use, and their fingerprint is remembered
on disk (in the cache folder, :mod:`~catenary_env.cache_folder`) under a digest of the simulator's source and
of numpy's, scipy's and numba's versions, so that later commands need not wait for them. The digest only
finds the memo; the key is the canaries' result.
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
    "FORCE_RESOLUTION",
    "Canary",
    "data_fingerprint",
    "model_fingerprint",
    "presets_fingerprint",
    "simulator_fingerprint",
]

FORCE_RESOLUTION = 1e-4
"""N: the canaries' forces are hashed rounded to this. The compiled and numpy loops (and a reordering of the
arithmetic) agree to some 1e-9 N; at 1e-4 N they fall on two sides of a rounding boundary about once in a
thousand canary runs, while any change of the physics moves the forces by far more."""

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

SIMULATOR_PARTS = ("model", "fem", "statics", "dynamics", "analysis", "pipeline.py", "fingerprint.py")
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


@functools.lru_cache(maxsize=1)
def simulator_fingerprint() -> str:
    """A short hash of what the simulator computes: the canaries' rounded contact forces and statistics.

    Computed once per process; remembered on disk under :func:`source_digest` (see the module's notes).
    """
    key = source_digest()
    memo = _memo_file()
    known = _read_memo(memo).get(key)
    if isinstance(known, str):
        return known
    fingerprint = data_fingerprint([canary_values(canary) for canary in CANARIES])
    _write_memo(memo, key, fingerprint)
    return fingerprint


def canary_values(canary: Canary) -> dict[str, list[int] | list[str]]:
    """The canary's rounded results: the raw and filtered contact force (in :data:`FORCE_RESOLUTION`) and
    the statistics (7 significant digits); for the span-mode model also those of ``evaluate``, which
    stops its passage early."""
    catenary = dataclasses.replace(load_catenary(CANARY_CATENARY), modelling=canary.modelling)
    pantograph = load_pantograph(catenary.pantograph)
    design = level_design(catenary)
    arguments = (catenary, pantograph, design, CANARY_SPEED, canary.fidelity, CANARY_UPLIFT)
    simulation = simulate(*arguments)
    values = {
        "contact_force": _in_resolution(simulation.trajectory.contact_force),
        "filtered_force": _in_resolution(simulation.filtered_force),
        "statistics": _significant(dataclasses.astuple(simulation.statistics)),
    }
    if canary.fidelity.dynamics == "span-modes":
        statistics = evaluate_unchecked(*arguments).statistics  # the input checked by simulate
        values["evaluation"] = _significant(dataclasses.astuple(statistics)) if statistics else []
    return values


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
