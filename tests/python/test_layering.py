"""The import layering of python/indoorloc: no import cycle, and no module imports a higher layer.

Every module under python/indoorloc is parsed with ``ast`` (nothing is imported, so this needs no
compiled ``_core``). Its imports are all ``import`` / ``from ... import`` statements anywhere in
the file (module level, inside functions, under ``if`` or ``try``) and
``importlib.import_module("<literal>")`` calls. Importing ``indoorloc.a.b`` also runs the package
``indoorloc/a/__init__.py``, so that package counts as imported too (except ``indoorloc`` itself
and the importer's own packages, which are already being imported).

The layers, lowest first, are the table ``LAYERS`` below and docs/architecture.md ("Layers"). A
module belongs to the layer whose pattern names it exactly, else to the one layer with a wildcard
pattern that matches it (``*``: one name, ``**``: one or more dotted names). A new subsystem
``foo`` slots in by name: ``indoorloc/foo.py`` is a facade, ``experiments/foo_*.py`` an
experiment, ``cli/foo.py`` an entry point. A module that matches no pattern fails
``test_every_module_has_one_layer``: add a pattern rather than an exception.

Across the layers, the subsystems (``SUBSYSTEMS``: the package ``indoorloc/foo/`` or facade
``indoorloc/foo.py`` of each C++ subsystem) import only their declared neighbours
(``SUBSYSTEM_NEIGHBOURS``: fusion may use wifi, pdr and mapmatch; every subsystem may use core).
"""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Dict, Iterable, List, Mapping, NamedTuple, Optional, Set, Tuple

import pytest

PACKAGE = "indoorloc"
PACKAGE_DIR = Path(__file__).resolve().parents[2] / "python" / PACKAGE

#: (layer, what lives there, module-name patterns), lowest layer first. A module may import
#: modules of its own layer and of the layers below it, never of a layer above.
LAYERS: Tuple[Tuple[str, str, Tuple[str, ...]], ...] = (
    ("leaves", "import nothing from indoorloc: demo registry and data folders, progress bars, argument checks, "
               "packaged data files",
     ("indoorloc.registry", "indoorloc.progress", "indoorloc.validate", "indoorloc.data", "indoorloc.data.**")),
    ("_core", "the compiled module (pybind11) and its stubs",
     ("indoorloc._core", "indoorloc._core.**")),
    ("io, simulate", "file formats and simulated data: plain arrays and dataclasses, may build "
                     "_core types",
     ("indoorloc.io", "indoorloc.io.**", "indoorloc.simulate", "indoorloc.simulate.**")),
    ("facades", "one per subsystem (core, analog, mapmatch, network, pdr, wifi, fusion, ...) and "
                "metrics: every other top-level module",
     ("indoorloc.*", "indoorloc.core.**", "indoorloc.analog.**", "indoorloc.mapmatch.**", "indoorloc.network.**",
      "indoorloc.pdr.**", "indoorloc.wifi.**", "indoorloc.fusion.**")),
    ("package", "indoorloc/__init__.py: re-exports the facades",
     ("indoorloc",)),
    ("plots", "matplotlib figures",
     ("indoorloc.plots",)),
    ("experiments", "paper reproductions and the demos (registered in indoorloc.registry)",
     ("indoorloc.experiments", "indoorloc.experiments.**")),
    ("entry points", "the demo runner and the command line",
     ("indoorloc.demo", "indoorloc.__main__", "indoorloc.cli", "indoorloc.cli.**")),
)


#: The subsystems of the package, one per C++ subsystem (cpp/include/indoorloc/<s>/).
SUBSYSTEMS: Tuple[str, ...] = ("core", "analog", "mapmatch", "network", "pdr", "wifi", "fusion")
#: Which other subsystems a subsystem may import (core: every subsystem may).
SUBSYSTEM_NEIGHBOURS: Dict[str, Set[str]] = {"fusion": {"wifi", "pdr", "mapmatch"}}
#: Top-level modules that belong to a subsystem: the deprecated aliases of moved modules
#: (docs/api_changes.md lists the moves).
SUBSYSTEM_MODULES: Dict[str, str] = {
    "indoorloc.pdr_handheld": "pdr",
    "indoorloc.wifi_matcher": "wifi",
    "indoorloc.wifi_crowdsource": "fusion",
    "indoorloc.wifi_fixes": "fusion",
}


class Import(NamedTuple):
    target: str  # module name imported (resolved to a known module where possible)
    line: int
    implicit: bool  # a package run because a module inside it was imported


# ---------------------------------------------------------------------------------------------
# The checker (pure functions of {module name: source}, so that it is itself tested below)


