"""What a user-given path names, asked without ever raising.

A name from a run sheet or a protocol can be one the file system refuses to look up at all: a
component longer than 255 bytes (ENAMETOOLONG), a loop of symbolic links (ELOOP), a folder
that may not be searched (EACCES). :meth:`pathlib.Path.is_file` and its siblings raise for
some of these, so every check of such a name on the way in goes through :func:`path_kind`,
which answers with a word (or the system's reason) instead.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

__all__ = ["FILE", "FOLDER", "MISSING", "OTHER", "is_regular_file", "path_kind", "resolved"]

FILE, FOLDER, OTHER, MISSING = "file", "folder", "other", "missing"


def path_kind(path: str | Path) -> str:
    """What ``path`` names, links followed: ``"file"`` (a regular file), ``"folder"``,
    ``"other"`` (a pipe, socket or device), ``"missing"``, or else the system's reason why it
    cannot be looked up (``"File name too long"``, ``"Too many levels of symbolic links"``,
    ``"Permission denied"``). Never raises."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError) as exc:  # ValueError: a NUL byte in the name
        if isinstance(exc, OSError) and exc.errno in (errno.ENOENT, errno.ENOTDIR):
            return MISSING
        reason = exc.strerror if isinstance(exc, OSError) else None
        return reason or str(exc) or type(exc).__name__
    if stat.S_ISREG(mode):
        return FILE
    return FOLDER if stat.S_ISDIR(mode) else OTHER


def resolved(path: str | Path) -> Path | str:
    """``path`` made absolute with its links resolved, or the reason it cannot be (``"a symlink
    loop"``, ``"File name too long"``). Never raises."""
    try:
        return Path(path).resolve()
    except RuntimeError:  # pathlib's word for a loop of symbolic links
        return "a symlink loop"
    except (OSError, ValueError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) else None
        return reason or str(exc) or type(exc).__name__


def is_regular_file(path: str | Path) -> bool:
    """True when ``path`` names a regular file that can be looked up (links followed)."""
    return path_kind(path) == FILE
