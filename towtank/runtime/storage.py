"""A full disk told apart from a bug, whatever library met it (docs/formats.md §4).

A writer that runs out of space does not always say so with an ``OSError``: matplotlib's PDF
backend, flushing its zlib stream again while it closes the file, raises ``zlib.error`` on top
of the ``OSError`` (``Error -2 while flushing: inconsistent stream state``); a report writer in
a forked process comes back as a ``RuntimeError`` naming it. :func:`storage_error` finds the
storage failure behind such an exception: an ``OSError`` with a storage errno in its chain
(``__cause__``/``__context__``), or, when there is none, a file system with (almost) no space
left, which is taken as ``ENOSPC``. The command line then ends with exit 2, one sentence, and
the output folder as it was.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

__all__ = ["STORAGE_ERRNOS", "MIN_FREE_BYTES", "chained_errno", "free_bytes", "storage_error",
           "os_error"]

#: Errors of the storage, not of towtank: a full disk or quota, a read-only or failing file
#: system, no permission, a file or name the file system cannot hold.
STORAGE_ERRNOS = frozenset(
    getattr(errno, name) for name in ("ENOSPC", "EDQUOT", "EROFS", "EIO", "EACCES", "EPERM",
                                      "EFBIG", "ENAMETOOLONG") if hasattr(errno, name))

#: A file system with less free space than this [bytes] when a writer failed is taken as full:
#: the write that failed was larger than what was left.
MIN_FREE_BYTES = 1 << 20


def os_error(code: int, filename: str | os.PathLike[str] | None = None) -> OSError:
    """An ``OSError`` for ``code`` whose text is the system's one sentence (``strerror``)."""
    if filename is None:
        return OSError(code, os.strerror(code))
    return OSError(code, os.strerror(code), os.fspath(filename))


def chained_errno(exc: BaseException) -> int | None:
    """The errno of the first ``OSError`` with a storage errno in ``exc`` or its chain."""
    seen: set[int] = set()
    stack: list[BaseException] = [exc]
    while stack:
        e = stack.pop(0)
        if id(e) in seen:
            continue
        seen.add(id(e))
        if isinstance(e, OSError) and e.errno is not None and e.errno in STORAGE_ERRNOS:
            return int(e.errno)
        stack.extend(c for c in (e.__cause__, e.__context__) if c is not None)
    return None


def free_bytes(path: str | os.PathLike[str]) -> int | None:
    """Bytes an unprivileged writer may still use on the file system of ``path`` (or of its
    nearest existing parent); None when that cannot be told."""
    p = Path(path)
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        st = os.statvfs(p)
    except (OSError, AttributeError):  # pragma: no cover - not POSIX
        return None
    return st.f_bavail * st.f_frsize


def storage_error(exc: BaseException, folder: str | os.PathLike[str]) -> OSError | None:
    """The storage failure ``exc`` stands for while writing into ``folder``, or None.

    ``exc`` itself when it is an ``OSError`` with a storage errno; an ``OSError`` of that errno
    when one is in its chain (``zlib.error`` raised while a PDF is closed after its write
    failed); ``ENOSPC`` when ``folder``'s file system has less than :data:`MIN_FREE_BYTES`
    left (a library that hid the ``OSError``: h5py, a writer's forked process). None for
    everything else, an interrupt included: a bug stays a bug.
    """
    if not isinstance(exc, Exception):
        return None  # KeyboardInterrupt, SystemExit
    if isinstance(exc, OSError) and exc.errno in STORAGE_ERRNOS:
        return exc
    code = chained_errno(exc)
    if code is None:
        free = free_bytes(folder)
        if free is None or free >= MIN_FREE_BYTES:
            return None
        code = errno.ENOSPC
    return os_error(code)
