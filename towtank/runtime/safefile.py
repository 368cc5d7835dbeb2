"""Reading back what towtank keeps in an output folder without trusting what is there.

Anything may have been put in an output folder in towtank's place: a FIFO (a read hangs), a
link to ``/dev/zero`` or to a 12 GB file (a read fills the memory), a folder. These helpers
open a path only if it is a regular file, never through a symbolic link and never blocking,
and read it with a cap (:func:`read_regular`) or by streaming (:func:`sha256_regular`).
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

__all__ = ["read_regular", "sha256_regular", "is_real_dir", "open_regular"]

_FLAGS = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0) \
    | getattr(os, "O_BINARY", 0)


def open_regular(path: str | Path) -> int | None:
    """A read-only descriptor of ``path`` if it is a regular file reached without following a
    link at its last component, else None (the caller closes it)."""
    try:
        fd = os.open(path, _FLAGS)
    except OSError:
        return None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            return None
    except OSError:
        os.close(fd)
        return None
    return fd


def read_regular(path: str | Path, max_bytes: int) -> bytes | None:
    """The bytes of ``path`` if it is a regular file (not a link, FIFO, device or folder) of at
    most ``max_bytes`` [bytes]; else None."""
    fd = open_regular(path)
    if fd is None:
        return None
    try:
        if os.fstat(fd).st_size > max_bytes:
            return None
        chunks, total = [], 0
        while True:
            block = os.read(fd, 1 << 20)
            if not block:
                break
            total += len(block)
            if total > max_bytes:  # grew while being read
                return None
            chunks.append(block)
        return b"".join(chunks)
    except OSError:
        return None
    finally:
        os.close(fd)


def sha256_regular(path: str | Path) -> str | None:
    """sha256 of ``path`` read in blocks if it is a regular file (not a link), else None."""
    fd = open_regular(path)
    if fd is None:
        return None
    h = hashlib.sha256()
    try:
        while True:
            block = os.read(fd, 1 << 20)
            if not block:
                break
            h.update(block)
    except OSError:
        return None
    finally:
        os.close(fd)
    return h.hexdigest()


def is_real_dir(path: str | Path) -> bool:
    """Whether ``path`` is a folder and not a symbolic link to one."""
    try:
        return stat.S_ISDIR(os.lstat(path).st_mode)
    except OSError:
        return False
