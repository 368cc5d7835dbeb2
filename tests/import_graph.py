"""The package's import graph, read from the source with :mod:`ast` (nothing is imported).

Used by ``tests/test_layout.py`` and, as a script, to measure the layout::

    python tests/import_graph.py [PACKAGE_DIR]

prints every import circle (strongly connected group of modules), the number of function-local
imports and every cross-module use of a ``_private`` name.

Every ``import`` and ``from ... import`` counts, at the top of a module, under ``if
TYPE_CHECKING:`` or inside a function. ``from towtank.report import figures`` is an import of
the module ``towtank.report.figures`` (and of the package ``towtank.report``). A function-local
import marked as loaded on use (a comment holding :data:`STARTUP_MARK` on the import's line,
or on a comment line just above it or above the run of imports it belongs to) is kept out of the
circle check: the lazy imports that keep
pandas, scipy or matplotlib out of ``towtank inspect`` and ``--help``.
"""

from __future__ import annotations

import ast
import functools
import sys
from dataclasses import dataclass
from pathlib import Path

#: The comment that marks a function-local import as a measured loaded on use.
STARTUP_MARK = "loaded on use"


@dataclass(frozen=True)
class Import:
    """One import statement's edge: ``module`` imports ``target`` (absolute dotted names)."""

    module: str
    target: str
    names: tuple[str, ...]
    line: int
    local: bool  # inside a function
    startup: bool  # marked with STARTUP_MARK


