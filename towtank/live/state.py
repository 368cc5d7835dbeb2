"""The live state of a watched day: ``<output folder>/.live/state.json`` and its figures.

The watcher (:mod:`towtank.live.session`) writes them; the page server reads them. Every file
is written atomically (a temporary name in the same folder, fsync, ``os.replace``), so a reader
sees the previous version or the new one, never a part. The layout of state.json is in
docs/formats.md ("towtank watch").

The folder is towtank's own: :func:`claim_live_dir` makes it (with the marker
:data:`MARKER_NAME`) or checks, before anything is written, that it is a real folder towtank
made and that none of the names watch writes or removes there is a symbolic link or an entry
of another kind; :func:`atomic_write_bytes` never writes through a link either, and
:func:`remove_leftovers` removes only what a killed watch left under towtank's own names.
"""

from __future__ import annotations

import datetime as dt
import io
import json
import math
import os
import re
import shutil
import stat
import tempfile
from pathlib import Path
from typing import Any

from towtank.errors import ProtocolError
from towtank.runtime.safefile import read_regular

__all__ = ["LIVE_DIR", "STATE_NAME", "WATCH_LOCK", "MARKER_NAME", "FIGURE_NAMES",
           "MAX_STATE_BYTES", "atomic_write_bytes", "clean_json", "now_iso", "write_state",
           "save_figure", "claim_live_dir", "remove_leftovers", "refusal", "entry_kind"]

LIVE_DIR = ".live"
STATE_NAME = "state.json"
#: The lock file a running watch holds (its process id in it).
WATCH_LOCK = ".watch.lock"
#: The file that marks a live folder as made by towtank watch.
MARKER_NAME = ".towtank-live"
MARKER_TEXT = b"towtank watch's live state folder: state.json and the figures it names\n"
#: The figures watch draws for the page.
FIGURE_NAMES = ("latest_run.png", "damping.png", "added_mass.png", "captive.png")
#: Largest state.json read back [bytes]: a day's state is well under 1 MiB.
MAX_STATE_BYTES = 16 << 20

#: Regular files watch writes, whose leftovers (a listing of a fits drawing, a temporary file
#: of an atomic write) a killed watch may leave; and the folders it draws reports into.
_FILES = (STATE_NAME, *FIGURE_NAMES, WATCH_LOCK, MARKER_NAME)
_TEMPORARY = "|".join(re.escape(n) for n in _FILES)
_LEFTOVER_FILE = re.compile(rf"\.fits-\d+\.json|\.(?:{_TEMPORARY})\.\w+\.tmp")
_LEFTOVER_DIR = re.compile(r"\.report-\d+")
#: Resolution of the live page's figures [dpi]: small PNGs, drawn quickly.
FIGURE_DPI = 60

_UMASK = os.umask(0o022)  # read once (setting it is the only way), then put back
os.umask(_UMASK)


def now_iso() -> str:
    """The current UTC time, ISO 8601 to the second (``2026-11-26T13:02:11+00:00``)."""
    return dt.datetime.now(dt.UTC).replace(microsecond=0).isoformat()


