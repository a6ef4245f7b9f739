"""The uplift calibration is computed once per model, speed and fidelity, kept on disk, and announced.

The simulator's calibration is replaced by a counter (the subject is when it runs, not what it gives); one
test runs a second process on the file that the first one wrote.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from catenary_env import fingerprint, pipeline
from catenary_env.calibration_cache import CACHE_ENV, CacheWarning, cache_file, cached_uplift
from catenary_env.cli import main
from catenary_env.model.design import level_design
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.problems import PROBLEMS, clear_caches

ROOT = Path(__file__).resolve().parents[1]
FAKE_FORCE = 123.456


@pytest.fixture
def calls(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[list[tuple[str, float]]]:
    """A cache folder of the test's own, and the calibrations run (catenary, speed in km/h)."""
    made: list[tuple[str, float]] = []

    def calibrate(catenary, pantograph, design, speed, fidelity, target_mean):  # type: ignore[no-untyped-def]
        made.append((catenary.name, round(speed * 3.6, 6)))
        return FAKE_FORCE

    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "cache"))
    monkeypatch.setattr(pipeline, "calibrate_uplift", calibrate)
    clear_caches()
    yield made
    clear_caches()  # the fake forces must not reach other tests


def test_a_second_process_reads_the_calibration_instead_of_computing_it(calls, capsys):
    assert PROBLEMS["B1"].uplift_force(300.0, "test") == FAKE_FORCE
    assert calls == [("benchmark", 300.0)]
    err = capsys.readouterr().err
    assert "calibrating the pantograph uplift on the reference design" in err  # announced
    assert cache_file().is_file()
    # Another process, with the real simulator: it returns the fake force, so it read the file.
    code = "from catenary_env.problems import PROBLEMS; print(PROBLEMS['B1'].uplift_force(300.0, 'test'))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT, env=os.environ
    )
    assert float(out.stdout) == FAKE_FORCE
    assert "calibrating" not in out.stderr  # nothing to announce


def test_the_same_calibration_runs_once_for_every_problem_and_command(calls, capsys):
    PROBLEMS["B1"].uplift_force(300.0, "test")
    clear_caches()  # as a new process: only the disk cache remains
    PROBLEMS["B2"].uplift_force(300.0, "test")  # the same catenary and reference design
    assert calls == [("benchmark", 300.0)]
    PROBLEMS["B1"].uplift_force(250.0, "test")  # another speed
    PROBLEMS["B1"].uplift_force(250.0, "study")  # another fidelity
    PROBLEMS["SW1"].uplift_force(250.0, "test")  # another catenary
    assert calls == [("benchmark", 300.0), ("benchmark", 250.0), ("benchmark", 250.0), ("stitched", 250.0)]
    assert len(json.loads(cache_file().read_text())["entries"]) == 4


def test_the_key_includes_the_models_fingerprint(calls):
    catenary = load_catenary("benchmark")
    pantograph = load_pantograph("benchmark")
    design = level_design(catenary)
    fidelity = pipeline.FIDELITIES["test"]
    cached_uplift(catenary, pantograph, design, 300.0, fidelity, 157.3)
    cached_uplift(catenary, pantograph, design, 300.0, fidelity, 157.3)
    assert len(calls) == 1
    # An edited copy that keeps the preset's name is another model: calibrated anew.
    heavier = dataclasses.replace(pantograph, masses=(7.0, *pantograph.masses[1:]))
    cached_uplift(catenary, heavier, design, 300.0, fidelity, 157.3)
    assert len(calls) == 2
    entries = json.loads(cache_file().read_text())["entries"].values()
    fingerprints = {entry["model_fingerprint"] for entry in entries}
    assert fingerprints == {
        fingerprint.model_fingerprint(catenary, pantograph),
        fingerprint.model_fingerprint(catenary, heavier),
    }
    cached_uplift(catenary, pantograph, design, 300.0, fidelity, 160.0)  # another target mean force
    assert len(calls) == 3


