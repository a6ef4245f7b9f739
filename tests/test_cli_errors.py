"""One error policy: every broken input a user can give ends in exit status 2 and one line naming it; any
other exception is a bug and keeps its traceback, with a line asking to report it.

Each case is a command line (``{tmp}`` is a folder of the test, ``{file}`` a file that the case's edit
makes there) and a text the one-line message must contain: the file, field, row, option or address.
"""

from __future__ import annotations

import sqlite3
import zipfile
from collections.abc import Callable
from pathlib import Path

import pytest

from catenary_env.cli import main
from catenary_env.cli.exits import EXIT_BUG, REPORT_LINE
from catenary_env.model.presets import preset_path
from optimizers import optimize

BENCHMARK = preset_path("catenary", "benchmark").read_text(encoding="utf-8")
PANTOGRAPH = preset_path("pantograph", "benchmark").read_text(encoding="utf-8")
SIM = ["simulate", "benchmark", "--speed", "300", "--fidelity", "test", "--uplift", "120"]
STATIC = ["static", "benchmark", "--fidelity", "test"]
FILE = ["static", "{file}"]
OPT = ["optimize", "synthetic-quadratic", "--budget", "10", "--workers", "1", "--quiet"]
PPO = ["optimize", "B1", "--optimizer", "ppo", "--budget", "2", "--fidelity", "test", "--quiet"]


def _catenary(old: str, new: str) -> Callable[[Path], None]:
    def make(path: Path) -> None:
        assert old in BENCHMARK
        path.write_text(BENCHMARK.replace(old, new, 1), encoding="utf-8")

    return make


def _text(text: str | bytes) -> Callable[[Path], None]:
    def make(path: Path) -> None:
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text, encoding="utf-8")

    return make


def _store(damage: Callable[[Path], None] | None = None) -> Callable[[Path], None]:
    """A run store with one finished run, then damaged."""

    def make(path: Path) -> None:
        optimize("synthetic-quadratic", "ga", budget=10, seed=0, fidelity="test", store=path)
        for suffix in ("-wal", "-shm"):
            Path(f"{path}{suffix}").unlink(missing_ok=True)
        if damage is not None:
            damage(path)

    return make


def _sql(statement: str) -> Callable[[Path], None]:
    def damage(path: Path) -> None:
        with sqlite3.connect(path) as connection:
            connection.execute(statement)
        connection.close()

    return damage


def _truncate(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2 + 100])


def _overwrite_page(path: Path) -> None:
    data = bytearray(path.read_bytes())
    page = int.from_bytes(data[16:18], "big")
    data[page : 2 * page] = b"\xa5" * page  # page 2: the first table's b-tree
    path.write_bytes(bytes(data))


def _zip(members: dict[str, str]) -> Callable[[Path], None]:
    def make(path: Path) -> None:
        with zipfile.ZipFile(path, "w") as archive:
            for name, text in members.items():
                archive.writestr(name, text)

    return make


def _foreign(path: Path) -> None:
    with sqlite3.connect(path) as connection:
        connection.execute("CREATE TABLE notes (text TEXT)")
    connection.close()


