"""The live state of a watched day: ``<output folder>/.live/state.json`` and its figures.

The watcher (:mod:`towtank.live.session`) writes them; the page server reads them. Every file
is written atomically (a temporary name in the same folder, fsync, ``os.replace``), so a reader
sees the previous version or the new one, never a part. The layout of state.json is in
docs/formats.md ("towtank watch").
"""

from __future__ import annotations

import datetime as dt
import io
import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["LIVE_DIR", "STATE_NAME", "atomic_write_bytes", "clean_json", "now_iso",
           "write_state", "save_figure"]

LIVE_DIR = ".live"
STATE_NAME = "state.json"
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


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically: a temporary file beside it, fsync, rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
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
