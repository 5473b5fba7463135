"""The import graph between packages (and between modules) has no loops, and the three
installed packages stay layered: ``engine`` below ``widgets`` below ``app``.

What counts as a package-level import loop
------------------------------------------
The graph's nodes are the *units* of the repository: each subpackage or top-level module
one level below ``engine``, ``widgets`` and ``app`` (``engine.studio``,
``engine.skeleton``, ``widgets.viewport``, ``app.main_window``). Unit A depends on unit
B when any module of A imports any module of B, wherever the import statement sits: at
module level, inside a function, or under ``if TYPE_CHECKING``. A deferred import
delays a loop to the first call and a type-only one still makes A's interface speak
B's types, so moving an import into a function cannot hide a loop from this test. A
loop is a strongly connected component of that graph with more than one unit; the
failure lists every edge inside it with the file, line and where the import sits.

Every ``.py`` file is parsed with :mod:`ast`, never imported. Imports through a string
table (``engine.solver``'s lazy names) are not seen; calls of
``importlib.import_module`` / ``__import__`` with a literal name are.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

#: Installed packages, lowest layer first: each may import only those before it.
LAYERS = ("engine", "widgets", "app")


@dataclass(frozen=True)
class Import:
    """One import statement's edge: ``source`` module imports ``target`` module at
    ``line`` of ``path``; ``where`` is ``module``, ``function`` or ``type-only``."""

    source: str
    target: str
    path: str
    line: int
    where: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line} ({self.where}) {self.source} -> {self.target}"


def module_files(packages: Iterable[str], root: Path = REPO) -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package ``__init__``) of every module under ``packages``."""
    out: dict[str, tuple[Path, bool]] = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            if "__pycache__" in path.parts:
                continue
            parts = list(path.relative_to(root).with_suffix("").parts)
            is_package = parts[-1] == "__init__"
            out[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return out


def _known(name: str, modules: Mapping[str, object]) -> str | None:
    """The longest prefix of ``name`` that is one of ``modules`` (``engine.x.Class`` -> ``engine.x``)."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def _nodes_within(tree: ast.AST, kinds: tuple[type, ...], test=lambda node: True) -> set[int]:
    inner: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, kinds) and test(node):
            inner.update(id(n) for n in ast.walk(node) if n is not node)
    return inner


def imports_of(
    module: str, source: str, is_package: bool, modules: Mapping[str, object], path: str = "<string>"
) -> list[Import]:
    """The imports of ``module`` (source text ``source``) that name one of ``modules``.

    Relative imports are resolved against the module's package; ``from p import x`` is an
    edge to ``p.x`` when that is a module, else to ``p``.
    """
    tree = ast.parse(source, filename=path)
    package = module.split(".") if is_package else module.split(".")[:-1]
    in_function = _nodes_within(tree, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
    type_only = _nodes_within(tree, (ast.If,), lambda n: "TYPE_CHECKING" in ast.unparse(n.test))
    found: list[Import] = []
    for node in ast.walk(tree):
        targets: list[str | None] = []
        if isinstance(node, ast.Import):
            targets = [_known(alias.name, modules) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = ".".join(package[: len(package) - node.level + 1]) if node.level else ""
            origin = ".".join(p for p in (base, node.module or "") if p)
            for alias in node.names:
                full = f"{origin}.{alias.name}"
                targets.append(full if full in modules else _known(origin, modules))
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant):
            func = node.func
            called = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
            if called in ("import_module", "__import__") and isinstance(node.args[0].value, str):
                targets = [_known(node.args[0].value, modules)]
        where = "type-only" if id(node) in type_only else "function" if id(node) in in_function else "module"
        found.extend(Import(module, t, path, node.lineno, where) for t in dict.fromkeys(targets) if t and t != module)
    return found


def unit_of(module: str) -> str:
    """The graph node of a module: its first two dotted parts (``engine.studio.session`` ->
    ``engine.studio``)."""
    return ".".join(module.split(".")[:2])


def unit_graph(imports: Iterable[Import], unit=unit_of) -> dict[str, dict[str, list[Import]]]:
    """unit -> unit it depends on -> the imports that make the edge (self-edges left out)."""
    graph: dict[str, dict[str, list[Import]]] = {}
    for imp in imports:
        a, b = unit(imp.source), unit(imp.target)
        if a != b:
            graph.setdefault(a, {}).setdefault(b, []).append(imp)
    return graph


def loops(graph: Mapping[str, Mapping[str, object]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan, iterative), each sorted."""
    nodes = sorted(set(graph) | {b for edges in graph.values() for b in edges})
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, {}))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, successors = work[-1]
            for nxt in successors:
                if nxt not in index:
                    index[nxt] = low[nxt] = len(index)
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(graph.get(nxt, {})))))
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
    return sorted(found)


