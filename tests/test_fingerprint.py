"""Stored results are reused only for the same model: the fingerprint follows the data and the numbers the
simulator computes, not the names or the source (docs/model.md, 'Results and the model that made them')."""

from __future__ import annotations

import dataclasses
import importlib
import itertools
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from catenary_env import fingerprint, pipeline
from catenary_env.cache_folder import CACHE_ENV
from catenary_env.fingerprint import model_fingerprint
from catenary_env.model.presets import load_catenary
from catenary_env.problems import get_problem
from experiments.model_stamp import STAMP, ModelStamp, model_section, stamp_study
from optimizers import GridSpace, catenary_problem

ROOT = Path(__file__).resolve().parents[1]


def test_fingerprint_is_stable_and_follows_the_data():
    benchmark = load_catenary("benchmark")
    assert model_fingerprint(benchmark) == model_fingerprint(load_catenary("benchmark"))
    edited = dataclasses.replace(
        benchmark, contact_wire=dataclasses.replace(benchmark.contact_wire, tension=20000.0)
    )
    assert edited.name == benchmark.name and model_fingerprint(edited) != model_fingerprint(benchmark)
    # Provenance notes are not model data.
    assert model_fingerprint(dataclasses.replace(benchmark, provenance={})) == model_fingerprint(benchmark)


def test_run_store_key_carries_the_problem_fingerprint():
    space = GridSpace.from_problem(catenary_problem("B1"))
    assert space.store_key == f"B1@{get_problem('B1').store_fingerprint()}"
    assert get_problem("B1").fingerprint() != get_problem("B2").fingerprint()


def test_run_store_key_follows_the_fidelities(monkeypatch):
    """A changed cut-off of the span-mode model (or any named fidelity's setting) is another model."""
    before, model = get_problem("B1").store_fingerprint(), get_problem("B1").fingerprint()
    study = pipeline.FIDELITIES["study"]
    monkeypatch.setitem(pipeline.FIDELITIES, "study", dataclasses.replace(study, near_cutoff=600.0))
    assert get_problem("B1").store_fingerprint() != before
    assert get_problem("B1").fingerprint() == model  # the model's data are the same


def test_a_simulator_that_computes_other_numbers_is_another_store_key(monkeypatch):
    """The one invalidation rule: the run store's key carries the simulator's fingerprint, not a revision."""
    before = catenary_problem("B1").model_fingerprint
    monkeypatch.setattr(fingerprint, "simulator_fingerprint", lambda: "other-forces")
    assert catenary_problem("B1").model_fingerprint != before


def test_the_simulator_computes_the_recorded_models_canaries(monkeypatch, tmp_path):
    """The canaries agree with those recorded for the current model (catenary_env/canaries.json), on any
    processor's BLAS kernels. A failure means the simulator computes other numbers: if that is meant, every
    stored and committed result was made by another model; record the new one with `python -m
    catenary_env.fingerprint --record` and make the results again."""
    fingerprint_now, recorded = fingerprint._read_record(fingerprint.CANARY_RECORD)
    values = [fingerprint.canary_values(canary) for canary in fingerprint.CANARIES]
    deviations = {
        (canary.name, name): max(abs(a - b) for a, b in zip(value, old[name], strict=True))
        for canary, value_set, old in zip(fingerprint.CANARIES, values, recorded, strict=True)
        for name, value in value_set.items()
        if name.endswith("force")
    }
    assert fingerprint.canaries_agree(values, recorded), f"largest force deviations (N): {deviations}"
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    monkeypatch.setattr(
        fingerprint, "canary_values", lambda canary: values[fingerprint.CANARIES.index(canary)]
    )
    assert fingerprint.simulator_fingerprint.__wrapped__() == fingerprint_now


def test_rounding_keeps_the_recorded_model_and_a_change_of_the_numbers_does_not(monkeypatch, tmp_path):
    """Forces that differ from the record by rounding (up to 1.5e-5 N between processors' BLAS kernels,
    docs/model.md) are the recorded model; by more than the tolerance (1e-3 N) another one, whose
    fingerprint hashes its own canaries."""
    rng = np.random.default_rng(0)
    forces = 120.0 + 40.0 * rng.standard_normal(400)
    canary = {"contact_force": forces.tolist(), "filtered_force": forces.tolist(), "statistics": [53.6, 0.0]}

    def shifted(force_shift, statistics_factor=1.0):  # type: ignore[no-untyped-def]
        return {
            "contact_force": (forces + force_shift).tolist(),
            "filtered_force": forces.tolist(),
            "statistics": [53.6 * statistics_factor, 0.0],
        }

    simulated = [canary]
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    monkeypatch.setattr(fingerprint, "canary_values", lambda _: simulated[0])
    monkeypatch.setattr(fingerprint, "CANARIES", fingerprint.CANARIES[:1])
    monkeypatch.setattr(fingerprint, "CANARY_RECORD", tmp_path / "canaries.json")
    compute = fingerprint.simulator_fingerprint.__wrapped__
    edits = itertools.count()

    def fingerprint_of(values):  # type: ignore[no-untyped-def]
        simulated[0] = values
        edit = next(edits)  # another source each time: the memo does not answer
        monkeypatch.setattr(fingerprint, "source_digest", lambda: f"edit {edit}")
        return compute()

    recorded = fingerprint.record_canaries(fingerprint.CANARY_RECORD, "the-model")
    assert recorded == "the-model" and fingerprint_of(canary) == "the-model"
    noise = 1.5e-5 * rng.uniform(-1.0, 1.0, forces.size)
    assert fingerprint_of(shifted(noise, 1.0 + 3e-8)) == "the-model"
    changed = [shifted(2e-3), shifted(0.0, 1.0 + 1e-5), {**canary, "statistics": [53.6, 1e-8]}]
    for values in changed:
        assert fingerprint_of(values) == fingerprint._hashed([values]) != "the-model"
    no_record = tmp_path / "none.json"
    monkeypatch.setattr(fingerprint, "CANARY_RECORD", no_record)
    assert fingerprint_of(canary) == fingerprint._hashed([canary])
    assert fingerprint.record_canaries(no_record) == fingerprint._hashed([canary])  # named by its hash
    assert fingerprint_of(shifted(noise)) == fingerprint._hashed([canary])


