"""Which model made a study's data: ``model.json`` in the study's folder (docs/model.md, 'Results and the
model that made them').

A study writes its stamp when its data are written: the catenary presets it simulated, the fingerprint of
those presets at the named fidelities with the simulator
(:func:`~catenary_env.fingerprint.presets_fingerprint`) and the simulator's own fingerprint. The report
(``catenary report``) recomputes the fingerprint and names the studies whose data another model made.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from catenary_env.fingerprint import presets_fingerprint, simulator_fingerprint
from catenary_env.problems import PROBLEMS

__all__ = ["STAMP", "ModelStamp", "catenaries_of", "model_section", "stamp_study"]

STAMP = "model.json"
"""The stamp's file name in a study's folder."""


@dataclass(frozen=True)
class ModelStamp:
    """The model that made a study's data.

    Attributes
    ----------
    catenaries : tuple of str
        The catenary presets simulated (each with its pantograph).
    fingerprint : str
        :func:`~catenary_env.fingerprint.presets_fingerprint` of those presets when the data were made.
    simulator : str
        :func:`~catenary_env.fingerprint.simulator_fingerprint` then.
    """

    catenaries: tuple[str, ...]
    fingerprint: str
    simulator: str

    @classmethod
    def now(cls, catenaries: Sequence[str]) -> ModelStamp:
        """The stamp of data made now on ``catenaries``."""
        names = tuple(sorted(set(catenaries)))
        return cls(names, presets_fingerprint(names), simulator_fingerprint())

    @classmethod
    def read(cls, folder: Path) -> ModelStamp | None:
        """The stamp in ``folder``; None where there is none or it cannot be read."""
        try:
            data = json.loads((Path(folder) / STAMP).read_text(encoding="utf-8"))
            return cls(tuple(data["catenaries"]), str(data["fingerprint"]), str(data["simulator"]))
        except (OSError, ValueError, KeyError, TypeError):
            return None

    def write(self, folder: Path) -> None:
        (Path(folder) / STAMP).write_text(json.dumps(asdict(self), indent=1) + "\n", encoding="utf-8")

    def is_current(self) -> bool:
        """Whether today's model (presets, fidelities, simulator) is the one that made the data."""
        return presets_fingerprint(self.catenaries) == self.fingerprint


def stamp_study(folder: Path, catenaries: Sequence[str]) -> None:
    """Record in ``folder`` that today's model made its data on ``catenaries`` (call it with the data).

    Data of the synthetic problems only (no catenary) come from no catenary model: no stamp, and an older
    one is removed.
    """
    if catenaries:
        # A run on some of a study's problems (one lane of several) leaves the data of the others in the
        # folder (their files, the rows of its logs): where today's model made those too, it names them all.
        old = ModelStamp.read(folder)
        kept = old.catenaries if old is not None and old.is_current() else ()
        ModelStamp.now((*kept, *catenaries)).write(folder)
    else:
        (Path(folder) / STAMP).unlink(missing_ok=True)


def catenaries_of(problems: Iterable[str]) -> tuple[str, ...]:
    """The catenary presets of the named design problems (a synthetic problem has none)."""
    return tuple(sorted({PROBLEMS[name].catenary for name in problems if name in PROBLEMS}))


def model_section(folders: dict[str, Path]) -> str:
    """The report's paragraph on the model behind each study's data (``folders``: study name to folder)."""
    other, unknown = [], []
    for name, folder in folders.items():
        stamp = ModelStamp.read(folder)
        if stamp is None:
            unknown.append(name)
        elif not stamp.is_current():
            what = (
                "another simulator"
                if stamp.simulator != simulator_fingerprint()
                else "other presets or fidelities"
            )
            other.append(f"{name} ({stamp.fingerprint}: {what})")
    lines = [f"Model: simulator fingerprint {simulator_fingerprint()}."]
    if other:
        lines.append("Made with another model than the current one: " + ", ".join(other) + ".")
    if unknown:
        lines.append("Made with an unrecorded model (no model.json): " + ", ".join(unknown) + ".")
    if not (other or unknown):
        lines.append("Every study's data were made with the current model.")
    return " ".join(lines)