def repository_imports(packages: Iterable[str] = LAYERS, root: Path = REPO) -> list[Import]:
    modules = module_files(packages, root)
    return [
        imp
        for name, (path, is_package) in modules.items()
        for imp in imports_of(name, path.read_text(encoding="utf-8"), is_package, modules, str(path.relative_to(root)))
    ]


def describe(graph: Mapping[str, Mapping[str, list[Import]]], component: list[str]) -> str:
    lines = [" <-> ".join(component)]
    for a in component:
        for b in component:
            for imp in graph.get(a, {}).get(b, []):
                lines.append(f"    {imp}")
    return "\n".join(lines)


def test_no_import_loop_between_packages():
    imports = repository_imports()
    assert any(unit_of(i.source) == "engine.studio" for i in imports), "no imports found: wrong folder?"
    graph = unit_graph(imports)
    found = loops(graph)
    assert not found, "import loops between packages (break them by moving what both sides share):\n" + "\n".join(
        describe(graph, c) for c in found
    )


def test_no_import_loop_between_modules():
    """Inside a package too, no two modules need each other (the same edges, one node per module)."""
    graph = unit_graph(repository_imports(), unit=lambda m: m)
    found = loops(graph)
    assert not found, "import loops between modules:\n" + "\n".join(describe(graph, c) for c in found)


def test_installed_packages_are_layered():
    graph = unit_graph(repository_imports(), unit=lambda m: m.split(".")[0])
    upward = [
        f"{imp}"
        for a, edges in graph.items()
        for b, imps in edges.items()
        if LAYERS.index(b) > LAYERS.index(a)
        for imp in imps
    ]
    assert not upward, f"packages may import only lower layers of {LAYERS}:\n" + "\n".join(upward)


# -- the checker itself --------------------------------------------------------------

FAKE = {"engine": 0, "engine.a": 0, "engine.a.x": 0, "engine.b": 0, "engine.b.y": 0, "engine.c": 0}


@pytest.mark.parametrize(
    ("source", "where", "target"),
    [
        ("from engine.b.y import f\n", "module", "engine.b.y"),
        ("from engine.b import y\n", "module", "engine.b.y"),
        ("from ..b import y\n", "module", "engine.b.y"),
        ("from . import x\n", "module", "engine.a.x"),
        ("import engine.c\n", "module", "engine.c"),
        ("def f():\n    from engine.b.y import g\n", "function", "engine.b.y"),
        ("if TYPE_CHECKING:\n    from engine.b.y import T\n", "type-only", "engine.b.y"),
        ("import importlib\nm = importlib.import_module('engine.b.y')\n", "module", "engine.b.y"),
    ],
)
def test_checker_resolves_each_import_form(source, where, target):
    (found,) = imports_of("engine.a.w", source, False, FAKE)
    assert (found.where, found.target) == (where, target)


def test_checker_finds_a_loop_hidden_in_a_function():
    a = imports_of("engine.a.x", "from engine.b.y import f\n", False, FAKE)
    b = imports_of("engine.b.y", "def g():\n    from engine.a.x import h\n", False, FAKE)
    c = imports_of("engine.c", "import engine.a.x\n", False, FAKE)
    graph = unit_graph(a + b + c)
    assert loops(graph) == [["engine.a", "engine.b"]]
    assert "(function) engine.b.y -> engine.a.x" in describe(graph, ["engine.a", "engine.b"])


def test_checker_finds_longer_loops_and_ignores_chains():
    assert loops({"a": {"b": []}, "b": {"c": []}, "c": {"a": []}, "d": {"a": []}}) == [["a", "b", "c"]]
    assert loops({"a": {"b": []}, "b": {"c": []}}) == []
