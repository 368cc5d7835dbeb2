"""Issue 20 item 12, issue 22: Ctrl-C in a terminal reaches the whole process group.

A terminal sends SIGINT to every process of the foreground group: ``towtank process``, its
fork server (perhaps still loading its libraries), its workers and the report's writers. Only
the main process may answer: exit 130, one sentence on stderr, no traceback from any process,
no process left behind and the output folder exactly as it was.

Each moment is reached for sure, not guessed from a delay: ``TOWTANK_TEST_PAUSE_AT`` holds the
main process at that stage until the signal comes (towtank.runtime.pause).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import weakref
from pathlib import Path

import pytest
from conftest import lab_environment

from towtank.runtime import interrupt, parallel
from towtank.runtime.pause import STAGES

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "protocols" / "sut2_hull.toml"

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="process groups and /proc")


def _towtank(*args: str, env: dict[str, str] | None = None) -> subprocess.Popen:
    """``towtank ARGS`` (the console script beside this Python, else ``python -m towtank``),
    in a process group of its own, as a terminal starts it."""
    script = Path(sys.executable).with_name("towtank")
    cmd = [str(script)] if script.is_file() else [sys.executable, "-m", "towtank"]
    return subprocess.Popen([*cmd, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, start_new_session=True)


def _environment(**extra: str) -> dict[str, str]:
    env = lab_environment()  # every core: the fork server, its workers, the forked writers
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    env.update(extra)
    return env


def _processes() -> dict[int, tuple[int, int, str, str]]:
    """pid -> (parent pid, process group, state, command line) of every process."""
    out = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(
                errors="replace")
        except OSError:
            continue
        out[int(entry.name)] = (int(fields[1]), int(fields[2]), fields[0], cmdline)
    return out


def _alive_in_group(pgid: int) -> dict[int, str]:
    """The processes of group ``pgid`` that are not dead (zombies waiting to be reaped are)."""
    return {pid: cmd for pid, (_, group, state, cmd) in _processes().items()
            if group == pgid and state != "Z"}


def _wait_for_pause(proc: subprocess.Popen, marker: Path, stage: str,
                    timeout: float = 180.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if marker.exists() and marker.read_text().startswith(f"{stage} "):
            return
        if proc.poll() is not None:
            raise AssertionError(f"towtank ended (exit {proc.returncode}) before reaching "
                                 f"{stage!r}: {proc.communicate()[1]}")
        time.sleep(0.02)
    raise AssertionError(f"towtank never reached {stage!r}")


def _digest(folder: Path) -> dict[str, str]:
    """sha256 of every file under ``folder`` (hidden ones and the cache too)."""
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture(scope="session")
def sample_out(tmp_path_factory, sample_report) -> Path:
    """The sample day processed once, completely (in this process: only the interrupted runs
    below need a process of their own): the outputs a Ctrl-C must leave alone. A copy of the
    session's written sample day (``sample_report``), which these tests must not touch."""
    out = tmp_path_factory.mktemp("interrupt") / "out"
    shutil.copytree(sample_report("sut2_hull").out, out)
    return out


