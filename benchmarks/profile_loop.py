"""Profile: where a passage's compiled time loop spends its time, line by line (docs/performance.md, 'Speed').

Runs passages of a preset's level design under Linux ``perf`` (sampling the processor's instruction pointer),
with the loop compiled afresh with numba's debug lines, and maps the samples that fall in the loop's machine
code onto the source lines they were compiled from. A helper that is inlined into the loop shows as its own
lines (``kernels.py:44`` is ``_dot``'s body, wherever it is called from); one that is called shows as the line
of its call. numba's debug lines name the loop's own file for every line, also for the shared helpers of other
modules that it inlines (the Newmark update of ``dynamics/newmark.py`` showed as lines of ``kernels.py``
under the element's responses): a line number that falls in a compiled function of more than one file is
printed with each file's text, ``or`` between them. It finds what timing the parts one at a time cannot:
work that no part of the arithmetic names (calls, reference counting, scalar fallbacks of vectorised
loops).

    python benchmarks/profile_loop.py                          # span-mode loop, benchmark catenary
    python benchmarks/profile_loop.py --model exact --passages 5
    python benchmarks/profile_loop.py --preset stitched --top 40
    python benchmarks/profile_loop.py --spans 40               # what grows with the section

Needs ``perf`` (allowed to sample this user's processes: ``kernel.perf_event_paranoid`` at 2 or less) and
binutils' ``addr2line``. It reads numba internals (the compiled object of the loop's library), so a numba
release may break it; the simulator does not depend on it. Prints the share of the loop's samples per source
line, the line's text, and the loop's share of all samples (most of the rest is the compilation).

The shares are a guide, not a measurement: the debug lines cost the compiler some of its freedom, and a
sample lands on the instruction after the one that stalled. Confirm what it points at by timing the loop with
and without.
"""

from __future__ import annotations

import argparse
import ast
import collections
import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

MODULES = {
    "span-modes": "catenary_env.dynamics.span_modes.kernels",
    "exact": "catenary_env.dynamics.exact.kernels",
}


