"""The design studies (experiments/design_studies.py) end to end in their quick setting, their resumption
from the run store and the result log, and their report from the data files alone."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

pytest.importorskip("matplotlib", reason="the studies' figures need matplotlib")

from experiments import design_studies  # noqa: E402
from experiments.common import read_csv  # noqa: E402

FILES = ("history.csv", "convergence.csv", "geometry.csv", "droppers.csv", "stiffness.csv", "speed.csv")


def test_convergence_rows_carry_the_elite():
    history = [
        {"generation": 0, "sigma_N": s, "feasible": f, "charged": 1}
        for s, f in ((30.0, 1), (20.0, 1), (np.nan, 0), (25.0, 1))
    ] + [{"generation": 1, "sigma_N": s, "feasible": 1, "charged": 1} for s in (40.0, 18.0)]
    rows = design_studies.convergence_rows(history, population=4, elite=2)
    assert rows[0] == {
        "generation": 0,
        "best_sigma_N": 20.0,
        "mean_sigma_N": 25.0,
        "feasible_share": 0.75,
        "simulations": 4,
    }
    # generation 1: the elite (20, 25) and the children (40, 18)
    assert rows[1]["best_sigma_N"] == 18.0 and rows[1]["mean_sigma_N"] == pytest.approx(25.75)
    assert rows[1]["simulations"] == 6
    assert [design_studies.generation_of(i, 4, 2) for i in range(8)] == [0, 0, 0, 0, 1, 1, 2, 2]


@pytest.fixture(
    scope="module",
    params=[
        # In every run: SW3 (it moves and removes droppers, and its reference design is not in its
        # variables) with one worker, the GA simulating in this process; seconds. A design study has no
        # synthetic stand-in: its statics and speed sweeps need a catenary.
        (1, ("SW3",)),
        # The real quick study: one problem of each catenary, one of heights only, with the spawned
        # worker processes of `python -m experiments.design_studies` (each importing, compiling and
        # calibrating on its own); tens of seconds.
        pytest.param((2, ("B1", "SW3")), marks=pytest.mark.slow),
    ],
    ids=["SW3-in-process", "B1-SW3-two-workers"],
)
def quick_study(request, tmp_path_factory):
    workers, problems = request.param
    out = tmp_path_factory.mktemp("results")
    config = design_studies.Config(full=False, out=out, problems=problems, workers=workers)
    return config, design_studies.main(config)


def test_quick_study_writes_every_file(quick_study):
    config, folder = quick_study
    for name in ("design.md", "speed.png", "convergence.png"):
        assert (folder / name).stat().st_size > 0
    for problem in config.problems:
        sub = folder / problem
        for name in FILES:
            assert read_csv(sub / name), f"{problem}/{name} is empty"
        assert (sub / "design.png").stat().st_size > 0
        summary = json.loads((sub / "summary.json").read_text())
        history = read_csv(sub / "history.csv")
        assert summary["simulations"] == sum(r["charged"] for r in history) <= config.budget
        assert summary["generations"] == 2 and summary["stop_reason"] == "generations"
        assert {r["design"] for r in read_csv(sub / "stiffness.csv")} >= {"reference"}
        speeds = {r["speed_kmh"] for r in read_csv(sub / "speed.csv")}
        assert speeds == set(config.speeds_kmh)
        feasible = [r["sigma_N"] for r in history if r["feasible"]]
        if feasible:
            # the optimum is the history's best, and simulating it again gives the same σ
            assert summary["sigma_optimum_N"] == min(feasible)
            assert summary["sigma_optimum_confirmed_N"] == pytest.approx(summary["sigma_optimum_N"], rel=1e-9)


def test_quick_study_resumes_without_simulating(quick_study, monkeypatch):
    config, folder = quick_study
    before = {p: (folder / p / "history.csv").read_text() for p in config.problems}
    log_lines = (folder / "log.jsonl").read_text().count("\n")

    def no_simulation(*args, **kwargs):
        raise AssertionError("resumed study simulated again")

    monkeypatch.setattr("optimizers.catenary_adapter.simulate_catenary_design", no_simulation)
    monkeypatch.setattr(design_studies, "_evaluate_group", no_simulation)
    monkeypatch.setattr(design_studies, "_static_data", no_simulation)
    design_studies.main(dataclasses.replace(config, workers=1))
    assert {p: (folder / p / "history.csv").read_text() for p in config.problems} == before
    assert (folder / "log.jsonl").read_text().count("\n") == log_lines


def test_report_needs_only_the_data(quick_study, monkeypatch):
    config, folder = quick_study
    for png in folder.rglob("*.png"):
        png.unlink()
    monkeypatch.setattr(design_studies, "optimize", None)
    monkeypatch.setattr(design_studies, "get_problem", None)
    text = design_studies.report(folder)
    assert "α ref. 100 N" in text and (folder / "speed.png").exists()
    for problem in config.problems:
        droppers = read_csv(folder / problem / "droppers.csv")
        forces = ", ".join(f"{r['force_N']:.1f}" for r in droppers if r["design"] == "reference")
        assert f"| {problem} | reference | {forces} |" in text  # static dropper forces
        assert (folder / problem / "design.png").exists()


def test_catenary_report_gathers_the_studies(quick_study, capsys):
    from experiments.cli.report import build_report

    config, folder = quick_study
    path = build_report(config.out)
    text = path.read_text()
    assert "## design:" in text and "| SW3 |" in text
    assert "![design](design/SW3/design.png)" in text and "![speed](design/speed.png)" in text
    assert "Not run yet:" in text and "`catenary experiment validation`" in text
