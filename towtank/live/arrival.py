"""When a run file is complete: the writer has closed it, or it has stopped changing.

:class:`ArrivalTracker` is pure logic: it is fed observations of files (size, modification
time, whether a writer holds the file open, the time of the observation) and says which files
became complete, which vanished before completing and which never stop changing. It never
reads a file and never sleeps, so it can be tested without a file system or a clock.
:func:`observe` makes one observation of a real file; :func:`writer_open` asks Linux whether
some process holds a file open for writing (a read lease, ``fcntl(F_SETLEASE, F_RDLCK)``).

A file is complete (docs/formats.md, "towtank watch") when

- no process holds it open for writing and it has not changed for :data:`QUIET_S`, or
- it has not changed for ``settle_s`` ([watch] settle_s, default 1 s), whatever the writer
  does (where a lease cannot be taken: a network share, a file of another user, another OS).

A file that changes after it was complete is complete again, with its new content, once it
settles again; a file still changing after ``never_stops_s`` is reported once.
"""

from __future__ import annotations

import errno
import math
import os
import signal
import stat
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["QUIET_S", "ArrivalTracker", "FileState", "Observation", "observe", "writer_open",
           "ignore_lease_breaks"]

#: A file its writer has closed must not have changed for this long to be complete [s]: a
#: writer that reopens it at once (to append the next block) is seen.
QUIET_S = 0.1

if sys.platform.startswith("linux"):  # pragma: no branch
    import fcntl

    _SETLEASE = getattr(fcntl, "F_SETLEASE", 1024)
    _RDLCK = getattr(fcntl, "F_RDLCK", 0)
    _UNLCK = getattr(fcntl, "F_UNLCK", 2)


@dataclass(frozen=True)
class Observation:
    """One look at a file.

    Parameters
    ----------
    size : int or None
        Size [bytes]; None when the file does not exist.
    mtime_ns : int
        Modification time [ns since the epoch].
    writer_open : bool or None
        Whether a process holds the file open for writing; None when it cannot be told.
    now : float
        Time of the observation [s since the epoch] (``time.time()``).
    """

    size: int | None
    mtime_ns: int
    writer_open: bool | None
    now: float


@dataclass
class FileState:
    """What the tracker knows of one file."""

    signature: tuple[int, int] | None = None  # (size, mtime_ns) last seen; None: absent
    changed_at: float = 0.0  # when it last changed [s]
    seen_at: float = 0.0  # when it was last looked at [s]
    first_seen: float | None = None  # when it appeared in its current run of changes [s]
    complete: tuple[int, int] | None = None  # the signature it was complete with
    writer_open: bool | None = None
    told_never_stops: bool = False


class ArrivalTracker:
    """The completeness of the run files a sheet names (pure logic: see the module's text).

    Parameters
    ----------
    settle_s : float
        A file unchanged this long is complete whatever its writer does [s].
    never_stops_s : float
        A file still changing this long after it appeared is reported once [s].
    quiet_s : float
        A file no writer holds must be unchanged this long [s] (:data:`QUIET_S`).
    """

    def __init__(self, settle_s: float = 1.0, never_stops_s: float = 600.0,
                 quiet_s: float = QUIET_S) -> None:
        self.settle_s = float(settle_s)
        self.never_stops_s = float(never_stops_s)
        self.quiet_s = float(quiet_s)
        self.files: dict[str, FileState] = {}

    def update(self, name: str, obs: Observation) -> str | None:
        """Take one observation of ``name``; return ``"complete"`` when the file has just
        become complete (once per content), ``"vanished"`` when it disappeared before it
        was complete, ``"removed"`` when a complete file disappeared, ``"never_stops"`` the
        first time it is seen still changing after ``never_stops_s``, else None."""
        st = self.files.setdefault(name, FileState())
        if obs.size is None:
            was, done = st.signature, st.complete
            st.signature, st.first_seen, st.writer_open = None, None, None
            st.told_never_stops = False
            if was is None:
                return None
            if done is not None and done == was:
                st.complete = None
                return "removed"
            st.complete = None
            return "vanished"
        sig = (int(obs.size), int(obs.mtime_ns))
        st.writer_open = obs.writer_open
        seen_before, st.seen_at = st.seen_at, obs.now
        if sig != st.signature:
            # the change happened between the last look and now; its mtime says when, unless
            # it lies outside (a share whose clock differs): then now, the latest it can be
            last_look = seen_before if st.signature is not None else -math.inf
            mtime = obs.mtime_ns / 1e9
            st.changed_at = mtime if last_look <= mtime <= obs.now else obs.now
            st.signature = sig
            if st.first_seen is None:
                st.first_seen = st.changed_at
        if st.complete == sig:
            return None
        quiet = obs.now - st.changed_at
        if (obs.writer_open is False and quiet >= self.quiet_s) or quiet >= self.settle_s:
            st.complete = sig
            st.first_seen = None
            st.told_never_stops = False
            return "complete"
        if (not st.told_never_stops and st.first_seen is not None
                and obs.now - st.first_seen >= self.never_stops_s):
            st.told_never_stops = True
            return "never_stops"
        return None

    def is_complete(self, name: str) -> bool:
        """Whether ``name`` exists and is complete with its current content."""
        st = self.files.get(name)
        return st is not None and st.signature is not None and st.complete == st.signature

    def is_waiting(self, name: str) -> bool:
        """Whether ``name`` exists but is not complete yet (still being written)."""
        st = self.files.get(name)
        return st is not None and st.signature is not None and st.complete != st.signature

    def forget(self, name: str) -> None:
        """Stop tracking ``name`` (no longer named by the sheet)."""
        self.files.pop(name, None)


def ignore_lease_breaks() -> None:
    """Ignore SIGIO: a writer opening a file while this process holds a lease on it sends
    SIGIO to this process, whose default action would end it. Call once, before
    :func:`writer_open` (the main thread only)."""
    sigio = getattr(signal, "SIGIO", None)
    if sigio is not None:
        signal.signal(sigio, signal.SIG_IGN)


def writer_open(path: str | Path) -> bool | None:
    """Whether a process holds ``path`` open for writing (Linux read lease), or None when it
    cannot be told (not Linux, a network share, a file of another user, leases disabled).

    The lease is released at once; :func:`ignore_lease_breaks` must have been called.
    """
    if not sys.platform.startswith("linux"):
        return None
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))
    except OSError:
        return None
    try:
        try:
            fcntl.fcntl(fd, _SETLEASE, _RDLCK)
        except OSError as exc:
            if exc.errno in (errno.EAGAIN, errno.EBUSY):
                return True
            return None  # EACCES (another owner), EINVAL (share, leases off)...
        try:
            fcntl.fcntl(fd, _SETLEASE, _UNLCK)
        except OSError:
            pass
        return False
    finally:
        os.close(fd)


def observe(path: str | Path, now: float, *, probe: bool = True) -> Observation:
    """One :class:`Observation` of ``path`` at ``now`` [s]: its size and mtime (None size when
    absent or not a regular file) and, when ``probe``, :func:`writer_open`."""
    try:
        st = os.stat(path)
    except OSError:
        return Observation(None, 0, None, now)
    if not stat.S_ISREG(st.st_mode):
        return Observation(None, 0, None, now)
    return Observation(st.st_size, st.st_mtime_ns, writer_open(path) if probe else None, now)
