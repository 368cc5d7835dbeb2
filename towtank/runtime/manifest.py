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
import hashlib
import json
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

__all__ = ["MANIFEST", "INCOMPLETE", "describe", "read_manifest", "write_manifest",
           "foreign_outputs", "refuse_foreign", "known", "recover_outputs",
           "atomic_write_text", "folder_mode", "unwritable", "writing_outputs"]

MANIFEST = ".towtank-outputs.json"
INCOMPLETE = "OUTPUTS-INCOMPLETE.txt"
_KIND = "towtank output manifest"


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _entry(path: Path) -> dict[str, Any]:
    st = path.stat()
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": _sha256(path)}


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


def read_manifest(folder: Path) -> dict[str, Any] | None:
    """The manifest of ``folder``, or None when it has none (or one that is not towtank's)."""
    try:
        data = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("kind") != _KIND or \
            not isinstance(data.get("files"), dict):
        return None
    return data


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``path`` by a rename of a temporary file beside it."""
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except BaseException:  # a full disk: no half-written temporary is left beside it
        tmp.unlink(missing_ok=True)
        raise


def write_manifest(folder: Path, files: dict[str, list[dict[str, Any]]], *,
                   complete: bool = True) -> None:
    """Write the manifest of ``folder`` (atomically)."""
    data = {"kind": _KIND, "complete": complete, "written": time.time(), "files": files}
    atomic_write_text(folder / MANIFEST, json.dumps(data, indent=1, sort_keys=True) + "\n")


def known(path: Path, entries: list[dict[str, Any]]) -> bool:
    try:
        st = path.stat()
    except OSError:
        return False
    same = [e for e in entries if e.get("size") == st.st_size]
    if any(e.get("mtime_ns") == st.st_mtime_ns for e in same):
        return True  # as written (size and modification time): no need to read it
    return bool(same) and _sha256(path) in {e.get("sha256") for e in same}


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
    from towtank.errors import ProtocolError

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
            if data and data.get("complete") and isinstance(data.get("written"), int | float):
                if best is None or data["written"] > best[0]:
                    best = (float(data["written"]), cand)
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
    import tempfile

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
    import shutil
    import tempfile

    folder = Path(folder)
    if folder.exists():
        refuse_foreign(folder, names)
    folder.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".towtank-tmp-", dir=folder))
    try:
        yield tmp
        written = sorted(p.name for p in tmp.iterdir() if p.name in names)
        for name in written:
            os.replace(tmp / name, folder / name)
        data = read_manifest(folder)
        files = dict(data["files"]) if data else {}
        files.update(describe(folder, set(written)))
        write_manifest(folder, files)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
