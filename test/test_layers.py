"""The package's architecture as a test: no import circles anywhere in ``roe_sep/`` and no upward import.

Layers, lowest first (a module may import its own layer and the ones below, never one above):

    errors, stamps  <-  core, checks, children, process_exit, jsonutil  <-  interfaces, validate, bag, ndm, graph
        <-  nodes  <-  run, report, plots, engine, campaign  <-  cli, docgen

``roe_sep.errors`` imports nothing of roe_sep (every layer may import it); the report imports no node, not even
through another module (it is built offline from a bag).

Every import counts, also the ones inside functions (a lazy import hides a circle, it does not remove it). Only
imports of ``roe_sep`` modules are followed; ``from pkg import name`` is an edge to the submodule ``pkg.name`` when
that exists, else to ``pkg`` itself. The core also never imports ROS (rclpy or any message package).
"""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "roe_sep"

LAYERS = {"errors": 0, "stamps": 0, "core": 1, "checks": 1, "children": 1, "process_exit": 1, "jsonutil": 1,
          "interfaces": 2, "validate": 2, "bag": 2, "ndm": 2, "graph": 2, "nodes": 3, "run": 4, "report": 4, "plots": 4,
          "engine": 4, "campaign": 4, "cli": 5, "docgen": 5}
ROS_MODULES = ("rclpy", "roe_sep_msgs", "rosgraph_msgs", "diagnostic_msgs", "builtin_interfaces", "geometry_msgs",
               "std_msgs", "rcl_interfaces", "ament_index_python")


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict:
    return {module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def imports(name: str, path: Path, known: set):
    """(target roe_sep module, line) of every import in a module, and the top-level names of other imports."""
    is_pkg = path.name == "__init__.py"
    base = name.split(".") if is_pkg else name.split(".")[:-1]
    edges, external = [], []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                (edges if alias.name.split(".")[0] == "roe_sep" else external).append((alias.name, node.lineno))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parent = base[: len(base) - (node.level - 1)]
                target = ".".join(parent + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "roe_sep":
                external.append((target, node.lineno))
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                edges.append((sub if sub in known else target, node.lineno))
    return [(t, line) for t, line in edges if t in known], external


def layer(name: str):
    parts = name.split(".")
    return LAYERS.get(parts[1]) if len(parts) > 1 else -1


@pytest.fixture(scope="module")
def graph():
    mods = modules()
    known = set(mods)
    out = {}
    for name, path in mods.items():
        out[name] = imports(name, path, known)
    return out


def test_every_module_has_a_layer(graph):
    assert [m for m in graph if layer(m) is None] == []


def test_no_upward_import(graph):
    upward = [f"{src} (layer {layer(src)}) imports {dst} (layer {layer(dst)}) at line {line}"
              for src, (edges, _) in graph.items() for dst, line in edges if layer(dst) > layer(src)]
    assert upward == []


def test_core_imports_no_ros(graph):
    bad = [f"{src} imports {ext} at line {line}" for src, (_, external) in graph.items() if layer(src) <= LAYERS["core"]
           for ext, line in external if ext.split(".")[0] in ROS_MODULES]
    assert bad == []


def test_errors_import_nothing_of_roe_sep(graph):
    assert graph["roe_sep.errors"][0] == []


def reachable(adjacency: dict, start: str) -> set:
    """Every module ``start`` imports, directly or through others."""
    seen, todo = set(), [start]
    while todo:
        for w in adjacency.get(todo.pop(), ()):
            if w not in seen:
                seen.add(w)
                todo.append(w)
    return seen


def test_report_imports_no_node(graph):
    adjacency = {src: {dst for dst, _ in edges} for src, (edges, _) in graph.items()}
    assert sorted(m for m in reachable(adjacency, "roe_sep.report") if m.startswith("roe_sep.nodes")) == []


def test_report_builds_without_the_nodes_package():
    """In a fresh interpreter, importing the report and building the report of the recorded default run (which
    validates its messages) loads no module of ``roe_sep.nodes``."""
    code = ("import sys, roe_sep.report as r; safe = r.build_report(sys.argv[1])['safe']; "
            "print(safe, sorted(m for m in sys.modules if m.startswith('roe_sep.nodes')))")
    out = subprocess.run([sys.executable, "-c", code, str(ROOT.parent / "bags" / "default_run")], capture_output=True,
                         text=True, timeout=120, check=True)
    assert out.stdout.strip() == "True []"


def find_cycles(adjacency: dict) -> list:
    """Strongly connected components with more than one module, or a module importing itself (Tarjan)."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in adjacency.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in adjacency.get(v, ()):
                out.append(sorted(comp))

    for v in sorted(adjacency):
        if v not in index:
            visit(v)
    return out


def test_no_import_circles(graph):
    adjacency = {src: {dst for dst, _ in edges if dst != src} for src, (edges, _) in graph.items()}
    assert find_cycles(adjacency) == []


def test_the_checks_can_fail():
    """The detectors themselves: a two-module circle and an upward edge are found."""
    assert find_cycles({"a": {"b"}, "b": {"a"}, "c": {"a"}}) == [["a", "b"]]
    assert layer("roe_sep.cli.design") > layer("roe_sep.core.config")
    assert layer("roe_sep.core.relmotion.roe") == 1 and layer("roe_sep.nodes.sim") == 3
    assert reachable({"report": {"x"}, "x": {"nodes.sim"}, "nodes.sim": set()}, "report") == {"x", "nodes.sim"}


def test_a_run_process_does_not_import_what_it_does_not_use():
    """The runner and the node processes import neither ``scipy.stats`` nor ``scipy.optimize`` at start-up (about
    0.5 CPU-s per process; the modules that need them import them where they are used, docs/benchmarks.md)."""
    code = ("import sys, roe_sep.run, roe_sep.cli, roe_sep.nodes.suite; "
            "print(sorted(m for m in ('scipy.stats', 'scipy.optimize', 'scipy.special') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip() == "[]"
