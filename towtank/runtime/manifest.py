"""What towtank wrote in an output folder: a manifest, so that nothing else is ever touched.

Every set of outputs carries ``.towtank-outputs.json``: each file towtank wrote (``runs.csv``,
``figures/hull.png``, ...) with its size, modification time and sha256. Before a day is written,
each entry of the folder that carries an output's name is checked against it; one that
towtank did not write (or that was changed since) stops the day before anything is written,
naming it (docs/formats.md §4). While a folder that also holds the user's own files is updated
entry by entry, ``OUTPUTS-INCOMPLETE.txt`` says so, and the manifest lists both sets; a set
that a kill left half swapped is found and put back by the next run.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import shutil
import stat
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

if sys.platform == "win32":  # pragma: no cover - Windows locks with msvcrt, others with fcntl
    import msvcrt
else:
    import fcntl

from towtank.errors import ProtocolError
from towtank.runtime.safefile import read_regular, sha256_regular

__all__ = ["MANIFEST", "INCOMPLETE", "describe", "read_manifest", "write_manifest",
           "foreign_outputs", "refuse_foreign", "known", "recover_outputs",
           "atomic_write_text", "folder_mode", "unwritable", "writing_outputs",
           "inside_name", "lock_target", "lock_path", "output_lock"]

MANIFEST = ".towtank-outputs.json"
INCOMPLETE = "OUTPUTS-INCOMPLETE.txt"
_KIND = "towtank output manifest"


def _entry(path: Path) -> dict[str, Any]:
    st = path.stat()
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": sha256_regular(path)}


def describe(folder: Path, names: set[str] | frozenset[str]) -> dict[str, list[dict[str, Any]]]:
    """Manifest entries of the files under ``folder`` named ``names`` (folders recursed):
    relative path (``/`` separated) -> [size, mtime_ns, sha256]."""
    out: dict[str, list[dict[str, Any]]] = {}
    for name in sorted(names):
        path = folder / name
        if path.is_file() and not path.is_symlink():
            out[name] = [_entry(path)]
        elif path.is_dir() and not path.is_symlink():
            for sub in sorted(path.rglob("*")):
                if sub.is_file() and not sub.is_symlink():
                    out[sub.relative_to(folder).as_posix()] = [_entry(sub)]
    return out


#: A larger manifest is not read (one of a day with thousands of exported runs is < 10 MB).
MAX_MANIFEST_BYTES = 64 << 20


#: A file's digest as the manifest records it (sha256, lowercase hex).
_SHA256 = re.compile(r"[0-9a-f]{64}")


def _entries(value: Any) -> list[dict[str, Any]]:
    """A manifest's list of versions of one file, with every malformed one dropped: a
    version is {size (an int >= 0) [bytes], mtime_ns (an int) [ns], sha256 (64 hex digits)}."""
    if not isinstance(value, list):
        return []
    return [e for e in value if isinstance(e, dict) and type(e.get("size")) is int
            and e["size"] >= 0 and type(e.get("mtime_ns")) is int
            and isinstance(e.get("sha256"), str) and _SHA256.fullmatch(e["sha256"])]


def inside_name(rel: Any) -> bool:
    """Whether ``rel`` names an entry inside a folder as the manifest writes names: a
    relative ``/``-separated path with no empty, ``.`` or ``..`` part, no backslash and no
    NUL (never an absolute path nor one that climbs out of the folder)."""
    if not isinstance(rel, str) or not rel or "\0" in rel or "\\" in rel:
        return False
    return all(part not in ("", ".", "..") for part in rel.split("/"))


def _seconds(value: Any) -> float:
    """``value`` as a time [s]: a finite number >= 0, else 0."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return 0.0
    try:
        seconds = float(value)
    except OverflowError:  # an integer beyond any float
        return 0.0
    return seconds if math.isfinite(seconds) and seconds >= 0 else 0.0


