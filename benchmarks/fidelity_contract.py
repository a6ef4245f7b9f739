"""The accuracy contract of the span-mode ("study") model against the exact ("reference") one.

docs/performance.md, 'Model fidelities'. Cases:

- the reference design of each of the 8 problems at 200, 250, 300 and 350 km/h;
- 20 seeded random statically feasible designs of B1, B2, B3, SW1, SW2 and SW3 at 300 km/h;
- the EN 50318:2002 model at 250 and 300 km/h (its own section and uplift force);
- installation-tolerance draws (docs/acceptance.md, 'Installation tolerances'): the level wire of B1 and SW1
  and their recorded optima, built with random deviations of every dropper's height and position, so that
  every span differs and each is its own span type of the span-mode model (:data:`TOLERANCE_CASES`).
- two pantographs :data:`TRAIN_SPACING` m apart (docs/model.md, 'Several pantographs'): the reference
  design of each of the 8 problems and 20 random designs of each of :data:`TRAIN_PROBLEMS` at 300 km/h,
  the trailing pantograph with the leading one's uplift force; each pantograph is a row of the table, held
  to the same tolerances (and the rank correlation over each problem's random designs, per pantograph).

Both models run each case with the same uplift force (the problem's, calibrated on the study model).
The contract holds when, in every case, σ is within 1 % of the reference, the mean within 0.5 %, the
actual maximum and minimum within 2 % of the mean, the feasibility verdict the same; Spearman's rank
correlation of σ over each problem's random designs at least 0.99; and for the EN 50318 model σ 1 %,
mean 0.5 %, extremes 2 % of the mean, the largest support uplift 2 %.

The reference results are data (``benchmarks/results/fidelity_reference.json``) with the model
fingerprint they were computed under (:func:`fingerprint`); they are recomputed only when it changes or
with ``--recompute``. The contract's figures (``benchmarks/results/fidelity_contract.json``) carry the same
fingerprint; a test fails when it is not the current one, naming :data:`REFRESH`.

    python benchmarks/fidelity_contract.py            # table; exit status 1 when the contract fails
    python benchmarks/fidelity_contract.py --json     # one JSON object with the figures and "passed"
    python benchmarks/fidelity_contract.py --workers 2
    python benchmarks/fidelity_contract.py --only tolerance   # the cases whose name contains "tolerance"
    python benchmarks/fidelity_contract.py --workers 2 --trains-only   # the two-pantograph cases alone
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy.stats import spearmanr  # noqa: E402

from catenary_env.fingerprint import model_fingerprint  # noqa: E402
from catenary_env.model.design import level_design  # noqa: E402
from catenary_env.model.presets import load_catenary, load_pantograph  # noqa: E402
from catenary_env.model.tolerances import PRACTICE, Tolerances, draw_deviations  # noqa: E402
from catenary_env.pipeline import FIDELITIES, Fidelity, evaluate, solve_static  # noqa: E402
from catenary_env.problems import PROBLEMS  # noqa: E402
from catenary_env.train import SINGLE, Train  # noqa: E402

REFERENCE_FILE = Path(__file__).parent / "results" / "fidelity_reference.json"
CONTRACT_FILE = Path(__file__).parent / "results" / "fidelity_contract.json"
REFRESH = (
    "python benchmarks/fidelity_contract.py --workers 2 --json > benchmarks/results/fidelity_contract.json"
)
"""The command that measures the contract again on the current model (the exact model's results too, when
the model changed), and records it with its fingerprint."""
SPEEDS_KMH = (200.0, 250.0, 300.0, 350.0)
"""The reference designs' speeds, km/h: the studies' range (the RL studies train on 200-320 km/h), and 350."""
RANDOM_PROBLEMS = ("B1", "B2", "B3", "SW1", "SW2", "SW3")
RANDOM_DESIGNS = 20
SEED = 2026
TOLERANCE = {"std": 0.01, "mean": 0.005, "extremes": 0.02, "uplift": 0.02, "spearman": 0.99}
TOLERANCE_CASES = (
    ("B1", "reference", 2.0, (0, 1)),
    ("B1", "reference", 5.0, (0,)),
    ("B1", "optimum", 1.0, (0,)),
    ("SW1", "reference", 2.0, (0, 1)),
    ("SW1", "reference", 5.0, (0,)),
    ("SW1", "optimum", 1.0, (0,)),
)
"""(problem, design, ± height mm, draws) of the tolerance cases: draws of seed :data:`SEED` with the practice
dropper-position error; the optima are the design studies' recorded ones (results/design)."""
OPTIMA = {"B1": (-0.012, -0.01, -0.016, -0.02, -0.018), "SW1": (-0.01, -0.005, -0.019, -0.01)}
"""The design studies' recorded optima of B1 and SW1 (results/design/<problem>/summary.json), m."""
TRAIN_SPACING = 200.0
"""m between the two pantographs of the two-pantograph cases."""
TRAIN_PROBLEMS = ("B1", "SW1")
TRAIN_SPEED_KMH = 300.0
PANTOGRAPH_ROWS = ("leading", "trailing")


