"""The two-pantograph study (experiments/pantographs.py): a cheap setting in the default suite, the real quick
run behind the ``slow`` marker."""

from __future__ import annotations

import json

import pytest

from experiments import pantographs


def test_the_optima_table_on_a_cheap_setting(tmp_path):
    # SW1 alone, its optimum given as the reference design itself: it cannot beat the level wire.
    designs = tmp_path / "designs" / "design" / "SW1"
    designs.mkdir(parents=True)
    (designs / "summary.json").write_text(json.dumps({"optimum_x": [0.0, 0.0, 0.0, 0.0]}))
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


@pytest.mark.slow  # the real quick study: a minute or two
def test_the_quick_study_writes_its_data_and_remakes_its_report(tmp_path):
    folder = pantographs.main(pantographs.Config(out=tmp_path, workers=1))
    for name in (
        "optima.csv",
        "speed.csv",
        "designs.json",
        "pantographs.md",
        "pantographs.png",
        "model.json",
    ):
        assert (folder / name).stat().st_size > 0, name
    speeds = pantographs.read_csv(folder / "speed.csv")
    assert {r["design"] for r in speeds} <= {"single", "worst"}
    assert {r["speed_kmh"] for r in speeds} == set(pantographs.Config().speeds_kmh)
