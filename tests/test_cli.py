"""The ``catenary`` command line: JSON for scripts, clear errors before any solve, help with units."""

from __future__ import annotations

import importlib.metadata
import json

import pytest

from catenary_env import cli
from catenary_env.cli import main


def test_static_json_gives_dropper_lengths_and_forces(capsys):
    assert main(["static", "benchmark", "--fidelity", "test", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["feasible"] and len(out["dropper_lengths"]) == 9
    assert sum(out["dropper_forces"]) > 600.0  # the span's contact wire weighs about 730 N


def test_simulate_json_gives_the_statistics(capsys):
    assert main(["simulate", "en50318-2002", "--speed", "250", "--fidelity", "test", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    stats = out["statistics"]
    assert 80.0 < stats["mean"] < 130.0 and stats["std"] > 0.0
    assert out["uplift_force"] == pytest.approx(117.5)


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["simulate", "benchmark", "--speed", "600"], "speed"),
        (["simulate", "benchmark", "--speed", "-5", "--uplift", "150"], "speed"),
        (
            ["static", "benchmark", "--droppers", "5", "4", "46", "50", "--offsets", "0", "0", "0", "0"],
            "dropper_positions",
        ),
        (
            [
                "static",
                "benchmark",
                "--offsets",
                "0.9",
                "0.9",
                "0.9",
                "0.9",
                "0.9",
                "0.9",
                "0.9",
                "0.9",
                "0.9",
            ],
            "contact_wire_offsets",
        ),
        (["static", "benchmark", "--element", "0"], "fidelity.contact_wire_element"),
        (["static", "no-such-preset"], "no-such-preset"),
    ],
)
def test_bad_input_exits_2_naming_the_field(capsys, argv, field):
    assert main(argv) == 2
    assert field in capsys.readouterr().err


def test_help_explains_options_with_units(capsys):
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    text = capsys.readouterr().out
    assert "km/h" in text and "N" in text and "--plot" in text


def test_presets_lists_and_copies(tmp_path, capsys):
    assert main(["presets"]) == 0
    assert "benchmark" in capsys.readouterr().out
    target = tmp_path / "mine.toml"
    assert main(["presets", "--copy", "benchmark", str(target)]) == 0
    assert "[provenance]" in target.read_text()
    assert main(["static", str(target), "--fidelity", "test", "--json"]) == 0


def test_presets_copy_refuses_to_overwrite_without_force_and_copies_pantographs(tmp_path, capsys):
    mine = tmp_path / "mine.toml"
    mine.write_text("# my edits\n")
    assert main(["presets", "--copy", "benchmark", str(mine)]) == 2
    assert "--force" in capsys.readouterr().err and mine.read_text() == "# my edits\n"
    assert main(["presets", "--copy", "benchmark", str(mine), "--force"]) == 0
    assert "span_length" in mine.read_text()
    head = tmp_path / "head.toml"
    assert main(["presets", "--copy", "benchmark", str(head), "--pantograph"]) == 0
    assert "masses" in head.read_text() and "the pantograph preset" in capsys.readouterr().out
    assert main(["simulate", "benchmark", "--speed", "250", "--pantograph", str(head), "--uplift", "120",
                 "--fidelity", "test", "--json"]) == 0  # fmt: skip


def test_the_packages_above_plug_their_commands_in():
    _, handlers = cli.build_parser()
    assert {"optimize", "experiment", "report"} <= set(handlers)  # entry points, not imports


def test_a_command_plugin_that_fails_to_load_says_so_in_one_line(monkeypatch, capsys):
    broken = importlib.metadata.EntryPoint(
        name="broken", value="no_such_package.cli:add_commands", group=cli.COMMANDS_GROUP
    )
    monkeypatch.setattr(importlib.metadata, "entry_points", lambda group: [broken])
    _, handlers = cli.build_parser()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'broken'" in err and "no_such_package" in err
    assert "simulate" in handlers and "optimize" not in handlers  # the simulator's own commands stay


@pytest.mark.parametrize(
    ("argv", "warned"),
    [
        (["--speed", "440", "--uplift", "120"], "of the contact wire's wave speed"),
        (["--speed", "250", "--uplift", "1e6"], "uplift_force = 1e+06 N is outside"),
    ],
)
def test_physically_odd_input_is_warned_about(capsys, argv, warned):
    status = main(["simulate", "benchmark", *argv, "--fidelity", "test", "--spans", "3", "--json"])
    err = capsys.readouterr().err
    assert warned in err and "warning" in err
    assert status == 0  # a warning, not a refusal
