"""Saved design policies: one file, stable-baselines3's zip archive with the policy's record inside it,
checked when read back before anything in it is unpickled."""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from catenary_env.errors import CatenaryError

from ..base import OptimizationResult
from ..problem import GridProblem
from ..recorder import package_version
from .learners import LEARNERS, import_stable_baselines3, learner_name_of_model
from .policy import DesignPolicy, EnvSpec, ObservationScaling

POLICY_MEMBER = "catenary_env_policy.json"
"""The member of a saved policy's zip archive that describes it (stable-baselines3 ignores it)."""
POLICY_FORMAT = 2
"""Format of the record; format 1 (PPO only: no ``learner``, no ``excluded_speeds``) is read too."""

MODEL_MEMBERS = frozenset(
    {"data", "policy.pth", "policy.optimizer.pth", "pytorch_variables.pth", "_stable_baselines3_version",
     "system_info.txt", "actor.optimizer.pth", "critic.optimizer.pth", "ent_coef_optimizer.pth"}
)  # fmt: skip
"""The members of a PPO or SAC model saved by stable-baselines3 (``BaseAlgorithm.save``; SAC's optimisers are
saved one per network); ``data`` (JSON, whose ``:serialized:`` entries are pickled) and ``policy.pth`` (the
weights) are always there."""


class PolicyFileError(CatenaryError, ValueError):
    """A file given as a saved policy that is not one (missing, a folder, not a zip archive, no record or a
    damaged one, other members than a saved model's); the message names the file and what is wrong."""


@dataclass(frozen=True)
class PolicyRecord:
    """What a saved policy file says about its policy, beside the network.

    Attributes
    ----------
    problem : str
        The problem's name (``"B1"``).
    learner : str
        ``"ppo"`` or ``"sac"`` (:data:`LEARNERS`).
    variable_names : tuple of str
        The variables of the designs it proposes.
    model_fingerprint : str
        The fingerprint of the problem's model when trained (an edited preset or a new simulator revision
        changes it).
    env_spec : EnvSpec
        The env trained on: its speed, or its speed range and held-out speed bands, and fidelity.
    budget, seed : int
        The training run's simulations and seed.
    run_id : int or None
        The training run in its store.
    best_x : tuple of float or None
        The best design met in training, m.
    best_sigma : float or None
        Its σ, N, at ``best_speed_kmh``.
    best_speed_kmh : float or None
        The speed ``best_x`` was simulated at, km/h.
    package_version : str
        The version of the package that trained it.
    command : str
        The command that reproduces the training run ("" when not given).
    """

    problem: str
    learner: str
    variable_names: tuple[str, ...]
    model_fingerprint: str
    env_spec: EnvSpec
    budget: int
    seed: int
    run_id: int | None
    best_x: tuple[float, ...] | None
    best_sigma: float | None
    best_speed_kmh: float | None
    package_version: str
    command: str = ""

    @property
    def speeds(self) -> str:
        """The speeds (and contact-wire tensions) trained on, in words."""
        return self.env_spec.conditions


def save_policy(
    policy: DesignPolicy,
    path: str | os.PathLike[str],
    problem: GridProblem,
    result: OptimizationResult | None = None,
    command: str = "",
) -> Path:
    """Save a trained policy as one file: stable-baselines3's zip with :data:`POLICY_MEMBER` inside.

    The file is written beside ``path`` and renamed onto it, so an interrupted save leaves no half file.

    Parameters
    ----------
    policy : DesignPolicy
        The trained policy.
    path : path-like
        The file to write (any name; ``.zip`` is the custom).
    problem : GridProblem
        Its problem (name, variables, model fingerprint).
    result : OptimizationResult, optional
        The training run's record (budget, seed, run, best design met).
    command : str
        The command that reproduces the training run, kept in the record.

    Returns
    -------
    Path
        ``path``.
    """
    target = Path(path)
    record = {
        "format": POLICY_FORMAT,
        "problem": problem.name,
        "learner": learner_name_of_model(policy.model),
        "variable_names": list(problem.variable_names),
        "model_fingerprint": str(getattr(problem, "model_fingerprint", "")),
        "env_spec": policy.env_spec.as_dict(),
        "observation_scaling": None
        if policy.observation_scaling is None
        else {
            "mean": np.asarray(policy.observation_scaling.mean).tolist(),
            "var": np.asarray(policy.observation_scaling.var).tolist(),
            "epsilon": policy.observation_scaling.epsilon,
            "clip": policy.observation_scaling.clip,
        },
        "budget": None if result is None else result.budget,
        "seed": None if result is None else result.seed,
        "run_id": None if result is None else result.run_id,
        "best_x": None if result is None else result.best_x,
        "best_sigma": None if result is None else result.best_sigma,
        "best_speed_kmh": None if result is None else result.best_speed_kmh,
        "package_version": package_version(),
        "command": command,
        "units": {"best_x": "m", "best_sigma": "N", "best_speed_kmh": "km/h", "env_spec.speed_kmh": "km/h"},
    }
    handle, temporary = tempfile.mkstemp(suffix=".zip", prefix=f".{target.name}-", dir=target.parent)
    os.close(handle)
    try:
        policy.model.save(temporary)
        with zipfile.ZipFile(temporary, "a") as archive:
            archive.writestr(POLICY_MEMBER, json.dumps(record, indent=1))
        os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise
    return target


