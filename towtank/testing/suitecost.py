"""Where a test run's time goes: a pytest plugin, apart from the suite (it asserts nothing).

``python -m pytest -q -n 2 -p towtank.testing.suitecost --suite-cost cost.csv``

For every test of the run it records, over the test's whole protocol (set-up, call,
tear-down):

* ``wall_s``: the wall-clock time [s];
* ``cpu_s``: the CPU time of the test process [s] (user + system, :func:`resource.getrusage`
  ``RUSAGE_SELF``: every thread of it);
* ``children_s``: the CPU time of the child processes the test process waited for in it [s]
  (``RUSAGE_CHILDREN``: a command the test started, a forked writer or a worker pool it
  reaped). A process that another child started (a fork server's workers) is counted when
  that child ends, in the test where it ends.

A shared fixture's set-up (session, package or module scope) is part of the first test that
asks for it; it is also listed on its own (``fixture`` rows, not added to the totals), so that
a fixture set up once per pytest-xdist worker shows as often as it is set up. Each process of
the run (the pytest-xdist workers and the process that started them) also gets an ``outside``
row: its CPU outside the tests (imports, collection, the end of the session), its whole CPU by
``RUSAGE_SELF`` less its tests'.

With pytest-xdist each worker writes its rows into a folder of the run's; the process that
started the run joins them into the CSV file (``kind, worker, name, wall_s, cpu_s,
children_s``) and prints the totals, the heaviest tests and files, and the fixtures set up
more than once. Linux and macOS (the ``resource`` module).
"""

from __future__ import annotations

import atexit
import csv
import os
import resource
import shutil
import tempfile
import time
from collections import Counter, defaultdict
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

__all__ = ["COLUMNS", "check_output", "read_rows", "summary_lines"]

#: The CSV's columns, in order.
COLUMNS = ("kind", "worker", "name", "wall_s", "cpu_s", "children_s")
#: The variable that names the folder the test processes write their rows into; set by the
#: process that starts the run, inherited by its pytest-xdist workers.
PARTS_ENV = "TOWTANK_SUITE_COST_PARTS"
#: Fixture scopes listed on their own.
SHARED_SCOPES = ("session", "package", "module")


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("towtank suite cost")
    group.addoption("--suite-cost", metavar="PATH", default=None,
                    help="write the wall and CPU time of every test (and of its child "
                         "processes) to PATH (CSV) and print where the run's time went")
    group.addoption("--suite-cost-top", metavar="N", type=int, default=15,
                    help="tests and files listed in the printed summary (default 15)")
    group.addoption("--suite-cost-limit", metavar="CPU_S", type=float, default=None,
                    help="also list every test of the run that cost more than CPU_S CPU-s "
                         "with its child processes (the suite marks such tests heavy)")


def _cpu(who: int) -> float:
    """User + system CPU time [s] of this process (``RUSAGE_SELF``) or of its waited-for
    children (``RUSAGE_CHILDREN``)."""
    use = resource.getrusage(who)
    return use.ru_utime + use.ru_stime