def _pattern_regex(pattern: str) -> "re.Pattern[str]":
    parts = []
    for part in pattern.split("."):
        if part == "**":
            parts.append(r"[^.]+(?:\.[^.]+)*")
        elif part == "*":
            parts.append(r"[^.]+")
        else:
            parts.append(re.escape(part))
    return re.compile(r"\.".join(parts) + r"\Z")


def layer_of(module: str, layers=LAYERS) -> Optional[int]:
    """Index in ``layers`` of the module's layer; None when no pattern names it.

    Raises ValueError when several wildcard patterns of different layers match and no exact one.
    """
    for index, (_, _, patterns) in enumerate(layers):
        if module in patterns:
            return index
    matches = {index for index, (_, _, patterns) in enumerate(layers)
               for p in patterns if ("*" in p and _pattern_regex(p).match(module))}
    if len(matches) > 1:
        names = [layers[i][0] for i in sorted(matches)]
        raise ValueError(f"{module} matches the patterns of several layers: {names}")
    return matches.pop() if matches else None


def package_sources(package_dir: Path = PACKAGE_DIR) -> Dict[str, str]:
    """{module name: source} of every .py file of the package."""
    sources = {}
    for path in sorted(package_dir.rglob("*.py")):
        parts = list(path.relative_to(package_dir.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        sources[".".join(parts)] = path.read_text(encoding="utf-8")
    return sources


def compiled_modules(package_dir: Path = PACKAGE_DIR) -> Set[str]:
    """Names of the compiled modules, from the stubs ``_core/*.pyi``."""
    names = {f"{PACKAGE}._core"}
    for stub in (package_dir / "_core").glob("*.pyi"):
        if stub.stem != "__init__":
            names.add(f"{PACKAGE}._core.{stub.stem}")
    return names


def _is_ours(name: str) -> bool:
    return name == PACKAGE or name.startswith(PACKAGE + ".")


def _resolve_from(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    parts = module.split(".")
    base = parts if is_package else parts[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(module: str, source: str, known: Set[str], packages: Set[str]) -> List[Import]:
    """Every import of an indoorloc module in ``source`` (static, at any depth of the file)."""
    found: List[Tuple[str, int]] = []
    for node in ast.walk(ast.parse(source, filename=module)):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = _resolve_from(module, module in packages, node)
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                found.append((sub if sub in known else base, node.lineno))
        elif (isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant)
              and isinstance(node.args[0].value, str)
              and ((isinstance(node.func, ast.Attribute) and node.func.attr == "import_module")
                   or (isinstance(node.func, ast.Name) and node.func.id == "import_module"))):
            found.append((node.args[0].value, node.lineno))
    result: Dict[Import, None] = {}  # ordered set: `from m import a, b` is one import of m
    own_packages = {".".join(module.split(".")[:i]) for i in range(1, module.count(".") + 2)}
    for target, line in found:
        if not _is_ours(target):
            continue
        result[Import(target, line, False)] = None
        parts = target.split(".")
        for i in range(2, len(parts)):
            parent = ".".join(parts[:i])
            if parent in packages and parent not in own_packages:
                result[Import(parent, line, True)] = None
    return list(result)


def import_graph(sources: Mapping[str, str], compiled: Iterable[str] = ()) -> Dict[str, List[Import]]:
    """{module: its imports of indoorloc modules} for the modules of ``sources``."""
    known = set(sources) | set(compiled)
    packages = {m.rsplit(".", 1)[0] for m in known if "." in m}
    return {m: imports_of(m, src, known, packages) for m, src in sources.items()}


def find_cycles(graph: Mapping[str, List[Import]]) -> List[List[str]]:
    """One cycle (``[a, b, ..., a]``) per strongly connected component that has one (Tarjan)."""
    succ = {m: sorted({i.target for i in imps if i.target in graph}) for m, imps in graph.items()}
    index: Dict[str, int] = {}
    low: Dict[str, int] = {}
    stack: List[str] = []
    on_stack: Set[str] = set()
    components: List[List[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in succ[v]:
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
            components.append(component)

    for v in sorted(succ):
        if v not in index:
            visit(v)

    cycles = []
    for component in components:
        members = set(component)
        start = min(component)
        if len(component) == 1 and start not in succ[start]:
            continue
        # Shortest path start -> ... -> start inside the component (breadth first).
        previous: Dict[str, str] = {}
        frontier = [start]
        while frontier and start not in previous:
            nxt = []
            for v in frontier:
                for w in succ[v]:
                    if w in members and w not in previous:
                        previous[w] = v
                        nxt.append(w)
            frontier = nxt
        path = [start]
        v = previous[start]
        while v != start:
            path.append(v)
            v = previous[v]
        path.append(start)
        cycles.append(path[::-1])
    return cycles


def layer_violations(graph: Mapping[str, List[Import]], layers=LAYERS) -> List[str]:
    """One line per import of a higher layer: where, what, and the two layers."""
    problems = []
    for module, imps in sorted(graph.items()):
        own = layer_of(module, layers)
        for imp in imps:
            other = layer_of(imp.target, layers)
            if own is None or other is None or other <= own:
                continue
            how = f" (runs package {imp.target})" if imp.implicit else ""
            problems.append(f"{module}:{imp.line} ({layers[own][0]}) imports {imp.target}{how} "
                            f"({layers[other][0]})")
    return problems


def subsystem_of(module: str, modules: Mapping[str, str] = SUBSYSTEM_MODULES) -> Optional[str]:
    """The subsystem a module belongs to (``indoorloc.<s>`` or inside it), else None."""
    if module in modules:
        return modules[module]
    parts = module.split(".")
    if len(parts) >= 2 and parts[0] == PACKAGE and parts[1] in SUBSYSTEMS:
        return parts[1]
    return None


def subsystem_violations(graph: Mapping[str, List[Import]], modules: Mapping[str, str] = SUBSYSTEM_MODULES,
                         neighbours: Mapping[str, Set[str]] = SUBSYSTEM_NEIGHBOURS) -> List[str]:
    """One line per import of another subsystem that is neither core nor a declared neighbour."""
    problems = []
    for module, imps in sorted(graph.items()):
        own = subsystem_of(module, modules)
        if own is None:
            continue
        for imp in imps:
            other = subsystem_of(imp.target, modules)
            if other is None or other in (own, "core") or other in neighbours.get(own, set()):
                continue
            problems.append(f"{module}:{imp.line} ({own}) imports {imp.target} ({other})")
    return problems


def _format_cycle(cycle: List[str], graph: Mapping[str, List[Import]]) -> str:
    steps = []
    for a, b in zip(cycle, cycle[1:]):
        line = min(i.line for i in graph[a] if i.target == b)
        steps.append(f"{a}:{line} -> {b}")
    return "; ".join(steps)


# ---------------------------------------------------------------------------------------------
# The package


@pytest.fixture(scope="module")
def graph() -> Dict[str, List[Import]]:
    assert PACKAGE_DIR.is_dir(), PACKAGE_DIR
    return import_graph(package_sources(), compiled_modules())


def test_every_module_has_one_layer(graph):
    unplaced = [m for m in graph if layer_of(m) is None]
    assert not unplaced, f"no layer for {unplaced}: add a pattern to LAYERS (docs/architecture.md)"


def test_every_import_names_an_existing_module(graph):
    known = set(graph) | compiled_modules()
    unknown = [f"{m}:{i.line} imports {i.target}" for m, imps in graph.items() for i in imps
               if i.target not in known]
    assert not unknown, "imports of modules that do not exist: " + "; ".join(unknown)


def test_no_import_cycle(graph):
    cycles = find_cycles(graph)
    assert not cycles, "import cycles: " + " | ".join(_format_cycle(c, graph) for c in cycles)


def test_no_module_imports_a_higher_layer(graph):
    problems = layer_violations(graph)
    assert not problems, "imports of a higher layer:\n" + "\n".join(problems)


def test_subsystems_import_only_declared_neighbours(graph):
    problems = subsystem_violations(graph)
    assert not problems, "imports between subsystems not declared in SUBSYSTEM_NEIGHBOURS:\n" + "\n".join(problems)


def test_every_subsystem_module_listed_exists(graph):
    assert set(SUBSYSTEM_MODULES) <= set(graph), f"stale: {set(SUBSYSTEM_MODULES) - set(graph)}"


def test_checker_finds_imports_between_subsystems():
    graph = _fake({
        "indoorloc.wifi": "from indoorloc import pdr\nfrom indoorloc import core",
        "indoorloc.pdr": "",
        "indoorloc.core": "",
        "indoorloc.fusion": "from indoorloc import wifi, pdr, mapmatch",
        "indoorloc.fusion.site": "from indoorloc.network import solve",
        "indoorloc.network": "def solve():\n    pass",
        "indoorloc.mapmatch": "",
    })
    assert subsystem_violations(graph) == [
        "indoorloc.fusion.site:1 (fusion) imports indoorloc.network (network)",
        "indoorloc.wifi:1 (wifi) imports indoorloc.pdr (pdr)",
    ]


def test_leaves_import_nothing_from_indoorloc(graph):
    leaves = [m for m in graph if layer_of(m) == 0]
    assert "indoorloc.registry" in leaves
    assert {m: [i.target for i in graph[m]] for m in leaves if graph[m]} == {}


def test_a_new_subsystem_slots_in_by_name():
    names = [layer[0] for layer in LAYERS]
    expect = {
        "indoorloc.fusion": "facades",
        "indoorloc.mapmatch": "facades",
        "indoorloc.metrics": "facades",
        "indoorloc.experiments.fusion_demo": "experiments",
        "indoorloc.cli.fusion": "entry points",
        "indoorloc.io.floor_plan": "io, simulate",
        "indoorloc.simulate.walk": "io, simulate",
        "indoorloc._core.fusion": "_core",
        "indoorloc.registry": "leaves",
        "indoorloc.plots": "plots",
        "indoorloc.demo": "entry points",
        "indoorloc": "package",
    }
    assert {m: names[layer_of(m)] for m in expect} == expect


def test_import_indoorloc_loads_no_edge_module():
    # Facades may use io only inside functions: `import indoorloc` stays computational
    # (CONVENTIONS rule 11: no file formats, plots, CLI or matplotlib).
    code = ("import sys, indoorloc; print(' '.join(sorted(m for m in sys.modules if m.split('.')[0] == "
            "'matplotlib' or m.startswith(('indoorloc.io', 'indoorloc.plots', 'indoorloc.cli', "
            "'indoorloc.demo', 'indoorloc.experiments', 'indoorloc.simulate')))))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            env={**os.environ, "CI": "true"}, check=True)
    assert result.stdout.split() == []


# ---------------------------------------------------------------------------------------------
# The checker on made-up packages: it must see function-level, relative and implicit imports.


def _fake(sources: Dict[str, str]) -> Dict[str, List[Import]]:
    return import_graph(sources, compiled=["indoorloc._core", "indoorloc._core.mapmatch"])


def test_checker_finds_a_cycle_through_a_function_level_import():
    graph = _fake({
        "indoorloc": "from indoorloc import mapmatch",
        "indoorloc.mapmatch": "from indoorloc._core.mapmatch import RoadNetwork\n"
                              "def f():\n    from indoorloc.io.road_network import warehouse",
        "indoorloc.io": "from indoorloc.io.road_network import warehouse",
        "indoorloc.io.road_network": "def g():\n    from indoorloc import mapmatch",
    })
    cycles = find_cycles(graph)
    assert cycles and set(cycles[0]) == {"indoorloc.mapmatch", "indoorloc.io", "indoorloc.io.road_network"}
    assert cycles[0][0] == cycles[0][-1]
    assert layer_violations(graph) == [
        "indoorloc.io.road_network:2 (io, simulate) imports indoorloc.mapmatch (facades)"]


def test_checker_finds_upward_relative_dynamic_and_implicit_imports():
    graph = _fake({
        "indoorloc.registry": "from . import demo",
        "indoorloc.progress": "import importlib\ndef f():\n    importlib.import_module('indoorloc.plots')",
        "indoorloc.plots": "",
        "indoorloc.demo": "",
        "indoorloc.cli": "",
        "indoorloc.experiments": "import indoorloc.cli",
        "indoorloc.io": "",
        "indoorloc.io.x": "from .. import registry\nfrom ..experiments import y",
        "indoorloc.experiments.y": "",
        "indoorloc.simulate": "from indoorloc.experiments.y import z",
    })
    assert find_cycles(graph) == []
    assert layer_violations(graph) == [
        "indoorloc.experiments:1 (experiments) imports indoorloc.cli (entry points)",
        "indoorloc.io.x:2 (io, simulate) imports indoorloc.experiments.y (experiments)",
        "indoorloc.io.x:2 (io, simulate) imports indoorloc.experiments (runs package "
        "indoorloc.experiments) (experiments)",
        "indoorloc.progress:3 (leaves) imports indoorloc.plots (plots)",
        "indoorloc.registry:1 (leaves) imports indoorloc.demo (entry points)",
        "indoorloc.simulate:1 (io, simulate) imports indoorloc.experiments.y (experiments)",
        "indoorloc.simulate:1 (io, simulate) imports indoorloc.experiments (runs package "
        "indoorloc.experiments) (experiments)",
    ]


def test_checker_rejects_an_ambiguous_layer_table():
    layers = (("a", "", ("indoorloc.*",)), ("b", "", ("indoorloc.**",)))
    with pytest.raises(ValueError, match="several layers"):
        layer_of("indoorloc.x", layers)
    assert layer_of("indoorloc.x.y", layers) == 1