CASES: list[tuple[str, list[str], str, Callable[[Path], None] | None]] = [
    # -- catenary and pantograph files ---------------------------------------------------------------
    ("missing-file", ["static", "{tmp}/nosuch.toml"], "nosuch.toml", None),
    ("unknown-preset", ["static", "benchmrk"], "benchmrk", None),
    ("empty-file", ["static", "{file}"], "{file}", _text("")),
    ("not-toml", ["static", "{file}"], "{file}", _text("span_length = = 3\n[")),
    ("binary-file", ["static", "{file}"], "{file}", _text(b"\x00\xff\xfe binary")),
    ("folder-as-preset", ["static", "{tmp}"], "{tmp}", None),
    ("missing-field", ["static", "{file}"], "contact_wire.tension", _catenary("tension = 22000.0 ", "# ")),
    ("unknown-field", ["static", "{file}"], "suports", _catenary("[supports]", "[suports]")),
    ("string-number", FILE, "contact_wire.tension", _catenary("tension = 22000.0", 'tension = "a"')),
    ("too-few-spans", ["static", "{file}"], "n_spans", _catenary("n_spans = 20", "n_spans = 2")),
    ("huge-span", FILE, "span_length", _catenary("span_length = 55.0", "span_length = 1e300")),
    ("low-system", FILE, "system_height", _catenary("system_height = 1.2", "system_height = 0.3")),
    ("negative-span", FILE, "span_length", _catenary("span_length = 55.0", "span_length = -5.0")),
    ("pantograph-as-catenary", ["static", "{file}"], "{file}", _text(PANTOGRAPH)),
    ("catenary-as-pantograph", [*SIM, "--pantograph", "{file}"], "{file}", _text(BENCHMARK)),
    ("unknown-pantograph", [*SIM, "--pantograph", "nosuch"], "nosuch", None),
    # -- option values ---------------------------------------------------------------------------------
    ("speed-too-high", ["simulate", "benchmark", "--speed", "600"], "speed", None),
    ("speed-negative", [*SIM, "--speed", "-5"], "speed", None),
    ("speed-zero", [*SIM, "--speed", "0"], "speed", None),
    ("speed-nan", [*SIM, "--speed", "nan"], "speed", None),
    ("uplift-negative", [*SIM, "--uplift", "-5"], "uplift", None),
    ("target-mean-negative", [*SIM[:4], "--target-mean", "-1"], "target", None),
    ("presag-huge-negative", [*STATIC, "--presag", "-0.5"], "--presag", None),
    ("presag-simulate", [*SIM, "--presag", "-0.5"], "--presag", None),
    ("offsets-huge", [*STATIC, "--offsets", *["0.9"] * 9], "contact_wire_offsets", None),
    ("offsets-not-a-number", [*STATIC, "--offsets", "0", "x"], "--offsets", None),
    ("offsets-count", [*STATIC, "--offsets", "0", "0"], "offsets", None),
    ("presag-and-offsets", [*STATIC, "--presag", "0.01", "--offsets", *["0"] * 9], "--presag", None),
    (
        "droppers-outside",
        [*STATIC, "--droppers", "5", "4", "46", "50", "--offsets", *"0000"],
        "dropper",
        None,
    ),
    ("spans-zero", [*STATIC, "--spans", "0"], "n_spans", None),
    ("analysis-spans", [*STATIC, "--analysis-spans", "9"], "analysis_spans", None),
    ("element-zero", [*STATIC, "--element", "0"], "contact_wire_element", None),
    ("time-step-zero", [*SIM, "--time-step", "0"], "time_step", None),
    ("points-zero", [*STATIC, "--stiffness", "--points", "0"], "--points", None),
    # -- output paths, checked before computing --------------------------------------------------------------
    ("plot-missing-folder", [*STATIC, "--plot", "{tmp}/no/such/fig.png"], "{tmp}/no/such", None),
    ("plot-is-folder", [*STATIC, "--plot", "{tmp}"], "--plot", None),
    ("simulate-plot-missing", [*SIM, "--plot", "{tmp}/no/fig.png"], "{tmp}/no", None),
    ("copy-missing-folder", ["presets", "--copy", "benchmark", "{tmp}/no/mine.toml"], "{tmp}/no", None),
    ("copy-unknown", ["presets", "--copy", "nosuch", "{tmp}/mine.toml"], "nosuch", None),
    ("copy-overwrite", ["presets", "--copy", "benchmark", "{file}"], "--force", _text("# mine\n")),
    # -- design problems -------------------------------------------------------------------------------
    ("evaluate-count", ["evaluate", "B1", "--x", "0.0"], "B1", None),
    ("evaluate-bounds", ["evaluate", "B1", "--x", "5", "5", "5", "5"], "B1", None),
    # -- optimiser options ---------------------------------------------------------------------------------
    ("budget-zero", ["optimize", "synthetic-quadratic", "--budget", "0"], "budget", None),
    ("seed-negative", [*OPT, "--seed", "-1"], "seed", None),
    ("unknown-problem", ["optimize", "nosuch", "--budget", "5"], "nosuch", None),
    ("unknown-optimizer", [*OPT, "--optimizer", "nosuch"], "or an RL learner: ppo, sac", None),
    ("workers-zero", [*OPT, "--workers", "0"], "workers", None),
    ("max-evaluations-zero", [*OPT, "--max-evaluations", "0"], "--max-evaluations", None),
    ("progress-every-negative", [*OPT, "--progress-every", "-1"], "--progress-every", None),
    ("speed-range-ga", [*OPT, "--speed-range", "200", "300"], "--speed-range", None),
    ("workers-and-scheduler", [*OPT, "--scheduler", "tcp://127.0.0.1:9"], "--workers", None),
    ("scheduler-bad-address", [*OPT[:-3], "--scheduler", "nowhere:::"], "nowhere:::", None),
    ("resume-no-match", [*OPT, "--store", "{file}", "--resume", "--seed", "7"], "--resume", _store()),
    ("save-policy-not-ppo", [*OPT, "--save-policy", "{tmp}/p.zip"], "--save-policy", None),
    ("save-policy-missing-folder", [*PPO, "--save-policy", "{tmp}/no/p.zip"], "{tmp}/no", None),
    # -- saved policies --------------------------------------------------------------------------------
    ("propose-missing-file", ["propose", "{tmp}/nosuch.zip", "--speed", "260"], "nosuch.zip", None),
    ("propose-not-a-policy", ["propose", "{file}", "--speed", "260"], "{file}", _text("hello\n")),
    ("propose-zip-no-record", ["propose", "{file}", "--speed", "260"], "{file}", _zip({"data": "{}"})),
    (
        "propose-damaged-record",
        ["propose", "{file}", "--speed", "260"],
        "catenary_env_policy.json",
        _zip({"catenary_env_policy.json": '{"format": 1}'}),
    ),
    ("propose-folder", ["propose", "{tmp}", "--speed", "260"], "{tmp}", None),
    # -- studies: their own options, checked before anything is simulated ---------------------------------
    ("experiment-workers", ["experiment", "presag", "--workers", "0"], "--workers", None),
    ("experiment-unknown-option", ["experiment", "validation", "--problems", "B1"], "--problems", None),
    ("unknown-option", ["presets", "--nosuch"], "catenary presets: error: unrecognized arguments", None),
    ("experiment-negative-seed", ["experiment", "rl-amortised", "--seeds", "0", "-1"], "--seeds", None),
    ("experiment-design-seed", ["experiment", "design", "--seed", "-1"], "--seed", None),
    ("experiment-unknown-optimizer", ["experiment", "optimizers", "--optimizers", "nosuch"], "or ppo", None),
    ("experiment-out-is-a-file", ["experiment", "validation", "--out", "{file}/x"], "--out", _text("x")),
    # -- run stores ----------------------------------------------------------------------------------------
    ("store-is-folder", [*OPT, "--store", "{tmp}"], "{tmp}", None),
    ("store-missing-folder", [*OPT, "--store", "{tmp}/no/runs.sqlite"], "{tmp}/no", None),
    ("store-not-sqlite", [*OPT, "--store", "{file}"], "{file}", _text("hello\n")),
    ("store-foreign", [*OPT, "--store", "{file}"], "{file}", _foreign),
    ("store-truncated", [*OPT, "--store", "{file}"], "{file}", _store(_truncate)),
    ("store-overwritten-page", [*OPT, "--store", "{file}"], "{file}", _store(_overwrite_page)),
    ("store-dropped-table", [*OPT, "--store", "{file}"], "{file}", _store(_sql("DROP TABLE evaluations"))),
    (
        "store-tampered-row",
        [*OPT, "--store", "{file}", "--optimizer", "ga", "--seed", "0", "--resume", "--fidelity", "test"],
        "row",
        _store(_sql("UPDATE evaluations SET x = 'tampered' WHERE idx = 3")),
    ),
]


