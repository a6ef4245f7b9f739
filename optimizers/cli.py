"""``catenary optimize``: run an optimiser on a design problem from the command line; ``catenary propose``:
the designs of a saved PPO policy.

    catenary optimize PROBLEM --optimizer NAME --budget N [--seed S] [--speed KMH] [--fidelity study|test]
                      [--store PATH] [--resume] [--workers N] [--scheduler tcp://HOST:PORT] [--json]
                      [--speed-range LO HI] [--save-policy FILE]
    catenary propose POLICY --speed KMH [KMH ...] [--no-evaluate] [--fidelity study|test] [--json]

``optimize`` is also available as ``python -m optimizers PROBLEM ...``. :func:`add_parser` adds the
sub-command to the ``catenary`` parser and :func:`run` executes it; bad input exits with status 2 and a
message.

A ppo run saves its trained policy: with ``--save-policy FILE`` there, else beside the run store, as
``<store>.ppo-<problem>-run<ID>.zip`` (a run store ``:memory:`` keeps none unless ``--save-policy`` is
given); the summary says where.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from catenary_env.cli_errors import UsageError, check_output_path, interruption, print_error

from . import ga, nevergrad_adapters  # noqa: F401  (register the built-in optimisers)
from .base import OPTIMIZERS, OptimizationResult
from .cli_runs import add_runs_parser, list_runs
from .progress import LOG_INTERVAL
from .store import StoreError

__all__ = [
    "DEFAULT_STORE",
    "add_arguments",
    "add_commands",
    "add_parser",
    "add_propose_parser",
    "propose",
    "run",
]

DEFAULT_STORE = "catenary-runs.sqlite"
"""Run store used when ``--store`` is not given (in the current directory)."""

RL_OPTIMIZERS = ("ppo",)

DESCRIPTION = (
    "Optimise the design of a catenary problem (docs/problems.md) with the study's genetic algorithm, a "
    "nevergrad optimiser or a PPO design policy. Every evaluation is committed to an SQLite run store as it "
    "completes: an interrupted run continues with --resume, and a design already simulated in the store is "
    "not simulated again."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``optimize`` options to a parser."""
    names = sorted(OPTIMIZERS) + list(RL_OPTIMIZERS)
    parser.add_argument(
        "problem",
        metavar="PROBLEM",
        help="design problem: BPresag, B1, B2, B3, SWPresag, SW1, SW2, SW3 (docs/problems.md), or a cheap "
        "synthetic one for trying things out: synthetic-quadratic, synthetic-quadratic-slow",
    )
    parser.add_argument(
        "--optimizer",
        default="ga",
        choices=names,
        metavar="NAME",
        help=f"optimiser, one of: {', '.join(names)} (default: ga, the study's genetic algorithm)",
    )
    parser.add_argument(
        "--budget",
        type=int,
        required=True,
        metavar="N",
        help="simulations the run may spend (an integer >= 1); re-evaluating a design the run has "
        "already seen is free, and a ppo run takes exactly N env steps",
    )
    parser.add_argument(
        "--seed",
        type=int,
        default=0,
        metavar="S",
        help="random seed (an integer >= 0); the same seed gives the same run (default: 0)",
    )
    parser.add_argument(
        "--speed", type=float, default=300.0, metavar="KMH", help="design train speed, km/h (default: 300)"
    )
    parser.add_argument(
        "--speed-range",
        type=float,
        nargs=2,
        default=None,
        metavar=("LO", "HI"),
        help="ppo only: train a speed-conditioned policy over speeds LO..HI km/h, drawn per episode "
        "(the best sigma is then the lowest met over speeds, reported with its speed)",
    )
    parser.add_argument(
        "--save-policy",
        default=None,
        metavar="FILE",
        help="ppo only: save the trained policy to FILE, a zip that 'catenary propose' reads (default: "
        "beside the run store, <store>.ppo-<problem>-run<ID>.zip; none for --store :memory:)",
    )
    parser.add_argument(
        "--fidelity",
        choices=("study", "test"),
        default="study",
        help="'study': 20 spans, statistics on the 10 central ones, 1 ms time step; 'test': 5 spans, "
        "coarse mesh, for trying things out only (default: study)",
    )
    parser.add_argument(
        "--store",
        default=DEFAULT_STORE,
        metavar="PATH",
        help=f"SQLite run store file, created if absent (default: ./{DEFAULT_STORE}); "
        "':memory:' keeps nothing",
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="continue the latest run in the store with the same problem, optimiser, budget, seed, "
        "speed and fidelity: its stored evaluations are replayed, not simulated; refused, listing the "
        "store's runs, when it holds none",
    )
    parser.add_argument(
        "--resume-or-start",
        action="store_true",
        help="like --resume, but start the run when the store holds none (for a command re-run until done)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="local worker processes for the simulations; 1 simulates in this process "
        f"(default: the number of CPUs, {os.cpu_count() or 1})",
    )
    parser.add_argument(
        "--scheduler",
        default=None,
        metavar="tcp://HOST:PORT",
        help="address of a Dask distributed scheduler: send the simulations to that cluster "
        "instead of local processes (needs catenary-env[parallel])",
    )
    parser.add_argument(
        "--max-evaluations",
        type=int,
        default=None,
        metavar="N",
        help="cap on evaluations including free repeats of designs already seen (default: 10 x the budget)",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print the result (best design in m, best sigma in N, the full history) as JSON",
    )
    parser.add_argument(
        "--quiet", action="store_true", help="no progress on stderr (neither the line nor the log lines)"
    )
    parser.add_argument(
        "--progress-every",
        type=float,
        default=LOG_INTERVAL,
        metavar="S",
        help="when stderr is not a terminal (a log, nohup), a progress line every S seconds "
        f"(default: {LOG_INTERVAL:g})",
    )


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``optimize`` to the sub-commands of the ``catenary`` command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "optimize", help="optimise a design problem (GA, nevergrad, PPO)", description=DESCRIPTION
    )
    add_arguments(parser)
    return parser


