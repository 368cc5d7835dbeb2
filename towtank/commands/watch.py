"""``towtank watch``: the day processed run by run while the tank runs (docs/formats.md,
"towtank watch").

Loads the libraries once, gives a verdict line per run already in the data folder, then
watches the data folder and the run sheet (:class:`towtank.live.session.WatchSession`),
starts the page server (``python -m towtank.live.server``, a process of its own) and opens the
page in a browser. Ctrl-C, SIGTERM or SIGHUP ends it: the output folder holds the last complete
set and the page server is stopped (and stops by itself if watch is killed).
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import importlib.util
import os
import signal
import socket
import stat
import subprocess
import sys
import threading
import webbrowser
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

from towtank.errors import ProtocolError
from towtank.live.server import listening_socket, port_problem
from towtank.live.session import WatchSession, watch_options
from towtank.live.state import LIVE_DIR, WATCH_LOCK, claim_live_dir, refusal
from towtank.report.safetext import clean_text
from towtank.runner import DayStopped, Plan, prepare
from towtank.runtime import parallel
from towtank.runtime.manifest import try_lock

EXIT_UNUSABLE = 2
SERVER_MODULE = "towtank.live.server"
#: The page server's address: loopback only.
HOST = "127.0.0.1"
#: Signals that end watch as Ctrl-C does (the page server stopped, the outputs whole).
END_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP")
                    if hasattr(signal, name))


class Stopped(BaseException):
    """SIGTERM or SIGHUP came: watch ends as after Ctrl-C, with exit 128 + the signal."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


@dataclass
class EndSignals:
    """The SIGTERM and SIGHUP that came (``came``); ``ending``: watch is ending already."""

    came: list[int] = field(default_factory=list)
    ending: bool = False


@contextlib.contextmanager
def ending_on_signals() -> Iterator[EndSignals]:
    """Within the block, SIGTERM and SIGHUP raise :class:`Stopped` in the main thread until
    watch is ending (``ending``), so that the page server and the drawings are stopped and
    the lock let go as after Ctrl-C; each is also recorded (watchfiles turns any exception a
    signal handler raises into KeyboardInterrupt). Outside the main thread nothing changes."""
    got = EndSignals()
    if threading.current_thread() is not threading.main_thread():
        yield got
        return

    def handler(signum: int, frame: object) -> None:
        got.came.append(signum)
        if not got.ending:
            raise Stopped(signum)

    previous = {sig: signal.signal(sig, handler) for sig in END_SIGNALS}
    try:
        yield got
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


def _err(msg: str) -> None:
    print(f"towtank: {clean_text(msg)}", file=sys.stderr, flush=True)


def _say(line: str) -> None:
    print(clean_text(line), flush=True)


def start_server(live_dir: Path, sock: socket.socket) -> subprocess.Popen[bytes] | None:
    """The page server as a process of its own, serving on ``sock`` (bound and listening;
    closed here, the server keeps its copy) and stopping when this process ends however it
    ends; or None (said why) when it cannot start."""
    port = sock.getsockname()[1]
    try:
        if any(importlib.util.find_spec(m) is None for m in ("starlette", "uvicorn")):
            _err("the page server's libraries (starlette, uvicorn) are not installed; "
                 "watching without the browser page.")
            return None
        return subprocess.Popen(
            [sys.executable, "-m", SERVER_MODULE, "--state", str(live_dir), "--port",
             str(port), "--host", HOST, "--fd", str(sock.fileno()),
             "--watch-pid", str(os.getpid())],
            stdin=subprocess.DEVNULL, pass_fds=(sock.fileno(),))
    except OSError as exc:
        _err(f"the page server could not be started ({exc.strerror or exc}); watching "
             "without the browser page.")
        return None
    finally:
        sock.close()  # forked drawings must not hold the port after the server ends


