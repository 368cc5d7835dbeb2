"""``towtank watch``: the day processed run by run while the tank runs (docs/formats.md,
"towtank watch").

Loads the libraries once, gives a verdict line per run already in the data folder, then
watches the data folder and the run sheet (:class:`towtank.live.session.WatchSession`),
starts the page server (``python -m towtank.live.server``, a process of its own) and opens the
page in a browser. Ctrl-C ends it: the output folder holds the last complete set.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import webbrowser
from pathlib import Path
from typing import TextIO

from towtank.errors import ProtocolError
from towtank.ingest.protocol import load_protocol, with_output_dir
from towtank.live.session import WatchSession
from towtank.live.state import LIVE_DIR
from towtank.report.safetext import clean_text
from towtank.runtime import parallel
from towtank.runtime.manifest import recover_outputs, try_lock

EXIT_UNUSABLE = 2
SERVER_MODULE = "towtank.live.server"


def _err(msg: str) -> None:
    print(f"towtank: {clean_text(msg)}", file=sys.stderr, flush=True)


def _say(line: str) -> None:
    print(clean_text(line), flush=True)


def start_server(live_dir: Path, port: int) -> subprocess.Popen[bytes] | None:
    """The page server as a process of its own, or None (said why) when it cannot start."""
    if importlib.util.find_spec(SERVER_MODULE) is None:
        _err(f"the page server ({SERVER_MODULE}) is not installed; watching without the "
             "browser page.")
        return None
    try:
        return subprocess.Popen(
            [sys.executable, "-m", SERVER_MODULE, "--state", str(live_dir), "--port",
             str(port)], stdin=subprocess.DEVNULL)
    except OSError as exc:
        _err(f"the page server could not be started ({exc.strerror or exc}); watching "
             "without the browser page.")
        return None


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
    open (the process's life); ProtocolError when another ``towtank watch`` holds it."""
    live_dir.mkdir(parents=True, exist_ok=True)
    fh = open(live_dir / ".watch.lock", "a+", encoding="utf-8")  # noqa: SIM115 - held open
    if not try_lock(fh.fileno()):
        fh.seek(0)
        other = fh.read().strip()
        fh.close()
        raise ProtocolError(
            f"another towtank watch{f' (process {other})' if other.isdigit() else ''} is "
            f"already watching into {live_dir.parent}; stop it first or give --out another "
            "folder.")
    fh.seek(0)
    fh.truncate()
    fh.write(str(os.getpid()))
    fh.flush()
    return fh


def watch_command(args: argparse.Namespace) -> int:
    """The ``watch`` sub-command; returns the exit status (KeyboardInterrupt goes up)."""
    if args.out is not None:
        recovered = recover_outputs(Path(args.out).resolve())
        if recovered:
            _err(recovered)
    try:
        protocol = load_protocol(args.protocol)
        protocol, out = with_output_dir(
            protocol, args.out if args.out is not None else protocol.campaign.output_dir)
    except ProtocolError as exc:
        _err(str(exc))
        return EXIT_UNUSABLE
    jobs = args.jobs if args.jobs is not None else protocol.processing.jobs
    if jobs is not None and jobs > parallel.default_jobs():
        jobs = parallel.default_jobs()
    try:  # one watcher per output folder: two would write over each other's live state
        lock = hold_watch_lock(Path(out).resolve() / LIVE_DIR)
    except ProtocolError as exc:
        _err(str(exc))
        return EXIT_UNUSABLE
    except OSError as exc:
        _err(f"the output folder {out} cannot be written ({exc.strerror or exc}).")
        return EXIT_UNUSABLE
    session = WatchSession(protocol, out, jobs=jobs, report=not args.no_report,
                           date=args.date, echo=_say)
    out = session.out
    if not args.quiet:
        _say(f"{protocol.name}: watching {session.data_dir} and {session.sheet_path.name}; "
             f"outputs in {out}. Ctrl-C to stop.")
    try:
        session.step()  # the runs already there: their verdicts, the outputs
    except ProtocolError as exc:
        _err(str(exc))
        return EXIT_UNUSABLE
    server = None
    try:
        if not args.no_server:
            server = start_server(out / LIVE_DIR, args.port)
            if server is not None:
                url = f"http://127.0.0.1:{args.port}/"
                _say(f"the live page: {url}")
                if not args.no_browser:
                    webbrowser.open(url)
        session.run()
    except KeyboardInterrupt:  # the workers and the fork server ignore Ctrl-C: ended here
        parallel.end_forkserver()
        raise
    finally:
        session.close()
        stop_server(server)
        lock.close()  # the next watch of this folder may start
        if session.pdf_stale and session.day is not None and len(session.day.runs):
            covered = ("has no report.pdf yet" if session.pdf_runs is None else
                       f"has a report.pdf of {len(session.pdf_runs)} of the "
                       f"{len(session.day.runs)} runs so far")
            _err(f"the output folder {covered}; 'towtank process' writes the whole report "
                 "(the runs come from the cache).")
    return 0
