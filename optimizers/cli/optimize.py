"""``catenary optimize``: run an optimiser on a design problem from the command line.

    catenary optimize PROBLEM --optimizer NAME --budget N [--seed S] [--speed KMH] [--fidelity study|test]
                      [--store PATH] [--resume] [--archive FOLDER] [--workers N]
                      [--scheduler tcp://HOST:PORT] [--json]
                      [--speed-range LO HI] [--held-out-speeds A B [A B ...]] [--save-policy FILE]

``optimize`` is also available as ``python -m optimizers PROBLEM ...``. :func:`add_parser` adds the
sub-command to the ``catenary`` parser and :func:`run` executes it; bad input is refused with one line
(``catenary_env/cli/exits.py``).

A ppo or sac run (an RL design policy) saves its trained policy: with ``--save-policy FILE`` there, else
beside the run store, as ``<store>.<learner>-<problem>-run<ID>.zip`` (a run store ``:memory:`` keeps none
unless ``--save-policy`` is given), with the command that reproduces it in its record; the summary says
where. Its ``--workers`` are the envs stepped at once, each in its process (default 1: in this process).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shlex
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from catenary_env.cli.exits import interruption
from catenary_env.cli.options import add_train_arguments, train_of
from catenary_env.cli.paths import check_output_path
from catenary_env.cli.progress import LOG_INTERVAL
from catenary_env.errors import MissingDependency, UnknownNameError, UsageError

from .. import ga, nevergrad_adapters  # noqa: F401  (register the built-in optimisers)
from ..archive import restore_runs
from ..base import OPTIMIZERS, OptimizationResult
from ..plugins import get_optimizer, load_plugins
from ..store import RunStore

__all__ = ["DEFAULT_STORE", "DESCRIPTION", "add_arguments", "add_parser", "run"]

DEFAULT_STORE = "catenary-runs.sqlite"
"""Run store used when ``--store`` is not given (in the current directory)."""

RL_OPTIMIZERS = ("ppo", "sac")
"""The RL learners (``optimizers.rl.LEARNERS``), trained on a design env rather than asked and told."""

ENV_OPTIONS = {
    "speed": "--speed",
    "speed_range": "--speed-range",
    "excluded_speeds": "--held-out-speeds",
    "contact_wire_tension": "--contact-wire-tension",
    "contact_wire_tension_range": "--contact-wire-tension-range",
    "excluded_tensions": "--held-out-tensions",
}
"""The option of each field of an RL run's env, to name in the env's refusal of it."""

DESCRIPTION = (
    "Optimise the design of a catenary problem (docs/problems.md) with the study's genetic algorithm, a "
    "nevergrad optimiser or an RL design policy (PPO or SAC). Every evaluation is committed to an SQLite "
    "run store as it completes: an interrupted run continues with --resume, and a design already simulated "
    "in the store is not simulated again."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``optimize`` options to a parser."""
    load_plugins()
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
        metavar="NAME",
        help=f"optimiser, one of: {', '.join(names)}, or one registered later or by an installed package "
        "(docs/problems.md, 'Your own optimiser'; default: ga, the study's genetic algorithm)",
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
        help="ppo and sac only: train a speed-conditioned policy over speeds LO..HI km/h, drawn per "
        "episode (the best sigma is then the lowest met over speeds, reported with its speed)",
    )
    parser.add_argument(
        "--held-out-speeds",
        type=float,
        nargs="+",
        default=[],
        metavar="KMH",
        help="with --speed-range: pairs A B of km/h bounding bands of speeds never drawn in training (held "
        "out, to evaluate the policy there), e.g. 225 235 285 295",
    )
    parser.add_argument(
        "--contact-wire-tension",
        type=float,
        default=None,
        metavar="N",
        help="the catenary design problems: their catenary with the contact wire at this tension, N, within "
        "70-130 %% of the preset's (default: the preset's); ppo and sac take --contact-wire-tension-range",
    )
    parser.add_argument(
        "--contact-wire-tension-range",
        type=float,
        nargs=2,
        default=None,
        metavar=("LO", "HI"),
        help="ppo and sac only: train a policy conditioned on the contact wire's tension as well, drawn per "
        "episode from LO..HI N (within 70-130 %% of the preset's)",
    )
    parser.add_argument(
        "--held-out-tensions",
        type=float,
        nargs="+",
        default=[],
        metavar="N",
        help="with --contact-wire-tension-range: pairs A B of N bounding bands of tensions never drawn in "
        "training, e.g. 21500 22500",
    )
    parser.add_argument(
        "--save-policy",
        default=None,
        metavar="FILE",
        help="ppo and sac only: save the trained policy to FILE, a zip that 'catenary propose' reads "
        "(default: beside the run store, <store>.<learner>-<problem>-run<ID>.zip; none for --store :memory:)",
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
        "store's runs, when it holds none, and while another process is making that run",
    )
    parser.add_argument(
        "--resume-or-start",
        action="store_true",
        help="like --resume, but start the run when the store holds none (for a command re-run until done)",
    )
    parser.add_argument(
        "--archive",
        type=Path,
        default=None,
        metavar="FOLDER",
        help="a run archive (one file a run, to commit or copy away): the runs it holds and the store "
        "lacks are restored into the store first, so --resume continues a run made elsewhere; the run goes "
        "into it when it finishes, with a snapshot every ten minutes while it runs and when it is stopped",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="local worker processes for the simulations; 1 simulates in this process "
        f"(default: the number of CPUs, {os.cpu_count() or 1}; ppo and sac: the envs stepped at once, "
        "default 1, and the budget a multiple of them)",
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
    add_train_arguments(parser, objective=True)


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``optimize`` to the sub-commands of the ``catenary`` command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "optimize",
        help="optimise a design problem (GA, nevergrad, optuna, PPO, SAC)",
        description=DESCRIPTION,
    )
    add_arguments(parser)
    return parser


