"""The pre-sag study's figure plots σ against pre-sag at a speed the data has (the quick setting has no
300 km/h: its left panel was empty)."""

from __future__ import annotations

import pytest

pytest.importorskip("matplotlib", reason="the studies' figures need matplotlib")

from catenary_env.plots import pyplot  # noqa: E402
from experiments import presag  # noqa: E402
from experiments.common import write_csv  # noqa: E402


def _rows(speeds: tuple[float, ...]) -> list[dict]:
    return [
        {
            "problem": name,
            "catenary": catenary,
            "speed_kmh": speed,
            "presag_m": s,
            "feasible": 1,
            "sigma_N": 30.0 + 100.0 * s + speed / 100.0,
            "mean_N": 150.0,
            "uplift_N": 160.0,
            "reason": "",
        }
        for name, catenary in (("BPresag", "benchmark"), ("SWPresag", "stitched"))
        for speed in speeds
        for s in (-0.02, 0.0, 0.02, 0.04)
    ]


@pytest.mark.parametrize(
    ("speeds", "shown"),
    [
        (presag.Config(full=False).speeds_kmh, 320.0),  # the quick setting: 200, 260, 320 km/h
        (presag.Config(full=True).speeds_kmh, 300.0),
    ],
)
def test_the_left_panel_shows_the_data_nearest_the_design_speed(tmp_path, monkeypatch, speeds, shown):
    plt = pyplot()
    figures = []
    monkeypatch.setattr(plt, "close", figures.append)  # keep the figure to look at it
    write_csv(tmp_path / "presag.csv", _rows(speeds))
    presag.report(tmp_path)
    (figure,) = figures
    left = figure.axes[0]
    assert len(left.lines) == 2 and all(len(line.get_xdata()) == 4 for line in left.lines)
    assert f"{shown:g} km/h" in left.get_title()
    assert (tmp_path / "presag.png").is_file()
    figure.clf()
