"""Study 5c: design policies conditioned on the contact-wire tension as well as the speed (docs/problems.md,
'Experiments').

Study 5b (:mod:`experiments.rl_amortised`) trains a policy that answers for every speed of one catenary.
A designer also chooses the catenary: here the policy is conditioned on the contact wire's tension as well,
drawn at each episode from :data:`TENSION_RANGE` outside the held-out bands :data:`HELD_OUT_TENSIONS`
(and the speed from study 5b's range, outside its held-out bands), on B1. Each tension is its own catenary
(docs/problems.md, 'Contact-wire tension'), simulated under the preset's uplift force at the speed.

1. *Learning curves*, as in study 5b.
2. *The table*: at the training tensions and the held-out ones (:data:`TABLE_TENSIONS`), all at
   :data:`SPEED_KMH`, σ of the reference design (the level wire), of the GA optimum at that tension (a GA run
   of :attr:`Config.ga_budget` simulations each) and of each policy's design, and the gap policy / GA.
3. *The amortisation ledger* over the table's tensions (:func:`experiments.rl_analysis.amortisation_ledger`):
   N is a number of catenaries (tension and speed) instead of speeds.

Every run goes to the run store and is resumed from it, as in study 5b; a step of the policy is stored
under the model of its tension (:func:`optimizers.rl.train_design_policy`). Outputs
(``out/rl/tension/``): ``steps.csv``, ``ga_runs.csv``, ``ga_curves.csv``, ``designs.csv``, ``ledger.csv``,
``tension.md``, ``learning_curves.png``, ``policies/`` (each loadable with ``catenary propose ...
--contact-wire-tension N``, with the command that reproduces it beside it); with ``--archive``, ``cost.md``.

Settings. Full: the study fidelity, SAC (the learner of study 5b that came nearest the GA), 3 seeds of
10,000 steps on 2 envs, GA runs of 1000 simulations at each of the five tensions. Quick: the "test" fidelity,
one seed of 8 steps, GA runs of 12 simulations at two tensions (a smoke test, not a result).

    python -m experiments.rl_tension [--full] [--learners sac] [--seeds 0 1 2] [--envs 2] [--out results]
"""

from __future__ import annotations

import argparse
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from optimizers.catenary_adapter import CatenaryProblem, catenary_problem
from optimizers.rl import EnvSpec, design_for_speed, load_policy, save_policy
from optimizers.store import RunStore

from . import rl_amortised, rl_analysis
from .common import (
    STORE,
    add_full_option,
    markdown_table,
    read_csv,
    run_cli,
    run_study,
    study_dir,
    write_csv,
)
from .design_evaluations import evaluate_designs, study_problem
from .rl_amortised import HELD_OUT, SPEED_RANGE

NAME = "rl/tension"
PROBLEM = "B1"
TENSION_RANGE = (20000.0, 28000.0)
"""Contact-wire tensions drawn in training, N: 91–127 % of the benchmark catenary's 22 kN. Below some
20 kN the level wire loses contact at 260–300 km/h (docs/problems.md, 'Contact-wire tension')."""
HELD_OUT_TENSIONS = ((21500.0, 22500.0), (25500.0, 26500.0))
"""Tension bands never drawn in training, N: the preset's own tension is one of them."""
TABLE_TENSIONS = ((20000.0, False), (22000.0, True), (24000.0, False), (26000.0, True), (28000.0, False))
"""(tension in N, held out) of the table."""
SPEED_KMH = 300.0
"""The speed of the table, km/h."""


@dataclass(frozen=True)
class Config(rl_amortised.Config):
    """The study's settings (quick unless ``full``): study 5b's, with SAC alone by default, on B1."""

    learners: tuple[str, ...] = ("sac",)

    def __post_init__(self) -> None:
        object.__setattr__(self, "problems", (PROBLEM,))
        super().__post_init__()

    @property
    def tensions(self) -> tuple[tuple[float, bool], ...]:
        """(tension in N, held out) of the table."""
        return TABLE_TENSIONS if self.full else ((22000.0, True), (24000.0, False))


def label(tension: float) -> str:
    """The table's name of the problem at a tension: ``"B1 at 22 kN"``."""
    return f"{PROBLEM} at {tension / 1000:g} kN"


def trained_on(name: str) -> str:
    """The problem a policy was trained on, of a table's name (:func:`label`)."""
    return name.split(" at ")[0]


def env_spec(config: Config) -> EnvSpec:
    return EnvSpec(
        rl_amortised.env_id(PROBLEM), None, SPEED_RANGE, config.fidelity, HELD_OUT, TENSION_RANGE,
        HELD_OUT_TENSIONS,
    )  # fmt: skip


