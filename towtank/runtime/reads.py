"""Every file a day reads, recorded as it is opened (so that none can be left out).

The day's replay fingerprint (:class:`towtank.runtime.cache.DayStamp`) must change when any
file the day read changes: the protocol and the run sheet, but also a tare table, a hull
table, a reference CSV, a zeros file, and any file a future section names. Rather than a list
of such files kept by hand, :func:`recording` records every file opened for reading in this
process (a :func:`sys.addaudithook` hook on Python's ``open`` event, which every reader goes
through: ``open``, ``Path.read_*``, pandas, openpyxl, numpy), with its stat as it was opened,
wherever it lives; only towtank's own code, Python's standard library and installed libraries
(recorded in the fingerprint by their versions) and the kernel's pseudo file systems are left
out (:func:`exempt_roots`).
The run files read in worker processes are stamped by the workers themselves.
"""

from __future__ import annotations

import contextlib
import mimetypes
import os
import stat
import sys
import sysconfig
import threading
import zoneinfo
from collections.abc import Iterator
from pathlib import Path

__all__ = ["recording", "Recorder", "Stamp", "exempt_roots", "python_files", "recorded"]

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


#: The kernel's pseudo file systems: what they hold describes the running system (and its
#: times change as it is read); no day's data is there.
PSEUDO_ROOTS = ("/proc", "/sys", "/dev")
#: Folder names of installed Python libraries.
LIBRARY_FOLDERS = ("site-packages", "dist-packages")


def exempt_roots() -> tuple[str, ...]:
    """Folders whose files are not a day's inputs, each ending with a separator.

    Only the files the day's fingerprint records otherwise: towtank's own code (its files'
    sizes and times), Python's standard library (Python's version) with the system's time
    zone tables it reads (:data:`zoneinfo.TZPATH`), the installed libraries (their names and
    versions), the compiled modules of all three where Python keeps them apart from the
    sources (:data:`sys.pycache_prefix`, set by ``PYTHONPYCACHEPREFIX``: a module imported
    during the day is read from there), and the kernel's pseudo file systems
    (:data:`PSEUDO_ROOTS`). Every other file the day reads is an input wherever it lives: on a
    USB stick under ``/run/media``, under ``/mnt``, ``/etc``, ``/usr/local/share``, a home
    folder.
    """
    roots = {str(Path(__file__).resolve().parents[1]), *PSEUDO_ROOTS, *zoneinfo.TZPATH}
    if sys.pycache_prefix:
        roots.add(sys.pycache_prefix)
    paths = sysconfig.get_paths()
    roots.update(paths[key] for key in ("stdlib", "platstdlib", "purelib", "platlib")
                 if key in paths)
    roots.update(p for p in sys.path if p and os.path.isdir(p)
                 and any(part in LIBRARY_FOLDERS for part in Path(p).parts))
    return tuple(sorted(os.path.join(os.path.abspath(r), "") for r in roots if r))


def python_files() -> tuple[str, ...]:
    """The system files Python's standard library reads as its own settings, which are
    not a day's inputs either: the MIME type tables of :mod:`mimetypes`."""
    return tuple(os.path.abspath(f) for f in mimetypes.knownfiles)


def recorded(name: str, skip: tuple[str, ...] = (),
             roots: tuple[str, ...] | None = None) -> bool:
    """Whether the file ``name`` (an absolute path) that a day read is one of its inputs.

    It is, wherever it lives, unless it lies under one of ``roots`` (default
    :func:`exempt_roots`), is one of :func:`python_files`, or is (or lies under) an entry of
    ``skip`` (absolute paths: towtank's own bookkeeping, such as the output folder's cache).
    """
    under = (exempt_roots() if roots is None else roots) + tuple(
        os.path.join(s, "") for s in skip)
    return not (name.startswith(under) or name in skip or name in python_files())


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
        skip = tuple(os.path.abspath(s) for s in self.skip)
        roots = exempt_roots()
        self.files = {name: st for name, st in self._seen.items()
                      # None: not a regular file (or gone): a probe, a folder
                      if st is not None and recorded(name, skip, roots)}
        return self.files


@contextlib.contextmanager
def recording(skip: list[str | Path] | None = None) -> Iterator[Recorder]:
    """Record the files opened for reading in this process while the block runs (or until
    the recorder's :meth:`Recorder.stop`).

    Files under (or equal to) an entry of ``skip`` and under :func:`exempt_roots` are left
    out (:func:`recorded`).
    """
    rec = Recorder(list(skip or ())).start()
    try:
        yield rec
    finally:
        rec.stop()
