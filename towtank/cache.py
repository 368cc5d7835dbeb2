"""Incremental cache of per-run reductions, in the output folder (``.cache/``).

A reduction is stored under the sha256 of its run file and a hash of every setting that affects
that run (processing settings, channel mapping, manual window, set values, file name), so an
unchanged run is not read again and a changed setting invalidates exactly the runs it affects.
The file's sha256 is remembered with its size and modification time: while those are unchanged
the file is not even opened. Fits and outputs are always recomputed from the reductions.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import pickle
import tempfile
from dataclasses import asdict
from pathlib import Path
from typing import Any

from towtank import __version__

CACHE_FORMAT = 1


def settings_key(protocol: Any, row: dict[str, Any]) -> str:
    """Hash of everything besides the file's bytes that changes a run's reduction."""

    def num(x: Any) -> Any:
        return None if isinstance(x, float) and math.isnan(x) else x

    payload = {
        "format": CACHE_FORMAT,
        "version": __version__,
        "processing": asdict(protocol.processing),
        "channels": {k: asdict(v) for k, v in sorted(protocol.channels.items())},
        "file": str(row["file"]),
        "window": [num(row.get("window_start_s")), num(row.get("window_end_s"))],
        "nominal": [num(row.get("speed_nominal")), num(row.get("accel_nominal"))],
    }
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _atomic_write(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class RunCache:
    """Per-run reductions on disk; a missing or damaged entry is simply a miss."""

    def __init__(self, directory: str | Path):
        self.dir = Path(directory)
        self._index_path = self.dir / "files.json"
        try:
            self._index: dict[str, list[Any]] = json.loads(self._index_path.read_text())
        except (OSError, ValueError):
            self._index = {}
        self._dirty = False

    def known_sha(self, path: Path) -> str | None:
        """The file's sha256 if its size and mtime are those recorded with it."""
        try:
            st = path.stat()
        except OSError:
            return None
        rec = self._index.get(str(path.resolve()))
        if rec and rec[0] == st.st_size and rec[1] == st.st_mtime_ns:
            return str(rec[2])
        return None

    def remember_sha(self, path: Path, sha: str) -> None:
        try:
            st = path.stat()
        except OSError:
            return
        self._index[str(path.resolve())] = [st.st_size, st.st_mtime_ns, sha]
        self._dirty = True

    def _entry(self, sha: str, key: str) -> Path:
        return self.dir / "runs" / f"{sha[:32]}-{key}.pkl"

    def get(self, sha: str, key: str) -> Any | None:
        try:
            with open(self._entry(sha, key), "rb") as fh:
                return pickle.load(fh)
        except Exception:  # noqa: BLE001 - any damage is a miss
            return None

    def put(self, sha: str, key: str, value: Any) -> None:
        _atomic_write(self._entry(sha, key), pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))

    def flush(self) -> None:
        if self._dirty:
            _atomic_write(self._index_path, json.dumps(self._index, sort_keys=True).encode())
            self._dirty = False