def main(config: Config) -> Path:
    from catenary_env.envs import register_envs

    register_envs()
    folder = study_dir(config.out, NAME)
    (folder / "policies").mkdir(exist_ok=True)
    tables: dict[str, list[dict[str, Any]]] = {k: [] for k in ("steps", "ga", "curves", "designs")}
    store_path = config.store or Path(config.out) / STORE
    rl_amortised.check_starts_at_reference(PROBLEM)
    with RunStore(store_path) as store:
        rl_amortised.restore_archive(config, store, store_path)
        reference = tuple(float(v) for v in study_problem(PROBLEM).reference_x())  # type: ignore[union-attr]
        _simulate(store, config, [("reference", -1, t, reference) for t, _ in config.tensions], tables)
        _ga_runs(store, config, tables)
        for learner in config.learners:
            for seed in config.seeds:
                _policy(store, store_path, config, learner, seed, folder, tables)
                _speed_only_policy(store, config, learner, seed, tables)
    rl_amortised.write_tables(config, folder, tables)
    report(folder)
    if config.archive is not None:
        rl_amortised.write_cost(Path(config.archive), folder, config.envs, "The tension study's cost")
    return folder


def _at(tension: float) -> CatenaryProblem:
    return catenary_problem(PROBLEM, contact_wire_tension=tension)


def _simulate(
    store: RunStore,
    config: Config,
    designs: list[tuple[str, int, float, tuple[float, ...]]],
    tables: dict[str, list[dict[str, Any]]],
) -> None:
    """Simulate (or find in the store) each (design, seed, tension, x) at :data:`SPEED_KMH`; add its row.
    One design a tension (another problem each): in this process, without a pool to start for each."""
    held_out = dict(config.tensions)
    for design, seed, tension, x in designs:
        (outcome,) = evaluate_designs(store, _at(tension), [(x, SPEED_KMH)], config.fidelity)
        tables["designs"].append(
            {
                "problem": label(tension), "design": design, "seed": seed, "speed_kmh": SPEED_KMH,
                "tension_N": tension, "held_out": int(held_out.get(tension, False)),
                "feasible": int(outcome.feasible), "sigma_N": rl_amortised.sigma_or_nan(outcome),
                "x_m": rl_amortised.x_text(x),
            }
        )  # fmt: skip


def study_runs(config: Config) -> list[rl_amortised.StudyRun]:
    """The study's runs in the order :func:`main` makes them: the GA runs, then the policies."""
    runs = [
        rl_amortised.ga_study_run(config, _at(tension), SPEED_KMH, PROBLEM, f"ga on {label(tension)}")
        for tension, _ in config.tensions
    ]
    for learner in config.learners:
        for seed in config.seeds:
            name = f"{learner} on {PROBLEM} over tensions, seed {seed}"
            runs.append(rl_amortised.policy_study_run(config, env_spec(config), PROBLEM, learner, seed, name))
    return runs


def lane(config: Config) -> str:
    """``--lane``: :func:`rl_amortised.make_free_runs` over the study's runs."""
    return rl_amortised.make_free_runs(config, study_runs(config))


def _ga_runs(store: RunStore, config: Config, tables: dict[str, list[dict[str, Any]]]) -> None:
    """A GA run at each tension of the table, at :data:`SPEED_KMH`."""
    optima = []
    for tension, _ in config.tensions:
        result = rl_amortised.ga_run(
            store, config=config, problem=_at(tension), speed=SPEED_KMH, population_of=PROBLEM
        )
        tables["ga"].append(rl_amortised.ga_row(label(tension), SPEED_KMH, config, result, PROBLEM))
        tables["curves"].extend(rl_amortised.best_so_far(label(tension), SPEED_KMH, result))
        if result.best_x is not None:
            optima.append(("ga", 0, tension, tuple(result.best_x)))
    _simulate(store, config, optima, tables)


def _policy(
    store: RunStore,
    store_path: Path,
    config: Config,
    learner: str,
    seed: int,
    folder: Path,
    tables: dict[str, list[dict[str, Any]]],
) -> None:
    """Train (or resume) one policy, save it with the command that reproduces it, simulate its designs."""
    problem = catenary_problem(PROBLEM)
    policy, result = rl_amortised.train_policy(
        store, config=config, env=env_spec(config), problem=problem, learner=learner, seed=seed
    )
    tables["steps"].extend(rl_amortised.step_rows(store, PROBLEM, learner, seed, result))
    path = folder / "policies" / f"{learner}-{PROBLEM}-tension-seed{seed}.zip"
    command = reproduce_command(config, store_path, learner, seed, path)
    save_policy(policy, path, problem, result, command)
    path.with_suffix(".txt").write_text(command + "\n", encoding="utf-8")
    designs = [
        (learner, seed, t, tuple(design_for_speed(policy, problem, SPEED_KMH, t).tolist()))
        for t, _ in config.tensions
    ]
    _simulate(store, config, designs, tables)
    best = "no feasible design" if result.best_sigma is None else f"best σ met {result.best_sigma:.3f} N"
    print(f"{learner} on {PROBLEM} over tensions, seed {seed}: {best}", file=sys.stderr, flush=True)


