"""The shape of the house, read from the code with `ast`: who may import whom, no
import circles, no file over 500 lines and no function over 100 lines.

Every import counts, also the lazy ones inside functions and those only for type
annotations: a circle of annotations is still a circle of meaning.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("planner", "app", "hardware_sim", "tactile")
GENERATED = ROOT / "hardware_sim" / "api_client"

#: Layers from the ground up: a module may import its own layer's package and lower
#: layers only. `planner.recognition` and `planner.image` stand side by side and do
#: not import each other.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("planner.errors", "planner.geometry", "planner.memo", "planner.compiled", "planner.arrays"),
    ("planner.types",),
    ("planner.models",),
    ("planner.recognition", "planner.image"),
    ("planner.planning",),
    ("planner.drawing",),
    ("planner.codec", "planner.render"),
    ("planner",),
    ("app", "hardware_sim"),
    ("tactile",),
)
#: Third-party packages the pure library must never import.
NOT_IN_PLANNER = ("fastapi", "starlette", "httpx", "uvicorn", "pydantic", "app", "hardware_sim")


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _sources() -> Iterator[Path]:
    for package in PACKAGES:
        yield from sorted((ROOT / package).rglob("*.py"))


MODULES = {_module_name(p): p for p in _sources()}


def _imports(name: str, path: Path) -> set[str]:
    """Every module `name` imports (absolute names; relative imports resolved;
    ``from pkg import mod`` counted as importing ``pkg.mod`` when that is a module)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                module = ".".join([*base, *([node.module] if node.module else [])])
            else:
                module = node.module or ""
            submodules = {f"{module}.{a.name}" for a in node.names} & MODULES.keys()
            found.update(submodules)
            if len(submodules) < len(node.names):
                found.add(module)
    return found


GRAPH = {
    name: {m for m in _imports(name, path) if m in MODULES and m != name}
    for name, path in MODULES.items()
}
EXTERNAL = {name: _imports(name, path) for name, path in MODULES.items()}


def _layer(module: str) -> tuple[int, str]:
    """(layer index, the layer's package) of a module: the longest prefix listed."""
    best: tuple[int, int, str] | None = None
    for i, names in enumerate(LAYERS):
        for prefix in names:
            inside = module == prefix or module.startswith(prefix + ".")
            if inside and (best is None or len(prefix) > best[1]):
                best = (i, len(prefix), prefix)
    assert best is not None, f"{module} stands in no layer: add it to LAYERS"
    return best[0], best[2]


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_import_reader_sees_lazy_and_annotation_imports(tmp_path):
    source = tmp_path / "mod.py"
    source.write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from planner.types import Pose\n"
        "def f():\n    import planner.geometry\n    from . import sibling\n"
    )
    found = _imports("planner.planning.mod", source)
    assert {"planner.types", "planner.geometry", "planner.planning"} <= found


def test_the_cycle_finder_finds_a_circle_and_nothing_else():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_the_planner_imports_no_service_hardware_or_http():
    offenders = {
        (name, m)
        for name, found in EXTERNAL.items()
        if name.split(".")[0] == "planner"
        for m in found
        if m.split(".")[0] in NOT_IN_PLANNER
    }
    assert not offenders


@pytest.mark.parametrize(("lower", "other"), [("app", "hardware_sim"), ("hardware_sim", "app")])
def test_service_and_simulator_do_not_import_each_other(lower, other):
    offenders = {
        (name, m)
        for name, found in GRAPH.items()
        if name.split(".")[0] == lower
        for m in found
        if m.split(".")[0] in (other, "tactile")
    }
    assert not offenders


def test_no_import_runs_up_or_across_the_layers():
    offenders = []
    for name, found in GRAPH.items():
        here, package = _layer(name)
        for m in found:
            there, other = _layer(m)
            if there > here or (there == here and other != package):
                offenders.append(f"{name} -> {m}")
    assert not offenders


def test_no_import_circle_between_modules():
    assert _cycles(GRAPH) == []


def test_no_import_circle_between_packages():
    def package(module: str) -> str:
        return module if MODULES[module].name == "__init__.py" else module.rpartition(".")[0]

    packages: dict[str, set[str]] = {}
    for name, found in GRAPH.items():
        mine = package(name)
        packages.setdefault(mine, set()).update(
            p for p in map(package, found) if p != mine and not mine.startswith(p + ".")
        )
    assert _cycles(packages) == []


def _hand_written() -> list[Path]:
    return [p for p in MODULES.values() if GENERATED not in p.parents]


def test_no_file_over_500_lines():
    long = {
        str(p.relative_to(ROOT)): n
        for p in _hand_written()
        if (n := p.read_text(encoding="utf-8").count("\n")) > 500
    }
    assert not long


def test_no_function_over_100_lines():
    long = {}
    for path in _hand_written():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > 100:
                    long[f"{path.relative_to(ROOT)}:{node.name}"] = lines
    assert not long
