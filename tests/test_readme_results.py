"""The README's result tables say what the committed results say (no drift); those are the full studies."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from experiments.optimizer_comparison import OPTIMIZERS

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "results" / "design"


def _rows(path: Path) -> list[dict[str, str]]:
    """A committed CSV file's rows, as text."""
    with path.open(encoding="utf-8", newline="") as f:
        return list(csv.DictReader(f))


def _headline_rows() -> dict[str, list[str]]:
    """README rows ``| problem | σ ref | σ opt | reduction | confirmed | generations | simulations |``."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    table = text[text.index("| problem | σ reference (N) | σ optimum (N) | reduction |") :].split("\n\n")[0]
    rows = [[cell.strip() for cell in line.strip("|").split("|")] for line in table.splitlines()[2:]]
    return {row[0]: row[1:] for row in rows}


def _reduction(reference: float, optimum: float) -> float:
    return 100.0 * (1.0 - optimum / reference)


def test_the_readme_headline_table_is_the_committed_design_results():
    rows = _headline_rows()
    done = sorted(p.parent.name for p in DESIGN.glob("*/summary.json"))
    assert sorted(rows) == done  # every committed study, and no other
    for problem, cells in rows.items():
        s = json.loads((DESIGN / problem / "summary.json").read_text(encoding="utf-8"))
        ref, opt = s["sigma_reference_N"], s["sigma_optimum_N"]
        ref_exact, opt_exact = s["sigma_reference_confirmed_N"], s["sigma_optimum_confirmed_N"]
        assert cells[:3] == [f"{ref:.2f}", f"{opt:.2f}", f"{_reduction(ref, opt):.1f} %"], problem
        confirmed = f"{ref_exact:.2f} → {opt_exact:.2f} ({_reduction(ref_exact, opt_exact):.1f} %)"
        assert cells[3] == confirmed, problem
        assert cells[4:] == [str(s["generations"]), str(s["simulations"])], problem


def test_the_committed_comparison_is_the_full_one_on_b1_and_sw1():
    """Study 4 as docs/problems.md sets it: seven optimisers, five seeds, 300 simulations a run."""
    runs = _rows(ROOT / "results" / "optimizers" / "runs.csv")
    committed = [
        o for o in OPTIMIZERS if o not in ("tpe", "gp")
    ]  # the model-based ones came later (issue 26)
    for problem in ("B1", "SW1"):
        for optimizer in committed:
            chosen = [r for r in runs if r["problem"] == problem and r["optimizer"] == optimizer]
            assert sorted(int(r["seed"]) for r in chosen) == [0, 1, 2, 3, 4], (problem, optimizer)
            assert {(r["status"], r["fidelity"], r["budget"]) for r in chosen} == {("done", "study", "300")}


def test_the_readme_block_of_the_full_protocol_is_its_committed_results():
    """The README's block on the full protocol is what ``python -m experiments.benchmark_summary`` writes from
    the committed results: the count of finished runs, the fixed-budget table, the ECDF figure, the ranks
    and what the best-known designs say of the design studies."""
    from experiments.benchmark_summary import block

    written = block(ROOT)
    assert written in (ROOT / "README.md").read_text(encoding="utf-8")
    folder = ROOT / "results" / "full-protocol" / "optimizers"
    done = sum(r["status"] == "done" for r in _rows(folder / "runs.csv"))
    assert (f"**Partial: {done} of " in written) == (done < 590)
    assert "#### Fixed budget: best σ (N), median [IQR] of the runs" in written
    assert "#### Ranks over" in written and "(results/full-protocol/optimizers/ecdf.png)" in written
    for problem in ("B1", "B2", "B3", "SW1", "SW2", "SW3"):
        assert f"\n- {problem}: " in written


def _rl_tables() -> dict[str, str]:
    """The tables of ``results/rl/rl.md`` by their section title."""
    written = (ROOT / "results" / "rl" / "rl.md").read_text(encoding="utf-8")
    sections = [s.split("\n\n", 1) for s in written.split("### ")[1:]]
    return {title: table.strip() for title, table in sections}


def test_the_readme_rl_tables_are_the_committed_rl_study():
    tables = _rl_tables()
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for title in ("Speed-conditioned policy against GA optima", "One design for 200–320 km/h"):
        assert tables[title] in readme, title


def test_the_committed_rl_study_is_the_full_one_on_b1_and_sw1():
    """Study 5 as docs/problems.md sets it: 3 seeds × 1000 steps of PPO at 300 km/h, a speed-conditioned
    policy of 2000 steps, GA runs of 1000 simulations at 200, 260, 300 and 320 km/h, a mean-σ GA of 300
    evaluations."""
    rl = ROOT / "results" / "rl"
    steps, ga = _rows(rl / "steps.csv"), _rows(rl / "ga_runs.csv")
    for problem in ("B1", "SW1"):
        learning = [s for s in steps if s["problem"] == problem and s["part"] == "learning"]
        for seed in ("0", "1", "2"):
            assert sum(s["seed"] == seed for s in learning) == 1000, (problem, seed)
        assert {float(s["speed_kmh"]) for s in learning} == {300.0}
        policy = [s for s in steps if s["problem"] == problem and s["part"] == "speed_policy"]
        assert len(policy) == 2000 and 200.0 <= min(float(s["speed_kmh"]) for s in policy)
        assert max(float(s["speed_kmh"]) for s in policy) <= 320.0
        runs = {r["objective"]: r for r in ga if r["problem"] == problem}
        for speed in (200, 260, 300, 320):
            assert runs[f"sigma at {speed} km/h"]["n_simulations"] == "1000", (problem, speed)
        assert runs["mean sigma over 7 speeds, 200-320 km/h"]["budget"] == "300", problem


def test_the_readme_two_pantograph_table_is_the_committed_study():
    """Each README row of the two-pantograph table: σ of each pantograph and the trailing one's contact loss
    as ``results/pantographs/optima.csv`` has them (the study fidelity)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    table = text[text.index("| problem | design | σ leading (N) | σ trailing (N) |") :].split("\n\n")[0]
    committed = {
        (r["problem"], r["design"]): r for r in _rows(ROOT / "results" / "pantographs" / "optima.csv")
    }
    lines = table.splitlines()[2:]
    assert lines
    for line in lines:
        problem, design, leading, trailing, loss, _ = (cell.strip() for cell in line.strip("|").split("|"))
        row = committed[(problem, design)]
        assert [leading, trailing] == [
            f"{float(row['sigma_leading_N']):.2f}",
            f"{float(row['sigma_trailing_N']):.2f}",
        ]
        loss_value = float(row["loss_trailing_percent"])
        assert loss == ("0" if loss_value == 0.0 else f"{loss_value:.2f} %"), (problem, design)
