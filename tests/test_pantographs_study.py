"""The two-pantograph study (experiments/pantographs.py): a cheap setting in the default suite, the real quick
run behind the ``slow`` marker."""

from __future__ import annotations

import json

import pytest

from experiments import pantographs


class _InProcess:
    """A stand-in for a process pool: maps in this process."""

    def __init__(self, max_workers: int) -> None:
        pass

    def __enter__(self) -> _InProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def map(self, function, *iterables):  # noqa: ANN001, ANN201
        return map(function, *iterables)


def test_the_optima_table_on_a_cheap_setting(tmp_path, monkeypatch):
    # SW1 alone, its optimum given as the reference design itself: it cannot beat the level wire. A fixed
    # uplift force spares the calibration.
    from catenary_env.problems.design_problem import DesignProblem

    monkeypatch.setattr(DesignProblem, "uplift_force", lambda self, speed_kmh=300.0, fidelity="study": 160.0)
    designs = tmp_path / "designs" / "design" / "SW1"
    designs.mkdir(parents=True)
    (designs / "summary.json").write_text(json.dumps({"optimum_x": [0.0, 0.0, 0.0, 0.0]}))
    monkeypatch.setattr(
        pantographs, "ProcessPoolExecutor", _InProcess
    )  # the patch holds in this process only
    config = pantographs.Config(
        out=tmp_path, workers=1, designs=tmp_path / "designs", problems=("SW1",), optima_only=True
    )
    folder = pantographs.main(config)
    rows = pantographs.read_csv(folder / "optima.csv")
    assert [r["design"] for r in rows] == ["level", "optimum"]
    level, optimum = rows
    assert optimum["sigma_trailing_N"] == pytest.approx(level["sigma_trailing_N"], rel=1e-12)
    assert level["sigma_trailing_N"] != pytest.approx(level["sigma_leading_N"], rel=1e-3)
    assert [r["beats_level_trailing"] for r in pantographs.beats_level(rows)] == [0, 0]
    assert (folder / "model.json").exists() and not (folder / "speed.csv").exists()
    written = (folder / "pantographs.md").read_text(encoding="utf-8")
    (folder / "pantographs.md").unlink()
    pantographs.report(folder)
    assert (folder / "pantographs.md").read_text(encoding="utf-8") == written


def test_the_quick_gas_train_fits_its_section():
    config = pantographs.Config()
    assert config.ga_fidelity == "test" and config.ga_spacing("B1") == 55.0
    assert pantographs.Config(full=True).ga_spacing("SW1") == pantographs.SPACING


def test_the_gas_problem_simulates_its_train():
    # The GA of part 2 sees the train through the optimisers' adapter: its σ is the worse pantograph's, not
    # the single pantograph's (the store keys them apart too).
    from catenary_env.problems import evaluate_problem
    from optimizers.catenary_adapter import catenary_problem

    train = pantographs.train_of("B1", "worst", pantographs.Config().ga_spacing("B1"))
    problem = catenary_problem("B1", train)
    x = (0.0, 0.0, 0.0, 0.0, 0.0)
    outcome = problem.simulate(x, 300.0, "test")
    both = evaluate_problem("B1", x, 300.0, "test", train=train).pantograph_statistics
    assert outcome.sigma == pytest.approx(max(s.std for s in both), rel=1e-12)
    assert outcome.sigma != pytest.approx(catenary_problem("B1").simulate(x, 300.0, "test").sigma, rel=1e-3)
    assert problem.model_fingerprint != catenary_problem("B1").model_fingerprint


@pytest.mark.slow  # the real quick study: a minute or two
def test_the_quick_study_writes_its_data_and_remakes_its_report(tmp_path):
    folder = pantographs.main(pantographs.Config(out=tmp_path, workers=1))
    for name in (
        "optima.csv",
        "speed.csv",
        "designs.json",
        "searches.json",
        "pantographs.md",
        "pantographs.png",
        "model.json",
    ):
        assert (folder / name).stat().st_size > 0, name
    searches = json.loads((folder / "searches.json").read_text(encoding="utf-8"))
    assert set(searches) == set(pantographs.Config().ga_problems)
    assert all(one["least_contact_loss_percent"] >= 0.0 for one in searches.values())
    assert "GA, worse pantograph" in (folder / "pantographs.md").read_text(encoding="utf-8")
    speeds = pantographs.read_csv(folder / "speed.csv")
    assert {r["design"] for r in speeds} <= {"single", "worst"}
    assert {r["speed_kmh"] for r in speeds} == set(pantographs.Config().speeds_kmh)