def read_manifest(folder: Path, name: str = MANIFEST) -> dict[str, Any] | None:
    """The manifest ``name`` of ``folder``, or None when it has none (or one that is not
    towtank's).

    Nothing in it is trusted: it is read only if it is a regular file (not a link, FIFO or
    folder) of at most :data:`MAX_MANIFEST_BYTES`; an entry whose name is not a path inside
    the folder (:func:`inside_name`) or that is not a list of {size, mtime_ns, sha256}
    records (:func:`_entries`) is dropped (the file it names then counts as not towtank's);
    ``written`` that is not a finite time >= 0 [s] reads as 0 and ``complete`` as False
    unless it is true."""
    raw = read_regular(folder / name, MAX_MANIFEST_BYTES)
    if raw is None:
        return None
    try:
        data = json.loads(raw.decode("utf-8"))
    except (ValueError, RecursionError):
        return None
    if not isinstance(data, dict) or data.get("kind") != _KIND or \
            not isinstance(data.get("files"), dict):
        return None
    files = {k: _entries(v) for k, v in data["files"].items() if inside_name(k)}
    data["files"] = {k: v for k, v in files.items() if v}
    data["written"] = _seconds(data.get("written"))
    data["complete"] = data.get("complete") is True
    return data


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``path`` by a rename of a temporary file beside it (a name of its own: two
    writers never share one)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.tmp-", dir=path.parent)
    try:
        os.fchmod(fd, 0o666 & ~_umask()) if hasattr(os, "fchmod") else None
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _umask() -> int:
    umask = os.umask(0o022)
    os.umask(umask)
    return umask


def write_manifest(folder: Path, files: dict[str, list[dict[str, Any]]], *,
                   complete: bool = True) -> None:
    """Write the manifest of ``folder`` (atomically)."""
    data = {"kind": _KIND, "complete": complete, "written": time.time(), "files": files}
    atomic_write_text(folder / MANIFEST, json.dumps(data, indent=1, sort_keys=True) + "\n")


def known(path: Path, entries: list[dict[str, Any]]) -> bool:
    """Whether ``path`` is a regular file (not a link, FIFO or device) that is one of the
    versions ``entries`` of the manifest describe."""
    try:
        st = os.lstat(path)
    except OSError:
        return False
    if not stat.S_ISREG(st.st_mode):
        return False
    same = [e for e in entries if e.get("size") == st.st_size]
    if any(e.get("mtime_ns") == st.st_mtime_ns for e in same):
        return True  # as written (size and modification time): no need to read it
    return bool(same) and sha256_regular(path) in {e.get("sha256") for e in same}


def foreign_outputs(folder: Path, names: set[str] | frozenset[str]) -> list[str]:
    """Entries of ``folder`` that carry an output's name (``names``) but that towtank did not
    write, or that were changed since: relative paths, sorted. A symbolic link is never
    towtank's."""
    if not folder.is_dir():
        return []
    manifest = read_manifest(folder)
    files: dict[str, list[dict[str, Any]]] = manifest["files"] if manifest else {}
    foreign: list[str] = []
    for name in sorted(names):
        path = folder / name
        if not os.path.lexists(path):
            continue
        if path.is_symlink():
            foreign.append(name)
        elif path.is_dir():
            for sub in sorted(path.rglob("*")):
                rel = sub.relative_to(folder).as_posix()
                if sub.is_symlink() or (sub.is_file() and not known(sub, files.get(rel, []))):
                    foreign.append(rel)
                elif not sub.is_dir() and not sub.is_file():
                    foreign.append(rel)
        elif not known(path, files.get(name, [])):
            foreign.append(name)
    return foreign


def refuse_foreign(out_dir: Path, names: set[str] | frozenset[str]) -> None:
    """Stop (ProtocolError) when ``out_dir`` holds an entry named as one of the outputs
    ``names`` (or the incomplete-set marker) that towtank did not write, or that was changed
    since towtank wrote it: writing the day would replace it."""
    foreign = foreign_outputs(out_dir, set(names) | {INCOMPLETE})
    if foreign:
        more = len(foreign) - 5
        shown = ", ".join(foreign[:5]) + (f" and {more} more" if more > 0 else "")
        raise ProtocolError(
            f"the output folder {out_dir} holds {shown}, which towtank did not write (or which "
            "was changed since towtank wrote it); towtank never replaces a file it did not "
            "write: move it away, or choose another folder with --out."
        )


