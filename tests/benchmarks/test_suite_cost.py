"""The suite-cost plugin (towtank.testing.suitecost) counts what it says: a test's own CPU, the
CPU of the processes it waited for, and sleeping as wall time only; with pytest-xdist every
worker's rows are joined into one file. No time of towtank is asserted: the tests burn known
CPU themselves (``time.process_time``) and check the plugin's account of it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from towtank.testing import suitecost

BURN_S = 0.3  # [s] of CPU each burning test spends, by its own process clock

TESTS = f"""\
import subprocess, sys, time

import pytest

BURN = (f"import time\\nend = time.process_time() + {BURN_S}\\n"
        "while time.process_time() < end: pass")


@pytest.fixture(scope="session")
def shared():
    return 1


def test_burns(shared):
    exec(BURN)


def test_sleeps(shared):
    time.sleep({BURN_S})


def test_waits_for_a_child(shared):
    subprocess.run([sys.executable, "-c", BURN], check=True)
"""


@pytest.fixture(scope="module")
def xdist_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, list[dict]]:
    """The three tests above run by two pytest-xdist workers with ``--suite-cost``: what
    pytest printed and the rows of the file."""
    folder = tmp_path_factory.mktemp("suite_cost")
    (folder / "test_three.py").write_text(TESTS, encoding="utf-8")
    out = folder / "cost.csv"
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p",
         "towtank.testing.suitecost", "--suite-cost", str(out), "-n", "2", "--rootdir",
         str(folder), str(folder / "test_three.py")],
        cwd=folder, capture_output=True, text=True, timeout=300, check=False,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(
            p for p in (str(Path(suitecost.__file__).parents[2]),
                        os.environ.get("PYTHONPATH")) if p)})
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout, suitecost.read_rows(out)


@pytest.mark.heavy
def test_each_test_is_counted_once_with_its_own_and_its_childrens_cpu(xdist_run):
    _, rows = xdist_run
    tests = {r["name"].split("::")[1]: r for r in rows if r["kind"] == "test"}
    assert sorted(tests) == ["test_burns", "test_sleeps", "test_waits_for_a_child"]
    burns, sleeps, waits = (tests[n] for n in sorted(tests))
    # the CPU the test spent is in its own column, and the wall time holds it
    assert burns["cpu_s"] >= BURN_S - 0.005 and burns["wall_s"] >= burns["cpu_s"] - 0.005
    assert burns["children_s"] == 0.0
    # sleeping is wall time, not CPU
    assert sleeps["wall_s"] >= BURN_S - 0.005 and sleeps["cpu_s"] < BURN_S / 2
    # the child's CPU (its start-up and its burn) is the child's column, not the test's
    assert waits["children_s"] >= BURN_S - 0.005 and waits["cpu_s"] < BURN_S / 2


@pytest.mark.heavy
def test_the_workers_rows_are_joined_with_each_processs_cpu_outside_the_tests(xdist_run):
    printed, rows = xdist_run
    tests = [r for r in rows if r["kind"] == "test"]
    outside = {r["worker"]: r for r in rows if r["kind"] == "outside"}
    assert {r["worker"] for r in tests} <= {"gw0", "gw1"}
    assert sorted(outside) == ["gw0", "gw1", "main"]  # each worker and the starting process
    assert all(r["cpu_s"] > 0 for r in outside.values())
    fixtures = [r for r in rows if r["kind"] == "fixture"]
    # the session fixture: set up once by each worker that ran a test of it
    assert len(fixtures) == len({r["worker"] for r in tests})
    assert all(r["name"] == "shared (session)" for r in fixtures)
    assert "towtank suite cost" in printed and "3 tests:" in printed
    assert printed.index("test_waits_for_a_child") < printed.index("test_sleeps")  # by cost


def test_summary_adds_the_columns_and_ranks_the_heaviest():
    def row(kind, worker, name, wall, cpu, children):
        return dict(zip(suitecost.COLUMNS, (kind, worker, name, wall, cpu, children),
                        strict=True))

    rows = [row("test", "gw0", "a.py::t1", 2.0, 1.0, 0.5),
            row("test", "gw1", "b.py::t2", 5.0, 3.0, 0.0),
            row("test", "gw1", "a.py::t3", 0.5, 0.25, 0.0),
            row("fixture", "gw0", "day (session)", 1.0, 0.75, 0.0),
            row("fixture", "gw1", "day (session)", 1.0, 0.5, 0.0),
            row("outside", "gw0", "x", 0.0, 2.0, 0.0),
            row("outside", "gw1", "x", 0.0, 2.0, 0.0)]
    lines = suitecost.summary_lines(rows, top=2, run_wall_s=5.0)
    assert lines[0].startswith("3 tests: 4.8 CPU-s (4.2 in the test processes, 0.5 in")
    assert "4.0 CPU-s in 2 process(es)" in lines[1]
    assert "8.8 CPU-s counted (1.75 cores busy" in lines[2]
    listed = [line.split()[-1] for line in lines if line.startswith("  ") and "%" in line]
    assert listed[:2] == ["b.py::t2", "a.py::t1"]  # the two heaviest tests, heaviest first
    assert lines[-1] == "     0.50  day (session): 2 set-ups"  # all but the costlier one
    limited = suitecost.summary_lines(rows, top=1, limit_cpu_s=1.25)
    # every test over the limit, whatever top: the heavy tests a run has not marked
    assert limited[-3:] == ["tests over 1.25 CPU-s: 2", "     3.00  b.py::t2",
                            "     1.50  a.py::t1"]
    assert suitecost.summary_lines(rows, limit_cpu_s=3.0)[-1] == "tests over 3 CPU-s: 0"


def test_an_output_path_holding_another_file_is_refused_before_the_run(tmp_path):
    """Only an earlier run's suite-cost file is overwritten; any other file, a folder or a
    link is refused in one sentence, and nothing is written."""
    earlier = tmp_path / "earlier.csv"
    earlier.write_text(",".join(suitecost.COLUMNS) + "\n", encoding="utf-8")
    suitecost.check_output(earlier)
    suitecost.check_output(tmp_path / "new.csv")
    notes = tmp_path / "notes.csv"
    notes.write_text("run,speed\n1,1.2\n", encoding="utf-8")
    link = tmp_path / "link.csv"
    link.symlink_to(earlier)
    for path in (notes, tmp_path, link, tmp_path / "dangling.csv"):
        if path.name == "dangling.csv":
            path.symlink_to(tmp_path / "nowhere")
        with pytest.raises(pytest.UsageError, match="exists and is not a suite-cost file"):
            suitecost.check_output(path)
    assert notes.read_text(encoding="utf-8") == "run,speed\n1,1.2\n"


@given(st.lists(st.tuples(
    st.sampled_from(["test", "fixture", "outside"]),
    st.text(min_size=1, max_size=30).filter(lambda s: "\x00" not in s),
    st.floats(0, 1e4, allow_nan=False), st.floats(0, 1e4, allow_nan=False),
    st.floats(0, 1e4, allow_nan=False)), max_size=8))
def test_a_part_file_reads_back_as_written(tmp_path_factory, entries):
    """Any name (commas, quotes, line ends) and time read back as written, to the 0.1 ms the
    file keeps."""
    folder = tmp_path_factory.mktemp("part")
    recorder = suitecost._Recorder(folder, "gw7")
    for kind, name, wall, cpu, children in entries:
        recorder.row(kind, name, wall, cpu, children)
    recorder._fh.close()
    back = suitecost.read_rows(recorder.path)
    assert [(r["kind"], r["worker"], r["name"]) for r in back] == [
        (kind, "gw7", name) for kind, name, *_ in entries]
    for r, (_, _, *times) in zip(back, entries, strict=True):
        for column, value in zip(("wall_s", "cpu_s", "children_s"), times, strict=True):
            assert r[column] == pytest.approx(value, abs=5e-5 + 1e-12 * value)