def load_policy(path: str | os.PathLike[str]) -> tuple[DesignPolicy, PolicyRecord]:
    """Read a policy saved by :func:`save_policy`.

    Loading the model unpickles parts of it (stable-baselines3 does: the ``:serialized:`` entries of its
    ``data`` member): a policy file from someone else can run code. Load only files you made or trust. What
    is not a policy file is refused before stable-baselines3 reads it (:func:`check_policy_file`).

    Raises
    ------
    PolicyFileError
        Not a policy file (missing, a folder, not a zip, no :data:`POLICY_MEMBER`, other members than a saved
        PPO or SAC model's), or a damaged one: the message names the file and what is wrong.
    """
    source = Path(path)
    record, scaling = check_policy_file(source)
    sb3 = import_stable_baselines3()
    try:
        model = getattr(sb3, record.learner.upper()).load(source, device="cpu")
    except Exception as error:  # whatever torch or pickle raise on a damaged archive
        raise PolicyFileError(
            f"{source}: the {record.learner} model inside cannot be loaded ({type(error).__name__}: {error})"
        ) from error
    return DesignPolicy(model, record.env_spec, scaling), record


def check_policy_file(source: Path) -> tuple[PolicyRecord, ObservationScaling | None]:
    """The record of a policy file and its observation scaling, after checking that the file has a saved
    policy's layout: a zip archive of :data:`MODEL_MEMBERS` and :data:`POLICY_MEMBER`, whose ``data`` is
    JSON. Nothing is unpickled.

    Raises
    ------
    PolicyFileError
        The file is missing, a folder, or not a policy file.
    """
    if source.is_dir():
        raise PolicyFileError(f"{source}: is a folder; give a policy file")
    try:
        with zipfile.ZipFile(source) as archive:
            members = {name: archive.read(name) for name in {"data", POLICY_MEMBER} & set(archive.namelist())}
            names = set(archive.namelist())
    except FileNotFoundError:
        raise PolicyFileError(f"{source}: no such policy file; {_SAVE_HINT}") from None
    except OSError as error:
        raise PolicyFileError(f"{source}: cannot be read ({error.strerror or error})") from None
    except zipfile.BadZipFile:
        raise PolicyFileError(f"{source}: not a design policy (not a zip archive); {_SAVE_HINT}") from None
    if POLICY_MEMBER not in names:
        raise PolicyFileError(
            f"{source}: a zip archive without {POLICY_MEMBER}, not a design policy; {_SAVE_HINT}"
        )
    record = _policy_record(source, members[POLICY_MEMBER])
    missing, foreign = {"data", "policy.pth"} - names, names - MODEL_MEMBERS - {POLICY_MEMBER}
    if missing or foreign:
        lacks, extra = ", ".join(sorted(missing)) or "none", ", ".join(sorted(foreign)) or "none"
        raise PolicyFileError(
            f"{source}: not the layout of a saved design policy (missing: {lacks}; other members: {extra}); "
            f"{_SAVE_HINT}"
        )
    try:
        json.loads(members["data"])
    except ValueError as error:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        raise PolicyFileError(f"{source}: the model's data member is not JSON ({error})") from None
    return record


_SAVE_HINT = "save one with: catenary optimize PROBLEM --optimizer ppo --budget N --save-policy FILE"


def _policy_record(source: Path, text: bytes) -> tuple[PolicyRecord, ObservationScaling | None]:
    """The record of a policy file and its observation scaling; ValueError naming the field that is wrong."""
    try:
        data = json.loads(text)
        if not isinstance(data, dict) or data.get("format") not in (1, POLICY_FORMAT):
            found = data.get("format") if isinstance(data, dict) else data
            raise ValueError(f"format: {found!r} is not 1 or {POLICY_FORMAT}")
        learner = str(data.get("learner", "ppo"))
        if learner not in LEARNERS:
            raise ValueError(f"learner: {learner!r} is not one of {', '.join(LEARNERS)}")
        spec = data["env_spec"]
        env_spec = EnvSpec(
            str(spec["env_id"]),
            None if spec["speed_kmh"] is None else float(spec["speed_kmh"]),
            None if spec["speed_range"] is None else tuple(float(v) for v in spec["speed_range"]),
            str(spec["fidelity"]),
            tuple((float(a), float(b)) for a, b in spec.get("excluded_speeds", ())),
            None
            if spec.get("contact_wire_tension_range") is None
            else tuple(float(v) for v in spec["contact_wire_tension_range"]),
            tuple((float(a), float(b)) for a, b in spec.get("excluded_tensions", ())),
        )
        raw = data["observation_scaling"]
        scaling = None if raw is None else ObservationScaling(
            np.asarray(raw["mean"], dtype=np.float64), np.asarray(raw["var"], dtype=np.float64),
            float(raw["epsilon"]), float(raw["clip"]),
        )  # fmt: skip
        best_x = data.get("best_x")
        record = PolicyRecord(
            problem=str(data["problem"]),
            learner=learner,
            variable_names=tuple(str(v) for v in data["variable_names"]),
            model_fingerprint=str(data["model_fingerprint"]),
            env_spec=env_spec,
            budget=int(data["budget"] or 0),
            seed=int(data["seed"] or 0),
            run_id=data.get("run_id"),
            best_x=None if best_x is None else tuple(float(v) for v in best_x),
            best_sigma=data.get("best_sigma"),
            best_speed_kmh=data.get("best_speed_kmh"),
            package_version=str(data.get("package_version", "")),
            command=str(data.get("command", "")),
        )
    except (ValueError, KeyError, TypeError) as error:
        raise PolicyFileError(
            f"{source}: {POLICY_MEMBER} is damaged ({type(error).__name__}: {error})"
        ) from None
    return record, scaling