class _Recorder:
    """The rows of one test process, written to its part file as they come."""

    def __init__(self, parts: Path, worker: str) -> None:
        self._self, self._children = resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN
        self.worker = worker
        self.path = parts / f"{worker}.csv"
        self._fh = open(self.path, "w", newline="", encoding="utf-8")  # noqa: SIM115
        self._out = csv.writer(self._fh)
        self._out.writerow(COLUMNS)
        self.test_cpu = 0.0

    def row(self, kind: str, name: str, wall: float, cpu: float, children: float) -> None:
        self._out.writerow([kind, self.worker, name, f"{wall:.4f}", f"{cpu:.4f}",
                            f"{children:.4f}"])
        self._fh.flush()

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item: pytest.Item) -> Iterator[None]:
        wall0, cpu0, child0 = time.perf_counter(), _cpu(self._self), _cpu(self._children)
        yield
        cpu = _cpu(self._self) - cpu0
        self.test_cpu += cpu
        self.row("test", item.nodeid, time.perf_counter() - wall0, cpu,
                 _cpu(self._children) - child0)

    @pytest.hookimpl(hookwrapper=True)
    def pytest_fixture_setup(self, fixturedef: Any) -> Iterator[None]:
        if fixturedef.scope not in SHARED_SCOPES:
            yield
            return
        wall0, cpu0, child0 = time.perf_counter(), _cpu(self._self), _cpu(self._children)
        yield
        self.row("fixture", f"{fixturedef.argname} ({fixturedef.scope})",
                 time.perf_counter() - wall0, _cpu(self._self) - cpu0,
                 _cpu(self._children) - child0)

    def close(self) -> None:
        """The ``outside`` row (this process's CPU outside its tests), then the file closed."""
        self.row("outside", "start-up, collection and the session's end", 0.0,
                 max(0.0, _cpu(self._self) - self.test_cpu), 0.0)
        self._fh.close()


def pytest_configure(config: pytest.Config) -> None:
    path = config.getoption("--suite-cost")
    if path is None:
        return
    workerinput = getattr(config, "workerinput", None)
    if workerinput is None:  # the process that started the run: the folder of the parts
        check_output(Path(path))
        parts = Path(tempfile.mkdtemp(prefix="towtank-suite-cost-"))
        atexit.register(shutil.rmtree, parts, ignore_errors=True)  # an interrupted run too
        os.environ[PARTS_ENV] = str(parts)  # before pytest-xdist starts its workers
        config.stash[_PARTS] = parts
        config.stash[_STARTED] = time.perf_counter()
        worker = "main"
    else:
        parts = Path(os.environ[PARTS_ENV])
        worker = str(workerinput["workerid"])
    recorder = _Recorder(parts, worker)
    config.stash[_RECORDER] = recorder
    config.pluginmanager.register(recorder, "towtank-suite-cost-recorder")


def check_output(path: Path) -> None:
    """Refuse (:class:`pytest.UsageError`, one sentence) an output path that holds anything
    but an earlier run's suite-cost file, before the run: no other file is overwritten."""
    if not path.exists() and not path.is_symlink():
        return
    try:
        with open(path, encoding="utf-8", newline="") as fh:
            ours = path.is_file() and not path.is_symlink() and (
                fh.readline().rstrip("\r\n") == ",".join(COLUMNS))
    except (OSError, UnicodeDecodeError):
        ours = False
    if not ours:
        raise pytest.UsageError(f"--suite-cost: {path} exists and is not a suite-cost file "
                                f"written by an earlier run; give a new path.")


def pytest_unconfigure(config: pytest.Config) -> None:
    recorder = config.stash.get(_RECORDER, None)
    if recorder is not None and getattr(config, "workerinput", None) is not None:
        recorder.close()  # a worker: its rows are complete


def pytest_terminal_summary(terminalreporter: Any, config: pytest.Config) -> None:
    parts = config.stash.get(_PARTS, None)
    if parts is None:
        return  # not asked for, or a worker
    config.stash[_RECORDER].close()  # this process's own rows (the tests of a run without -n)
    rows = [r for f in sorted(parts.glob("*.csv")) for r in read_rows(f)]
    out = Path(config.getoption("--suite-cost"))
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows({k: r[k] for k in COLUMNS} for r in rows)
    os.replace(tmp, out)
    shutil.rmtree(parts, ignore_errors=True)
    terminalreporter.section("towtank suite cost")
    run_wall = time.perf_counter() - config.stash[_STARTED]
    for line in summary_lines(rows, top=config.getoption("--suite-cost-top"),
                              run_wall_s=run_wall,
                              limit_cpu_s=config.getoption("--suite-cost-limit")):
        terminalreporter.write_line(line)
    terminalreporter.write_line(f"every row: {out}")


_PARTS = pytest.StashKey[Path]()
_RECORDER = pytest.StashKey[_Recorder]()
_STARTED = pytest.StashKey[float]()