def recover_outputs(out_dir: Path) -> str | None:
    """Put back the last complete set of outputs when a kill between the two renames of a
    swap left no ``out_dir`` (the old set in ``.NAME.old-*``, the new in ``.NAME.tmp-*``).

    Returns a sentence saying what was put back, or None.
    """
    if os.path.lexists(out_dir):
        return None
    best: tuple[float, Path] | None = None
    for pattern in (f".{out_dir.name}.old-*", f".{out_dir.name}.tmp-*"):
        for cand in out_dir.parent.glob(pattern):
            data = read_manifest(cand) if cand.is_dir() else None
            if data and data["complete"] and (best is None or data["written"] > best[0]):
                best = (data["written"], cand)
    if best is None:
        return None
    try:
        os.rename(best[1], out_dir)
    except OSError:
        return (f"the last complete set of outputs is in {best[1]} (an interrupted run left "
                f"no {out_dir}); it could not be moved back.")
    return (f"an interrupted run had left no {out_dir}: the last complete set of outputs "
            f"({best[1].name}) was put back.")


def folder_mode(folder: Path, like: Path | None) -> None:
    """Give a new output folder the mode a folder made with the umask has (or, when the output
    folder exists, its mode and group): temporary folders are made 0700."""
    try:
        if like is not None and like.is_dir():
            st = like.stat()
            os.chmod(folder, st.st_mode & 0o7777)
            if hasattr(os, "chown"):
                try:
                    os.chown(folder, -1, st.st_gid)
                except OSError:
                    pass
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(folder, 0o777 & ~umask)
    except OSError:
        pass


def unwritable(out_dir: Path) -> str | None:
    """Why no outputs can be written at ``out_dir`` (its parent is not a folder this process
    may create files in: read-only, no permission, a virtual file system), or None.

    Checked by creating (and removing) a temporary folder beside it, as the outputs will be.
    """
    parent = out_dir.parent
    while not parent.exists() and parent != parent.parent:  # created only when writing
        parent = parent.parent
    try:
        probe = tempfile.mkdtemp(prefix=f".{out_dir.name}.probe-", dir=parent)
        os.rmdir(probe)
    except OSError as exc:
        return exc.strerror or type(exc).__name__
    return None


@contextlib.contextmanager
def writing_outputs(folder: Path, names: set[str] | frozenset[str]) -> Iterator[Path]:
    """Write some of towtank's own files (``names``) into ``folder`` without touching anyone
    else's: refuse (ProtocolError, before anything is written) when ``folder`` holds an entry
    of one of those names that towtank did not write; yield a temporary folder inside it to
    write them into; then move each into place by a rename and list it in the folder's
    manifest. For ``predict`` and ``simulate``, which write beside what the user keeps."""
    folder = Path(folder).absolute()
    with output_lock(folder):  # one writer at a time, whatever the command
        if folder.exists():
            refuse_foreign(folder, names)
        folder.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=".towtank-tmp-", dir=folder))
        try:
            yield tmp
            refuse_foreign(folder, names)  # again: a file may have appeared meanwhile
            written = sorted(p.name for p in tmp.iterdir() if p.name in names)
            for name in written:
                os.replace(tmp / name, folder / name)
            data = read_manifest(folder)
            files = dict(data["files"]) if data else {}
            files.update(describe(folder, set(written)))
            write_manifest(folder, files)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


# ------------------------------------------------------------------------------ the lock
LOCK_TEXT = "towtank output lock: the process writing into the folder beside this file is "
#: How long a second writer waits for the first to finish before it gives up [s].
LOCK_WAIT_S = 60.0

_held_lock = threading.Lock()
_held: dict[str, list[Any]] = {}  # folder -> [thread ident, depth, fd]


def lock_target(out_dir: str | Path) -> Path:
    """The output folder ``out_dir`` as its lock names it: its real path (a link to it
    followed, a relative path made absolute), so that every name of one folder takes the one
    lock (``--out olink`` where olink -> o locks o)."""
    return Path(out_dir).resolve()


def lock_path(out_dir: str | Path) -> Path:
    """The lock file of output folder ``out_dir``: ``.NAME.towtank-lock`` beside its real
    path (:func:`lock_target`; not in it: the folder itself is replaced by a rename)."""
    out_dir = lock_target(out_dir)
    return out_dir.parent / f".{out_dir.name}.towtank-lock"


