"""The full protocol's cost measured from its run archive (experiments/protocol_cost.py): simulations charged
and made, simulation time, and run time without the interruptions between sessions."""

from __future__ import annotations

import pytest

from experiments import protocol_cost
from optimizers.archive import finished_runs, write_run_file


def _run(optimizer: str, problem: str, seed: int, created_at: str) -> dict:
    return {
        "run_id": seed + 1, "optimizer": optimizer, "problem": problem, "budget": 3, "seed": seed,
        "speed_kmh": 300.0, "fidelity": "study", "options": "{}", "package_version": "0.1.0",
        "created_at": created_at, "finished_at": created_at, "stop_reason": "budget",
    }  # fmt: skip


def _row(idx: int, stamp: str, wall_time: float, cached: int = 0, source: str = "simulation") -> dict:
    return {
        "idx": idx, "created_at": stamp, "wall_time": wall_time, "cached": cached, "charged": 1,
        "source": source,
    }  # fmt: skip


def test_the_cost_leaves_out_interruptions_cached_designs_and_untimed_run_times(tmp_path):
    """A run resumed after an hour's break costs its work only; a design from the store costs no simulation
    time; a run rebuilt from an export counts its simulations but has no run time."""
    day = "2026-12-02T10:"
    resumed = [
        _row(0, day + "00:10+00:00", 8.0),
        _row(1, day + "00:20+00:00", 9.0),
        _row(2, "2026-12-02T11:30:00+00:00", 1.0, cached=1),  # after a session's end: not counted
    ]
    write_run_file(tmp_path, _run("gp", "SW1@abc", 0, day + "00:00+00:00"), resumed)
    exported = [_row(i, day + "00:00+00:00", 2.0, source="export") for i in range(3)]
    write_run_file(tmp_path, _run("gp", "B1@def", 1, day + "00:00+00:00"), exported)

    costs = {c["problem"]: c for c in (protocol_cost.run_cost(*r) for r in finished_runs(tmp_path))}
    assert costs["SW1"]["catenary"] == "stitched" and costs["B1"]["catenary"] == "benchmark"
    assert (costs["SW1"]["charged"], costs["SW1"]["simulated"]) == (3, 2)
    assert costs["SW1"]["simulation_time_s"] == 17.0
    assert costs["SW1"]["run_time_s"] == 20.0  # 10 s + 10 s; the 70-minute gap is an interruption
    assert costs["B1"]["run_time_s"] is None and costs["B1"]["simulation_time_s"] == 6.0

    text = protocol_cost.report(tmp_path)
    assert "| all | 2 | 6 | 5 | 0.0 |" in text
    assert "| gp | stitched | 1 | 0.3 (0.3–0.3) | 1 | 0.3 (0.3–0.3) |" in text
    assert "| gp | benchmark | 1 | 0.1 (0.1–0.1) | 0 | – |" in text
    assert "Run time of the 1 runs with time stamps (the others were rebuilt from an export)" in text


def test_a_generation_resumed_in_another_session_counts_its_work_once(tmp_path):
    """A GA generation interrupted and resumed holds designs of both sessions, in the rows' order but not the
    clock's (and parallel workers stamp a generation's designs out of order): the run time is the work of each
    session, never negative."""
    rows = [
        _row(0, "2026-12-04T16:14:12+00:00", 1.0),
        _row(1, "2026-12-04T18:46:02+00:00", 1.0),  # resumed 2.5 h later
        _row(2, "2026-12-04T16:14:11+00:00", 1.0),
        _row(3, "2026-12-04T18:46:03+00:00", 1.0),
    ]
    write_run_file(tmp_path, _run("ga", "B1@abc", 0, "2026-12-04T16:14:10+00:00"), rows)
    (cost,) = (protocol_cost.run_cost(*r) for r in finished_runs(tmp_path))
    assert cost["run_time_s"] == 3.0  # 16:14:10-12 and 18:46:02-03


def test_a_run_on_two_cores_reports_its_wall_time_and_core_time(tmp_path):
    """The amortised RL study's runs step two envs at once: the run time is wall time on two cores, twice
    that in core-hours, beside the simulations' own (core) time."""
    day = "2026-12-03T10:"
    rows = [_row(i, day + f"{i:02d}:00+00:00", 100.0) for i in range(1, 37)]  # 36 min, 3600 s simulated
    write_run_file(tmp_path, _run("ppo", "B1@abc", 0, day + "00:00+00:00"), rows)
    text = protocol_cost.report(tmp_path, "The amortised RL study's cost", cores=2)
    assert text.startswith("# The amortised RL study's cost")
    assert "Each run held 2 cores" in text and "rebuilt from an export" not in text
    assert "0.6 h on 2 cores (1.2 core-hours), against 1.0 core-hours of simulation" in text
    assert "| ppo | benchmark | 1 | 60.0 (60.0–60.0) | 1 | 36.0 (36.0–36.0) |" in text


def test_a_report_with_nowhere_to_go_is_refused_naming_the_option(tmp_path, capsys):
    archive = tmp_path / "rl" / "amortised" / "archive"
    archive.mkdir(parents=True)
    with pytest.raises(SystemExit) as stopped:
        protocol_cost.main(["--archive", str(archive)])
    assert stopped.value.code == 2
    assert f"--out {archive.parent / 'optimizers' / 'cost.md'}: no folder" in capsys.readouterr().err