def clean_json(value: Any) -> Any:
    """``value`` with every NaN or infinity replaced by None and numpy scalars made plain,
    recursively (JSON has no NaN)."""
    if isinstance(value, dict):
        return {str(k): clean_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [clean_json(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        try:
            value = value.item()
        except (TypeError, ValueError):
            return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    return str(value)


def refusal(path: Path, what: str) -> str:
    """The sentence refusing ``path``, a place of the live state that is ``what`` (``a
    symbolic link``...)."""
    return (f"{path} is {what}, where towtank watch keeps its live state; watch never writes "
            "through a link nor into a file or folder it did not make: move it away, or "
            "choose another output folder with --out.")


def _kind(name: str) -> str | None:
    """What watch keeps under ``name`` in the live folder: ``file``, ``folder`` or None (not
    one of its names)."""
    if name in _FILES or _LEFTOVER_FILE.fullmatch(name):
        return "file"
    return "folder" if _LEFTOVER_DIR.fullmatch(name) else None


def entry_kind(path: Path) -> str | None:
    """What is at ``path``, its last component not followed: ``file`` (a regular file),
    ``folder``, ``link`` (a symbolic link), ``other`` (a pipe, socket or device), or None when
    nothing is there."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return None
    if stat.S_ISREG(mode):
        return "file"
    if stat.S_ISDIR(mode):
        return "folder"
    return "link" if stat.S_ISLNK(mode) else "other"


_WHAT = {"link": "a symbolic link", "folder": "a folder", "file": "a file",
         "other": "not a regular file (a pipe, socket or device)"}


def _is_towtank_state(path: Path) -> bool:
    """Whether ``path`` is a regular file holding a state towtank watch wrote."""
    raw = read_regular(path, MAX_STATE_BYTES)
    try:
        state = json.loads(raw.decode("utf-8")) if raw is not None else None
    except (ValueError, RecursionError):
        return False
    return (isinstance(state, dict) and type(state.get("version")) is int
            and isinstance(state.get("verdicts"), list))


def claim_live_dir(live_dir: Path) -> Path:
    """The live folder ``live_dir``, made (with its marker) when absent, after checking that
    watch may write and remove its files there; ProtocolError (one sentence) otherwise.

    Refused: a ``live_dir`` that is a symbolic link or not a folder; a folder without the
    marker that holds anything but watch's own names (a state.json that is not a towtank
    state included), so a user's folder is never written into; any of watch's names (state.json,
    the figures, the lock, a leftover ``.report-N`` or ``.fits-N.json``...) that is a symbolic
    link or an entry of another kind. A folder an earlier towtank watch made before the marker
    existed is recognised by its names and state and marked.
    """
    live_dir = Path(live_dir)
    if not os.path.lexists(live_dir):
        live_dir.parent.mkdir(parents=True, exist_ok=True)
        try:
            live_dir.mkdir()
        except FileExistsError:  # made meanwhile: checked as any other
            pass
    kind = entry_kind(live_dir)
    if kind != "folder":
        raise ProtocolError(refusal(live_dir, _WHAT.get(str(kind), "not a folder")))
    names = sorted(os.listdir(live_dir))
    for name in names:
        want, got = _kind(name), entry_kind(live_dir / name)
        if want is not None and got is not None and got != want:
            raise ProtocolError(refusal(live_dir / name, _WHAT[got]))
    marker = live_dir / MARKER_NAME
    if read_regular(marker, len(MARKER_TEXT)) == MARKER_TEXT:
        return live_dir
    foreign = [n for n in names if _kind(n) is None or n == MARKER_NAME
               or (n == STATE_NAME and not _is_towtank_state(live_dir / n))]
    if foreign:
        more = f" and {len(foreign) - 3} more" if len(foreign) > 3 else ""
        raise ProtocolError(refusal(
            live_dir, f"a folder towtank did not make (it holds {', '.join(foreign[:3])}{more})"))
    atomic_write_bytes(marker, MARKER_TEXT)
    return live_dir


def remove_leftovers(live_dir: Path) -> list[str]:
    """Remove what a killed watch left in its live folder: its report folders
    (``.report-N``), fits listings (``.fits-N.json``) and temporary files, each only when it is
    of the kind watch makes (never through a link); the names removed."""
    gone = []
    for name in sorted(os.listdir(live_dir)) if entry_kind(live_dir) == "folder" else []:
        path = live_dir / name
        if _LEFTOVER_DIR.fullmatch(name) and entry_kind(path) == "folder":
            shutil.rmtree(path, ignore_errors=True)
        elif _LEFTOVER_FILE.fullmatch(name) and entry_kind(path) == "file":
            path.unlink(missing_ok=True)
        else:
            continue
        gone.append(name)
    return gone


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically: a temporary file beside it, fsync, rename.

    ProtocolError (one sentence) when the folder is a symbolic link or ``path`` is anything
    but a regular file: a link is never replaced nor written through."""
    path.parent.mkdir(parents=True, exist_ok=True)
    for place, want in ((path.parent, ("folder",)), (path, (None, "file"))):
        kind = entry_kind(place)
        if kind not in want:
            raise ProtocolError(refusal(place, _WHAT.get(str(kind), "gone")))
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)  # as any file the user writes (mkstemp gives 0600)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def write_state(live_dir: Path, state: dict[str, Any]) -> Path:
    """Write ``state`` (NaN made null) as ``live_dir/state.json``, atomically."""
    text = json.dumps(clean_json(state), indent=1, ensure_ascii=False, allow_nan=False)
    path = live_dir / STATE_NAME
    atomic_write_bytes(path, (text + "\n").encode("utf-8"))
    return path


def save_figure(fig: Any, live_dir: Path, name: str, dpi: int = FIGURE_DPI) -> str:
    """Save a matplotlib figure as ``live_dir/name`` (PNG, atomically); return ``name``."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    atomic_write_bytes(live_dir / name, buf.getvalue())
    return name