def _lock_fd(fd: int, blocking: bool) -> bool:
    if sys.platform == "win32":  # pragma: no cover - Windows
        try:
            os.lseek(fd, 0, os.SEEK_SET)
            msvcrt.locking(fd, msvcrt.LK_LOCK if blocking else msvcrt.LK_NBLCK, 1)
            return True
        except OSError:
            return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
        return True
    except BlockingIOError:
        return False


def try_lock(fd: int) -> bool:
    """Take the exclusive lock of the open file ``fd`` without waiting (fcntl's flock, or
    msvcrt on Windows); False when another process holds it. Held until ``fd`` is closed."""
    return _lock_fd(fd, blocking=False)


def _holder(fd: int) -> str:
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        text = os.read(fd, 4096).decode("utf-8", "replace")
    except OSError:
        return "another process"
    pid = text[len(LOCK_TEXT):].split()[0] if text.startswith(LOCK_TEXT) else ""
    return f"process {pid}" if pid.isdigit() else "another process"


@contextlib.contextmanager
def output_lock(out_dir: str | Path, wait_s: float | None = None) -> Iterator[None]:
    """Hold the exclusive lock of output folder ``out_dir`` while the block runs.

    The one way a command takes an output folder's lock: every command that writes into one
    (process, watch, predict, simulate, steady, identify, scale's cache, synth) holds it for
    the whole write, so two writers (two processes, or two threads of a notebook) never mix
    their files: the second waits up to ``wait_s`` [s] (default :data:`LOCK_WAIT_S`) for the
    first, then stops (ProtocolError) with a sentence naming the holder's process id. The
    folder is named by its real path (:func:`lock_target`): a link to it takes the same lock.
    The lock is an advisory lock (``flock``) on ``.NAME.towtank-lock`` beside the folder,
    which holds the pid: the system releases it when its holder ends, however it ends, so a
    lock left by a killed run is no obstacle. Re-entrant within one thread.
    """
    out_dir = lock_target(out_dir)
    if wait_s is None:
        wait_s = LOCK_WAIT_S
    key = str(out_dir)
    me = threading.get_ident()
    with _held_lock:
        held = _held.get(key)
        if held is not None and held[0] == me:
            held[1] += 1
            mine = True
        else:
            mine = False
    if mine:
        try:
            yield
        finally:
            with _held_lock:
                _held[key][1] -= 1
        return
    path = lock_path(out_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    deadline = time.monotonic() + wait_s
    while True:
        fd = _open_lock(path, out_dir)
        try:
            if _lock_fd(fd, blocking=False):
                if _same_file(fd, path):
                    break
                # the holder removed the file as it let go: lock the one now at that name
            elif time.monotonic() >= deadline:
                raise ProtocolError(
                    f"{_holder(fd)} is writing into {out_dir} (it holds {path.name}); wait "
                    "for it to finish, or choose another folder with --out.")
        except BaseException:
            os.close(fd)
            raise
        os.close(fd)
        time.sleep(0.05)
    try:
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, f"{LOCK_TEXT}{os.getpid()}\n".encode())
    except BaseException:
        os.close(fd)
        raise
    with _held_lock:
        _held[key] = [me, 1, fd]
    try:
        yield
    finally:
        with _held_lock:
            del _held[key]
        with contextlib.suppress(OSError):
            if _same_file(fd, path):
                os.unlink(path)  # still locked: a waiter finds it gone and opens a new one
        os.close(fd)


def _open_lock(path: Path, out_dir: Path) -> int:
    """A descriptor of the lock file ``path`` (made if missing), checked to be towtank's."""
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags, 0o666)
    except OSError as exc:
        raise ProtocolError(f"the lock file {path} of the output folder cannot be opened "
                            f"({exc.strerror}); remove whatever is in its place.") from None
    try:
        st = os.fstat(fd)
        head = os.read(fd, len(LOCK_TEXT)).decode("utf-8", "replace") \
            if stat.S_ISREG(st.st_mode) else ""
    except OSError:
        head, st = "?", None
    if st is None or not stat.S_ISREG(st.st_mode) or not LOCK_TEXT.startswith(head):
        os.close(fd)
        raise ProtocolError(f"{path} is not towtank's lock file of {out_dir.name} (towtank "
                            "never writes into a file it did not make): move it away.")
    return fd


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` still names the file open as ``fd``."""
    try:
        a, b = os.fstat(fd), os.lstat(path)
    except OSError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)