def run(args: argparse.Namespace) -> int:
    """Execute ``optimize``; return the exit status (0; 130 or 143 when interrupted, saying how to resume)."""
    if args.max_evaluations is not None and args.max_evaluations < 1:
        raise UsageError(f"--max-evaluations {args.max_evaluations}: must be at least 1 evaluation")
    if not args.progress_every >= 0.0:
        raise UsageError(f"--progress-every {args.progress_every}: must be a number of seconds >= 0")
    if args.optimizer not in RL_OPTIMIZERS:
        try:
            get_optimizer(args.optimizer)  # one line naming those available, before anything is opened
        except UnknownNameError as error:
            raise UsageError(f"{error.args[0]}; or an RL learner: {', '.join(RL_OPTIMIZERS)}") from None
    if args.save_policy is not None:
        if args.optimizer not in RL_OPTIMIZERS:
            raise UsageError(f"--save-policy is for --optimizer ppo or sac, not {args.optimizer}")
        check_output_path(args.save_policy, "--save-policy")
    try:
        with _store(args) as store:
            if args.optimizer in RL_OPTIMIZERS:
                result, policy_path = _run_rl(args, store)
            else:
                result, policy_path = _run_optimizer(args, store), None
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


@contextlib.contextmanager
def _store(args: argparse.Namespace) -> Iterator[RunStore | str]:
    """The run store the run goes to: with ``--archive``, opened here, the archive's runs restored into it."""
    if args.archive is None:
        yield args.store
        return
    with RunStore(args.store) as store:
        restored = restore_runs(store, args.archive)
        if restored and not args.quiet:
            print(f"{restored} run(s) restored from {args.archive} into {args.store}", file=sys.stderr)
        yield store


def _run_optimizer(args: argparse.Namespace, store: RunStore | str) -> OptimizationResult:
    from ..runner import optimize

    if args.speed_range is not None:
        raise UsageError(
            "--speed-range is for --optimizer ppo or sac; the other optimisers design for one --speed"
        )
    if args.scheduler and args.workers is not None:
        raise UsageError(
            f"--workers {args.workers} with --scheduler {args.scheduler}: the cluster's workers run the "
            "simulations; give one of the two"
        )
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    return optimize(
        _problem(args), args.optimizer, args.budget, args.seed, speed_kmh=args.speed, fidelity=args.fidelity,
        store=store, resume=args.resume or args.resume_or_start, start_if_none=args.resume_or_start,
        n_workers=workers, scheduler=args.scheduler, max_evaluations=args.max_evaluations, quiet=args.quiet,
        progress_interval=args.progress_every, archive=args.archive,
    )  # fmt: skip


def _problem(args: argparse.Namespace) -> Any:
    """The problem's name, or the catenary problem with ``--pantographs``' train (docs/model.md, 'Several
    pantographs') and at ``--contact-wire-tension`` (docs/problems.md, 'Contact-wire tension')."""
    if args.contact_wire_tension_range is not None or args.held_out_tensions:
        raise UsageError(
            f"--contact-wire-tension-range/--held-out-tensions: ppo and sac only, not {args.optimizer}; "
            "give --contact-wire-tension"
        )
    if not args.pantographs and args.contact_wire_tension is None:
        return args.problem
    from catenary_env.problems import get_problem
    from catenary_env.train import SINGLE

    from ..catenary_adapter import catenary_problem

    option = "--pantographs" if args.pantographs else "--contact-wire-tension"
    try:
        leading = get_problem(args.problem).pantograph_definition
    except KeyError:
        raise UsageError(f"{option}: for the catenary design problems, not {args.problem!r}") from None
    train = SINGLE
    if args.pantographs:
        first, train = train_of(args, leading)
        if first != leading:
            raise UsageError(
                f"--pantographs {args.pantographs}: the leading pantograph is the problem's, {leading.name}"
            )
    return catenary_problem(args.problem, train, args.contact_wire_tension)