def add_commands(subparsers: Any) -> dict[str, Callable[[argparse.Namespace], int]]:
    """Add ``catenary optimize``, ``propose`` and ``runs``: the ``catenary_env.commands`` entry point of this
    package."""
    add_parser(subparsers)
    add_propose_parser(subparsers)
    add_runs_parser(subparsers, DEFAULT_STORE)
    return {"optimize": run, "propose": propose, "runs": list_runs}


def run(args: argparse.Namespace) -> int:
    """Execute ``optimize``; return the exit status (0; 2 for bad input; 130 or 143 when interrupted)."""
    try:
        if args.save_policy is not None:
            if args.optimizer not in RL_OPTIMIZERS:
                raise UsageError(f"--save-policy is for --optimizer ppo, not {args.optimizer}")
            check_output_path(args.save_policy, "--save-policy")
        if args.optimizer in RL_OPTIMIZERS:
            result, policy_path = _run_rl(args)
        else:
            result, policy_path = _run_optimizer(args), None
    except (StoreError, ImportError, ValueError, TypeError, KeyError, OSError) as error:
        if getattr(args, "debug", False):
            raise
        return print_error("optimize", error)
    except KeyboardInterrupt as error:
        how, status = interruption(error)
        print(
            f"\ncatenary optimize: {how}; the evaluations completed are in {args.store}: run the same "
            "command with --resume to continue",
            file=sys.stderr,
        )
        return status
    if args.json:
        data = result.to_dict()
        data["policy"] = None if policy_path is None else str(policy_path)
        data["units"] = RESULT_UNITS
        print(json.dumps(data))
    else:
        print(_summary(result, args.store, policy_path))
    return 0


RESULT_UNITS = {
    "best_x, history.x": "m",
    "best_sigma, history.sigma": "N",
    "speed_kmh, best_speed_kmh, history.speed_kmh": "km/h",
    "history.wall_time": "s",
}
"""Units of the numbers in ``catenary optimize --json``."""


def _run_optimizer(args: argparse.Namespace) -> OptimizationResult:
    from .runner import optimize

    if args.speed_range is not None:
        raise ValueError("--speed-range is for --optimizer ppo; the other optimisers design for one --speed")
    if args.scheduler and args.workers is not None:
        raise UsageError(
            f"--workers {args.workers} with --scheduler {args.scheduler}: the cluster's workers run the "
            "simulations; give one of the two"
        )
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    return optimize(
        args.problem, args.optimizer, args.budget, args.seed, speed_kmh=args.speed, fidelity=args.fidelity,
        store=args.store, resume=args.resume or args.resume_or_start, start_if_none=args.resume_or_start,
        n_workers=workers, scheduler=args.scheduler,
        max_evaluations=args.max_evaluations, quiet=args.quiet, progress_interval=args.progress_every,
    )  # fmt: skip


