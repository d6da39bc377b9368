"""The import graph of the installed package, read from its sources with :mod:`ast`.

One edge per imported module of ``regopack`` (``core/``) or ``regopack.plugins``
(``plugins/``), with the kind of the statement: ``module`` (runs when the
importer is imported), ``local`` (inside a function) or ``typing`` (under
``if TYPE_CHECKING:``, never run). ``from pkg import name`` is an edge to
``pkg.name`` when that is a module, else to ``pkg``.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
ROOTS = {"core": "regopack", "plugins": "regopack.plugins"}
"""Source folder and the package it installs as (``[tool.setuptools] package-dir``)."""


@dataclass(frozen=True)
class Edge:
    """One import statement: ``src`` imports ``dst`` at ``line``."""

    src: str
    dst: str
    kind: str
    line: int

    def __str__(self) -> str:
        return f"{self.src} -> {self.dst} ({self.kind}, line {self.line})"


def module_name(path: Path, folder: Path, package: str) -> str:
    """Dotted name of the module in ``path`` (a package's ``__init__`` is the package)."""
    parts = list(path.relative_to(folder).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join([package, *parts])


class _Imports(ast.NodeVisitor):
    def __init__(self, name: str, is_package: bool, known: set[str]) -> None:
        self.name, self.is_package, self.known = name, is_package, known
        self.kinds = ["module"]
        self.edges: list[Edge] = []

    def _inside(self, kind: str, nodes: list[ast.stmt] | list[ast.expr]) -> None:
        self.kinds.append(kind)
        for node in nodes:
            self.visit(node)
        self.kinds.pop()

    def visit_FunctionDef(self, node: ast.FunctionDef | ast.AsyncFunctionDef) -> None:
        for decorator in node.decorator_list:
            self.visit(decorator)
        self._inside("local", node.body)

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_Lambda(self, node: ast.Lambda) -> None:
        self._inside("local", [node.body])

    def visit_If(self, node: ast.If) -> None:
        test = node.test
        typing = getattr(test, "id", getattr(test, "attr", None)) == "TYPE_CHECKING"
        if typing and self.kinds[-1] == "module":
            self._inside("typing", node.body)
            for stmt in node.orelse:
                self.visit(stmt)
        else:
            self.generic_visit(node)

    def _known(self, name: str) -> str:
        parts = name.split(".")
        while parts and ".".join(parts) not in self.known:
            parts.pop()
        return ".".join(parts) or name

    def _add(self, dst: str, line: int) -> None:
        if dst == "regopack" or dst.startswith("regopack."):
            self.edges.append(Edge(self.name, self._known(dst), self.kinds[-1], line))

    def visit_Import(self, node: ast.Import) -> None:
        for alias in node.names:
            self._add(alias.name, node.lineno)

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        base = node.module or ""
        if node.level:
            parts = self.name.split(".")[: None if self.is_package else -1]
            parts = parts[: len(parts) - node.level + 1]
            base = ".".join([*parts, *([node.module] if node.module else [])])
        for alias in node.names:
            sub = f"{base}.{alias.name}"
            self._add(sub if sub in self.known else base, node.lineno)


def build_graph(repo: Path = REPO) -> tuple[dict[str, Path], list[Edge]]:
    """Every module of the package (name and file) and every import between them."""
    modules: dict[str, Path] = {}
    for folder, package in ROOTS.items():
        for path in sorted((repo / folder).rglob("*.py")):
            modules[module_name(path, repo / folder, package)] = path
    known = set(modules)
    edges: list[Edge] = []
    for name, path in modules.items():
        visitor = _Imports(name, path.name == "__init__.py", known)
        visitor.visit(ast.parse(path.read_text(encoding="utf-8"), filename=str(path)))
        edges.extend(e for e in visitor.edges if e.src != e.dst)
    return modules, list(dict.fromkeys(edges))


def cycles(edges: list[Edge]) -> list[set[str]]:
    """Strongly connected components of more than one module (Tarjan's algorithm)."""
    graph: dict[str, set[str]] = defaultdict(set)
    for e in edges:
        graph[e.src].add(e.dst)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[set[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(component)

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found