def _run_rl(args: argparse.Namespace, store: RunStore | str) -> tuple[OptimizationResult, Path | None]:
    import dataclasses

    from ..catenary_adapter import catenary_problem
    from ..rl import LEARNERS, save_policy, train_design_policy

    if args.scheduler:
        raise UsageError(f"--scheduler is not for --optimizer {args.optimizer}: its envs run on this machine")
    try:
        from catenary_env.envs import register_envs
    except ImportError as error:
        raise MissingDependency(
            f"{args.optimizer} needs the design envs: pip install catenary-env[gym] ({error})"
        ) from error
    register_envs()
    if args.contact_wire_tension is not None:
        raise UsageError(
            f"--contact-wire-tension is not for --optimizer {args.optimizer}: give "
            "--contact-wire-tension-range LO HI, the tensions a policy is trained on"
        )
    problem = catenary_problem(args.problem)
    spec = rl_env_spec(problem.name, args)
    n_envs = args.workers or 1
    if n_envs < 1 or args.budget % n_envs:
        raise UsageError(
            f"--workers {n_envs} with --budget {args.budget}: the budget must be a multiple of it"
        )
    options = dataclasses.replace(LEARNERS[args.optimizer](), n_envs=n_envs)
    policy, result = train_design_policy(
        spec, problem, args.budget, args.seed, options=options, store=store,
        resume=args.resume or args.resume_or_start, start_if_none=args.resume_or_start, quiet=args.quiet,
        archive=args.archive,
    )  # fmt: skip
    path = args.save_policy
    if path is None and args.store != ":memory:":
        path = f"{Path(args.store).with_suffix('')}.{args.optimizer}-{problem.name}-run{result.run_id}.zip"
    if path is None:
        return result, None
    return result, save_policy(policy, path, problem, result, rl_command(args, path))


def rl_env_spec(problem: str, args: argparse.Namespace) -> Any:
    """The env of an RL run from its options (``--speed`` or ``--speed-range``, ``--held-out-speeds``,
    ``--contact-wire-tension-range``, ``--held-out-tensions``)."""
    from ..rl import EnvSpec

    speed_bands = _bands(args.held_out_speeds, args.speed_range, "--held-out-speeds", "km/h", "--speed-range")
    tension_bands = _bands(
        args.held_out_tensions, args.contact_wire_tension_range, "--held-out-tensions", "N",
        "--contact-wire-tension-range",
    )  # fmt: skip
    speed_range = tuple(args.speed_range) if args.speed_range is not None else None
    tension_range = (
        None if args.contact_wire_tension_range is None else tuple(args.contact_wire_tension_range)
    )
    env_id = f"Catenary-{problem}-v0"
    try:
        spec = EnvSpec(
            env_id, None if speed_range else args.speed, speed_range, args.fidelity, speed_bands,
            tension_range, tension_bands,
        )  # fmt: skip
        spec.make().close()  # refuses bad speeds, tensions and bands, naming them, before any training
    except ValueError as error:
        field = re.match(r"[a-z_]*", str(error)).group()  # the env's refusals start with the field
        option = ENV_OPTIONS.get(field, "/".join(ENV_OPTIONS.values()))
        raise UsageError(f"{option}: {error}") from None
    return spec


def _bands(
    values: list[float], value_range: Any, option: str, unit: str, range_option: str
) -> tuple[tuple[float, float], ...]:
    """The held-out bands ``((a, b), ...)`` of an option's pairs of values; a UsageError for an odd count or
    bands without their range."""
    if values and (value_range is None or len(values) % 2):
        raise UsageError(
            f"{option} {' '.join(f'{v:g}' for v in values)}: pairs of {unit} A B, with {range_option}"
        )
    return tuple((values[i], values[i + 1]) for i in range(0, len(values), 2))


def rl_command(args: argparse.Namespace, policy: str | os.PathLike[str]) -> str:
    """The ``catenary optimize`` command that reproduces (resumes) an RL run and saves its policy again."""
    words = [
        "catenary", "optimize", args.problem, "--optimizer", args.optimizer, "--budget", str(args.budget),
        "--seed", str(args.seed), "--fidelity", args.fidelity, "--workers", str(args.workers or 1),
    ]  # fmt: skip
    if args.speed_range is not None:
        words += ["--speed-range", *(f"{v:g}" for v in args.speed_range)]
        if args.held_out_speeds:
            words += ["--held-out-speeds", *(f"{v:g}" for v in args.held_out_speeds)]
    else:
        words += ["--speed", f"{args.speed:g}"]
    if args.contact_wire_tension_range is not None:
        words += ["--contact-wire-tension-range", *(f"{v:g}" for v in args.contact_wire_tension_range)]
        if args.held_out_tensions:
            words += ["--held-out-tensions", *(f"{v:g}" for v in args.held_out_tensions)]
    words += ["--store", str(args.store), "--resume-or-start", "--save-policy", str(policy)]
    return shlex.join(words)


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
