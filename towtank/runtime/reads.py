"""Every file a day reads, recorded as it is opened (so that none can be left out).

The day's replay fingerprint (:class:`towtank.runtime.cache.DayStamp`) must change when any
file the day read changes: the protocol and the run sheet, but also a tare table, a hull
table, a reference CSV, a zeros file, and any file a future section names. Rather than a list
of such files kept by hand, :func:`recording` records every file opened for reading in this
process (a :func:`sys.addaudithook` hook on Python's ``open`` event, which every reader goes
through: ``open``, ``Path.read_*``, pandas, openpyxl, numpy), with its stat as it was opened;
files of the Python installation, towtank's own code and the system's folders are left out.
The run files read in worker processes are stamped by the workers themselves.
"""

from __future__ import annotations

import contextlib
import os
import stat
import sys
import sysconfig
import threading
from collections.abc import Iterator
from pathlib import Path

__all__ = ["recording", "Recorder", "Stamp"]

Stamp = tuple[int, int, int, int]  # (size, mtime_ns, ctime_ns, inode)

_lock = threading.Lock()
_recorders: list[dict[str, Stamp | None]] = []
_installed = False


def _reading(mode: object, flags: object) -> bool:
    if isinstance(mode, str):
        return not any(c in mode for c in "wax+")
    if isinstance(flags, int):
        return flags & (os.O_WRONLY | os.O_RDWR) == 0
    return True


def _hook(event: str, args: tuple) -> None:
    if event != "open" or not _recorders:
        return
    try:
        path, mode, flags = args
        if path is None or isinstance(path, int) or not _reading(mode, flags):
            return
        name = os.path.abspath(os.fsdecode(path))
    except Exception:  # noqa: BLE001 - an audit hook must never raise
        return
    with _lock:
        for rec in _recorders:
            if name not in rec:
                rec[name] = _stamp(name)


def _stamp(name: str) -> Stamp | None:
    try:
        st = os.stat(name)
    except (OSError, ValueError):
        return None
    if not stat.S_ISREG(st.st_mode):
        return None
    return (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)


def _system_roots() -> tuple[str, ...]:
    """Folders whose files are not a day's inputs: the Python installation (its libraries
    and their data), towtank's own code (in the day's fingerprint already) and the system's."""
    roots = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix,
             str(Path(__file__).resolve().parents[1])}
    for key in ("stdlib", "platstdlib", "purelib", "platlib", "data"):
        with contextlib.suppress(KeyError):
            roots.add(sysconfig.get_paths()[key])
    roots.update(p for p in sys.path if p and os.path.isdir(p) and "site-packages" in p)
    roots.update(("/proc", "/sys", "/dev", "/etc", "/usr", "/lib", "/run"))
    return tuple(os.path.join(os.path.abspath(r), "") for r in roots if r)


class Recorder:
    """The files opened for reading in this process between its start and :meth:`stop`."""

    def __init__(self, skip: list[str | Path]):
        #: folders whose files are not inputs (e.g. the output folder's cache); may be added
        #: to until :meth:`stop`
        self.skip = skip
        #: after :meth:`stop`: every regular file opened for reading, by absolute path, with
        #: its (size, mtime_ns, ctime_ns, inode) as it was first opened
        self.files: dict[str, Stamp] = {}
        self._seen: dict[str, Stamp | None] = {}
        self._on = False

    def start(self) -> Recorder:
        global _installed
        with _lock:
            if not _installed:
                sys.addaudithook(_hook)
                _installed = True
            if not self._on:
                _recorders.append(self._seen)
                self._on = True
        return self

    def stop(self) -> dict[str, Stamp]:
        """Stop recording; return (and keep in :attr:`files`) what was opened."""
        with _lock:
            if self._on:
                _recorders.remove(self._seen)
                self._on = False
        roots = _system_roots() + tuple(os.path.join(os.path.abspath(s), "")
                                        for s in self.skip)
        self.files = {name: st for name, st in self._seen.items()
                      # None: not a regular file (or gone): a probe, a folder
                      if st is not None and not name.startswith(roots)
                      and not any(name == os.path.abspath(s) for s in self.skip)}
        return self.files


@contextlib.contextmanager
def recording(skip: list[str | Path] | None = None) -> Iterator[Recorder]:
    """Record the files opened for reading in this process while the block runs (or until
    the recorder's :meth:`Recorder.stop`).

    Files under (or equal to) an entry of ``skip`` and under :func:`_system_roots` are left
    out.
    """
    rec = Recorder(list(skip or ())).start()
    try:
        yield rec
    finally:
        rec.stop()
