"""The package's layout: no import circle, no borrowed private name, imports one way.

The subpackages are layers, lowest first (:data:`LAYERS`). A module may import its own layer and
the layers below it, never one above: the data flows from ingest to report, and the folder
listing reads like the pipeline. ``towtank.testing`` sits on top (it may use everything) and
nothing below it imports it, except the one command that writes synthetic days
(``towtank.commands.synth``). Every import counts, the ones inside functions and under
``TYPE_CHECKING`` included, so that the structure cannot erode silently.

No module takes part in an import circle (:func:`import_graph.circles`: a top-level import, or
a function-local one that is not marked as loaded on use, closing a loop), and no module
imports another module's ``_private`` name: a name two modules share is public in its one home.
Each checker is first shown to catch a planted violation in a small package of its own.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import import_graph
import pytest
from import_graph import (
    STARTUP_MARK,
    Import,
    circles,
    graph,
    modules,
    parse_file,
    private_attribute_uses,
    private_uses,
)

PACKAGE = Path(__file__).resolve().parents[1] / "towtank"


@functools.cache
def _towtank_edges() -> tuple[Import, ...]:
    return tuple(import_graph.all_imports(PACKAGE))


@pytest.fixture(scope="module", autouse=True)
def _free_the_parsed_modules():
    """The checks share one parse of each module (import_graph.parse); freed after them."""
    yield
    import_graph.parse.cache_clear()


def all_imports(package_dir: Path) -> list[Import]:
    """Every import of the package (towtank's read once: it does not change during the tests)."""
    if package_dir == PACKAGE:
        return list(_towtank_edges())
    return import_graph.all_imports(package_dir)

#: Lowest first. Top-level modules are layers of their own: ``errors`` (the exceptions every
#: stage raises) at the bottom, ``pipeline`` (wires the stages for a day) above the stages, and
#: the package's ``__init__`` (the public API, loaded lazily) at the top with the commands.
LAYERS: list[tuple[str, ...]] = [
    ("errors",),
    ("messages",),
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
    ("runner",),
    ("api",),
    ("live",),
    ("commands", "__main__", "__init__"),
    ("testing",),
]

#: The one production module allowed to import the test tooling: ``towtank synth``.
SYNTH_COMMAND = "commands.synth"

#: Names every module may take from the package's ``__init__`` (no import of the API).
INIT_NAMES = {"__version__"}

#: Import circles still there, each as its exact set of modules; the test fails when one of
#: them grows, shrinks or goes (then take it out of this list), and on any other circle.
ALLOWED_CIRCLES: list[frozenset[str]] = []

#: Cross-module imports of a ``_private`` name still there: (importer, module, name).
ALLOWED_PRIVATE: set[tuple[str, str, str]] = set()


# --------------------------------------------------------------------------------- checkers
def unit_of(dotted: str) -> str:
    """The layer unit of a module: its subpackage, or the top-level module (``__init__`` for
    the package itself)."""
    parts = dotted.split(".")[1:]
    return parts[0] if parts else "__init__"


def layer_of(unit: str, layers: list[tuple[str, ...]]) -> int:
    for i, names in enumerate(layers):
        if unit in names:
            return i
    raise AssertionError(f"{unit} is in no layer of test_layout.LAYERS: add it there")


def layer_violations(edges: list[Import], known: set[str], root: str,
                     layers: list[tuple[str, ...]], exempt: tuple[tuple[str, str], ...] = ()
                     ) -> list[str]:
    """Imports of a module in a higher layer; ``exempt`` (importer's unit path, target unit)
    pairs are allowed."""
    wrong = []
    for e in edges:
        if e.target != root and not e.target.startswith(root + "."):
            continue
        if e.target == root:  # `from pkg import x`: x is a submodule (its own edge) or an API name
            if all(n in INIT_NAMES or f"{root}.{n}" in known for n in e.names):
                continue
        own = layer_of(unit_of(e.module), layers)
        unit = unit_of(e.target)
        if (e.module.removeprefix(root + "."), unit) in exempt:
            continue
        if layer_of(unit, layers) > own:
            wrong.append(f"{e.module} (line {e.line}) imports {e.target}")
    return wrong


def unexpected_circles(package_dir: Path, allowed: list[frozenset[str]]) -> list[str]:
    """Circles not in ``allowed`` and allowed circles no longer found, in words."""
    mods = modules(package_dir)
    found = {frozenset(c) for c in circles(graph(all_imports(package_dir), set(mods)))}
    out = [f"import circle: {' -> '.join(sorted(c))}" for c in found - set(allowed)]
    out += [f"allowed circle gone or changed, update ALLOWED_CIRCLES: {sorted(c)}"
            for c in set(allowed) - found]
    return sorted(out)


def unexpected_private(package_dir: Path, allowed: set[tuple[str, str, str]]) -> list[str]:
    mods = modules(package_dir)
    found = set()
    for e in private_uses(all_imports(package_dir), set(mods)):
        names = [n for n in e.names if n.startswith("_") and not n.startswith("__")]
        found |= {(e.module, e.target, n) for n in names or [""]}
    out = [f"{m} imports {n or t} from {t}" for m, t, n in sorted(found - allowed)]
    out += [f"allowed private import gone, update ALLOWED_PRIVATE: {x}"
            for x in sorted(allowed - found)]
    return out


# ------------------------------------------------------------------------- the package itself
def test_every_module_is_in_a_layer():
    for module in modules(PACKAGE):
        layer_of(unit_of(module), LAYERS)


@pytest.mark.heavy
def test_imports_run_down_the_data_path_only():
    mods = modules(PACKAGE)
    wrong = layer_violations(all_imports(PACKAGE), set(mods), "towtank", LAYERS,
                             exempt=((SYNTH_COMMAND, "testing"),))
    assert not wrong, "imports against the data path:\n" + "\n".join(wrong)


@pytest.mark.heavy
def test_nothing_in_production_imports_the_test_tooling():
    users = sorted({
        e.module for e in all_imports(PACKAGE)
        if e.target.startswith("towtank.testing")
        and not e.module.startswith("towtank.testing")
        and e.module != f"towtank.{SYNTH_COMMAND}"
    })
    assert not users


def test_no_import_circle_anywhere():
    """In any subpackage or across them; a function-local import counts unless it is marked
    as loaded on use."""
    problems = unexpected_circles(PACKAGE, ALLOWED_CIRCLES)
    assert not problems, "\n".join(problems)


def test_no_module_imports_another_modules_private_name():
    problems = unexpected_private(PACKAGE, ALLOWED_PRIVATE)
    assert not problems, "\n".join(problems)


def test_no_module_reads_another_modules_private_name_as_an_attribute():
    """``q._name`` of a module ``q`` of the package (an alias, ``import ... as q``, or the
    module's dotted name) borrows a private name as much as ``from q import _name`` does."""
    found = [f"{m}:{line} reads {name}" for m, line, name in private_attribute_uses(PACKAGE)]
    assert not found, "\n".join(found)


def test_function_local_imports_are_marked_start_up_savings():
    """Every function-local import in the package, of towtank's own modules or a library's,
    is loaded on use, marked so; all others are at the top."""
    unmarked = sorted({
        f"{e.module}:{e.line} imports {e.target}" for e in all_imports(PACKAGE)
        if e.local and not e.startup
    })
    assert not unmarked, "\n".join(unmarked)


# ----------------------------------------------------------- the checkers catch what is planted
def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "pkg"
    for rel, text in {"__init__.py": "", **files}.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return root


def test_a_planted_circle_is_found_also_through_a_function_local_import(tmp_path):
    pkg = _package(tmp_path, {
        "low/__init__.py": "",
        "low/a.py": "from pkg.low.b import f\n",
        "low/b.py": "def f():\n    from pkg.low import a\n    return a\n",
        "low/c.py": "from . import a\n",
    })
    assert unexpected_circles(pkg, []) == ["import circle: pkg.low.a -> pkg.low.b"]
    assert unexpected_circles(pkg, [frozenset({"pkg.low.a", "pkg.low.b"})]) == []


def test_a_circle_across_subpackages_is_found(tmp_path):
    pkg = _package(tmp_path, {
        "x/__init__.py": "", "y/__init__.py": "",
        "x/m.py": "from pkg.y import n\n",
        "y/n.py": "from pkg.x.m import thing\n",
    })
    assert unexpected_circles(pkg, []) == ["import circle: pkg.x.m -> pkg.y.n"]


def test_a_marked_start_up_saving_closes_no_circle(tmp_path):
    pkg = _package(tmp_path, {
        "a.py": "from pkg.b import g\n",
        "b.py": f"def g():\n    # {STARTUP_MARK}: a is heavy\n    from pkg import a\n",
    })
    assert unexpected_circles(pkg, []) == []
    # the same import unmarked closes the circle
    (pkg / "b.py").write_text("def g():\n    from pkg import a\n", encoding="utf-8")
    assert unexpected_circles(pkg, []) == ["import circle: pkg.a -> pkg.b"]


def test_an_allowed_circle_that_is_gone_must_leave_the_list(tmp_path):
    pkg = _package(tmp_path, {"a.py": "import os\n"})
    (problem,) = unexpected_circles(pkg, [frozenset({"pkg.a", "pkg.b"})])
    assert "ALLOWED_CIRCLES" in problem


def test_a_planted_private_import_is_found(tmp_path):
    pkg = _package(tmp_path, {
        "a.py": "_secret = 1\npublic = 2\n",
        "b.py": "from pkg.a import _secret, public\n",
        "c.py": "def f():\n    from .a import _secret\n    return _secret\n",
        "d.py": "from pkg.a import public\n",
    })
    assert unexpected_private(pkg, set()) == ["pkg.b imports _secret from pkg.a",
                                              "pkg.c imports _secret from pkg.a"]
    assert unexpected_private(pkg, {("pkg.b", "pkg.a", "_secret"),
                                    ("pkg.c", "pkg.a", "_secret")}) == []


def test_a_planted_private_attribute_of_a_module_is_found(tmp_path):
    pkg = _package(tmp_path, {
        "sub/__init__.py": "",
        "sub/quality.py": "_num = 1\npublic = 2\n\n\ndef f():\n    return _num\n",
        "alias.py": "from pkg.sub import quality as _quality\n_num = _quality._num\n",
        "as_name.py": "import pkg.sub.quality as q\n\n\ndef g():\n    return q._num(1)\n",
        "dotted.py": "import pkg.sub.quality\nx = pkg.sub.quality._num\n",
        "relative.py": "from .sub import quality\ny = quality._num\n",
        "fine.py": "from pkg.sub import quality\nz = quality.public\n",
        "own.py": "import os\n_own = 1\n\n\nclass A:\n    _x = 1\n\n\n"
                  "def h(a):\n    return a._x, os._exit\n",
    })
    assert private_attribute_uses(pkg) == [
        ("pkg.alias", 2, "pkg.sub.quality._num"),
        ("pkg.as_name", 5, "pkg.sub.quality._num"),
        ("pkg.dotted", 2, "pkg.sub.quality._num"),
        ("pkg.relative", 2, "pkg.sub.quality._num"),
    ]


def test_a_planted_upward_import_is_found(tmp_path):
    layers = [("ingest",), ("report",), ("commands", "__init__")]
    pkg = _package(tmp_path, {
        "ingest/__init__.py": "", "report/__init__.py": "", "commands/__init__.py": "",
        "ingest/read.py": "def f():\n    from pkg.report import figures\n",
        "report/figures.py": "from pkg.ingest import read\nfrom pkg import __version__\n",
        "commands/cli.py": "from pkg.report.figures import x\n",
    })
    mods = modules(pkg)
    wrong = layer_violations(all_imports(pkg), set(mods), "pkg", layers)
    assert wrong == ["pkg.ingest.read (line 2) imports pkg.report",
                     "pkg.ingest.read (line 2) imports pkg.report.figures"]


@pytest.mark.parametrize("module", ["towtank.ingest.protocol", "towtank.ingest.runfile",
                                    "towtank.ingest.zerofile", "towtank.ingest.speedlog"])
def test_the_ingest_readers_and_the_protocol_import_no_circle(module):
    """The ingest circle of issue #24 (protocol, runfile, sections, speedlog, zerofile,
    vehicle_protocol) stays broken: none of them can reach itself."""
    g = graph(all_imports(PACKAGE), set(modules(PACKAGE)))

    def reach(a: str, seen: set[str]) -> set[str]:
        for b in g[a]:
            if b not in seen:
                seen.add(b)
                reach(b, seen)
        return seen

    assert module not in reach(module, set())


READERS = ("readers", "plaincsv", "arrayfiles", "columns", "timing", "segments", "calibration",
           "runfile", "speedlog", "zerofile", "runsheet", "describe")
PARSERS = ("protocol", "sections", "schema", "vehicle_protocol", "design_inputs")


def test_the_readers_depend_on_the_protocol_types_not_on_its_parsers():
    """The config layer: the readers of run files, logs, zeros files and sheets take the
    protocol's types (towtank.ingest.protocol_types), never the parsers that build them."""
    wrong = sorted({
        f"{e.module} imports {e.target}" for e in all_imports(PACKAGE)
        if e.module.removeprefix("towtank.ingest.") in READERS
        and e.target.removeprefix("towtank.ingest.") in PARSERS
        and e.target.startswith("towtank.ingest.")
    })
    assert not wrong, "\n".join(wrong)


# ------------------------------------------------------------------ messages are read by field
#: Names of a message (a warning, a note, a rejection's reason, a sentence) in the code.
MESSAGE_NAME = re.compile(
    r"(?:^|_)(?:reason|reasons|note|notes|warning|warnings|message|messages|sentence|"
    r"sentences|notice|notices|rejection|rejections|said|detail)$")
#: The text fields of a Notice or a Rejection.
MESSAGE_FIELDS = {"text", "reason", "detail"}
#: Text tests of a str method and of the ``re`` functions (the argument holding the text).
TEXT_METHODS = {"startswith", "endswith"}
RE_TEXT_ARG = {"match": 1, "search": 1, "fullmatch": 1, "sub": 2, "subn": 2, "findall": 1}
PATTERN_TEXT_ARG = {"match": 0, "search": 0, "fullmatch": 0, "sub": 1, "subn": 1, "findall": 0}

#: Functions that read message text on purpose, each (module, function), with why:
ALLOWED_TEXT_READS: set[tuple[str, str]] = {
    # the one place a RunError's sentence (raised deep in the readers, with no kind) is split
    # into a Rejection's reason and whether the file goes before it
    ("towtank.messages", "Rejection.of_run_error"),
    # the day-wide grouping of the reductions' per-run warnings (plain sentences that the
    # worker processes return), compared word for word without their run and file prefixes
    ("towtank.analysis.daywide", "own_reason"),
    # `towtank inspect` on one file: the hint it adds to a RunError's sentence (a segment) and
    # the sentence's own punctuation
    ("towtank.commands.inspect", "inspect_run.load"),
    ("towtank.commands.inspect", "inspect_run"),
    # npTDMS's own warnings while it reads a file: the library says what it found only in
    # their words (input text, like the file's)
    ("towtank.ingest.readers", "TdmsLog.first"),
}


def _message_named(node: ast.AST, aliases: frozenset[str] = frozenset()) -> bool:
    """An expression that names a message: ``reason``, ``red.notes``, ``rejection.reason``,
    ``notice.text``, ``warnings[0]``, ``str(rejection)``, or a name in ``aliases``."""
    if isinstance(node, ast.Subscript):
        return _message_named(node.value, aliases)
    if isinstance(node, ast.IfExp):
        return _message_named(node.body, aliases) or _message_named(node.orelse, aliases)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and \
            node.func.id == "str" and node.args:
        return _message_named(node.args[0], aliases)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and \
            node.func.attr in ("strip", "lower", "rstrip", "lstrip"):
        return _message_named(node.func.value, aliases)
    if isinstance(node, ast.Name):
        return node.id in aliases or bool(MESSAGE_NAME.search(node.id))
    if isinstance(node, ast.Attribute):
        return bool(MESSAGE_NAME.search(node.attr)) or (
            node.attr in MESSAGE_FIELDS and _message_named(node.value, aliases))
    return False


def _aliases(scope: ast.AST) -> frozenset[str]:
    """Names that hold a message in ``scope``: ``n`` of ``for n in red.notes``, ``text`` of
    ``text = str(reason).strip()``."""
    names: set[str] = set()
    grew = True
    while grew:
        grew = False
        for node in ast.walk(scope):
            target, value = None, None
            if isinstance(node, ast.comprehension | ast.For):
                target, value = node.target, node.iter
            elif isinstance(node, ast.Assign) and len(node.targets) == 1:
                target, value = node.targets[0], node.value
            if isinstance(target, ast.Name) and target.id not in names and \
                    _message_named(value, frozenset(names)):
                names.add(target.id)
                grew = True
    return frozenset(names)


def _plural(node: ast.AST) -> bool:
    """A name of several messages (``notes``, ``day.warnings``): ``notice in warnings`` asks
    whether an object is among them, not what their words say."""
    name = node.id if isinstance(node, ast.Name) else \
        node.attr if isinstance(node, ast.Attribute) else ""
    return name.endswith("s") and name not in MESSAGE_FIELDS


def _text_reads(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, function) of every test of a message's text in ``tree``: ``.startswith`` or
    ``.endswith`` on it, ``re.match``/``re.sub``/... (or a compiled pattern's) on it, or
    ``x in`` it."""
    found: list[tuple[int, str]] = []

    def visit(node: ast.AST, where: str, aliases: frozenset[str]) -> None:
        for child in ast.iter_child_nodes(node):
            inner, names = where, aliases
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                inner = f"{where}.{child.name}" if where else child.name
                names = aliases | _aliases(child)
            hit = False
            if isinstance(child, ast.Call) and isinstance(child.func, ast.Attribute):
                attr, target = child.func.attr, child.func.value
                if attr in TEXT_METHODS:
                    hit = _message_named(target, names)
                elif isinstance(target, ast.Name) and target.id == "re":
                    k = RE_TEXT_ARG.get(attr)
                    hit = k is not None and len(child.args) > k and \
                        _message_named(child.args[k], names)
                else:
                    k = PATTERN_TEXT_ARG.get(attr)
                    hit = k is not None and len(child.args) > k and \
                        _message_named(child.args[k], names)
            elif isinstance(child, ast.Compare):  # "x" in reason; "x" in notes (a list)
                lefts = [child.left, *child.comparators[:-1]]
                hit = any(isinstance(op, ast.In | ast.NotIn) and _message_named(right, names) and (
                    not _plural(right) or isinstance(left, ast.Constant | ast.JoinedStr))
                    for op, left, right in zip(child.ops, lefts, child.comparators, strict=True))
            if hit:
                found.append((child.lineno, where))
            visit(child, inner, names)

    visit(tree, "", frozenset())
    return found


def message_text_reads(package_dir: Path, allowed: set[tuple[str, str]]) -> list[str]:
    """Every test of a message's text in the package, outside the ``allowed``
    (module, function) pairs; and allowed pairs no longer found."""
    root = package_dir.name
    out, seen = [], set()
    for path in sorted(package_dir.rglob("*.py")):
        rel = path.relative_to(package_dir).with_suffix("")
        module = ".".join((root, *rel.parts)).removesuffix(".__init__")
        for line, function in _text_reads(parse_file(path)):
            if (module, function) in allowed:
                seen.add((module, function))
                continue
            out.append(f"{module}:{line} ({function or 'module'}) reads a message's text")
    out += [f"allowed text read gone, update ALLOWED_TEXT_READS: {a}"
            for a in sorted(allowed - seen)]
    return out


def test_no_message_is_parsed_by_its_text():
    """A program decides by a message's fields (stage, run, kind), never by its words."""
    problems = message_text_reads(PACKAGE, ALLOWED_TEXT_READS)
    assert not problems, "\n".join(problems)


def test_a_planted_test_of_a_reason_is_found(tmp_path):
    pkg = _package(tmp_path, {
        "a.py": ("import re\n"
                 "def f(rejection, red, line):\n"
                 "    if rejection.reason.startswith('x'):\n"
                 "        return 1\n"
                 "    if 'usable' in red.notes[0]:\n"
                 "        return 2\n"
                 "    if re.match('run', str(rejection)):\n"
                 "        return 3\n"
                 "    if [n for n in red.warnings if n.endswith('.')]:\n"
                 "        return 4\n"
                 "    if red in day.rejections or 'x' in line:\n"
                 "        return 5\n"
                 "    return line.startswith('#')\n"),
    })
    assert message_text_reads(pkg, set()) == ["pkg.a:3 (f) reads a message's text",
                                             "pkg.a:5 (f) reads a message's text",
                                             "pkg.a:7 (f) reads a message's text",
                                             "pkg.a:9 (f) reads a message's text"]
    assert message_text_reads(pkg, {("pkg.a", "f")}) == []


# ------------------------------------------------------------- one front door, results fixed
#: The runner of a day (towtank.runner): the one module that calls the pipeline's
#: process_day / process_sheet (the pipeline itself and the test tooling aside).
RUNNER = "runner"
DAY_PROCESSORS = ("process_day", "process_sheet")

#: The types of the results a stage returns: a value annotated with one, or named as the
#: results are (``day``, ``red``), is never changed after it is made.
RESULT_TYPES = frozenset({"DayResult", "RunReduction", "HullResult", "FinResult",
                          "ScalingResult", "VehicleResult", "TareResult", "IdentifyResult",
                          "Reduced", "DayRun"})
RESULT_NAMES = frozenset({"day", "red"})
MUTATORS = frozenset({"append", "extend", "insert", "update", "pop", "clear", "setdefault",
                      "remove"})

#: Mutations of a result still there, each as (module, function, the code); none.
ALLOWED_MUTATIONS: set[tuple[str, str, str]] = set()


def pipeline_importers(edges: list[Import], root: str, unit: str) -> list[str]:
    """The modules of the layer ``unit`` that import the pipeline."""
    pipeline = f"{root}.pipeline"
    return sorted({f"{e.module} (line {e.line})" for e in edges if unit_of(e.module) == unit
                   and (e.target == pipeline or e.target.startswith(pipeline + "."))})


def day_processors(package_dir: Path) -> list[str]:
    """Modules other than the runner, the pipeline and the test tooling that call (or import)
    the pipeline's process_day or process_sheet."""
    root = package_dir.name
    out = []
    for module, path in modules(package_dir).items():
        if unit_of(module) in (RUNNER, "pipeline", "testing"):
            continue
        for node in ast.walk(parse_file(path)):
            if isinstance(node, ast.ImportFrom) and (node.module or "").endswith("pipeline") \
                    and (node.module or "").split(".")[0] in (root, ""):
                names = [a.name for a in node.names if a.name in DAY_PROCESSORS]
                out += [f"{module} (line {node.lineno}) imports {n}" for n in names]
            elif isinstance(node, ast.Attribute) and node.attr in DAY_PROCESSORS \
                    and isinstance(node.value, (ast.Name, ast.Attribute)) \
                    and ast.unparse(node.value).rpartition(".")[2] == "pipeline":
                out.append(f"{module} (line {node.lineno}) calls {ast.unparse(node)}")
    return sorted(out)


def _is_result(annotation: ast.expr | None) -> bool:
    """Whether an annotation is a result type (``DayResult``, ``"DayResult | None"``); a
    container of results (``dict[int, RunReduction]``) is not one."""
    if isinstance(annotation, ast.Constant) and isinstance(annotation.value, str):
        try:
            return _is_result(ast.parse(annotation.value, mode="eval").body)
        except SyntaxError:
            return False
    if isinstance(annotation, ast.BinOp) and isinstance(annotation.op, ast.BitOr):
        return _is_result(annotation.left) or _is_result(annotation.right)
    if isinstance(annotation, ast.Attribute):
        return annotation.attr in RESULT_TYPES
    return isinstance(annotation, ast.Name) and annotation.id in RESULT_TYPES


def _annotated(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> set[str]:
    """Names of ``fn`` (arguments and annotated locals) annotated with a result type."""
    is_result = _is_result
    args = fn.args
    names = {a.arg for a in [*args.posonlyargs, *args.args, *args.kwonlyargs]
             if is_result(a.annotation)}
    names |= {n.target.id for n in ast.walk(fn) if isinstance(n, ast.AnnAssign)
              and isinstance(n.target, ast.Name) and is_result(n.annotation)}
    return names


def _result_attribute(node: ast.expr, results: set[str]) -> bool:
    """Whether ``node`` is ``x.attr`` (or deeper) of a result-like name ``x``."""
    while isinstance(node, ast.Attribute | ast.Subscript):
        node = node.value
        if isinstance(node, ast.Name):
            return node.id in results
    return False


def result_mutations(package_dir: Path) -> set[tuple[str, str, str]]:
    """Every place a production module changes a result after it is made: a mutating call
    on one of its attributes (``day.warnings.append(...)``), an item or attribute assigned or
    deleted (``day.inputs[k] = v``, ``red.notes = [...]``), as (module, function, code)."""
    found = set()
    for module, path in modules(package_dir).items():
        if unit_of(module) == "testing":
            continue
        tree = parse_file(path)
        for fn in ast.walk(tree):
            if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            results = set(RESULT_NAMES) | _annotated(fn)
            for node in ast.walk(fn):
                code = None
                if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                        and node.func.attr in MUTATORS \
                        and _result_attribute(node.func.value, results) \
                        and isinstance(node.func.value, ast.Attribute | ast.Subscript):
                    code = f"{ast.unparse(node.func)}(...)"
                elif isinstance(node, ast.Assign | ast.AugAssign | ast.AnnAssign | ast.Delete):
                    targets = node.targets if isinstance(node, ast.Assign | ast.Delete) \
                        else [node.target]
                    code = next((f"{ast.unparse(t)} = ..." for t in targets
                                 if isinstance(t, ast.Attribute | ast.Subscript)
                                 and _result_attribute(t, results)), None)
                if code is not None:
                    found.add((module, fn.name, code))
    return found


def test_no_report_module_imports_the_pipeline():
    wrong = pipeline_importers(all_imports(PACKAGE), "towtank", "report")
    assert not wrong, "the report imports the pipeline:\n" + "\n".join(wrong)


def test_only_the_runner_processes_a_day():
    wrong = day_processors(PACKAGE)
    assert not wrong, "a day processed beside towtank.runner:\n" + "\n".join(wrong)


def test_no_result_is_changed_after_it_is_made():
    found = result_mutations(PACKAGE)
    wrong = sorted(found - ALLOWED_MUTATIONS)
    gone = sorted(ALLOWED_MUTATIONS - found)
    assert not wrong, "a result changed after it was made:\n" + "\n".join(map(str, wrong))
    assert not gone, f"fixed: take these out of ALLOWED_MUTATIONS: {gone}"


def test_a_planted_pipeline_import_and_day_processing_are_found(tmp_path):
    pkg = _package(tmp_path, {
        "pipeline.py": "def process_day(p):\n    return p\n",
        "runner.py": "from pkg.pipeline import process_day\n",
        "report/__init__.py": "",
        "report/pdf.py": "from pkg.pipeline import process_day\n",
        "live/__init__.py": "",
        "live/session.py": "def batch(s):\n    from pkg import pipeline\n"
                           "    return pipeline.process_sheet(s)\n",
        "report/fine.py": "from pkg.runner import process_day\n",
    })
    assert pipeline_importers(all_imports(pkg), "pkg", "report") == ["pkg.report.pdf (line 1)"]
    assert day_processors(pkg) == [
        "pkg.live.session (line 3) calls pipeline.process_sheet",
        "pkg.report.pdf (line 1) imports process_day"]


def test_a_planted_mutation_of_a_result_is_found(tmp_path):
    pkg = _package(tmp_path, {
        "report/__init__.py": "",
        "report/outputs.py": (
            "from dataclasses import replace\n\n"
            "def write(day, more):\n"
            "    day.warnings.append(more)\n"
            "    return replace(day, warnings=[*day.warnings, more])\n\n"
            "def add(result: 'DayResult', path, sha):\n"
            "    result.inputs[path] = sha\n"
            "    result.report_date = None\n\n"
            "def fine(day, rows):\n"
            "    rows.append(day.warnings[0])\n"
            "    warnings = list(day.warnings)\n"
            "    warnings.extend(rows)\n"
            "    return warnings\n"),
    })
    assert result_mutations(pkg) == {
        ("pkg.report.outputs", "write", "day.warnings.append(...)"),
        ("pkg.report.outputs", "add", "result.inputs[path] = ..."),
        ("pkg.report.outputs", "add", "result.report_date = ..."),
    }
