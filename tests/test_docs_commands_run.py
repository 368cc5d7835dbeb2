"""Every ``towtank …`` command quoted in README.md, docs/*.md and the comments of
protocols/*.toml runs, and ends with the exit status the documents give it (0 unless they say
otherwise); so does the example of ``towtank --help`` that inspects a sample run.

The commands are found in fenced blocks (a line that starts with ``towtank``, or with
``… && towtank``) and in inline code (`` `towtank …` ``, also across a line break). A quote that
is only a command's name (`` `towtank watch` ``) or a synopsis (placeholders: ``PROTOCOL``,
``FILE``, ``[--out DIR]``, ``a|b``, ``...``) names no files to run on and is not run. Each command
runs in-process through the command line's ``main``, from a temporary copy of the repository's
protocols/ and sample_runs/, so that nothing is written into the repository; the commands of one
document run in its order (a ``predict`` writes the model.json the next ``simulate`` reads), and a
command quoted twice runs once.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from conftest import draw_only_pages
from test_vehicle_inputs import hang_bound  # a command that hangs fails its test

from towtank.commands import watch
from towtank.commands.cli import EPILOG, main

REPO = Path(__file__).resolve().parents[1]
FENCE = re.compile(r"^```[^\n]*\n(.*?)^```", re.S | re.M)
SPAN = re.compile(r"`([^`]+)`")
#: A placeholder of a synopsis: a word in capitals (PROTOCOL, FILE, MODEL.json, N), an optional
#: part, alternatives or an ellipsis.
PLACEHOLDER = re.compile(r"(^|\s)[A-Z][A-Z0-9_]*(\.[A-Za-z0-9]+)?(\s|$)|\[|\||\.\.\.|…")
#: Longest a documented command may take here before it counts as hung [s].
HANG_S = 300
#: `towtank watch` runs until Ctrl-C, "exit 130" (README, "At the tank"); the test stops it
#: once it has given the runs already in the data folder their verdicts.
EXIT_STATUS = {"watch": 130}
#: Documented commands that fail because of a known bug of another issue.
KNOWN_BUGS: dict[str, str] = {}


@dataclass(frozen=True)
class Quoted:
    """A command quoted in a document: its text, where, and how (fenced, inline, comment)."""

    command: str
    source: str
    line: int
    how: str

    @property
    def runnable(self) -> bool:
        """Names files to run on: more than a command's name, and no placeholder."""
        words = self.command.split()
        return words[1:] == ["--help"] or (len(words) > 2 and not PLACEHOLDER.search(
            self.command))


def _inline(text: str, source: str, how: str) -> Iterator[Quoted]:
    for m in SPAN.finditer(text):
        command = " ".join(m.group(1).split())
        if command.startswith("towtank "):
            yield Quoted(command, source, text.count("\n", 0, m.start()) + 1, how)


def markdown_commands(path: Path) -> list[Quoted]:
    """The ``towtank …`` commands of a Markdown file, in fenced blocks and inline code."""
    text = path.read_text(encoding="utf-8")
    source = str(path.relative_to(REPO))
    out = []
    for block in FENCE.finditer(text):
        first = text.count("\n", 0, block.start(1)) + 1
        for i, line in enumerate(block.group(1).splitlines()):
            k = line.find("towtank ")
            if k < 0 or (line[:k].strip() and not line[:k].strip().endswith("&&")):
                continue
            out.append(Quoted(line[k:].split("  #")[0].strip(), source, first + i, "fenced"))
    rest = FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    return out + list(_inline(rest, source, "inline"))


def protocol_commands(path: Path) -> list[Quoted]:
    """The ``towtank …`` commands in inline code in a protocol's comments."""
    lines = path.read_text(encoding="utf-8").splitlines()
    text = "\n".join(ln.lstrip()[1:] if ln.lstrip().startswith("#") else "" for ln in lines)
    return list(_inline(text, str(path.relative_to(REPO)), "comment"))


def quoted_commands() -> list[Quoted]:
    docs = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
    return [q for p in docs for q in markdown_commands(p)] + [
        q for p in sorted((REPO / "protocols").glob("*.toml")) for q in protocol_commands(p)]


QUOTED = quoted_commands()
RUNNABLE = [q for q in QUOTED if q.runnable]
#: The example of `towtank --help` that inspects a run of the sample day.
HELP_INSPECT = next(ln.strip() for ln in EPILOG.splitlines()
                    if ln.strip().startswith("towtank inspect "))


def _case(q: Quoted):  # noqa: ANN202 - a pytest ParameterSet
    marks = [pytest.mark.xfail(strict=True, reason=KNOWN_BUGS[q.command])] \
        if q.command in KNOWN_BUGS else []
    return pytest.param(q, marks=marks, id=f"{q.source}:{q.line}:{q.command}")