SPEED_ONLY = "speed only"
"""The table's word for study 5b's policies, conditioned on the speed alone (trained at the preset's
tension)."""


def _speed_only_policy(
    store: RunStore, config: Config, learner: str, seed: int, tables: dict[str, list[dict[str, Any]]]
) -> None:
    """Study 5b's policy of the same learner and seed on B1 (conditioned on the speed alone, trained at the
    preset's tension), where its results are in ``out`` at this fidelity: its design at :data:`SPEED_KMH`,
    simulated at each tension of the table. What conditioning on the tension adds is the difference."""
    path = Path(config.out) / rl_amortised.NAME / "policies" / f"{learner}-{PROBLEM}-seed{seed}.zip"
    if not path.is_file():
        return
    policy, record = load_policy(path)
    if record.env_spec.fidelity != config.fidelity or record.env_spec.contact_wire_tension_range is not None:
        return
    x = tuple(design_for_speed(policy, catenary_problem(PROBLEM), SPEED_KMH).tolist())
    _simulate(store, config, [(f"{learner} {SPEED_ONLY}", seed, t, x) for t, _ in config.tensions], tables)


def reproduce_command(config: Config, store: Path, learner: str, seed: int, policy: Path) -> str:
    """The command that reproduces (resumes from the store) one policy's run and saves it again: ``catenary
    optimize`` in the full setting, else the study's own command restricted to that run."""
    if rl_amortised.trains_with_defaults(config, learner):
        tensions = [
            "--contact-wire-tension-range", *(f"{v:g}" for v in TENSION_RANGE),
            "--held-out-tensions", *(f"{v:g}" for band in HELD_OUT_TENSIONS for v in band),
        ]  # fmt: skip
        return rl_amortised.optimize_command(config, store, PROBLEM, learner, seed, policy, tensions)
    return shlex.join(
        [
            "catenary", "experiment", "rl-tension", *(["--full"] if config.full else []),
            "--learners", learner, "--seeds", str(seed), "--envs", str(config.envs),
            "--store", str(store), "--out", str(config.out),
        ]
    )  # fmt: skip


# -- report (from the data files alone) -------------------------------------------------------------------

TABLE_COLUMNS = [("tension_kN", "contact-wire tension (kN)", "g"), *rl_analysis.TABLE_COLUMNS[2:]]
"""Study 5b's table with the tension in place of the problem and the speed."""


def report(folder: Path) -> str:
    """Tables and figures from the CSV files (no simulation)."""
    steps = read_csv(folder / "steps.csv")
    designs = read_csv(folder / "designs.csv")
    curves = read_csv(folder / "ga_curves.csv") if (folder / "ga_curves.csv").is_file() else []
    ga_runs = read_csv(folder / "ga_runs.csv")
    window = rl_analysis.window_of(steps)
    trained = [d for d in designs if not str(d["design"]).endswith(SPEED_ONLY)]  # no training here
    ledger = rl_analysis.amortisation_ledger(trained, curves, ga_runs, steps, trained_on=trained_on)
    write_csv(folder / "ledger.csv", ledger)
    tension_of = {r["problem"]: r["tension_N"] for r in designs}
    table = [
        {**row, "tension_kN": tension_of[row["problem"]] / 1000.0}
        for row in sorted(rl_analysis.speed_table(designs), key=lambda r: tension_of[r["problem"]])
    ]
    sections = [
        (
            f"Learning curves (windows of {window} steps)",
            rl_analysis.learning_summary(steps, window),
            rl_analysis.LEARNING_COLUMNS,
        ),
        (
            f"Policies against a GA run per tension at {SPEED_KMH:g} km/h "
            f"({rl_analysis.ga_budgets(ga_runs)}; –: no feasible design; {SPEED_ONLY}: study 5b's policy, "
            "trained at 22 kN only)",
            table,
            TABLE_COLUMNS,
        ),
        (
            "Amortisation ledger (N: catenaries, a tension and a speed each)",
            [r for r in ledger if r["n_speeds"] == rl_analysis.LEDGER_SPEEDS[0]],
            rl_analysis.LEDGER_COLUMNS,
        ),
    ]
    text = "\n\n".join(
        f"### {title}\n\n{markdown_table(rows, columns, missing='–')}" for title, rows, columns in sections
    )
    (folder / "tension.md").write_text(text + "\n", encoding="utf-8")
    rl_analysis.learning_figure(steps, window, folder / "learning_curves.png")
    return text


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment rl-tension``, ``python -m experiments.rl_tension``)."""
    add_full_option(parser, "the study fidelity, SAC, 3 seeds of 10,000 steps, five GA runs of 1000 (hours)")
    rl_amortised.add_training_arguments(parser, ("sac",))


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.rl_tension``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.rl_tension")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.rl_tension"))