@dataclasses.dataclass(frozen=True)
class Case:
    """One contract case: a problem's design (``x``, m) at a speed, or the EN 50318 model."""

    name: str
    problem: str  # "" for the EN 50318 model
    x: tuple[float, ...]
    speed_kmh: float
    uplift_force: float
    random: bool
    tolerance_mm: float = 0.0
    draw: int = -1
    spacing: float = 0.0  # m to a trailing pantograph; 0: one pantograph


def _random_designs(problem_name: str, count: int, seed: int) -> list[tuple[float, ...]]:
    """``count`` grid designs drawn uniformly, keeping those that are statically feasible."""
    problem = PROBLEMS[problem_name]
    rng = np.random.default_rng([seed, list(PROBLEMS).index(problem_name)])
    fidelity = FIDELITIES["study"]
    out: list[tuple[float, ...]] = []
    while len(out) < count:
        x = problem.from_grid_index(rng.integers(0, problem.n_levels))
        try:
            design = problem.design(x)
            if solve_static(problem.catenary_definition, design, fidelity).infeasibility():
                continue
        except Exception:  # noqa: BLE001 - a design the catenary cannot build, or no equilibrium
            continue
        out.append(tuple(float(v) for v in x))
    return out


def contract_cases() -> list[Case]:
    """The cases; each one's uplift force is the stored reference run's, so that both models see the same."""
    stored = _stored()

    def uplift(case: str, problem: str, speed: float) -> float:
        if case in stored:
            return float(stored[case]["uplift_force"])
        return PROBLEMS[problem].uplift_force(speed, "study")

    cases = []
    for name, problem in PROBLEMS.items():
        for speed in SPEEDS_KMH:
            x = problem.reference_x()
            force = uplift(f"{name} reference {speed:.0f}", name, speed)
            x = () if x is None else tuple(float(v) for v in x)
            cases.append(Case(f"{name} reference {speed:.0f}", name, x, speed, force, False))
    for name in RANDOM_PROBLEMS:
        force = uplift(f"{name} random 00", name, 300.0)
        for i, x in enumerate(_random_designs(name, RANDOM_DESIGNS, SEED)):
            cases.append(Case(f"{name} random {i:02d}", name, x, 300.0, force, True))
    en = load_pantograph("en50318-2002")
    for speed in (250.0, 300.0):
        cases.append(Case(f"EN50318 {speed:.0f}", "", (), speed, float(en.uplift_force), False))
    for name, design, mm, draws in TOLERANCE_CASES:
        x = tuple(PROBLEMS[name].reference_x().tolist()) if design == "reference" else OPTIMA[name]
        force = uplift(f"{name} reference 300", name, 300.0)
        for k in draws:
            label = f"{name} {design} tolerance {mm:g}mm {k:02d}"
            cases.append(Case(label, name, x, 300.0, force, False, mm, k))
    return cases + train_cases(uplift)


