"""Issue 33 ("Trust, third round"), towtank watch and its page server.

- watch never writes or removes through a symbolic link in its own places (``.live``, its lock,
  state.json, the figures, the leftovers of a killed watch) nor into a folder it did not make:
  one sentence, exit 2, the user's files byte for byte as they were;
- a full disk while the live state, its figures or the report are written is one sentence,
  said once, and the verdicts go on; the files there stay whole;
- SIGTERM, SIGHUP or SIGKILL to watch stops its page server (the port is free again), and a
  port in use is refused in one sentence before anything is written;
- the page server reads nothing from the state folder that could hang it or fill the memory
  (a FIFO, a link to /dev/zero, a huge file, a folder): 503 with one sentence, the other routes
  still answer.

The command runs in-process (``towtank.commands.cli.main``) except where the process is what is
tested (signals, a parent killed). Waits are bounded by timeouts that only catch a hang.
"""

from __future__ import annotations

import errno
import json
import os
import queue
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from towtank.commands import cli
from towtank.live import session as live_session
from towtank.live import state as live_state
from towtank.live.session import WatchSession
from towtank.testing import synthetic as syn
from towtank.testing.bench_watch import start_watch, watch_session
from towtank.testing.browser import free_port
from towtank.testing.days import RunSpec

ROOT = Path(__file__).resolve().parents[1]
HANG_S = 60.0  # bounds a hang only
PLAN = [RunSpec("sting", 0.0, v, 0.5) for v in (0.8, 1.6, 2.0)] + \
    [RunSpec("hull", 0.0, 1.6, 0.5)]


def make_day(root: Path) -> Path:
    """A generated day whose run files wait in ``root/all`` (the data folder is empty); the
    protocol ``root/p.toml`` writes into ``root/out``."""
    syn.make_hull_day(root / "day", runs=PLAN, fs=50.0, file_format="csv", sheet_format="csv",
                      seed=7)
    shutil.move(root / "day" / "data", root / "all")
    (root / "day" / "data").mkdir()
    sections = syn.hull_protocol_sections("day", "out", sheet_format="csv")
    sections["watch"] = {"settle_s": 1.0, "pdf_interval_s": 0.0}
    return syn.write_protocol(root / "p.toml", **sections)


def snapshot(folder: Path) -> dict[str, Any]:
    """Every entry under ``folder`` (links not followed): a file's bytes, a link's target."""
    out: dict[str, Any] = {}
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder).as_posix()
        if path.is_symlink():
            out[rel] = ("link", os.readlink(path))
        elif path.is_dir():
            out[rel] = ("folder",)
        else:
            out[rel] = ("file", path.read_bytes())
    return out


@pytest.fixture
def no_loop(monkeypatch):
    """``towtank watch`` in-process without its endless loop: a watch that is not refused
    returns 0 after its first look instead of watching forever."""
    monkeypatch.setattr(WatchSession, "run", lambda self, *a, **k: None)


def watch(protocol: Path, capsys, *extra: str) -> tuple[int, str, str]:
    code = cli.main(["watch", str(protocol), "--no-browser", "--no-report", *extra])
    got = capsys.readouterr()
    return code, got.out, got.err


