"""The ``catenary`` command line: JSON for scripts, clear errors before any solve, help with units."""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import subprocess
import sys
from pathlib import Path

import pytest

from catenary_env import cli
from catenary_env.cli import main
from catenary_env.pipeline import FIDELITIES

ROOT = Path(__file__).resolve().parents[1]


def test_static_json_gives_dropper_lengths_and_forces(capsys):
    assert main(["static", "benchmark", "--fidelity", "test", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["feasible"] and len(out["dropper_lengths"]) == 9
    assert sum(out["dropper_forces"]) > 600.0  # the span's contact wire weighs about 730 N
    assert out["start_spans"] == 0  # 5 spans: from the parabolic start


def test_static_says_a_long_section_was_started_from_a_short_one(capsys):
    """docs/model.md, 'Shape-finding': the Newton iterations counted are the section's, after its start."""
    assert main(["static", "benchmark", "--fidelity", "test", "--spans", "16"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert "16 spans" in first and "11 spans solved first, then 0 Newton iterations" in first


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


def test_a_command_plugin_that_fails_to_load_says_why_when_run(monkeypatch, capsys):
    broken = importlib.metadata.EntryPoint(
        name="broken", value="no_such_package.cli:add_commands", group=cli.COMMANDS_GROUP
    )
    monkeypatch.setattr(importlib.metadata, "entry_points", lambda group: [broken])
    _, handlers = cli.build_parser()
    assert "simulate" in handlers and "optimize" not in handlers  # the simulator's own commands stay
    assert capsys.readouterr().err == ""  # silent until the broken command is asked for
    assert main(["broken", "--budget", "3"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "catenary broken: error:" in err
    assert "ModuleNotFoundError" in err and "no_such_package" in err
    with pytest.raises(ModuleNotFoundError):  # --debug: the real error, with its traceback
        main(["--debug", "broken"])


def test_a_package_shadowing_the_plugins_is_named(monkeypatch, tmp_path, capsys):
    # A folder named like a package of the project (``optimizers``), first on the path: the command
    # fails to load, and the message names the module that shadows the project's.
    shadow = tmp_path / "optimizers"
    shadow.mkdir()
    (shadow / "__init__.py").write_text("")
    # Its own cli.py too: under an editable install, setuptools' finder would otherwise still serve the
    # project's ``optimizers.cli`` below the shadowing package, and the command would load.
    (shadow / "cli.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path))
    for name in [m for m in sys.modules if m == "optimizers" or m.startswith("optimizers.")]:
        monkeypatch.delitem(sys.modules, name)
    assert main(["optimize", "B1", "--budget", "3"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(shadow) in err and "shadows" in err


def test_the_simulators_own_commands_start_without_the_simulator():
    # ``catenary presets`` imports neither numpy nor the plug-ins (measured: 1.05 s -> 0.33 s to start).
    code = (
        "import sys; from catenary_env.cli import main; main(['presets']); "
        "print(sorted(m for m in ('numpy', 'scipy', 'gymnasium', 'optimizers') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout
    assert out.splitlines()[-1] == "[]"


def test_fidelity_names_agree_with_the_pipeline():
    assert sorted(cli.FIDELITY_NAMES) == sorted(FIDELITIES)


def test_help_texts_have_no_markup():
    for argv in ([], ["static"], ["simulate"], ["evaluate"], ["optimize"], ["propose"], ["experiment"]):
        parser, _ = cli.build_parser(argv[0] if argv else None)
        text = parser.format_help() if not argv else _subparser(parser, argv[0]).format_help()
        assert "``" not in text and ":func:" not in text and "SPEC" not in text, (argv, text)


def _subparser(parser, name):
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices[name]


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


def _study_parsers():
    from experiments.cli.experiment import STUDIES
    from experiments.common import study_parser

    for name, study in STUDIES.items():
        module = importlib.import_module(f"experiments.{study.module}")
        yield f"experiment {name}", study_parser(module, f"catenary experiment {name}")


def test_every_option_of_every_command_and_study_is_explained():
    parser, _ = cli.build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    parsers = [*action.choices.items(), *_study_parsers()]
    assert len(parsers) == 12 + 12  # the commands and the studies
    for name, command in parsers:
        for option in command._actions:
            if not isinstance(option, argparse._HelpAction):
                assert option.help and len(option.help) > 10, f"catenary {name} {option.dest}: no help"
        assert "``" not in command.format_help(), name


@pytest.mark.parametrize(
    ("study", "module", "argv"),
    [
        ("design", "design_studies", ["--problems", "B1", "SW1", "--workers", "3", "--seed", "2", "--full"]),
        ("optimizers", "optimizer_comparison", ["--optimizers", "ga", "random", "--store", "s.sqlite"]),
        ("rl", "rl_studies", ["--problems", "SW1", "--workers", "2"]),
        (
            "rl-amortised",
            "rl_amortised",
            ["--problems", "SW1", "--learners", "sac", "--seeds", "4", "--envs", "1"],
        ),
        ("rl-tension", "rl_tension", ["--learners", "ppo", "--seeds", "1", "2", "--workers", "1"]),
        ("presag", "presag", ["--workers", "1"]),
        ("validation", "validation", []),
    ],
)
def test_catenary_experiment_takes_the_studys_own_options(tmp_path, monkeypatch, capsys, study, module, argv):
    # Both entry points give the study the same settings; nothing is simulated (main is replaced).
    studied = importlib.import_module(f"experiments.{module}")
    configs = []
    monkeypatch.setattr(studied, "main", lambda config: configs.append(config) or tmp_path)
    monkeypatch.setattr(studied, "report", lambda folder: "report")
    argv = [*argv, "--out", str(tmp_path)]
    assert main(["experiment", study, *argv]) == 0
    assert studied.cli(argv) == 0
    assert configs[0] == configs[1] and configs[0].out == tmp_path
    if argv[:-2]:  # the options beyond --out reached the study's settings
        assert configs[0] != studied.Config(out=tmp_path)
