"""Stored results are reused only for the same model: the fingerprint follows the data, not the names."""

from __future__ import annotations

import dataclasses

from catenary_env import pipeline
from catenary_env.model.presets import load_catenary
from catenary_env.pipeline import model_fingerprint
from catenary_env.problems import get_problem
from optimizers import GridSpace, catenary_problem


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
