"""The import graph: every import points down the pipeline, and no two modules import each other.

The modules are read with :mod:`ast`, not imported, so the test needs no optional dependency. Every
``import`` counts, also those inside functions and under ``TYPE_CHECKING``: an import deferred to run
time is still a dependency. The layers, lowest first::

    shared machinery < model (and errors) < fem < statics < dynamics < analysis < pipeline < problems < envs
          < catenary_env < cli < optimizers < experiments

A module may import modules of its own layer or of a lower one; the package ``catenary_env`` itself
(its ``__init__``, which re-exports the pipeline) sits above the environments and below the command line.
The shared machinery (the registry class, the cache folder) imports nothing of the project, so that every
layer may use it; the fingerprint and the uplift cache run the pipeline and serve every layer above it.
The project's errors (``catenary_env.errors``) sit at the bottom, with the model, so that every layer raises
them. The command line (``catenary_env.cli``) is the simulator's edge: nothing in the simulator imports it,
and it imports neither the optimisers nor the studies (their commands plug in through entry points).
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("catenary_env", "optimizers", "experiments")

LAYERS = (
    ("catenary_env.registry", "catenary_env.cache_folder"),
    ("catenary_env.model", "catenary_env.errors"),
    ("catenary_env.fem",),
    ("catenary_env.statics",),
    ("catenary_env.dynamics",),
    ("catenary_env.analysis",),
    (
        "catenary_env.pipeline",
        "catenary_env.train",
        "catenary_env.validation",
        "catenary_env.blas_threads",
        "catenary_env.fingerprint",
        "catenary_env.calibration_cache",
    ),
    ("catenary_env.problems",),
    ("catenary_env.envs",),
    ("catenary_env",),  # the package's __init__: the re-exported API
    ("catenary_env.cli", "catenary_env.plots"),
    ("optimizers",),
    ("experiments",),
)
"""Module-name prefixes of each layer, lowest first; the longest matching prefix decides."""


def module_files() -> dict[str, Path]:
    """Every module of the three packages by dotted name (a package by its ``__init__``)."""
    modules = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            modules[".".join(parts)] = path
    return modules


MODULES = module_files()


def layer(module: str) -> int:
    """Index in :data:`LAYERS` of a module, by its longest matching prefix."""
    best, best_length = -1, -1
    for index, prefixes in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_length:
                best, best_length = index, len(prefix)
    if best < 0:
        raise AssertionError(f"{module} belongs to no layer: add it to LAYERS")
    return best


def imported_modules(module: str, path: Path) -> Iterator[tuple[str, int]]:
    """The project modules that ``module`` imports, with the line of each import."""
    is_package = path.name == "__init__.py"
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            targets = [_known_module(alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                origin = ".".join(
                    parts[: len(parts) - (node.level - 1)] + ([node.module] if node.module else [])
                )
            else:
                origin = node.module or ""
            # ``from package import module`` imports that module, ``from module import name`` the module.
            targets = [
                f"{origin}.{alias.name}" if f"{origin}.{alias.name}" in MODULES else _known_module(origin)
                for alias in node.names
            ]
        else:
            continue
        for target in targets:
            if target is not None and target != module:
                yield target, node.lineno


def _known_module(name: str) -> str | None:
    """The longest prefix of ``name`` that is a project module, or None for a third-party import."""
    parts = name.split(".")
    for end in range(len(parts), 0, -1):
        candidate = ".".join(parts[:end])
        if candidate in MODULES:
            return candidate
    return None


def import_graph() -> dict[str, dict[str, int]]:
    """``graph[a][b]``: the line at which module ``a`` imports module ``b``."""
    graph: dict[str, dict[str, int]] = {}
    for module, path in MODULES.items():
        edges: dict[str, int] = {}
        for target, line in imported_modules(module, path):
            edges.setdefault(target, line)
        graph[module] = edges
    return graph


def strongly_connected(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one module (import cycles)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for successor in graph.get(node, {}):
            if successor not in index:
                visit(successor)
                low[node] = min(low[node], low[successor])
            elif successor in on_stack:
                low[node] = min(low[node], index[successor])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return cycles


def test_every_module_has_a_layer() -> None:
    for module in MODULES:
        layer(module)


def test_no_module_imports_a_higher_layer() -> None:
    upward = [
        f"{MODULES[module].relative_to(ROOT)}:{line}: {module} ({LAYERS[layer(module)][0]}) imports "
        f"{target} ({LAYERS[layer(target)][0]})"
        for module, edges in import_graph().items()
        for target, line in edges.items()
        if layer(target) > layer(module)
    ]
    assert not upward, "imports that point up the pipeline:\n" + "\n".join(upward)


def test_the_command_line_is_the_simulators_edge() -> None:
    inward = [
        f"{MODULES[module].relative_to(ROOT)}:{line}: {module} imports {target}"
        for module, edges in import_graph().items()
        for target, line in edges.items()
        if module.startswith("catenary_env.")
        and not _in(module, "catenary_env.cli")
        and _in(target, "catenary_env.cli")
    ]
    assert not inward, "the simulator imports its command line:\n" + "\n".join(inward)
    outward = [
        f"{module} imports {target}"
        for module, edges in import_graph().items()
        if _in(module, "catenary_env.cli")
        for target in edges
        if target.partition(".")[0] in ("optimizers", "experiments")
    ]
    assert not outward, "the command line imports the packages that plug into it:\n" + "\n".join(outward)


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def test_no_import_cycle() -> None:
    cycles = strongly_connected(import_graph())
    assert not cycles, "modules that import each other: " + "; ".join(" <-> ".join(c) for c in cycles)


def test_the_two_dynamic_models_do_not_import_each_other() -> None:
    # Each model's preparation, loops and kernels stand on the shared dynamics modules only.
    models = ("catenary_env.dynamics.exact", "catenary_env.dynamics.span_modes")
    crossing = [
        f"{MODULES[module].relative_to(ROOT)}:{line}: {module} imports {target}"
        for module, edges in import_graph().items()
        for target, line in edges.items()
        for own, other in (models, models[::-1])
        if module.startswith(own) and (target == other or target.startswith(other + "."))
    ]
    assert not crossing, "one dynamic model imports the other:\n" + "\n".join(crossing)


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("from .a import b\n", {"pkg.a"}),
        ("from . import a\n", {"pkg.a"}),
        ("from ..up import thing\n", {"up"}),
        ("import pkg.a\n", {"pkg.a"}),
        ("import numpy\n", set()),
    ],
)
def test_the_parser_resolves_imports(
    source: str, expected: set[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "pkg" / "mod.py"
    path.parent.mkdir()
    path.write_text(source)
    monkeypatch.setitem(MODULES, "pkg.a", path)
    monkeypatch.setitem(MODULES, "pkg", path)
    monkeypatch.setitem(MODULES, "up", path)
    found = {target for target, _ in imported_modules("pkg.mod", path)}
    assert found == expected


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert strongly_connected({"a": {"b": 1}, "b": {"a": 2}, "c": {"a": 3}}) == [["a", "b"]]
