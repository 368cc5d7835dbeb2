"""The watch page's web server: a separate process serving the live state folder to a browser.

Run by ``towtank watch`` (or by hand)::

    python -m towtank.live.server --state OUT/.live --port 8050 [--host 127.0.0.1]

The server knows nothing of the day: it serves what the watcher wrote into the state folder
(``state.json`` and the PNG figures it names, each written atomically) and tells the page when
``state.json``'s ``version`` changes. Routes:

``/``                 the page (``static/index.html``)
``/state.json``       the file as written; 503 with a one-line JSON ``reason`` before the first,
                      and when it is not a regular file or is larger than :data:`MAX_READ_BYTES`
``/figures/{name}``   a figure, only if ``name`` is a value of the current state's ``figures``
                      (503 with a ``reason``, as state.json, when it cannot be read safely)
``/static/...``       the page's script and style, shipped in the package (no CDN)
``/events``           server-sent events: ``event: state`` with ``{"version": N}`` at connection
                      and whenever the version changes (the file is polled every 0.1 s), and a
                      keep-alive comment every 15 s

It listens on a loopback address only (127.0.0.1, ::1 or localhost) and answers only requests
addressed to one (a guard against DNS rebinding): the page is for the desk beside the tank, never
for the network.

Nothing in the state folder is trusted: every file is opened without following a link and
without blocking (a pipe would hang every route), checked to be a regular file and read with a
cap (a link to ``/dev/zero`` would fill the memory). ``towtank watch`` hands the server its
listening socket (``--fd``) and its own process id (``--watch-pid``): the server stops when
watch ends, however it ends.
"""

from __future__ import annotations

import argparse
import asyncio
import ctypes
import errno
import ipaddress
import json
import os
import signal
import socket
import stat
import sys
import threading
import time
from collections.abc import AsyncIterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from towtank.runtime.safefile import read_regular

if TYPE_CHECKING:
    from starlette.requests import Request
    from starlette.responses import Response
    from starlette.types import ASGIApp, Receive, Scope, Send

#: The state file the watcher writes into the state folder.
STATE_FILE = "state.json"
#: Seconds between two looks at ``state.json`` for a new version.
POLL_S = 0.1
#: Seconds between two keep-alive comments on an idle event stream.
KEEPALIVE_S = 15.0
#: Milliseconds the browser waits before reconnecting a dropped event stream.
RETRY_MS = 1000
#: The page's files, shipped as package data.
STATIC_DIR = Path(__file__).with_name("static")
#: Host names (besides loopback addresses) the server answers to.
LOOPBACK_NAMES = frozenset({"localhost"})
#: Headers that keep a browser from showing a stale state.
NO_STORE = {"Cache-Control": "no-store"}
#: Largest file (state.json, a figure) the server reads from the state folder [bytes]: the
#: watcher's state of a day is well under 1 MiB, a figure some 50 kB.
MAX_READ_BYTES = 16 << 20
#: Seconds between two looks at whether the watch process is still there, where the system
#: cannot signal its end (not Linux).
PARENT_POLL_S = 0.5


def read_capped(path: Path, max_bytes: int = MAX_READ_BYTES) -> tuple[bytes | None, str]:
    """The bytes of ``path``, or None and why not in one sentence: not there, a symbolic link,
    not a regular file (a pipe, device or folder), or larger than ``max_bytes`` [bytes].

    Opened without following a link and without blocking, checked with fstat, read with the
    cap (:func:`towtank.runtime.safefile.read_regular`): a pipe or a link to ``/dev/zero``
    neither hangs nor fills the memory.
    """
    try:
        st = os.lstat(path)
    except OSError:
        return None, f"no state yet: {path} has not been written"
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISREG(st.st_mode):
        what = "a symbolic link" if stat.S_ISLNK(st.st_mode) else \
            "not a regular file (a pipe, device or folder)"
        return None, (f"{path} is {what}, not a file towtank watch wrote; the page shows it "
                      "again once watch has written it")
    if st.st_size > max_bytes:
        return None, (f"{path} is {st.st_size / 2**20:.0f} MiB, more than the "
                      f"{max_bytes >> 20} MiB the page reads; it is not a file towtank watch "
                      "wrote")
    raw = read_regular(path, max_bytes)
    if raw is None:
        return None, f"{path} changed while it was read; it is read again at the next look"
    return raw, ""