class Workspace:
    """A temporary copy of protocols/ and sample_runs/ where the documented commands run."""

    def __init__(self, root: Path) -> None:
        self.root = root
        for name in ("protocols", "sample_runs"):
            shutil.copytree(REPO / name, root / name)
        self.done: dict[str, tuple[int, str]] = {}

    def run(self, command: str) -> tuple[int, str]:
        """Exit status and output of ``command`` (once per command text)."""
        if command not in self.done:
            out = io.StringIO()
            here = Path.cwd()
            os.chdir(self.root)
            try:
                with hang_bound(HANG_S), contextlib.redirect_stdout(out), \
                        contextlib.redirect_stderr(out):
                    try:
                        code = main(shlex.split(command)[1:])
                    except SystemExit as exc:  # --help
                        code = int(exc.code or 0)
            finally:
                os.chdir(here)
            self.done[command] = (code, out.getvalue())
        return self.done[command]

    def run_upto(self, q: Quoted) -> tuple[int, str]:
        """When ``q`` names a file that is still missing (an output of another command: a
        model.json), run the commands quoted before ``q`` in its document (their outputs may
        be its inputs) and the documented command whose ``--out`` is its folder
        (``reports/glider/model.json`` ← ``towtank predict … --out reports/glider``); then
        ``q``. A command whose files are all there (a protocol, the sample runs) runs on its
        own: whichever pytest worker it falls on, the days before it are not processed again."""
        missing = self._missing_folders(q)
        before = RUNNABLE[:RUNNABLE.index(q)] if missing else []
        for other in [b for b in before if b.source == q.source] + [
                b for b in RUNNABLE if _out(b) in missing]:
            if other != q and other.command not in KNOWN_BUGS and _verb(other) not in EXIT_STATUS:
                self.run(other.command)
        return self.run(q.command)

    def _missing_folders(self, q: Quoted) -> set[str]:
        """The folders of the files ``q`` names (``a/b/model.json``) that do not exist yet."""
        return {str(Path(w).parent) for w in shlex.split(q.command)[2:]
                if "/" in w and Path(w).suffix and not (self.root / w).exists()}


def _out(q: Quoted) -> str | None:
    """The ``--out`` folder a command writes into, if it says."""
    words = shlex.split(q.command)
    return words[words.index("--out") + 1] if "--out" in words[:-1] else None


def _verb(q: Quoted) -> str:
    return q.command.split()[1]


@pytest.fixture(scope="session")
def workspace(tmp_path_factory) -> Workspace:
    return Workspace(tmp_path_factory.mktemp("docs_commands"))


@pytest.fixture
def no_watch_loop(monkeypatch):
    """`towtank watch` gives the runs already there their verdicts, then a Ctrl-C stops it
    (no page server, no browser)."""
    def ctrl_c(self):  # noqa: ANN001, ANN202
        raise KeyboardInterrupt

    monkeypatch.setattr(watch.WatchSession, "run", ctrl_c)
    monkeypatch.setattr(watch, "start_server", lambda live_dir, port: None)
    monkeypatch.setattr(watch.webbrowser, "open", lambda url: True)


@pytest.fixture
def report_text_pages(monkeypatch):
    """The commands' PDF reports with their text pages drawn (title, summary, runs, quality)
    and their figure and thumbnail pages blank, still numbered: this test asks whether a
    documented command runs and ends as documented. Every page of both sample days' reports is
    drawn by ``towtank process`` and compared byte for byte with the API's in
    tests/test_one_front_door.py, and their pixels with the golden ones in
    tests/test_golden_outputs.py."""
    draw_only_pages(monkeypatch, lambda page: page.kind not in ("figure", "thumbs"))


def test_the_documents_quote_commands_to_run():
    """The extraction finds the commands a newcomer types (a miss would make the test below
    vacuous): the sample days, watch, the vehicle stage's predict → simulate/steady chains."""
    found = {q.command for q in RUNNABLE}
    for command in ("towtank process protocols/sut2_hull.toml",
                    "towtank process protocols/naca0015_fin.toml",
                    "towtank watch protocols/sut2_hull.toml", "towtank --help",
                    "towtank predict protocols/remus_vehicle.toml",
                    "towtank simulate reports/remus/model.json --manoeuvre turning"):
        assert command in found, command
    assert {q.source for q in RUNNABLE} >= {"README.md", "docs/method.md",
                                           "protocols/glider_parametric.toml"}
    skipped = [q.command for q in QUOTED if not q.runnable]
    assert "towtank inspect FILE" in skipped and "towtank watch" in skipped


@pytest.mark.heavy
@pytest.mark.parametrize("quoted", [_case(q) for q in RUNNABLE])
def test_every_documented_command_runs(quoted, workspace, no_watch_loop, report_text_pages):
    code, out = workspace.run_upto(quoted)
    expected = EXIT_STATUS.get(_verb(quoted), 0)
    assert code == expected, f"{quoted.source}:{quoted.line}: {quoted.command}\n{out[-3000:]}"


def test_the_help_example_inspects_a_run_that_succeeds(workspace):
    code, out = workspace.run(HELP_INSPECT)
    assert code == 0, out
    assert "steady means" in out and "plot: " in out