def train_cases(uplift) -> list[Case]:  # noqa: ANN001 - contract_cases' uplift(case, problem, speed)
    """The two-pantograph cases: named with their spacing, so that a stored result is never served for
    another one."""
    speed, tag = TRAIN_SPEED_KMH, f"2p{TRAIN_SPACING:.0f}"
    cases = []
    for name, problem in PROBLEMS.items():
        x = problem.reference_x()
        x = () if x is None else tuple(float(v) for v in x)
        force = uplift(f"{name} reference {speed:.0f}", name, speed)
        cases.append(
            Case(f"{name} {tag} reference {speed:.0f}", name, x, speed, force, False, spacing=TRAIN_SPACING)
        )
    for name in TRAIN_PROBLEMS:
        force = uplift(f"{name} random 00", name, speed)
        for i, x in enumerate(_random_designs(name, RANDOM_DESIGNS, SEED)):
            cases.append(
                Case(f"{name} {tag} random {i:02d}", name, x, speed, force, True, spacing=TRAIN_SPACING)
            )
    return cases


def _en_fidelity(dynamics: str) -> Fidelity:
    catenary = load_catenary("en50318-2002")
    return Fidelity(n_spans=catenary.n_spans, analysis_spans=catenary.analysis_spans, dynamics=dynamics)


def run_case(case: Case, dynamics: str) -> dict:
    """Statistics of one case on one model (``"exact"`` or ``"span-modes"``); with a trailing pantograph,
    each pantograph's too (``"pantographs"``)."""
    train = SINGLE
    if case.spacing:
        train = Train.behind([PROBLEMS[case.problem].pantograph_definition], case.spacing)
    if case.problem and case.x:
        fidelity = dataclasses.replace(FIDELITIES["study"], dynamics=dynamics)
        problem = PROBLEMS[case.problem]
        deviations = None
        if case.draw >= 0:
            tolerances = Tolerances(case.tolerance_mm / 1000.0, PRACTICE.position, PRACTICE.distribution)
            deviations = draw_deviations(tolerances, fidelity.n_spans, problem.n_droppers, SEED, case.draw)
        ev = problem.evaluate(case.x, case.speed_kmh, fidelity, case.uplift_force, deviations, train=train)
    elif case.problem:  # B3 and SW3 are compared with the level wire on the preset's droppers
        problem = PROBLEMS[case.problem]
        fidelity = dataclasses.replace(FIDELITIES["study"], dynamics=dynamics)
        ev = evaluate(
            problem.catenary_definition,
            problem.pantograph_definition,
            problem.reference_design(),
            case.speed_kmh / 3.6,
            fidelity,
            uplift_force=case.uplift_force,
            train=train,
        )
    else:
        catenary = load_catenary("en50318-2002")
        ev = evaluate(
            catenary,
            load_pantograph("en50318-2002"),
            level_design(catenary),
            case.speed_kmh / 3.6,
            _en_fidelity(dynamics),
            uplift_force=case.uplift_force,
        )
    stats = ev.statistics.as_dict() if ev.statistics is not None else None
    result = {"feasible": ev.feasible, "reason": ev.reason, "statistics": stats, "wall_time": ev.wall_time}
    if case.spacing:
        result["pantographs"] = [s.as_dict() for s in ev.pantograph_statistics]
    return result


def pantograph_rows(cases: list[Case], results: dict[str, dict]) -> dict[str, dict]:
    """Each two-pantograph case as one result per pantograph (``"<case> leading"``, ``"<case> trailing"``,
    its statistics, feasible when that pantograph keeps contact); the other cases as they are."""
    out = {}
    for case in cases:
        result = results[case.name]
        if not case.spacing:
            out[case.name] = result
            continue
        blocks = result.get("pantographs") or [None] * len(PANTOGRAPH_ROWS)
        for which, stats in zip(PANTOGRAPH_ROWS, blocks, strict=True):
            feasible = stats is not None and stats["contact_loss_percent"] == 0.0
            out[f"{case.name} {which}"] = result | {"statistics": stats, "feasible": feasible}
    return out


