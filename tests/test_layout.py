"""The package's layout: stages import one way, test tooling stays out of the production path.

The subpackages are layers, lowest first (:data:`LAYERS`). A module may import its own layer and
the layers below it, never one above: the data flows from ingest to report, and the folder
listing reads like the pipeline. ``towtank.testing`` sits on top (it may use everything) and
nothing below it imports it, except the one command that writes synthetic days
(``towtank.commands.synth``). Every import counts, the ones inside functions and under
``TYPE_CHECKING`` included, so that the structure cannot erode silently.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "towtank"

#: Lowest first. Top-level modules are layers of their own: ``errors`` (the exceptions every
#: stage raises) at the bottom, ``pipeline`` (wires the stages for a day) above the stages, and
#: the package's ``__init__`` (the public API, loaded lazily) at the top with the commands.
LAYERS: list[tuple[str, ...]] = [
    ("errors",),
    ("runtime",),
    ("stats",),
    ("reference",),
    ("signal",),
    ("ingest",),
    ("reduce",),
    ("analysis",),
    ("vehicle",),
    ("results",),
    ("pipeline",),
    ("report",),
    ("api",),
    ("commands", "__main__", "__init__"),
    ("testing",),
]

#: The one production module allowed to import the test tooling: ``towtank synth``.
SYNTH_COMMAND = "commands.synth"

#: Names every module may take from the package's ``__init__`` (no import of the API).
INIT_NAMES = {"__version__"}


def layer_of(unit: str) -> int:
    for i, names in enumerate(LAYERS):
        if unit in names:
            return i
    raise AssertionError(f"towtank.{unit} is in no layer of test_layout.LAYERS: add it there")


def _modules() -> list[tuple[str, Path]]:
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__" and len(parts) > 1:
            parts = parts[:-1]
        out.append((".".join(parts), path))
    return out


def _imports(path: Path, module: str) -> list[tuple[str, list[str], int]]:
    """(absolute module imported, names taken from it, line) for every import in ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(a.name, [], node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = ("towtank." + package).rstrip(".").split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            found.append((base, [a.name for a in node.names], node.lineno))
    return found


def _unit(dotted: str) -> str:
    """The layer unit of a towtank module: its subpackage, or the top-level module."""
    parts = dotted.split(".")[1:]
    return parts[0] if parts else "__init__"


def test_every_module_is_in_a_layer():
    for module, _ in _modules():
        layer_of(module.split(".")[0])


def test_imports_run_down_the_data_path_only():
    wrong = []
    for module, path in _modules():
        own = layer_of(module.split(".")[0])
        for target, names, line in _imports(path, module):
            if target != "towtank" and not target.startswith("towtank."):
                continue
            if target == "towtank":  # `from towtank import x`: x is a subpackage or a name
                units = [n for n in names if n not in INIT_NAMES]
                targets = [f"towtank.{n}" for n in units]
            else:
                targets = [target]
            for t in targets:
                unit = _unit(t)
                if unit == "testing" and module == SYNTH_COMMAND:
                    continue
                if layer_of(unit) > own:
                    wrong.append(f"towtank.{module} (line {line}) imports {t}")
    assert not wrong, "imports against the data path:\n" + "\n".join(wrong)


def test_nothing_in_production_imports_the_test_tooling():
    users = []
    for module, path in _modules():
        if module.startswith("testing") or module == SYNTH_COMMAND:
            continue
        for target, names, _ in _imports(path, module):
            if target.startswith("towtank.testing") or (
                target == "towtank" and "testing" in names
            ):
                users.append(module)
    assert not users


def test_report_modules_import_no_circle():
    """report: style < figures < pdf; provenance, tables below outputs; nothing imports outputs."""
    graph: dict[str, set[str]] = {}
    for module, path in _modules():
        if module.startswith("report."):
            graph[module] = {
                t.removeprefix("towtank.") for t, _, _ in _imports(path, module)
                if t.startswith("towtank.report.")
            }

    def reaches(a: str, b: str, seen: frozenset[str] = frozenset()) -> bool:
        return any(n == b or (n not in seen and reaches(n, b, seen | {n}))
                   for n in graph.get(a, ()))

    circles = [m for m in graph if reaches(m, m)]
    assert not circles


@pytest.mark.parametrize("limit", [1000])
def test_no_module_is_over_a_thousand_lines(limit):
    long = {m: n for m, p in _modules() if (n := len(p.read_text().splitlines())) > limit}
    assert not long