def read_rows(path: str | Path) -> list[dict[str, Any]]:
    """The rows of a suite-cost CSV file (or of one process's part of it), times as floats."""
    with open(path, newline="", encoding="utf-8") as fh:
        return [{**r, **{k: float(r[k]) for k in ("wall_s", "cpu_s", "children_s")}}
                for r in csv.DictReader(fh)]


def summary_lines(rows: list[dict[str, Any]], *, top: int = 15,
                  run_wall_s: float | None = None,
                  limit_cpu_s: float | None = None) -> list[str]:
    """What the run's time went to, as printed: the totals, the ``top`` heaviest tests and
    files by CPU (the test process's and its children's), and the shared fixtures set up more
    than once at a cost (0.01 CPU-s or more beyond the costliest set-up). ``run_wall_s``: the
    run's wall time [s], from its configuration to the summary (with it, the average number of
    cores the run kept busy). ``limit_cpu_s``: with it, every test over that many CPU-s [s] is
    listed last, whatever ``top`` (a shared fixture's set-up counts in the first test that asks
    for it, so a light test can be listed for its fixture: the fixtures' rows tell)."""
    tests = [r for r in rows if r["kind"] == "test"]
    outside = [r for r in rows if r["kind"] == "outside"]
    cost = {r["name"]: r["cpu_s"] + r["children_s"] for r in tests}
    own, children = sum(r["cpu_s"] for r in tests), sum(r["children_s"] for r in tests)
    lines = [
        f"{len(tests):,} tests: {own + children:.1f} CPU-s ({own:.1f} in the test processes, "
        f"{children:.1f} in the processes they waited for), {sum(r['wall_s'] for r in tests):.1f}"
        f" s of wall time",
        f"outside the tests: {sum(r['cpu_s'] for r in outside):.1f} CPU-s in "
        f"{len(outside)} process(es) (start-up, collection, the session's end)",
    ]
    if run_wall_s is not None:
        busy = own + children + sum(r["cpu_s"] for r in outside)
        lines.append(f"the run: {run_wall_s:.1f} s of wall time, {busy:.1f} CPU-s counted "
                     f"({busy / max(run_wall_s, 1e-9):.2f} cores busy on average)")
    by_file: Counter[str] = Counter()
    count: Counter[str] = Counter()
    for name, c in cost.items():
        by_file[name.split("::", 1)[0]] += c
        count[name.split("::", 1)[0]] += 1
    total = max(own + children, 1e-9)
    lines.append(f"heaviest tests (CPU-s with their child processes; share of {total:.1f}):")
    for name, c in sorted(cost.items(), key=lambda kv: -kv[1])[:top]:
        lines.append(f"  {c:7.2f}  {100 * c / total:4.1f} %  {name}")
    lines.append("heaviest files:")
    for name, c in by_file.most_common(top):
        lines.append(f"  {c:7.2f}  {100 * c / total:4.1f} %  {name} ({count[name]} tests)")
    setups: defaultdict[str, list[float]] = defaultdict(list)
    for r in rows:
        if r["kind"] == "fixture":
            setups[r["name"]].append(r["cpu_s"] + r["children_s"])
    again = sorted(((sum(v) - max(v), k, len(v)) for k, v in setups.items()
                    if len(v) > 1 and sum(v) - max(v) >= 0.01), reverse=True)
    if again:
        lines.append("shared fixtures set up more than once (CPU-s beyond the first set-up):")
        for extra, name, n in again[:top]:
            lines.append(f"  {extra:7.2f}  {name}: {n} set-ups")
    if limit_cpu_s is not None:
        over = sorted(((c, name) for name, c in cost.items() if c > limit_cpu_s), reverse=True)
        lines.append(f"tests over {limit_cpu_s:g} CPU-s: {len(over)}")
        lines.extend(f"  {c:7.2f}  {name}" for c, name in over)
    return lines
