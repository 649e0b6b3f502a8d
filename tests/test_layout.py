"""The package's structure: layer folders that import only downwards, no import circles, rooms that fit in one
reading, research outside the wheel (docs/architecture.md draws the layers)."""

from __future__ import annotations

import ast
from pathlib import Path

import frenbrdf

PACKAGE = Path(frenbrdf.__file__).resolve().parent
MAX_LINES = 500

#: The package's layers, bottom first, by the top-level module or folder each holds. A module may import
#: only from its own layer or the ones below it; "" is the package's face, ``frenbrdf/__init__.py``.
LAYERS = [
    {"exceptions", "configs", "presets"},  # foundations: the standard library, numpy, torch
    {"numerics"},  # thin wrappers over the Rust core
    {"io"},  # raw file formats, checkpoints, atomic writes
    {"models"},  # the networks, their losses, test-time refinement, the shipped model
    {"data"},  # material folders and splits, analytic families, material files, fitting
    {"render"},  # the metric renderer, lights, figures, image scores, mitsuba/
    {"training"},
    {"evaluation"},  # evaluating runs, tables, statistics, spectra, selection (variants)
    {"material"},  # a user's material: measurement files in, the reconstruct folder out
    {"cli", "demo", ""},  # commands and the public face
]


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(path): path for path in PACKAGE.rglob("*.py")}


def _imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The package's modules that ``name`` imports, at the top or inside functions."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([node.module] if node.module else []))
            # ``from pkg import name`` imports the submodule pkg.name when there is one; ``_native`` is the Rust core.
            targets = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules or alias.name == "_native" else base
                       for alias in node.names]
        else:
            continue
        found.update(target for target in targets if target in modules and target != name)
    return found


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import circle of the graph, or None (depth-first search with colours)."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for target in sorted(graph[node]):
            if state.get(target) == 1:
                return stack[stack.index(target):] + [target]
            if target not in state and (found := visit(target)):
                return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_the_cycle_finder_finds_a_circle():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) is None


def test_no_module_imports_one_that_imports_it_back():
    modules = _modules()
    graph = {name: _imports(name, path, modules) for name, path in modules.items()}
    # A package's __init__ only hands its modules' names on: the edges from it are not design.
    for name, path in modules.items():
        if path.name == "__init__.py":
            graph[name] = set()
    assert _cycle(graph) is None, " -> ".join(_cycle(graph))


def _layer(module: str) -> int:
    top = module.split(".")[1] if "." in module else ""
    (index,) = [i for i, members in enumerate(LAYERS) if top in members]
    return index


def test_every_top_level_module_and_folder_has_a_layer():
    tops = {path.relative_to(PACKAGE).parts[0].removesuffix(".py") for path in PACKAGE.rglob("*.py")}
    tops.discard("__init__")
    placed = set().union(*LAYERS)
    assert tops <= placed, f"top-level modules or folders in no layer of LAYERS: {sorted(tops - placed)}"


def test_no_import_runs_back_up_a_layer():
    modules = _modules()
    upward = [f"{name} -> {target}" for name, path in modules.items() for target in _imports(name, path, modules)
              if _layer(target) > _layer(name)]
    assert not upward, "imports from a lower layer to a higher one:\n" + "\n".join(sorted(upward))


def test_the_layer_check_sees_an_upward_import():
    assert _layer("frenbrdf.io.merl") < _layer("frenbrdf.models.nbrdf") < _layer("frenbrdf.cli")
    assert _layer("frenbrdf.render.mitsuba.bsdf") == _layer("frenbrdf.render.scoring")


def test_the_import_graph_sees_known_edges():
    modules = _modules()
    assert "frenbrdf.io.checkpoints" in _imports("frenbrdf.models.autoencoder", modules["frenbrdf.models.autoencoder"],
                                              modules)
    assert "frenbrdf.training.run" in _imports("frenbrdf.training.loop", modules["frenbrdf.training.loop"], modules)


def test_every_module_fits_in_one_reading():
    long = {str(path.relative_to(PACKAGE)): n for path in PACKAGE.rglob("*.py")
            if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_chart_sweeps_live_beside_the_benchmarks_not_in_the_package():
    assert not (PACKAGE / "sweep.py").exists()
    for path in PACKAGE.rglob("*.py"):
        assert "def chart_main" not in path.read_text(), path