def _run_rl(args: argparse.Namespace) -> tuple[OptimizationResult, Path | None]:
    from .catenary_adapter import catenary_problem
    from .rl import EnvSpec, save_policy, train_design_policy

    if args.scheduler or (args.workers or 1) > 1:
        print(
            "catenary optimize: note: ppo steps its env in this process; --workers/--scheduler are ignored",
            file=sys.stderr,
        )
    try:
        from catenary_env.envs import register_envs
    except ImportError as error:
        raise ImportError(f"ppo needs the design envs: pip install catenary-env[gym] ({error})") from error
    register_envs()
    problem = catenary_problem(args.problem)
    speed_range = tuple(args.speed_range) if args.speed_range is not None else None
    spec = EnvSpec(
        f"Catenary-{problem.name}-v0", None if speed_range else args.speed, speed_range, args.fidelity
    )
    policy, result = train_design_policy(
        spec, problem, args.budget, args.seed, store=args.store, resume=args.resume or args.resume_or_start,
        start_if_none=args.resume_or_start, quiet=args.quiet,
    )  # fmt: skip
    path = args.save_policy
    if path is None and args.store != ":memory:":
        path = f"{Path(args.store).with_suffix('')}.ppo-{problem.name}-run{result.run_id}.zip"
    return result, None if path is None else save_policy(policy, path, problem, result)


def _summary(result: OptimizationResult, store: str, policy: Path | None = None) -> str:
    lines = [
        f"{result.optimizer} on {result.problem} (seed {result.seed}): stopped by {result.stop_reason} after "
        f"{result.n_simulations}/{result.budget} simulations, {len(result.history)} evaluations; "
        f"run {result.run_id} in {store}",
    ]
    if result.best_x is None:
        lines.append("no feasible design found")
    else:
        speed = f" at {result.best_speed_kmh:g} km/h" if result.best_speed_kmh is not None else ""
        lines.append(f"best sigma = {result.best_sigma:.4f} N{speed}, for the design")
        lines.extend(
            f"  {name} = {value:.3f} m"
            for name, value in zip(result.variable_names, result.best_x, strict=True)
        )
        if result.speed_kmh is None:
            lines.append(
                "  (a speed range: the lowest sigma met in training, over designs at different speeds, "
                "which sigma does not compare; the policy's design at a speed: catenary propose POLICY "
                "--speed KMH)"
            )
    if policy is not None:
        lines.append(f"policy saved to {policy}: catenary propose {policy} --speed KMH gives its design")
    return "\n".join(lines)


# -- catenary propose ------------------------------------------------------------------------------------


def add_propose_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``propose`` to the sub-commands of the ``catenary`` command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "propose",
        help="the design a saved PPO policy proposes at a speed, and its sigma",
        description="Load a PPO design policy saved by 'catenary optimize PROBLEM --optimizer ppo' and print "
        "the design it proposes at each speed; unless --no-evaluate, simulate each design at its speed, "
        "with the problem's reference design (the level contact wire) for comparison. Load only policy "
        "files you trust: loading one unpickles parts of it, as stable-baselines3 does.",
    )
    parser.add_argument("policy", metavar="POLICY", help="the policy file (a zip saved by catenary optimize)")
    parser.add_argument(
        "--speed",
        type=float,
        nargs="+",
        required=True,
        metavar="KMH",
        help="train speeds, km/h, one design each (within the policy's training speeds for a meaningful "
        "design)",
    )
    parser.add_argument(
        "--no-evaluate",
        action="store_true",
        help="print the designs only, without simulating them",
    )
    parser.add_argument(
        "--fidelity",
        choices=("study", "test"),
        default=None,
        help="the model the designs are simulated on (default: the one the policy was trained on)",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object: the policy's record and, per speed, the design (m) and its sigma (N)",
    )
    return parser


def propose(args: argparse.Namespace) -> int:
    """Execute ``propose``; return the exit status (0; 2 for bad input)."""
    try:
        report = _proposals(args)
    except (ImportError, ValueError, TypeError, KeyError, OSError) as error:
        if getattr(args, "debug", False):
            raise
        return print_error("propose", error)
    except KeyboardInterrupt as error:
        how, status = interruption(error)
        print(f"\ncatenary propose: {how}", file=sys.stderr)
        return status
    print(json.dumps(report) if args.json else _proposal_table(report))
    return 0