def modules(package_dir: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` file under ``package_dir``."""
    root = package_dir.name
    out = {}
    for path in sorted(package_dir.rglob("*.py")):
        parts = [root, *path.relative_to(package_dir).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _parents(tree: ast.AST) -> dict[ast.AST, ast.AST]:
    return {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}


def _is_local(node: ast.AST, parents: dict[ast.AST, ast.AST]) -> bool:
    while node in parents:
        node = parents[node]
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            return True
    return False


def _marked(lines: list[str], lineno: int) -> bool:
    """Whether the import on line ``lineno`` (from 1) holds :data:`STARTUP_MARK`, or the comment
    just above it or above the run of imports and comments it ends does."""
    if STARTUP_MARK in lines[lineno - 1]:
        return True
    j = lineno - 2
    while j >= 0 and lines[j].strip().startswith(("#", "import ", "from ")):
        if STARTUP_MARK in lines[j]:
            return True
        j -= 1
    return False


@functools.cache
def parse(text: str) -> ast.Module:
    """``ast.parse(text)``, each distinct source parsed once (the checks only read the trees;
    ``parse.cache_clear()`` frees them)."""
    return ast.parse(text)


def parse_file(path: Path) -> ast.Module:
    """The syntax tree of the module at ``path`` (:func:`parse`)."""
    return parse(path.read_text(encoding="utf-8"))


def imports(path: Path, module: str, known: set[str]) -> list[Import]:
    """Every import in ``path`` (the module ``module``); ``known`` is the package's modules."""
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    tree = parse(text)
    parents = _parents(tree)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        local = _is_local(node, parents)
        startup = local and _marked(lines, node.lineno)

        def edge(target: str, names: tuple[str, ...] = (), line: int = node.lineno,
                 local: bool = local, startup: bool = startup) -> Import:
            return Import(module, target, names, line, local, startup)

        if isinstance(node, ast.Import):
            found += [edge(a.name) for a in node.names]
            continue
        base = node.module or ""
        if node.level:
            anchor = package.split(".")
            anchor = anchor[: len(anchor) - (node.level - 1)]
            base = ".".join(anchor + ([base] if base else []))
        names = tuple(a.name for a in node.names)
        found.append(edge(base, names))
        # `from pkg import sub`: sub is a module of its own
        found += [edge(f"{base}.{n}") for n in names if f"{base}.{n}" in known]
    return found


def all_imports(package_dir: Path) -> list[Import]:
    mods = modules(package_dir)
    known = set(mods)
    return [imp for m, p in mods.items() for imp in imports(p, m, known)]


def graph(edges: list[Import], known: set[str], *, skip_startup: bool = True,
          only_top: bool = False) -> dict[str, set[str]]:
    """module -> the package's modules it imports (a package's ``__init__`` is its own node).

    ``from a.b import c`` where ``c`` is a name (not a module) is an edge to ``a.b``.
    """
    g: dict[str, set[str]] = {m: set() for m in known}
    for e in edges:
        if e.target not in known or e.target == e.module:
            continue
        if (skip_startup and e.startup) or (only_top and e.local):
            continue
        g[e.module].add(e.target)
    return g


def circles(g: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (or a module importing itself).

    A package importing its own submodule and that submodule importing the package's
    ``__init__`` back is a circle like any other.
    """
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(g.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1 or v in g.get(v, ()):
                out.append(sorted(group))

    for v in sorted(g):
        if v not in index:
            visit(v)
    return sorted(out)


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def private_uses(edges: list[Import], known: set[str]) -> list[Import]:
    """Imports of another module's ``_private`` name (``from m import _x``, or of ``_m``).

    Importing a private *module* of one's own package (``from . import _ignore_sigint``)
    counts too, unless the importer is that package's ``__init__`` or a sibling module.
    """
    out = []
    for e in edges:
        if e.target not in known or e.target == e.module:
            continue
        if any(_private(n) and f"{e.target}.{n}" not in known for n in e.names):
            out.append(e)
            continue
        last = e.target.rpartition(".")[2]
        if _private(last) and e.module.rpartition(".")[0] != e.target.rpartition(".")[0] \
                and e.module != e.target.rpartition(".")[0]:
            out.append(e)
    return out


def _module_names(tree: ast.AST, module: str, package: str, known: set[str]) -> dict[str, str]:
    """Local name -> the package's module it is bound to, for every import in ``tree``:
    ``import a.b as x`` (x), ``import a.b`` (a, the top package) and ``from a import b as x``
    where ``a.b`` is a module."""
    out = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.asname:
                    out[a.asname] = a.name
                else:
                    out[a.name.split(".")[0]] = a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            for a in node.names:
                if f"{base}.{a.name}" in known:
                    out[a.asname or a.name] = f"{base}.{a.name}"
    return {name: target for name, target in out.items() if target in known}


def _dotted(node: ast.expr, names: dict[str, str]) -> str | None:
    """The dotted name ``node`` reads (``q``, ``towtank.report.quality``) with its first part
    replaced by the module it is bound to; None for anything else."""
    if isinstance(node, ast.Name):
        return names.get(node.id)
    if isinstance(node, ast.Attribute):
        base = _dotted(node.value, names)
        return None if base is None else f"{base}.{node.attr}"
    return None


def private_attribute_uses(package_dir: Path) -> list[tuple[str, int, str]]:
    """``alias._name``: a ``_private`` name read as an attribute of another module of the
    package (``import pkg.a as q; q._x``, ``from pkg import a; y = a._x``,
    ``pkg.a._x``): (importer, line, ``module._name``)."""
    mods = modules(package_dir)
    known = set(mods)
    out = []
    for m, p in mods.items():
        tree = parse_file(p)
        package = m if p.name == "__init__.py" else m.rpartition(".")[0]
        names = _module_names(tree, m, package, known)
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Attribute) and _private(node.attr)):
                continue
            owner = _dotted(node.value, names)
            if owner in known and owner != m:
                out.append((m, node.lineno, f"{owner}.{node.attr}"))
    return sorted(set(out))


def report(package_dir: Path) -> str:
    mods = modules(package_dir)
    known = set(mods)
    edges = all_imports(package_dir)
    lines = [f"modules: {len(mods)}"]
    local = [e for e in edges if e.local]
    # one per statement: `from a import b` counts once even when b is a module
    stmts = {(e.module, e.line) for e in local}
    inner = {(e.module, e.line) for e in local if e.target.split(".")[0] == package_dir.name}
    marked = {(e.module, e.line) for e in local if e.startup}
    lines.append(f"function-local import statements: {len(stmts)} "
                 f"({len(inner)} of the package's own modules; {len(marked)} marked "
                 f"'{STARTUP_MARK}')")
    for title, g in (
        ("circles, every import (loaded-on-use imports left out)", graph(edges, known)),
        ("circles, top-level imports only", graph(edges, known, only_top=True)),
    ):
        found = circles(g)
        lines.append(f"{title}: {len(found)}")
        lines += [f"  {len(c)}: " + " ".join(c) for c in found]
    priv = private_uses(edges, known)
    attrs = private_attribute_uses(package_dir)
    lines.append(f"cross-module imports of _private names: {len(priv)} "
                 f"({sum(len([n for n in e.names if _private(n)]) or 1 for e in priv)} names); "
                 f"module._private attribute uses: {len(attrs)}")
    lines += [f"  {e.module}:{e.line} from {e.target} import {', '.join(e.names)}" for e in priv]
    lines += [f"  {m}:{n} {a}" for m, n, a in attrs]
    return "\n".join(lines)


if __name__ == "__main__":
    here = Path(__file__).resolve().parents[1] / "towtank"
    print(report(Path(sys.argv[1]) if len(sys.argv) > 1 else here))