class StateFolder:
    """The state folder as the server reads it: ``state.json`` parsed once per change.

    Parameters
    ----------
    folder : Path
        The state folder (``<output folder>/.live``).
    """

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self._key: tuple[int, int, int, int] | None = None
        self._raw: bytes | None = None
        self._state: dict[str, Any] | None = None
        self._reason = ""

    @property
    def path(self) -> Path:
        """The state file."""
        return self.folder / STATE_FILE

    def read(self) -> tuple[bytes, dict[str, Any]] | None:
        """The state file's bytes and content, or None (see :attr:`reason`) before a valid one.

        The file is re-read only when its inode, size, modification time or type changed (the
        watcher replaces it atomically, so a new version is a new inode); it is read as
        :func:`read_capped` reads.
        """
        try:
            st = os.lstat(self.path)
        except OSError:
            self._key, self._raw, self._state = None, None, None
            self._reason = f"no state yet: {self.path} has not been written"
            return None
        key = (st.st_ino, st.st_size, st.st_mtime_ns, st.st_mode)
        if key != self._key:
            self._key = key
            self._raw, self._state = None, None
            raw, why = read_capped(self.path)
            if raw is None:
                self._reason = why
                return None
            try:
                state = json.loads(raw.decode("utf-8"))
            except (UnicodeDecodeError, ValueError, RecursionError) as exc:
                self._reason = f"{self.path} cannot be read as JSON ({type(exc).__name__})"
                return None
            if not isinstance(state, dict):
                self._reason = f"{self.path} holds no JSON object"
                return None
            self._raw, self._state = raw, state
        if self._raw is None or self._state is None:
            return None
        return self._raw, self._state

    @property
    def reason(self) -> str:
        """Why :meth:`read` gave None, in one sentence."""
        return self._reason

    def version(self) -> int | None:
        """The state's ``version``, or None before a valid state."""
        got = self.read()
        if got is None:
            return None
        v = got[1].get("version")
        return v if isinstance(v, int) and not isinstance(v, bool) else None

    def figure(self, name: str) -> Path | None:
        """The path of figure ``name`` if the current state lists it and something is there,
        else None.

        Only a plain file name that is a value of the state's ``figures`` passes: no path from
        the URL reaches the disk.
        """
        got = self.read()
        if got is None:
            return None
        figures = got[1].get("figures")
        listed = {v for v in figures.values() if isinstance(v, str)} \
            if isinstance(figures, dict) else set()
        if name not in listed or not _plain_name(name):
            return None
        path = self.folder / name
        return path if os.path.lexists(path) else None


def _plain_name(name: str) -> bool:
    """True for a file name with no folder part, not hidden and with no special character."""
    return (bool(name) and name == Path(name).name and not name.startswith(".")
            and not any(c in name for c in "/\\\0:"))


def is_loopback(host: str) -> bool:
    """True when ``host`` is a loopback address (127.0.0.0/8, ::1) or ``localhost``."""
    if host.lower() in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