def _sigint_kept_out(pid: int) -> bool:
    """Whether process ``pid`` ignores or blocks SIGINT (a Ctrl-C cannot stop it)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return True  # gone meanwhile
    masks = dict(line.split(":\t", 1) for line in status.splitlines() if ":\t" in line)
    bit = 1 << (signal.SIGINT - 1)
    return bool((int(masks["SigIgn"], 16) | int(masks["SigBlk"], 16)) & bit)


def _at_the_moment(stage: str, main_pid: int) -> None:
    """The group is where ``stage`` says it is (so that the signal hits what it should), and
    every process of it but the main one keeps Ctrl-C out."""
    procs = {pid: info for pid, info in _processes().items() if info[1] == main_pid}
    others = [pid for pid, info in procs.items() if pid != main_pid and info[2] != "Z"]
    assert not [(pid, procs[pid][3]) for pid in others if not _sigint_kept_out(pid)]
    assert not _sigint_kept_out(main_pid)
    server = [pid for pid, info in procs.items() if "multiprocessing.forkserver" in info[3]]
    workers = [pid for pid, info in procs.items() if info[0] in server and info[2] != "Z"]
    forked = [pid for pid, info in procs.items() if info[0] == main_pid and pid not in server
              and "resource_tracker" not in info[3] and info[2] != "Z"]
    if stage == "start":
        assert set(procs) == {main_pid}, procs
    if parallel.default_jobs() < 2:
        return  # no worker pool on one core
    if stage == "preload":  # the fork server is loading its libraries: no worker yet
        assert server and not workers, procs
    elif stage == "reduce":
        assert workers, procs
    elif stage == "writing":
        assert forked, procs


@pytest.mark.heavy
@pytest.mark.parametrize("stage", STAGES)
def test_ctrl_c_to_the_whole_group_is_exit_130_in_one_line(sample_out, tmp_path, stage):
    out = sample_out
    before = _digest(out)
    beside = sorted(p.name for p in out.parent.iterdir())
    marker = tmp_path / "paused"
    proc = _towtank("process", str(SAMPLE), "--out", str(out), "--no-cache",
                    env=_environment(TOWTANK_TEST_PAUSE_AT=stage,
                                     TOWTANK_TEST_PAUSE_FILE=str(marker)))
    try:
        _wait_for_pause(proc, marker, stage)
        _at_the_moment(stage, proc.pid)
        os.killpg(proc.pid, signal.SIGINT)  # what a terminal's Ctrl-C does
        stdout, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 130, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("towtank: interrupted"), err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    assert stdout == ""
    end = time.monotonic() + 5.0  # the main process ended them; give the kernel a moment
    while _alive_in_group(proc.pid) and time.monotonic() < end:
        time.sleep(0.05)
    assert not _alive_in_group(proc.pid)
    assert _digest(out) == before
    assert sorted(p.name for p in out.parent.iterdir()) == beside  # no temporary folder left


# ------------------------------------------------------------------ the pieces, in process
@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals reach the main thread only")
def test_a_ctrl_c_that_a_finalizer_dropped_is_raised_again():
    """Python drops an exception raised inside a weakref callback ("Exception ignored"): a
    Ctrl-C that came just then must not be lost (the day would end with exit 0)."""

    class Thing:
        pass

    def callback(_ref: object) -> None:
        os.kill(os.getpid(), signal.SIGINT)  # the handler runs here: KeyboardInterrupt, dropped

    hook = sys.unraisablehook
    with interrupt.watching() as seen:
        if signal.getsignal(signal.SIGINT) is not interrupt._handler:
            pytest.skip("Ctrl-C is handled by someone else here")
        thing = Thing()
        ref = weakref.ref(thing, callback)
        with pytest.raises(KeyboardInterrupt):
            del thing  # the callback runs, its KeyboardInterrupt is dropped...
            time.sleep(5)  # ...and raised again here
        assert seen and ref() is None
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert sys.unraisablehook is hook


def test_check_raises_a_dropped_ctrl_c():
    with interrupt.watching() as seen:
        interrupt.check()  # nothing came
        seen.append(True)  # as the handler does
        with pytest.raises(KeyboardInterrupt):
            interrupt.check()
        interrupt.handled()
        interrupt.check()  # reported: the process ends
    interrupt.check()


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="POSIX signal masks")
def test_processes_started_while_sigint_is_blocked_are_born_with_it_blocked():
    code = ("import signal; print(signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, []))")
    with parallel._sigint_blocked():
        inside = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    after = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert inside.stdout.strip() == "True" and after.stdout.strip() == "False"
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])


def _write_slowly(path: Path) -> None:
    path.write_text("started")
    time.sleep(30)
    path.write_text("finished")


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals reach the main thread only")
def test_run_beside_kills_its_processes_when_interrupted(tmp_path):
    if threading.active_count() > 1:
        pytest.skip("run_beside forks only when this process has one thread")
    files = [tmp_path / f"part{k}" for k in range(2)]

    def first() -> None:
        end = time.monotonic() + 10.0
        # a file exists from its open on, before "started" is in it: wait for the text
        while not all(f.exists() and f.read_text() == "started" for f in files) \
                and time.monotonic() < end:
            time.sleep(0.01)
        raise KeyboardInterrupt  # Ctrl-C while the others run

    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        parallel.run_beside([("first", first)] + [
            (f.name, lambda f=f: _write_slowly(f)) for f in files])
    assert time.monotonic() - start < 10.0
    assert [f.read_text() for f in files] == ["started", "started"]
    assert not [c for c in _processes().values() if c[0] == os.getpid() and c[2] != "Z"
                and "resource_tracker" not in c[3] and "forkserver" not in c[3]]


def test_the_pause_hook_does_nothing_without_its_variable(monkeypatch):
    from towtank.runtime.pause import pause_at

    monkeypatch.delenv("TOWTANK_TEST_PAUSE_AT", raising=False)
    slept: list[float] = []
    monkeypatch.setattr(time, "sleep", slept.append)
    for stage in STAGES:
        pause_at(stage)
    assert slept == []  # never held