def stop_server(proc: subprocess.Popen[bytes] | None) -> None:
    """End the page server (SIGTERM, then SIGKILL after 5 s)."""
    if proc is None or proc.poll() is not None:
        return
    proc.terminate()
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def hold_watch_lock(live_dir: Path) -> TextIO:
    """An exclusive lock on ``live_dir/.watch.lock``, held while the returned file stays
    open (the process's life); ProtocolError when another ``towtank watch`` holds it, when
    ``live_dir`` is not towtank's live folder (:func:`towtank.live.state.claim_live_dir`) or
    when the lock is a link or a file towtank did not write (only a process id is written
    there)."""
    claim_live_dir(live_dir)
    path = live_dir / WATCH_LOCK
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags, 0o666)
    except OSError as exc:
        if exc.errno in (errno.ELOOP, errno.ENXIO, errno.EISDIR):
            raise ProtocolError(refusal(path, "a symbolic link or not a regular file")) from None
        raise
    fh = os.fdopen(fd, "r+", encoding="utf-8", errors="replace")
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise ProtocolError(refusal(path, "not a regular file"))
        held = fh.read(64).strip()
        if held and not held.isdigit():
            raise ProtocolError(refusal(path, "not the lock file towtank watch writes"))
        if not try_lock(fd):
            raise ProtocolError(
                f"another towtank watch{f' (process {held})' if held.isdigit() else ''} is "
                f"already watching into {live_dir.parent}; stop it first or give --out another "
                "folder.")
        fh.seek(0)
        fh.truncate()
        fh.write(str(os.getpid()))
        fh.flush()
    except BaseException:
        fh.close()
        raise
    return fh


def listen(port: int) -> socket.socket:
    """The page's listening socket on 127.0.0.1:``port``; ProtocolError (one sentence naming
    the port and --port) when it is taken."""
    try:
        return listening_socket(HOST, port)
    except OSError as exc:
        raise ProtocolError(port_problem(HOST, port, exc)) from None


def watch_command(args: argparse.Namespace) -> int:
    """The ``watch`` sub-command; returns the exit status (KeyboardInterrupt goes up)."""
    try:  # the protocol loaded and the output folder checked as towtank process does
        plan = prepare(args.protocol, args.out, watch_options(
            jobs=args.jobs, report=not args.no_report, date=args.date))
    except DayStopped as exc:
        for note in exc.notes:
            _err(note)
        _err(str(exc))
        return EXIT_UNUSABLE
    for note in plan.notes:  # outputs an interrupted run left aside, put back
        _err(note)
    assert plan.out is not None
    try:  # the port first: a port in use stops watch before anything is written
        sock = None if args.no_server else listen(args.port)
    except ProtocolError as exc:
        _err(str(exc))
        return EXIT_UNUSABLE
    try:  # one watcher per output folder: two would write over each other's live state
        lock = hold_watch_lock(plan.out / LIVE_DIR)
    except (ProtocolError, OSError) as exc:
        if sock is not None:
            sock.close()
        _err(str(exc) if isinstance(exc, ProtocolError) else
             f"the output folder {plan.out} cannot be written ({exc.strerror or exc}).")
        return EXIT_UNUSABLE
    with ending_on_signals() as signals:
        try:
            return _watch(args, plan, sock)
        except (Stopped, KeyboardInterrupt):
            if not signals.came:
                raise  # Ctrl-C: the command line's sentence and exit 130
            signals.ending = True
            parallel.end_forkserver()
            first = signals.came[0]
            _err(f"stopped by {signal.Signals(first).name}; the output folder holds the "
                 "outputs of the last complete run (or none), never a part of one.")
            return 128 + first
        finally:
            lock.close()  # the next watch of this folder may start


def _watch(args: argparse.Namespace, plan: Plan, sock: socket.socket | None) -> int:
    """Watch with the lock held: the session, the page server (on ``sock``), the loop."""
    assert plan.out is not None
    server = None if sock is None else start_server(plan.out / LIVE_DIR, sock)
    session = None
    try:
        session = WatchSession(plan, echo=_say)
        out = session.out
        if not args.quiet:
            _say(f"{plan.protocol.name}: watching {session.data_dir} and "
                 f"{session.sheet_path.name}; outputs in {out}. Ctrl-C to stop.")
        try:
            session.step()  # the runs already there: their verdicts, the outputs
        except ProtocolError as exc:
            _err(str(exc))
            return EXIT_UNUSABLE
        if server is not None:
            url = f"http://{HOST}:{args.port}/"
            _say(f"the live page: {url}")
            if not args.no_browser:
                webbrowser.open(url)
        session.run()
    except ProtocolError as exc:  # the live folder is not towtank's
        _err(str(exc))
        return EXIT_UNUSABLE
    except KeyboardInterrupt:  # the workers and the fork server ignore Ctrl-C: ended here
        parallel.end_forkserver()
        raise
    finally:
        stop_server(server)
        if session is not None:
            session.close()
            _say_pdf_behind(session)
    return 0


def _say_pdf_behind(session: WatchSession) -> None:
    if session.pdf_stale and session.day is not None and len(session.day.runs):
        covered = ("has no report.pdf yet" if session.pdf_runs is None else
                   f"has a report.pdf of {len(session.pdf_runs)} of the "
                   f"{len(session.day.runs)} runs so far")
        _err(f"the output folder {covered}; 'towtank process' writes the whole report "
             "(the runs come from the cache).")