def test_a_simulator_that_computes_other_numbers_calibrates_anew(calls, monkeypatch):
    """The one invalidation rule: the simulator's fingerprint (its canaries' forces) is part of the key."""
    catenary, pantograph = load_catenary("benchmark"), load_pantograph("benchmark")
    arguments = (catenary, pantograph, level_design(catenary), 300.0, pipeline.FIDELITIES["test"], 157.3)
    cached_uplift(*arguments)
    cached_uplift(*arguments)
    assert len(calls) == 1
    monkeypatch.setattr(fingerprint, "simulator_fingerprint", lambda: "other-forces")
    cached_uplift(*arguments)
    assert len(calls) == 2


@pytest.mark.parametrize(
    "content",
    ["not json at all", '{"format": 1, "entries": [1, 2]}', '{"format": 99, "entries": {}}', "\x00\xff"],
)
def test_a_corrupt_cache_file_is_ignored_with_a_warning_and_rewritten(calls, content):
    path = cache_file()
    path.parent.mkdir(parents=True)
    path.write_text(content, encoding="latin-1")
    with pytest.warns(CacheWarning, match="unreadable"):
        assert PROBLEMS["B1"].uplift_force(300.0, "test") == FAKE_FORCE
    assert len(calls) == 1
    assert len(json.loads(path.read_text())["entries"]) == 1  # healed


def test_a_tampered_entry_is_recomputed(calls):
    PROBLEMS["B1"].uplift_force(300.0, "test")
    path = cache_file()
    data = json.loads(path.read_text())
    for entry in data["entries"].values():
        entry["uplift_force_n"] = "lots"
    path.write_text(json.dumps(data))
    clear_caches()
    assert PROBLEMS["B1"].uplift_force(300.0, "test") == FAKE_FORCE
    assert len(calls) == 2


def test_an_unwritable_cache_folder_warns_and_keeps_the_result_in_the_process(calls, monkeypatch, tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv(CACHE_ENV, str(blocker / "cache"))  # a folder inside a file cannot be made
    with pytest.warns(CacheWarning, match="cannot be written"):
        assert PROBLEMS["B1"].uplift_force(300.0, "test") == FAKE_FORCE
    assert PROBLEMS["B1"].uplift_force(300.0, "test") == FAKE_FORCE  # in memory: no second run
    assert len(calls) == 1


def test_the_cache_can_be_turned_off(calls, monkeypatch):
    monkeypatch.setenv(CACHE_ENV, "off")
    assert cache_file() is None
    PROBLEMS["B1"].uplift_force(300.0, "test")
    clear_caches()
    PROBLEMS["B1"].uplift_force(300.0, "test")
    assert len(calls) == 2


def test_the_default_folder_is_the_users_cache(monkeypatch, tmp_path):
    monkeypatch.delenv(CACHE_ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert cache_file() == tmp_path / "catenary-env" / "uplift.json"


@pytest.mark.parametrize(
    "design", [["--presag", "-0.5"], ["--offsets", *["0.9"] * 9], ["--droppers", "5", "4", "46", "50"]]
)
def test_simulate_refuses_a_bad_design_before_calibrating(calls, capsys, design):
    status = main(["simulate", "benchmark", "--speed", "300", "--fidelity", "test", *design])
    err = capsys.readouterr().err
    assert status == 2 and len(err.strip().splitlines()) == 1, err
    assert calls == []  # no calibration for a design that is refused
    assert "calibrating" not in err


def test_simulate_calibrates_once_and_says_how_its_time_was_spent(calls, capsys):
    argv = ["simulate", "benchmark", "--speed", "300", "--fidelity", "test", "--spans", "3", "--json"]
    assert main(argv) == 0
    first = json.loads(capsys.readouterr().out)
    clear_caches()
    assert main(argv) == 0
    second = json.loads(capsys.readouterr().out)
    assert len(calls) == 1
    assert first["uplift_force"] == second["uplift_force"] == FAKE_FORCE
    parts = first["shape_time"] + first["calibration_time"] + first["passage_time"]
    assert first["wall_time"] == pytest.approx(parts)
    assert first["units"]["uplift_force"] == "N"
