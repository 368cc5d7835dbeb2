"""Reading back what towtank keeps in an output folder without trusting what is there.

Anything may have been put in an output folder in towtank's place: a FIFO (a read hangs), a
link to ``/dev/zero`` or to a 12 GB file (a read fills the memory), a folder. These helpers
open a path only if it is a regular file, never through a symbolic link and never blocking,
and read it with a cap (:func:`read_regular`) or by streaming (:func:`sha256_regular`).
A table a protocol names (reference CSV, tare table) is refused before it is read when it is
not a regular file or is far too large for a table (:func:`check_table_size`). A text
table's lines are split only where a file's lines end (:func:`text_lines`).
"""

from __future__ import annotations

import hashlib
import os
import re
import stat
from pathlib import Path
from typing import Any

from towtank.errors import ProtocolError

__all__ = ["read_regular", "sha256_regular", "is_real_dir", "open_regular", "check_table_size",
           "MAX_TABLE_BYTES"]

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


#: Largest table a protocol names and towtank reads whole (the reference CSV, the tare table):
#: such a table has a few lines; a larger file is the wrong one (or damaged) and is refused in
#: one sentence before it is read rather than read into all of the memory.
MAX_TABLE_BYTES = 64 << 20


def check_table_size(path: Any, what: str, src: str) -> None:
    """Refuse (ProtocolError) a protocol table larger than :data:`MAX_TABLE_BYTES`, or one
    that is a pipe or a device (reading it would wait forever); a file that cannot be
    stat'ed is left to its reader, which says what is wrong with it."""
    try:
        st = os.stat(path)
    except OSError:
        return
    if not stat.S_ISREG(st.st_mode) and not stat.S_ISDIR(st.st_mode):
        raise ProtocolError(f"{src}: the {what} {os.path.basename(path)} is not a regular file "
                            "(a pipe, socket or device).")
    size = st.st_size
    if size > MAX_TABLE_BYTES:
        raise ProtocolError(
            f"{src}: the {what} {os.path.basename(path)} is {size / 2**20:.0f} MiB, but towtank "
            f"reads such tables up to {MAX_TABLE_BYTES >> 20} MiB (they hold a few lines): is "
            "it the right file?"
        )


_LINE_END = re.compile(r"\r\n|\r|\n")


def text_lines(text: str) -> list[str]:
    """The lines of a text file: split at ``\\r\\n``, ``\\r`` or ``\\n`` only.

    ``str.splitlines`` also splits at a form feed, a vertical tab, ``\\x1c``–``\\x1e``,
    ``\\x85`` and the Unicode line and paragraph separators, which a spreadsheet or a
    logger may leave inside a cell: a run sheet's cell ``"\\x0c0"`` would become a row of
    its own (run 0). As ``splitlines``, a final line end adds no empty line.
    """
    lines = _LINE_END.split(text)
    if lines and lines[-1] == "":
        lines.pop()
    return lines