def _proposals(args: argparse.Namespace) -> dict[str, Any]:
    """The policy's record and its design at each speed (simulated unless --no-evaluate)."""
    import dataclasses

    from catenary_env.model.design import check_speed

    from .problem_registry import resolve_problem
    from .rl import design_for_speed, load_policy

    policy, record = load_policy(args.policy)
    problem = resolve_problem(record.problem)
    _warn_if_stale(args.policy, record, problem)
    catenary = _catenary_definition(record.problem)
    for speed in args.speed:
        if catenary is not None:
            check_speed(catenary, speed / 3.6)
        if not _trained_for(record, speed):
            print(
                f"catenary propose: warning: {speed:g} km/h is outside the policy's training speeds "
                f"({record.speeds}): its design there is an extrapolation",
                file=sys.stderr,
            )
    fidelity = args.fidelity or record.env_spec.fidelity
    proposals = []
    for speed in args.speed:
        x = design_for_speed(policy, problem, speed)
        entry: dict[str, Any] = {
            "speed_kmh": speed,
            "design": dict(zip(problem.variable_names, x.tolist(), strict=True)),
        }
        if not args.no_evaluate:
            outcome = problem.simulate(tuple(float(v) for v in x), float(speed), fidelity)
            entry.update(feasible=outcome.feasible, sigma=outcome.sigma, reason=outcome.reason)
            entry["reference_sigma"] = _reference_sigma(record.problem, speed, fidelity)
        proposals.append(entry)
    policy_record = dataclasses.asdict(record)
    return {
        "policy": str(args.policy),
        "record": policy_record,
        "fidelity": None if args.no_evaluate else fidelity,
        "proposals": proposals,
        "units": {"speed_kmh": "km/h", "design": "m", "sigma, reference_sigma": "N"},
    }


def _catenary_definition(name: str) -> Any:
    """The catenary of a catenary design problem (for its speed limit), or None for another problem."""
    from catenary_env.problems import PROBLEMS

    return PROBLEMS[name].catenary_definition if name in PROBLEMS else None


def _reference_sigma(name: str, speed: float, fidelity: str) -> float | None:
    """σ of a catenary problem's reference design at the speed, N (None for another problem)."""
    from catenary_env.problems import PROBLEMS

    if name not in PROBLEMS:
        return None
    statistics = PROBLEMS[name].reference_evaluation(speed, fidelity).statistics
    return None if statistics is None else float(statistics.std)


def _trained_for(record: Any, speed: float) -> bool:
    spec = record.env_spec
    if spec.speed_range is not None:
        return spec.speed_range[0] <= speed <= spec.speed_range[1]
    return spec.speed_kmh is None or abs(speed - spec.speed_kmh) < 1e-9


def _warn_if_stale(path: str, record: Any, problem: Any) -> None:
    now = str(getattr(problem, "model_fingerprint", ""))
    if record.model_fingerprint and now and record.model_fingerprint != now:
        print(
            f"catenary propose: warning: {path} was trained on {record.problem} with model fingerprint "
            f"{record.model_fingerprint}; the problem's model is now {now} (an edited preset or a new "
            "simulator revision): its designs were learnt on the old model",
            file=sys.stderr,
        )


def _proposal_table(report: dict[str, Any]) -> str:
    record = report["record"]
    spec = record["env_spec"]
    trained = (
        f"{spec['speed_range'][0]:g}-{spec['speed_range'][1]:g} km/h"
        if spec["speed_range"] is not None
        else f"{spec['speed_kmh']:g} km/h"
    )
    lines = [
        f"{report['policy']}: ppo policy for {record['problem']}, trained on {trained} ({spec['fidelity']} "
        f"fidelity, budget {record['budget']}, seed {record['seed']}, run {record['run_id']})"
    ]
    for entry in report["proposals"]:
        lines.append(f"at {entry['speed_kmh']:g} km/h:")
        lines.extend(f"  {name} = {value:.3f} m" for name, value in entry["design"].items())
        if "feasible" in entry:
            lines.append(_sigma_line(entry, report["fidelity"]))
    return "\n".join(lines)


def _sigma_line(entry: dict[str, Any], fidelity: str) -> str:
    if not entry["feasible"]:
        return f"  infeasible ({fidelity} fidelity): {entry['reason']}"
    line = f"  sigma = {entry['sigma']:.3f} N ({fidelity} fidelity)"
    reference = entry.get("reference_sigma")
    if reference:
        change = 100.0 * (entry["sigma"] - reference) / reference
        line += f"; reference design (level contact wire): {reference:.3f} N, {change:+.1f} %"
    return line