@pytest.mark.parametrize(("argv", "culprit", "make"), [case[1:] for case in CASES], ids=[c[0] for c in CASES])
def test_broken_input_ends_in_one_line_naming_it(tmp_path, capsys, monkeypatch, argv, culprit, make):
    if "--scheduler" in argv and "--workers" not in culprit:
        pytest.importorskip(
            "distributed", reason="an unreachable scheduler is found only with dask installed"
        )
    monkeypatch.chdir(tmp_path)  # the default run store goes there
    file = tmp_path / "input.toml"
    if make is not None:
        make(file)
    capsys.readouterr()

    def fill(text: str) -> str:
        return text.replace("{tmp}", str(tmp_path)).replace("{file}", str(file))

    try:
        status = main([fill(arg) for arg in argv])
    except SystemExit as exit:  # argparse refuses a value of the wrong type
        status = exit.code
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert status == 2, err
    assert len(lines) == 1, err
    assert fill(culprit) in lines[0]
    assert "Traceback" not in err


def test_there_are_at_least_40_cases():
    assert len(CASES) >= 40


# -- bugs -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "error",
    [
        ZeroDivisionError("division by zero"),
        ValueError("an internal value"),
        KeyError("x"),
        OSError(5, "I/O"),
    ],
    ids=["ZeroDivisionError", "ValueError", "KeyError", "OSError"],
)
def test_an_internal_error_keeps_its_traceback_and_asks_to_report_it(monkeypatch, capsys, error):
    # Deep inside a command (the static shape of ``catenary static``), an exception that is not one of the
    # project's user errors: a bug, whatever its type, not a one-line "user error".
    import catenary_env.pipeline

    def broken(*args, **kwargs):
        raise error

    monkeypatch.setattr(catenary_env.pipeline, "solve_static", broken)
    status = main(["static", "benchmark", "--fidelity", "test"])
    err = capsys.readouterr().err
    assert status == EXIT_BUG != 2
    assert err.startswith("Traceback (most recent call last):")
    assert f"{type(error).__name__}: " in err and "in broken" in err
    assert err.splitlines()[-1] == f"catenary static: {REPORT_LINE}"
    assert "please report it" in REPORT_LINE
    with pytest.raises(type(error)):  # --debug: raised as it is, for a debugger
        main(["--debug", "static", "benchmark", "--fidelity", "test"])


def test_a_user_error_is_one_of_the_projects_own_types():
    # The one-line errors are CatenaryError subclasses; those that replaced a ValueError stay one.
    from catenary_env.errors import CatenaryError, UsageError
    from catenary_env.model.design import DesignError
    from catenary_env.statics.shape_finding import ShapeFindingError
    from optimizers.store import StoreError

    for error in (DesignError, ShapeFindingError, StoreError, UsageError):
        assert issubclass(error, CatenaryError)
    assert issubclass(DesignError, ValueError) and issubclass(UsageError, ValueError)
    assert not issubclass(ValueError, CatenaryError)


def test_an_os_error_of_a_file_the_user_named_becomes_a_user_error_naming_it():
    from catenary_env.errors import CatenaryError, UserFileError

    error = UserFileError.from_os_error(
        FileNotFoundError(2, "No such file or directory", "/no/such"), "--out"
    )
    assert str(error) == "--out /no/such: No such file or directory"
    assert isinstance(error, CatenaryError) and isinstance(error, OSError)