def child(args: argparse.Namespace) -> None:
    """In the profiled process: compile the loop, write its object code and address, then run the passages."""
    import importlib

    from catenary_env.dynamics.linear_system import linearise
    from catenary_env.model.design import level_design
    from catenary_env.model.presets import load_catenary, load_pantograph
    from catenary_env.pipeline import Fidelity, prepare_dynamics, run_passage, solve_static

    catenary = load_catenary(args.preset)
    pantograph = load_pantograph(catenary.pantograph)
    fidelity = Fidelity(dynamics=args.model, n_spans=args.spans, analysis_spans=args.spans // 2)
    static = solve_static(catenary, level_design(catenary), fidelity)
    system = linearise(static)
    prepared = prepare_dynamics(system, fidelity)

    def passage() -> None:
        run_passage(
            static, pantograph, args.speed / 3.6, fidelity, args.uplift, system=system, prepared=prepared,
            statistics_only=True,
        )  # fmt: skip

    passage()  # compiles the loop (a fresh cache: with debug lines)
    kernels = importlib.import_module(MODULES[args.model])
    (result,) = kernels.run_steps.overloads.values()
    library = result.library
    out = Path(args.child)
    (out / "loop.o").write_bytes(library._get_compiled_object())
    (out / "address").write_text(str(library.get_pointer_to_function(result.fndesc.mangled_name)))
    for _ in range(args.passages):
        passage()


COMPILED_DECORATORS = {"compilable", "inlined", "njit", "register_jitable"}
"""Decorators that compile a function into the loop: the loop's own helpers and the shared ones."""


def _decorator_name(decorator: ast.expr) -> str:
    """``njit`` for ``@njit`` and ``@njit(...)``; "" for an attribute or anything else."""
    target = decorator.func if isinstance(decorator, ast.Call) else decorator
    return target.id if isinstance(target, ast.Name) else ""


def _compiled_lines(module: str) -> dict[Path, tuple[list[str], list[tuple[int, int]]]]:
    """Each file whose compiled functions the loop ``module`` may inline (the loop's own file and those of
    the modules it imports relatively): its lines, and the line ranges of its compiled functions' code
    (after the docstring)."""
    own = Path(importlib.util.find_spec(module).origin)
    package = module.rpartition(".")[0]
    files = [own]
    for node in ast.walk(ast.parse(own.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
            spec = importlib.util.find_spec(f"{base}.{node.module}" if node.module else base)
            if spec is not None and spec.origin and spec.origin.endswith(".py"):
                files.append(Path(spec.origin))
    compiled: dict[Path, tuple[list[str], list[tuple[int, int]]]] = {}
    for path in files:
        source = path.read_text()
        ranges = []
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.FunctionDef) and any(
                _decorator_name(d) in COMPILED_DECORATORS for d in node.decorator_list
            ):
                body = node.body[1:] if ast.get_docstring(node) is not None else node.body
                ranges.append((body[0].lineno, node.end_lineno or body[0].lineno))
        if ranges:
            compiled[path] = (source.splitlines(), ranges)
    return compiled


def _texts(number: int, compiled: dict[Path, tuple[list[str], list[tuple[int, int]]]]) -> str:
    """The source of line ``number`` in every file where a compiled function holds it."""
    texts = [
        f"{path.name}: {lines[number - 1].strip()[:70]}"
        for path, (lines, ranges) in compiled.items()
        if any(first <= number <= last for first, last in ranges)
    ]
    return "  or  ".join(texts) if texts else "(no compiled function holds this line)"


def _symbol_size(obj: Path) -> tuple[int, int]:
    """Offset and size of the loop's function in its object code (``nm``)."""
    listing = subprocess.run(
        ["nm", "-S", "--defined-only", str(obj)], capture_output=True, text=True, check=True
    )
    for line in listing.stdout.splitlines():
        fields = line.split()  # offset, size, kind, name; the loop's wrappers start "_ZN7cpython" and "cfunc"
        name = fields[3] if len(fields) == 4 and fields[2] == "T" else ""
        if name.startswith("_ZN12catenary_env") and "7kernels9run_steps" in name:
            return int(fields[0], 16), int(fields[1], 16)
    raise RuntimeError(f"no run_steps in {obj}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--model", choices=sorted(MODULES), default="span-modes", help="the loop (default span-modes)"
    )
    parser.add_argument("--preset", default="benchmark", help="catenary preset (default: benchmark)")
    parser.add_argument("--speed", type=float, default=300.0, help="km/h (default 300)")
    parser.add_argument(
        "--uplift", type=float, default=170.0, help="pantograph uplift force, N (default 170)"
    )
    parser.add_argument("--spans", type=int, default=20, help="section length, spans (default 20)")
    parser.add_argument("--passages", type=int, default=20, help="passages sampled (default 20)")
    parser.add_argument("--top", type=int, default=30, help="source lines printed (default 30)")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args)
        return 0
    if args.passages < 1 or args.top < 1:
        parser.error("--passages and --top: must be at least 1")
    if args.spans < 4:
        parser.error("--spans: must be at least 4")
    missing = [tool for tool in ("perf", "nm", "addr2line") if shutil.which(tool) is None]
    if missing:
        print(f"profile_loop: needs {', '.join(missing)} (Linux perf and binutils)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        env = dict(
            os.environ,
            NUMBA_DEBUGINFO="1",  # the loop's source lines, in a cache of its own
            NUMBA_CACHE_DIR=str(out / "numba"),
            OPENBLAS_NUM_THREADS="1",
            PYTHONWARNINGS="ignore",  # numba's warnings on the lines of its own helpers
        )
        command = [sys.executable, __file__, "--child", folder, *sys.argv[1:]]
        record = ["perf", "record", "-q", "-F", "4000", "-o", str(out / "perf.data"), "--", *command]
        if subprocess.run(record, env=env).returncode != 0:
            print("profile_loop: perf record failed (is perf_event_paranoid at 2 or less?)", file=sys.stderr)
            return 2
        script = subprocess.run(
            ["perf", "script", "-i", str(out / "perf.data"), "-F", "ip"],
            capture_output=True,
            text=True,
            check=True,
        )
        ips = [int(word, 16) for word in script.stdout.split()]
        base = int((out / "address").read_text())
        start, size = _symbol_size(out / "loop.o")
        offsets = collections.Counter(ip - base + start for ip in ips if base <= ip < base + size)
        if not offsets:
            print("profile_loop: no sample fell in the loop", file=sys.stderr)
            return 1
        where = subprocess.run(
            ["addr2line", "-e", str(out / "loop.o"), *(hex(o) for o in offsets)],
            capture_output=True, text=True, check=True,
        ).stdout.split()  # fmt: skip
    lines: collections.Counter[str] = collections.Counter()
    for offset, place in zip(offsets, where, strict=True):
        lines[place] += offsets[offset]
    total = sum(offsets.values())
    print(f"{args.model} loop, {args.preset}, {args.spans} spans, {args.passages} passages: {total} samples"
          f" in the loop, {100 * total / len(ips):.0f} % of the process's")  # fmt: skip
    compiled = _compiled_lines(MODULES[args.model])
    for place, count in lines.most_common(args.top):
        number = place.rpartition(":")[2]
        text = _texts(int(number), compiled) if number.isdigit() else "(no source line)"
        print(f"{100 * count / total:5.1f} %  line {number:<5} {text}")
    return 0


if __name__ == "__main__":
    try:
        raise SystemExit(main())
    except KeyboardInterrupt:
        print("profile_loop: interrupted", file=sys.stderr)
        raise SystemExit(130) from None