def _exact_part(fidelity: Fidelity) -> dict:
    """The fields of a fidelity that the exact model reads (not the span-mode cut-offs)."""
    fields = dataclasses.asdict(fidelity)
    for name in ("near_cutoff", "far_cutoff", "near_spans"):
        fields.pop(name)
    return fields


def fingerprint() -> str:
    """The reference results' validity: the problems' models (with the simulator's fingerprint,
    :mod:`catenary_env.fingerprint`), the reference fidelity, the random designs' seed and count. A case's
    name carries its speed, so a case added at another speed joins the stored results."""
    problems = [PROBLEMS[name].fingerprint() for name in PROBLEMS]
    en = (load_catenary("en50318-2002"), load_pantograph("en50318-2002"), _exact_part(_en_fidelity("exact")))
    reference = _exact_part(FIDELITIES["reference"])
    return model_fingerprint(problems, *en, reference, SEED, RANDOM_DESIGNS)


def _stored() -> dict:
    if REFERENCE_FILE.exists():
        data = json.loads(REFERENCE_FILE.read_text())
        if data.get("fingerprint") == fingerprint():
            return data["cases"]
    return {}


def reference_results(cases: list[Case], workers: int, recompute: bool) -> dict[str, dict]:
    """The exact model's results of every case: from the data file when its fingerprint matches."""
    key = fingerprint()
    stored = {} if recompute else _stored()
    missing = [c for c in cases if c.name not in stored]
    if missing:
        print(f"computing the reference model for {len(missing)} cases ...", file=sys.stderr)
        for case, result in zip(missing, _map(run_case, missing, "exact", workers), strict=True):
            stored[case.name] = result | {"x": list(case.x), "uplift_force": case.uplift_force}
            REFERENCE_FILE.parent.mkdir(parents=True, exist_ok=True)
            REFERENCE_FILE.write_text(json.dumps({"fingerprint": key, "cases": stored}, indent=1))
    return stored


def _map(function, cases: list[Case], dynamics: str, workers: int):  # noqa: ANN001, ANN202
    """``function(case, dynamics)`` for each case, yielded in order as they complete."""
    if workers <= 1:
        yield from (function(c, dynamics) for c in cases)
        return
    with ProcessPoolExecutor(workers) as pool:
        yield from pool.map(function, cases, [dynamics] * len(cases))


def _errors(ref: dict, red: dict) -> dict[str, float]:
    r, s = ref["statistics"], red["statistics"]
    if r is None or s is None:
        return {}
    mean = r["mean"]
    return {
        "std": s["std"] / r["std"] - 1.0,
        "mean": s["mean"] / mean - 1.0,
        "max": (s["actual_max"] - r["actual_max"]) / mean,
        "min": (s["actual_min"] - r["actual_min"]) / mean,
        "uplift": s["max_support_uplift"] / r["max_support_uplift"] - 1.0,
    }


