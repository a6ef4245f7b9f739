"""``catenary propose POLICY --speed KMH``: the designs of a saved design policy (PPO or SAC), and their σ.

    catenary propose POLICY --speed KMH [KMH ...] [--contact-wire-tension N] [--no-evaluate]
                     [--fidelity study|test] [--json]

A policy file is a zip archive written by ``catenary optimize PROBLEM --optimizer ppo`` (or ``sac``): the
stable-baselines3 model (``data``, ``policy.pth``, ...) and the project's record, ``catenary_env_policy.json``
(docs/problems.md, 'Policy files'). Loading the model unpickles parts of it, as stable-baselines3 does: a
policy file from someone else can run code on this machine. Load only policy files you made or trust. A file
that is not a policy file (not a zip, no record, other members) is refused before stable-baselines3 reads it.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from catenary_env.cli.progress import ProgressDisplay
from catenary_env.errors import UsageError

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``propose`` to the sub-commands of the ``catenary`` command."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "propose",
        help="the design a saved design policy proposes at a speed, and its sigma",
        description="Load a design policy saved by 'catenary optimize PROBLEM --optimizer ppo' (or sac) and "
        "print the design it proposes at each speed; unless --no-evaluate, simulate each design at its "
        "speed, with the problem's reference design (the level contact wire) for comparison. Security: "
        "loading a policy unpickles parts of it, as stable-baselines3 does, so a policy file from someone "
        "else can run code on this machine; load only policy files you made or trust. A file that is not a "
        "policy file (not a zip archive, no catenary_env_policy.json record, other members than a saved PPO "
        "or SAC model's) is refused before stable-baselines3 reads it.",
    )
    parser.add_argument(
        "policy",
        metavar="POLICY",
        help="the policy file: a zip saved by catenary optimize --optimizer ppo or sac (only one you trust)",
    )
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
        "--contact-wire-tension",
        type=float,
        default=None,
        metavar="N",
        help="the contact wire's tension, N, for a policy trained over a range of tensions (required there, "
        "refused otherwise)",
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


def run(args: argparse.Namespace) -> int:
    """Execute ``propose``; return the exit status (0; a bad policy file or speed is refused)."""
    report = _proposals(args)
    print(json.dumps(report) if args.json else _proposal_table(report))
    return 0


def _proposals(args: argparse.Namespace) -> dict[str, Any]:
    """The policy's record and its design at each speed (simulated unless --no-evaluate)."""
    import dataclasses

    from catenary_env.model.design import check_speed

    from ..problem_registry import resolve_problem
    from ..rl import design_for_speed, load_policy

    policy, record = load_policy(args.policy)
    problem = resolve_problem(record.problem)
    _warn_if_stale(args.policy, record, problem)
    tension = _tension(args, record)
    if tension is not None:
        problem = problem.with_contact_wire_tension(tension)  # a tension outside the allowed range: refused
    catenary = _catenary_definition(record.problem, tension)
    for speed in args.speed:
        if catenary is not None:
            check_speed(catenary, speed / 3.6)
        if not _trained_for(record, speed, tension):
            print(
                f"catenary propose: warning: {speed:g} km/h{_at_tension(tension)} is outside the policy's "
                f"training {'speeds' if tension is None else 'conditions'} ({record.speeds}): its design "
                "there is an extrapolation or an interpolation",
                file=sys.stderr,
            )
    fidelity = args.fidelity or record.env_spec.fidelity
    proposals = []
    progress = ProgressDisplay("propose", len(args.speed), "speeds", quiet=args.json or args.no_evaluate)
    for speed in args.speed:
        x = design_for_speed(policy, problem, speed, tension)
        entry: dict[str, Any] = {
            "speed_kmh": speed,
            "contact_wire_tension": tension,
            "design": dict(zip(problem.variable_names, x.tolist(), strict=True)),
        }
        if not args.no_evaluate:
            outcome = problem.simulate(tuple(float(v) for v in x), float(speed), fidelity)
            entry.update(feasible=outcome.feasible, sigma=outcome.sigma, reason=outcome.reason)
            entry["reference_sigma"] = _reference_sigma(record.problem, speed, fidelity, tension)
        proposals.append(entry)
        progress.update(len(proposals))
    progress.finish()
    policy_record = dataclasses.asdict(record)
    return {
        "policy": str(args.policy),
        "record": policy_record,
        "speeds": record.speeds,
        "fidelity": None if args.no_evaluate else fidelity,
        "proposals": proposals,
        "units": {
            "speed_kmh": "km/h",
            "contact_wire_tension": "N",
            "design": "m",
            "sigma, reference_sigma": "N",
        },
    }


def _tension(args: argparse.Namespace, record: Any) -> float | None:
    """The contact-wire tension asked for, N: required by a policy trained over a tension range, refused by
    another (a UsageError naming the option)."""
    tension = getattr(args, "contact_wire_tension", None)
    conditioned = record.env_spec.contact_wire_tension_range is not None
    if conditioned and tension is None:
        raise UsageError(f"--contact-wire-tension: required, N: the policy was trained on {record.speeds}")
    if not conditioned and tension is not None:
        raise UsageError(
            f"--contact-wire-tension {tension:g}: the policy was trained on its preset's tension only "
            f"({record.speeds}); leave it out"
        )
    return tension


def _at_tension(tension: float | None) -> str:
    return "" if tension is None else f" with the contact wire at {tension / 1000:g} kN"


def _catenary_definition(name: str, tension: float | None = None) -> Any:
    """The catenary of a catenary design problem (for its speed limit), or None for another problem."""
    from catenary_env.problems import PROBLEMS

    return PROBLEMS[name].with_contact_wire_tension(tension).catenary_definition if name in PROBLEMS else None


def _reference_sigma(name: str, speed: float, fidelity: str, tension: float | None = None) -> float | None:
    """σ of a catenary problem's reference design at the speed (and tension), N (None for another problem)."""
    from catenary_env.problems import PROBLEMS

    if name not in PROBLEMS:
        return None
    problem = PROBLEMS[name].with_contact_wire_tension(tension)
    statistics = problem.reference_evaluation(speed, fidelity).statistics
    return None if statistics is None else float(statistics.std)


def _trained_for(record: Any, speed: float, tension: float | None = None) -> bool:
    spec = record.env_spec
    if spec.speed_range is not None:
        held_out = any(a <= speed <= b for a, b in spec.excluded_speeds)
        trained = spec.speed_range[0] <= speed <= spec.speed_range[1] and not held_out
    else:
        trained = spec.speed_kmh is None or abs(speed - spec.speed_kmh) < 1e-9
    if tension is None or spec.contact_wire_tension_range is None:
        return trained
    lo, hi = spec.contact_wire_tension_range
    held_out = any(a <= tension <= b for a, b in spec.excluded_tensions)
    return trained and lo <= tension <= hi and not held_out


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
    lines = [
        f"{report['policy']}: {record['learner']} policy for {record['problem']}, trained on "
        f"{report['speeds']} ({spec['fidelity']} fidelity, budget {record['budget']}, seed {record['seed']}, "
        f"run {record['run_id']})"
    ]
    if record["command"]:
        lines.append(f"reproduce: {record['command']}")
    for entry in report["proposals"]:
        lines.append(f"at {entry['speed_kmh']:g} km/h{_at_tension(entry['contact_wire_tension'])}:")
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
