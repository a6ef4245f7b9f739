"""Studies re-plot from their data files alone (docs/problems.md, 'Experiments'): no simulation in
``report``. The real quick studies run behind the ``slow`` marker (``python -m pytest -m slow``)."""

from __future__ import annotations

import importlib

import pytest

pytest.importorskip("matplotlib", reason="the studies' figures need matplotlib")

from experiments import convergence, presag, validation  # noqa: E402
from experiments.common import write_csv  # noqa: E402


def test_validation_report_reads_only_its_csv(tmp_path):
    rows = [
        {
            "speed_kmh": 300.0,
            "quantity": q,
            "value": v,
            "low": lo,
            "high": hi,
            "passed": int(lo <= v <= hi),
            "margin": max(lo - v, v - hi, 0.0),
        }
        for q, v, lo, hi in [
            ("mean", 113.1, 110, 120),
            ("std", 31.0, 32, 40),
            ("max_support_uplift", 0.056, 0.055, 0.065),
        ]
    ]
    write_csv(tmp_path / "en50318.csv", rows)
    table = validation.report(tmp_path)
    assert "FAIL (by 1.00 N)" in table and "56.00 mm" in table
    assert (tmp_path / "en50318.png").stat().st_size > 0


def test_convergence_report_reads_only_its_csv(tmp_path):
    rows = [
        {
            "n_spans": 5,
            "contact_wire_element_m": h,
            "messenger_wire_element_m": 2 * h,
            "time_step_s": dt,
            "n_dofs": 100,
            "sigma_N": s,
            "mean_N": 157.0,
            "actual_max_N": 250.0,
            "wall_time_s": 1.0,
            "change_vs_finest_percent": 100 * (s - 40.0) / 40.0,
        }
        for h, dt, s in [(0.5, 1e-3, 40.2), (0.25, 5e-4, 40.0)]
    ]
    write_csv(tmp_path / "convergence.csv", rows)
    assert "+0.50" in convergence.report(tmp_path)


def test_presag_report_finds_the_best_feasible_presag(tmp_path):
    rows = [
        {
            "problem": "BPresag",
            "catenary": "benchmark",
            "speed_kmh": 300.0,
            "presag_m": s,
            "feasible": f,
            "sigma_N": sigma,
            "mean_N": 157.0,
            "uplift_N": 170.0,
            "reason": "",
        }
        for s, f, sigma in [(0.0, 1, 40.0), (0.02, 1, 35.0), (0.04, 0, 30.0)]
    ]
    write_csv(tmp_path / "presag.csv", rows)
    table = presag.report(tmp_path)
    assert "| BPresag | 300 | 0.02 | 35.00 | 40.00 | 12.5 |" in table


@pytest.mark.parametrize(
    "module",
    [
        "ablation",
        "design_studies",
        "optimizer_comparison",
        "presag",
        "rl_studies",
        "rl_amortised",
        "tolerance",
    ],
)
@pytest.mark.parametrize("workers", ["0", "-2", "two"])
def test_a_study_refuses_a_worker_count_before_simulating(module, workers, capsys, monkeypatch):
    study = importlib.import_module(f"experiments.{module}")
    monkeypatch.setattr(study, "main", lambda config: pytest.fail("simulated with a bad --workers"))
    with pytest.raises(SystemExit) as exit_:
        study.cli(["--workers", workers])
    assert exit_.value.code == 2
    assert "--workers" in capsys.readouterr().err


@pytest.mark.slow  # the real quick studies: seconds (pre-sag) to minutes (ablation)
@pytest.mark.parametrize(
    ("module", "outputs"),
    [
        ("presag", ["presag.csv", "presag.md", "presag.png"]),
        ("convergence", ["convergence.csv", "convergence.md"]),
        ("ablation", ["ablation.csv", "ablation.json", "ablation.md", "ablation.png"]),
    ],
    ids=["presag", "convergence", "ablation"],
)
def test_a_quick_study_writes_its_data_and_remakes_its_report_from_them(module, outputs, tmp_path):
    study = importlib.import_module(f"experiments.{module}")
    folder = study.main(study.Config(out=tmp_path))
    for name in outputs:
        assert (folder / name).stat().st_size > 0, name
    table = next(name for name in outputs if name.endswith(".md"))
    written = (folder / table).read_text(encoding="utf-8")
    (folder / table).unlink()
    study.report(folder)
    assert (folder / table).read_text(encoding="utf-8") == written