def one_sentence(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("towtank: ") and ". " not in lines[0] and "Traceback" not in err
    return lines[0]


# --------------------------------------------------------------------- 3. links in watch's places
def _user_folder(root: Path) -> Path:
    """A folder of the user's holding what watch would write or remove in its live folder."""
    mine = root / "mine"
    (mine / ".report-keep").mkdir(parents=True)
    (mine / ".report-keep" / "draft.pdf").write_bytes(b"%PDF my draft")
    (mine / ".report-3").mkdir()
    (mine / ".report-3" / "report.pdf").write_bytes(b"%PDF my report")
    (mine / ".fits-1.json").write_text('{"mine": "yes"}')
    (mine / "state.json").write_text('{"my": "state"}')
    (mine / "latest_run.png").write_bytes(b"my png")
    (mine / "notes.txt").write_text("my notes\n")
    return mine


def _live_is_a_link(live: Path, mine: Path) -> None:
    live.parent.mkdir(parents=True, exist_ok=True)
    live.symlink_to(mine, target_is_directory=True)


def _in_live(name: str, target: str) -> Callable[[Path, Path], None]:
    def plant(live: Path, mine: Path) -> None:
        live.mkdir(parents=True)
        (live / name).symlink_to(mine / target)
    return plant


def _users_live_folder(live: Path, mine: Path) -> None:
    shutil.copytree(mine, live)  # a real folder, not made by towtank


def _lock_of_the_user(live: Path, mine: Path) -> None:
    live.mkdir(parents=True)
    (live / live_state.MARKER_NAME).write_bytes(live_state.MARKER_TEXT)
    (live / ".watch.lock").write_text("my lock notes\n")


def _live_is_a_file(live: Path, mine: Path) -> None:
    live.parent.mkdir(parents=True, exist_ok=True)
    live.symlink_to(mine / "notes.txt")


LINK_CASES = {
    ".live is a link to the user's folder": (_live_is_a_link, "symbolic link"),
    ".live is a link to the user's file": (_live_is_a_file, "symbolic link"),
    ".watch.lock is a link to notes.txt": (_in_live(".watch.lock", "notes.txt"), "link"),
    "state.json is a link": (_in_live("state.json", "state.json"), "symbolic link"),
    "latest_run.png is a link": (_in_live("latest_run.png", "latest_run.png"), "symbolic link"),
    ".fits-1.json is a link": (_in_live(".fits-1.json", ".fits-1.json"), "symbolic link"),
    ".report-3 is a link to a folder": (_in_live(".report-3", ".report-3"), "symbolic link"),
    ".live is the user's own folder": (_users_live_folder, "did not make"),
    ".watch.lock is the user's file": (_lock_of_the_user, "not the lock file"),
}


@pytest.mark.parametrize("case", list(LINK_CASES))
def test_a_link_or_a_foreign_entry_in_watchs_places_is_refused_untouched(
        tmp_path, capsys, no_loop, case):
    protocol = make_day(tmp_path)
    shutil.copy(tmp_path / "all" / "run_001.csv", tmp_path / "day" / "data" / "run_001.csv")
    mine = _user_folder(tmp_path)
    live = tmp_path / "out" / ".live"
    plant, words = LINK_CASES[case]
    plant(live, mine)
    before_mine, before_live = snapshot(mine), snapshot(live) if live.is_dir() else None
    code, out, err = watch(protocol, capsys, "--no-server")
    sentence = one_sentence(err)
    assert code == 2, err
    assert words in sentence and "--out" in sentence and str(live) in sentence
    assert snapshot(mine) == before_mine  # byte for byte
    if before_live is not None and not live.is_symlink():
        assert snapshot(live) == before_live
    assert not (tmp_path / "out" / "runs.csv").exists()  # nothing processed nor written
    assert "run 1" not in out


@pytest.mark.heavy
def test_a_link_put_in_the_live_folder_while_watching_is_one_sentence(tmp_path):
    protocol = make_day(tmp_path)
    s, lines = session_of(protocol)
    mine = _user_folder(tmp_path)
    s.step()
    (s.live_dir / "state.json").unlink()
    (s.live_dir / "state.json").symlink_to(mine / "state.json")
    before = snapshot(mine)
    for k in (1, 2):
        arrive(s, tmp_path, k)
    assert [line[:6] for line in lines if line.startswith("run ")] == ["run 1 ", "run 2 "]
    said = [m for m in s.said.messages if "symbolic link" in m]
    assert len(said) == 1 and "verdicts go on" in said[0]
    assert snapshot(mine) == before
    assert (s.live_dir / "state.json").is_symlink()
    s.close()


def test_a_live_folder_of_an_earlier_watch_is_taken_and_only_its_leftovers_removed(tmp_path):
    """A .live an earlier towtank watch made (before the marker): its leftovers of a killed
    watch go, anything else stays; a user's `.report-keep/` in a marked folder is never
    removed."""
    protocol = make_day(tmp_path)
    live = tmp_path / "out" / ".live"
    live.mkdir(parents=True)
    (live / ".watch.lock").write_text("4242")
    (live / "state.json").write_text(json.dumps({"version": 3, "verdicts": []}))
    (live / "latest_run.png").write_bytes(b"png")
    (live / ".report-4" / "figures").mkdir(parents=True)
    (live / ".report-4" / "report.pdf").write_bytes(b"%PDF")
    (live / ".fits-2.json").write_text("{}")
    (live / ".state.json.a1b2c3.tmp").write_text("{")
    s, _lines = session_of(protocol, live_figures=False)
    assert sorted(p.name for p in live.iterdir()) == [
        ".towtank-live", ".watch.lock", "latest_run.png", "state.json"]
    s.close()
    (live / ".report-keep").mkdir()
    (live / ".report-keep" / "mine.pdf").write_bytes(b"%PDF mine")
    (live / "notes.txt").write_text("mine")
    session_of(protocol, live_figures=False)[0].close()
    assert (live / ".report-keep" / "mine.pdf").read_bytes() == b"%PDF mine"
    assert (live / "notes.txt").read_text() == "mine"


# --------------------------------------------------------------------- 8. a full disk
def session_of(protocol: Path, **kw: Any) -> tuple[WatchSession, list[str]]:
    """The session of ``protocol`` in this process, drawing the live page's figures."""
    return watch_session(protocol, **{"live_figures": True, **kw})


def arrive(s: WatchSession, root: Path, run: int) -> list:
    """Run ``run``'s file copied into the data folder and seen settled: its verdict."""
    name = f"run_{run:03d}.csv"
    shutil.copy(root / "all" / name, root / "day" / "data" / name)
    s.clock = lambda: time.time() + 10.0 * run
    return s.step()


def _full(*args: Any, **kwargs: Any) -> None:
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


@pytest.mark.heavy
def test_a_full_disk_under_the_live_state_is_one_sentence_and_the_verdicts_go_on(
        tmp_path, monkeypatch):
    protocol = make_day(tmp_path)
    s, lines = session_of(protocol)
    arrive(s, tmp_path, 1)
    state_path = s.live_dir / "state.json"
    before = state_path.read_bytes()
    monkeypatch.setattr(live_state, "atomic_write_bytes", _full)  # state.json and figures
    for run in (2, 3):
        verdicts = arrive(s, tmp_path, run)
        assert [v.run for v in verdicts] == [run]
    assert sum(line.startswith(("run 2 ", "run 3 ")) for line in lines) == 2
    said = [m for m in s.said.messages if "No space left on device" in m]
    assert len(said) == len(set(said)), said  # each once, not per run
    state_said = [m for m in said if m.startswith("the live page's state could not")]
    assert len(state_said) == 1, s.said.messages
    assert "verdicts go on" in state_said[0] and str(s.live_dir) in state_said[0]
    assert state_path.read_bytes() == before  # whole: the last version written
    json.loads(before)
    monkeypatch.undo()  # room again: the page catches up
    arrive(s, tmp_path, 4)
    state = json.loads(state_path.read_text())
    assert [v["run"] for v in state["verdicts"]] == [1, 2, 3, 4]
    assert state["messages"][-1] == state_said[0]
    s.close()


def test_a_full_disk_under_the_report_drawing_is_one_sentence(tmp_path, monkeypatch):
    protocol = make_day(tmp_path)
    s, lines = session_of(protocol, report=True, live_figures=False)
    monkeypatch.setattr(live_session, "write_pdf", _full)  # in the forked drawing
    for run in (1, 2):
        arrive(s, tmp_path, run)
        job = s._job
        assert job is not None  # a drawing was started for the runs so far
        s._collect_report(wait=True)
        assert not job[1].exists()  # its folder removed
    said = [m for m in s.said.messages if "No space left on device" in m]
    assert len(said) == 1 and said[0].startswith("report.pdf and figures/"), s.said.messages
    assert "verdicts go on" in said[0]
    assert not any("could not be drawn" in m for m in s.said.messages)
    assert [line[:6] for line in lines if line.startswith("run ")] == ["run 1 ", "run 2 "]
    s.close()


# --------------------------------------------------------------------- 9. the page server's end
def test_a_port_in_use_is_refused_before_the_url_and_before_anything_is_written(
        tmp_path, capsys, no_loop):
    protocol = make_day(tmp_path)
    shutil.copy(tmp_path / "all" / "run_001.csv", tmp_path / "day" / "data" / "run_001.csv")
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        code, out, err = watch(protocol, capsys, "--port", str(port))
    sentence = one_sentence(err)
    assert code == 2
    assert f"port {port}" in sentence and "--port" in sentence and "in use" in sentence
    assert "http://" not in out and "run 1" not in out
    assert not (tmp_path / "out").exists()


def _start_watch(tmp_path: Path, port: int) -> tuple[subprocess.Popen[str], list[str]]:
    proc = start_watch(make_day(tmp_path), "--no-report", "--port", str(port))
    lines: queue.Queue[str | None] = queue.Queue()

    def pump() -> None:
        for line in proc.stdout or ():
            lines.put(line)
        lines.put(None)

    threading.Thread(target=pump, daemon=True).start()
    said: list[str] = []
    end = time.monotonic() + HANG_S
    while not any("the live page:" in line for line in said):
        assert time.monotonic() < end, f"no page line: {''.join(said)}"
        try:
            line = lines.get(timeout=1.0)
        except queue.Empty:
            continue
        assert line is not None, f"watch ended: {proc.stderr.read() if proc.stderr else ''}"
        said.append(line)
    _until(lambda: _get(port, "/") == 200, "the page")
    return proc, said


def _get(port: int, path: str) -> int | None:
    """The status of a GET of ``path`` on 127.0.0.1:``port``, None when nothing answers."""
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
            s.sendall(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                      "Connection: close\r\n\r\n".encode())
            head = s.recv(64).decode("latin-1")
    except OSError:
        return None
    parts = head.split()
    return int(parts[1]) if len(parts) > 1 and parts[1].isdigit() else None


def _refused(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
    except ConnectionRefusedError:
        return True
    except OSError:
        return False
    return False


def _until(check: Callable[[], bool], what: str) -> None:
    end = time.monotonic() + HANG_S
    while not check():
        assert time.monotonic() < end, f"{what} never came"
        time.sleep(0.1)


@pytest.mark.heavy
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="signals of Linux")
@pytest.mark.parametrize(("how", "code"), [("SIGTERM", 128 + 15), ("SIGHUP", 128 + 1),
                                           ("SIGKILL", -9)])
def test_the_page_server_stops_when_watch_is_ended_by_a_signal(tmp_path, how, code):
    port = free_port()
    proc, _said = _start_watch(tmp_path, port)
    try:
        os.kill(proc.pid, getattr(signal, how))  # watch alone, not its process group
        assert proc.wait(timeout=HANG_S) == code
        _until(lambda: _refused(port), f"port {port} free after {how}")
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # the page server too, whatever happened
        except ProcessLookupError:
            pass
        proc.wait(timeout=HANG_S)
    err = proc.stderr.read() if proc.stderr else ""
    assert "Traceback" not in err
    if how != "SIGKILL":
        assert f"stopped by {how}" in err
    assert _refused(port)  # and the next watch may take it


# --------------------------------------------------------------------- 10. what the server reads
with warnings.catch_warnings():  # starlette 1.x prefers httpx2; httpx works the same here
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient  # noqa: E402

from towtank.live import server  # noqa: E402

PNG = bytes.fromhex("89504e470d0a1a0a0000000d4948445200000001000000010806000000"
                    "1f15c4890000000d49444154789c6360f8cfc00000030101007a3b2c0f00"
                    "00000049454e44ae426082")


def _state(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    state = {"version": 1, "figures": {"latest_run": "latest_run.png"}, "verdicts": []}
    (folder / "state.json").write_text(json.dumps(state))
    (folder / "latest_run.png").write_bytes(PNG)


def _fifo(path: Path) -> None:
    os.mkfifo(path)


def _zero(path: Path) -> None:
    path.symlink_to("/dev/zero")


CAP = 16 << 20  # the server's cap on what it reads [bytes], as docs/formats.md states it


def _huge(path: Path) -> None:
    with open(path, "wb") as fh:  # sparse: no disk used
        fh.truncate(CAP + 1)


def _folder(path: Path) -> None:
    path.mkdir()


BAD = {"a FIFO": (_fifo, "not a regular file"), "a link to /dev/zero": (_zero, "symbolic link"),
       "a huge file": (_huge, "16 MiB"), "a folder": (_folder, "not a regular file")}


def _bounded(call: Callable[[], Any]) -> Any:
    """``call()`` in a thread, failing (not hanging) when it has not returned in 20 s."""
    box: list[Any] = []
    worker = threading.Thread(target=lambda: box.append(call()), daemon=True)
    worker.start()
    worker.join(20.0)
    assert box, "the request hung"
    return box[0]


def _unblock(path: Path) -> None:
    """A reader hung on the FIFO ``path`` (the old server) gets its end of file."""
    try:
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
    except OSError:
        pass


@pytest.mark.parametrize("bad", list(BAD))
@pytest.mark.parametrize("name", ["state.json", "latest_run.png"])
def test_an_unreadable_file_in_the_state_folder_is_503_and_the_rest_answers(
        tmp_path, bad, name):
    folder = tmp_path / ".live"
    _state(folder)
    path = folder / name
    path.unlink()
    plant, words = BAD[bad]
    plant(path)
    client = TestClient(server.create_app(folder), base_url="http://127.0.0.1:8050")
    route = "/state.json" if name == "state.json" else "/figures/latest_run.png"
    try:
        r = _bounded(lambda: client.get(route))
        assert r.status_code == 503
        reason = r.json()["reason"]
        assert words in reason and str(path) in reason and "\n" not in reason
        assert reason.count(". ") == 0
        assert _bounded(lambda: client.get("/")).status_code == 200
        assert _bounded(lambda: client.get("/static/page.js")).status_code == 200
        if name != "state.json":  # the state itself still served
            assert _bounded(lambda: client.get("/state.json")).status_code == 200
    finally:
        if bad == "a FIFO":
            _unblock(path)