class LoopbackHostOnly:
    """ASGI wrapper: answer 400 to a request whose Host header is not a loopback name."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        from starlette.responses import PlainTextResponse  # loaded on use: watch's port check

        if scope["type"] == "http":
            host = ""
            for key, value in scope.get("headers", []):
                if key == b"host":
                    host = value.decode("latin-1")
                    break
            name = host[1:host.find("]")] if host.startswith("[") else host.rsplit(":", 1)[0]
            if not is_loopback(name):
                await PlainTextResponse("the watch page answers on 127.0.0.1 only",
                                        status_code=400)(scope, receive, send)
                return
        await self.app(scope, receive, send)


def create_app(state_dir: str | Path, *, poll_s: float = POLL_S,
               keepalive_s: float = KEEPALIVE_S) -> ASGIApp:
    """The page's ASGI application over one state folder.

    Parameters
    ----------
    state_dir : str or Path
        The state folder the watcher writes (``<output folder>/.live``).
    poll_s : float
        Seconds between two looks at ``state.json`` for a new version [s].
    keepalive_s : float
        Seconds between two keep-alive comments on an idle event stream [s].
    """
    # loaded on use: towtank watch takes the port check and stop_with from this module
    # without the web framework (starlette)
    from starlette.applications import Starlette
    from starlette.responses import (
        FileResponse,
        JSONResponse,
        PlainTextResponse,
        Response,
        StreamingResponse,
    )
    from starlette.routing import Mount, Route  # loaded on use: as above
    from starlette.staticfiles import StaticFiles  # loaded on use: as above

    folder = StateFolder(Path(state_dir))

    async def page(request: Request) -> Response:
        return FileResponse(STATIC_DIR / "index.html", headers=NO_STORE)

    async def state_json(request: Request) -> Response:
        got = folder.read()
        if got is None:
            return JSONResponse({"reason": folder.reason}, status_code=503, headers=NO_STORE)
        return Response(got[0], media_type="application/json", headers=NO_STORE)

    async def figure(request: Request) -> Response:
        path = folder.figure(str(request.path_params["name"]))
        if path is None:
            return PlainTextResponse("not a figure of the current state", status_code=404)
        data, why = read_capped(path)
        if data is None:
            return JSONResponse({"reason": why}, status_code=503, headers=NO_STORE)
        return Response(data, media_type="image/png", headers={"Cache-Control": "no-cache"})

    async def events(request: Request) -> Response:
        return StreamingResponse(_event_stream(request, folder, poll_s, keepalive_s),
                                 media_type="text/event-stream",
                                 headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})

    app = Starlette(routes=[
        Route("/", page),
        Route("/state.json", state_json),
        Route("/figures/{name}", figure),
        Route("/events", events),
        Mount("/static", app=StaticFiles(directory=STATIC_DIR), name="static"),
    ])
    return LoopbackHostOnly(app)


async def _event_stream(request: Request, folder: StateFolder, poll_s: float,
                        keepalive_s: float) -> AsyncIterator[str]:
    """The server-sent events of one page: the version at connection and at every change."""
    yield f"retry: {RETRY_MS}\n\n"
    sent: int | None = None
    last = time.monotonic()
    while True:
        version = folder.version()
        now = time.monotonic()
        if version is not None and version != sent:
            sent, last = version, now
            yield f"id: {version}\nevent: state\ndata: {json.dumps({'version': version})}\n\n"
        elif now - last >= keepalive_s:
            last = now
            yield ": keep-alive\n\n"
        if await request.is_disconnected():
            return
        await asyncio.sleep(poll_s)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m towtank.live.server",
        description="Serve the watch page of a state folder on a loopback address.")
    p.add_argument("--state", required=True, metavar="DIR",
                   help="the state folder the watcher writes (<output folder>/.live)")
    p.add_argument("--port", type=int, default=8050, help="TCP port (default 8050)")
    p.add_argument("--host", default="127.0.0.1",
                   help="loopback address to listen on: 127.0.0.1 (default), ::1 or localhost")
    p.add_argument("--fd", type=int, default=None, metavar="N",
                   help="serve on this inherited listening socket (bound by towtank watch to "
                   "--host and --port) instead of binding one")
    p.add_argument("--watch-pid", type=int, default=None, metavar="PID",
                   help="stop when this process, the parent (towtank watch), ends")
    return p


def _fail(message: str) -> int:
    print(f"towtank watch page: {message}", file=sys.stderr)
    return 2


def listening_socket(host: str, port: int) -> socket.socket:
    """A socket bound to ``host``:``port`` (raises OSError when the port is taken)."""
    address = "127.0.0.1" if host.lower() in LOOPBACK_NAMES else host.strip("[]")
    family = socket.AF_INET6 if ":" in address else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((address, port))
        sock.listen(64)
    except OSError:
        sock.close()
        raise
    return sock


def port_problem(host: str, port: int, exc: OSError) -> str:
    """The sentence saying why ``host``:``port`` cannot be listened on."""
    if exc.errno == errno.EADDRINUSE:
        return (f"port {port} on {host} is already in use (another watch or program): choose "
                "another with --port.")
    return f"cannot listen on {host} port {port} ({exc.strerror or exc}): choose another --port."


#: prctl's option asking for a signal when the parent ends (linux/prctl.h).
PR_SET_PDEATHSIG = 1


def stop_with(pid: int) -> bool:
    """Have this process sent SIGTERM when process ``pid``, its parent, ends, however it ends
    (SIGKILL included): Linux's ``PR_SET_PDEATHSIG``, elsewhere a thread that looks every
    :data:`PARENT_POLL_S`. False when ``pid`` is no longer the parent (it ended already)."""
    asked = False
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            asked = libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0) == 0
        except (OSError, AttributeError):
            asked = False
    if os.getppid() != pid:  # it ended before the request: no signal would come
        return False
    if not asked:
        threading.Thread(target=_stop_when_orphaned, args=(pid,), daemon=True).start()
    return True


def _stop_when_orphaned(pid: int) -> None:
    while os.getppid() == pid:
        time.sleep(PARENT_POLL_S)
    os.kill(os.getpid(), signal.SIGTERM)


def main(argv: Sequence[str] | None = None) -> int:
    """Serve the page until SIGINT or SIGTERM (or the end of ``--watch-pid``); 2 with one
    sentence on bad arguments."""
    args = _parser().parse_args(argv)
    if not is_loopback(args.host):
        return _fail(f"--host {args.host} is not a loopback address: the page is served on "
                     "127.0.0.1, ::1 or localhost only, never on the network.")
    if not 1 <= args.port <= 65535:
        return _fail(f"--port {args.port} is not a TCP port (1 to 65535).")
    state_dir = Path(args.state)
    if state_dir.exists() and not state_dir.is_dir():
        return _fail(f"--state {state_dir} is a file, not the state folder.")
    if args.watch_pid is not None and not stop_with(args.watch_pid):
        return 0  # watch has ended: nobody to serve
    try:
        sock = socket.socket(fileno=args.fd) if args.fd is not None else \
            listening_socket(args.host, args.port)
    except OSError as exc:
        if args.fd is not None:
            return _fail(f"--fd {args.fd} is not a listening socket ({exc.strerror or exc}).")
        return _fail(port_problem(args.host, args.port, exc))
    # loaded on use: uvicorn only once the host and port are usable, so
    # that a refusal is said at once
    import uvicorn

    config = uvicorn.Config(create_app(state_dir), log_level="warning", access_log=False,
                            lifespan="off", timeout_graceful_shutdown=1)
    shown = f"[{args.host}]" if ":" in args.host else args.host
    print(f"towtank watch page: http://{shown}:{args.port}/", flush=True)
    uvicorn.Server(config).run(sockets=[sock])
    return 0


if __name__ == "__main__":
    sys.exit(main())