def test_a_change_of_the_physics_is_another_model():
    """The uplift force stands in for a change of the physics: 1e-4 of it (0.012 N) moves the span-mode
    canary's forces beyond the tolerance; 1e-12 of it does not."""
    canary = fingerprint.CANARIES[1]  # the span-mode model: the quickest
    values = fingerprint.canary_values(canary)
    assert len(values["contact_force"]) > 100 and max(values["contact_force"]) > 0
    uplift = fingerprint.CANARY_UPLIFT
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(fingerprint, "CANARY_UPLIFT", uplift * (1.0 + 1e-12))
        assert fingerprint.canaries_agree([fingerprint.canary_values(canary)], [values])
        patch.setattr(fingerprint, "CANARY_UPLIFT", uplift * (1.0 + 1e-4))
        assert not fingerprint.canaries_agree([fingerprint.canary_values(canary)], [values])


def test_the_memo_finds_the_canaries_result_by_the_source(monkeypatch, tmp_path):
    runs = []

    def canary_values(canary):  # type: ignore[no-untyped-def]
        runs.append(canary.name)
        return {"contact_force": [len(runs)]}

    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    monkeypatch.setattr(fingerprint, "canary_values", canary_values)
    compute = fingerprint.simulator_fingerprint.__wrapped__  # without this process's memory
    first = compute()
    assert len(runs) == len(fingerprint.CANARIES)
    assert compute() == first and len(runs) == len(fingerprint.CANARIES)  # read from the memo
    monkeypatch.setattr(fingerprint, "source_digest", lambda: "edited-source")
    assert compute() != first  # another source: the canaries ran again, and gave other numbers
    assert len(runs) == 2 * len(fingerprint.CANARIES)


def test_the_fidelity_contract_was_measured_on_the_current_model(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    contract = importlib.import_module("fidelity_contract")
    now = contract.fingerprint()
    for path in (contract.REFERENCE_FILE, contract.CONTRACT_FILE):
        recorded = json.loads(path.read_text(encoding="utf-8")).get("fingerprint")
        assert recorded == now, (
            f"{path.relative_to(ROOT)} was made with model {recorded}, the current one is {now}: measure the "
            f"contract again with: {contract.REFRESH}"
        )


def _committed(folder):
    """Whether git tracks a file in ``folder`` (True outside a git checkout): the working tree also holds
    folders that are not results (the run store's claims, results/runs.sqlite.claims)."""
    if not (ROOT / ".git").exists():
        return True
    listed = subprocess.run(["git", "ls-files", "--", str(folder)], cwd=ROOT, capture_output=True, text=True)
    return listed.returncode != 0 or bool(listed.stdout.strip())


def _study_folders(root):
    """The folders of committed studies: each folder of ``root``, or, for one that holds only folders (the
    results of a study run elsewhere, e.g. results/full-protocol/optimizers), each of those."""
    for folder in sorted(p for p in root.iterdir() if p.is_dir() and _committed(p)):
        if any(p.is_file() for p in folder.iterdir()):
            yield folder
        else:
            yield from _study_folders(folder)


def test_every_committed_study_names_the_model_that_made_it():
    studies = list(_study_folders(ROOT / "results"))
    assert studies
    for folder in studies:
        stamp = ModelStamp.read(folder)
        assert stamp is not None, f"{folder.relative_to(ROOT)} has no {STAMP}"
        assert stamp.catenaries and set(stamp.catenaries) <= {"benchmark", "stitched", "en50318-2002"}


def test_the_report_names_data_made_with_another_model(tmp_path):
    for name in ("current", "old", "unknown"):
        (tmp_path / name).mkdir()
    current = ModelStamp.now(["benchmark"])
    current.write(tmp_path / "current")
    dataclasses.replace(current, fingerprint="0ld0ld0ld0ld", simulator="0ld0ld0ld0ld").write(tmp_path / "old")
    text = model_section({name: tmp_path / name for name in ("current", "old", "unknown")})
    assert "another model than the current one: old (0ld0ld0ld0ld: another simulator)" in text
    assert "unrecorded model (no model.json): unknown" in text
    assert "current (" not in text
    assert model_section({"current": tmp_path / "current"}).endswith("made with the current model.")


def test_a_study_run_on_some_of_its_problems_keeps_the_others_current_catenaries(tmp_path):
    stamp_study(tmp_path, ["stitched"])
    stamp_study(tmp_path, ["benchmark"])  # a lane of the study on a benchmark problem only
    assert ModelStamp.read(tmp_path) == ModelStamp.now(["benchmark", "stitched"])
    dataclasses.replace(ModelStamp.now(["stitched"]), fingerprint="0ld0ld0ld0ld").write(tmp_path)
    stamp_study(tmp_path, ["benchmark"])  # the other data came from another model: not claimed
    assert ModelStamp.read(tmp_path) == ModelStamp.now(["benchmark"])


def test_a_study_of_synthetic_problems_only_names_no_catenary_model(tmp_path):
    stamp_study(tmp_path, ["benchmark"])
    assert ModelStamp.read(tmp_path) == ModelStamp.now(["benchmark"])
    stamp_study(tmp_path, [])  # the same folder rewritten by a study of the synthetic problems
    assert ModelStamp.read(tmp_path) is None