def evaluate_contract(cases: list[Case], reference: dict, reduced: dict) -> dict:
    reference, reduced = pantograph_rows(cases, reference), pantograph_rows(cases, reduced)
    rows = []
    for name in reduced:
        ref, red = reference[name], reduced[name]
        err = _errors(ref, red)
        rows.append(
            {
                "case": name,
                "std_reference": ref["statistics"]["std"] if ref["statistics"] else None,
                "std_study": red["statistics"]["std"] if red["statistics"] else None,
                "feasible_reference": ref["feasible"],
                "feasible_study": red["feasible"],
                "time_reference": ref["wall_time"],
                "time_study": red["wall_time"],
                **{f"error_{k}": v for k, v in err.items()},
            }
        )
    compared = [r for r in rows if "error_std" in r]
    std_err = np.abs([r["error_std"] for r in compared])
    mean_err = np.abs([r["error_mean"] for r in compared])
    ext_err = np.abs([max(abs(r["error_max"]), abs(r["error_min"])) for r in compared])
    verdicts_agree = all(r["feasible_reference"] == r["feasible_study"] for r in rows)
    spearman = {}
    groups = {name: (f"{name} random", "") for name in RANDOM_PROBLEMS}
    for name in TRAIN_PROBLEMS:
        for which in PANTOGRAPH_ROWS:
            groups[f"{name} 2p {which}"] = (f"{name} 2p{TRAIN_SPACING:.0f} random", which)
    for group, (prefix, suffix) in groups.items():
        picked = [r for r in compared if r["case"].startswith(prefix) and r["case"].endswith(suffix)]
        if len(picked) >= 3:
            rho = spearmanr([r["std_reference"] for r in picked], [r["std_study"] for r in picked]).statistic
            spearman[group] = float(rho)
    en = [r for r in compared if r["case"].startswith("EN50318")]
    en_uplift = max((abs(r["error_uplift"]) for r in en), default=0.0)
    checks = {
        "std": float(std_err.max()) <= TOLERANCE["std"],
        "mean": float(mean_err.max()) <= TOLERANCE["mean"],
        "extremes": float(ext_err.max()) <= TOLERANCE["extremes"],
        "verdicts": verdicts_agree,
        "spearman": all(v >= TOLERANCE["spearman"] for v in spearman.values()),
        "en50318_uplift": en_uplift <= TOLERANCE["uplift"],
    }
    ratio = [r["time_study"] / r["time_reference"] for r in compared if r["time_reference"] > 0]
    return {
        "cases": len(rows),
        "std_error_max": float(std_err.max()),
        "std_error_median": float(np.median(std_err)),
        "mean_error_max": float(mean_err.max()),
        "extremes_error_max": float(ext_err.max()),
        "en50318_support_uplift_error_max": float(en_uplift),
        "verdicts_agree": verdicts_agree,
        "spearman": spearman,
        "time_ratio_median": float(np.median(ratio)) if ratio else None,
        "checks": checks,
        "passed": all(checks.values()),
        "rows": rows,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--workers", type=int, default=1, help="processes for the simulations")
    parser.add_argument("--recompute", action="store_true", help="recompute the reference results")
    parser.add_argument("--reference-only", action="store_true", help="only compute the reference results")
    parser.add_argument("--only", metavar="TEXT", help="only the cases whose name contains TEXT")
    parser.add_argument("--trains-only", action="store_true", help="only the two-pantograph cases")
    args = parser.parse_args(argv)
    cases = [c for c in contract_cases() if args.only is None or args.only in c.name]
    if args.trains_only:
        cases = [c for c in cases if c.spacing]
    reference = reference_results(cases, args.workers, args.recompute)
    if args.reference_only:
        return 0
    reduced = dict(
        zip((c.name for c in cases), _map(run_case, cases, "span-modes", args.workers), strict=True)
    )
    report = {"fingerprint": fingerprint(), **evaluate_contract(cases, reference, reduced)}
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        for row in report["rows"]:
            if "error_std" in row:
                print(
                    f"{row['case']:<22} σ {row['std_reference']:8.3f} {row['std_study']:8.3f} N "
                    f"({100 * row['error_std']:+.3f} %)  mean {100 * row['error_mean']:+.3f} %  "
                    f"max {100 * row['error_max']:+.2f} %  min {100 * row['error_min']:+.2f} % of the mean"
                )
            else:
                print(
                    f"{row['case']:<22} infeasible: reference {row['feasible_reference']}, "
                    f"study {row['feasible_study']}"
                )
        print()
        for key in (
            "cases",
            "std_error_max",
            "std_error_median",
            "mean_error_max",
            "extremes_error_max",
            "en50318_support_uplift_error_max",
            "verdicts_agree",
            "spearman",
            "time_ratio_median",
            "checks",
            "passed",
        ):
            print(f"{key}: {report[key]}")
    return 0 if report["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
