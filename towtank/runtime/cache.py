"""Incremental cache of per-run reductions, in the output folder (``.cache/``).

A reduction is stored under the sha256 of its run file and a hash of every setting that affects
that run (processing settings, channel mapping, manual window, set values, file name), so an
unchanged run is not read again and a changed setting invalidates exactly the runs it affects.
The file's sha256 is remembered with its size and modification time: while those are unchanged
the file is not even opened. Fits and outputs are always recomputed from the reductions.

Layout, built for campaigns of thousands of runs:

* ``files.json`` -- the index: ``files`` maps a run file's real path to [size, mtime_ns,
  sha256, ctime_ns, inode]; ``entries`` maps an entry name (sha256 prefix and settings key) to
  [pack, offset, length, crc32] of its reduction.
* ``runs/pack-*.bin`` -- reductions back to back, each an uncompressed npz archive
  (:mod:`towtank.runtime.records`): nothing read back from the cache is ever unpickled, so a
  planted entry cannot run code, and every entry is checked field by field against the
  reduction's type, then its values against what a reduction can hold (the ``check`` given,
  :func:`towtank.reduce.sanity.sane_reduction`), before it is used; one that fails is a miss
  and the run's fresh reduction takes its place. New entries are gathered in memory and
  written as one pack (with the index) at :meth:`flush` and, while runs are being reduced, every
  :data:`PACK_SECONDS` seconds (at least :data:`PACK_ENTRIES` entries), instead of one file
  each; at most :data:`MAX_PACKS` packs are kept, beyond that they are merged into one.
Every file is written to a temporary name and renamed into place. A missing, truncated,
damaged or unexpected entry (or index) is simply a miss; so is a cache folder that is a
symbolic link or not a folder (then nothing is written into it either, and
:attr:`RunCache.problem` says so). Only regular files are read (a FIFO or a device in the
cache's place never blocks or fills the memory: :mod:`towtank.runtime.safefile`).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import platform
import re
import stat
import sys
import tempfile
import time
import zlib
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import towtank
from towtank import __version__
from towtank.runtime import records
from towtank.runtime.manifest import read_manifest
from towtank.runtime.safefile import is_real_dir, read_regular, sha256_regular

CACHE_FORMAT = 8  # of entries and settings keys (5: captive cov; 6: captive load trace;
#                   7: a drag along the tow, a fin run's blank lift and a captive file without
#                   fx rejected, runs reduced before them kept no more; 8: a fin run without
#                   a lift column rejected)
INDEX_FORMAT = 3  # of files.json
PACK_ENTRIES = 64  # a pack is written while runs are being reduced once this many wait
PACK_SECONDS = 2.0  # ... and this long has passed since the last (so an interrupt loses little)
MAX_PACKS = 16  # more packs than this are merged into one at flush
ORPHAN_AGE_S = 3600.0  # unindexed packs older than this are removed when packs are merged
MAX_INDEX_BYTES = 256 << 20  # a larger files.json is not read (a campaign's is a few MB)
MAX_PACK_BYTES = 2 << 30  # nor a larger pack
_PACK_NAME = re.compile(r"pack-[0-9a-f]{1,32}-[0-9]{1,10}\.bin")

#: The run-sheet values and [model] keys a captive run's reduction depends on (its test's
#: names as :data:`towtank.ingest.runsheet.CAPTIVE_TESTS`, repeated here: the runtime layer
#: sits below ingest).
CAPTIVE_TEST_NAMES = ("drift", "rudder", "arm", "sway", "yaw", "yaw_drift")
CAPTIVE_ROW_KEYS = ("plane", "drift_deg", "rudder_deg", "radius_m", "pmm_amplitude_m",
                    "pmm_frequency_hz")
CAPTIVE_MODEL_KEYS = ("mass_kg", "length_m", "izz_kg_m2", "iyy_kg_m2", "xg_m", "balance_x_m")
#: The [captive] keys a captive run's reduction depends on (which cycles a PMM run keeps, the
#: point its loads and motion refer to).
CAPTIVE_OPTION_KEYS = ("min_cycles", "amplitude_tolerance", "moment_ref")


def _num(x: Any) -> Any:
    return None if isinstance(x, float) and math.isnan(x) else x


@dataclass(frozen=True)
class _NoRead:
    """Stand-in for a protocol object without ``[read]`` (tests' stubs)."""


def protocol_settings(protocol: Any) -> dict[str, Any]:
    """The part of :func:`settings_key`'s payload that is the same for every run of a day."""
    return {
        "format": CACHE_FORMAT,
        "version": __version__,
        "processing": asdict(protocol.processing),
        "channels": {k: asdict(v) for k, v in sorted(protocol.channels.items())},
        "read": asdict(getattr(protocol, "read", None) or _NoRead()),
        "balance": asdict(protocol.balance) if getattr(protocol, "balance", None) else None,
    }


def settings_key(
    protocol: Any, row: dict[str, Any], common: dict[str, Any] | None = None,
    side_sha: str = "",
) -> str:
    """Hash of everything besides the file's bytes that changes a run's reduction.

    The sha256 of ``json.dumps(payload, sort_keys=True, default=str)`` with payload = format,
    version, processing settings, channel mapping (:func:`protocol_settings`, which may be
    given as ``common`` when the keys of many runs are made), file name, manual window, set
    values, the run's purpose (``test``, which decides which notes are warnings), ``config``
    when it is ``fin`` (a fin run without numbers in its lift column is rejected) and, when the
    sheet gives one, the run's ``segment``; a captive run's sheet settings, the model's
    inertia and the ``[captive]`` cycle options (:data:`CAPTIVE_OPTION_KEYS`); and the sha256
    of the run's side files (``side_sha``, or the row's ``side_files_sha``: its carriage log
    and zeros file).
    """
    payload = dict(protocol_settings(protocol) if common is None else common)
    payload.update({
        "file": str(row["file"]),
        "window": [_num(row.get("window_start_s")), _num(row.get("window_end_s"))],
        "nominal": [_num(row.get("speed_nominal")), _num(row.get("accel_nominal"))],
        "test": str(row.get("test", "")).strip().lower(),
    })
    try:  # the run's acquisition in a file holding several (NaN or <NA>: none given)
        segment = float(row.get("segment", math.nan))
    except (TypeError, ValueError):
        segment = math.nan
    if math.isfinite(segment):
        payload["segment"] = int(segment)
    if str(row.get("config", "")).strip().lower() == "fin":  # a fin run needs its lift
        payload["config"] = "fin"
    captive = {k: _num(row.get(k)) for k in CAPTIVE_ROW_KEYS if k in row}
    if payload["test"] in CAPTIVE_TEST_NAMES:  # the sheet's settings and the model's inertia
        model = getattr(protocol, "model", None)
        options = getattr(protocol, "captive", None)
        payload["captive"] = {**captive, "model": {k: getattr(model, k, None)
                                                   for k in CAPTIVE_MODEL_KEYS},
                              "cycles": {k: getattr(options, k, None)
                                         for k in CAPTIVE_OPTION_KEYS}}
    side = side_sha or row.get("side_files_sha")
    if side:  # its carriage log and zeros file are read with the run
        payload["side_files"] = side
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


def _valid_records(value: Any, ok: Any) -> dict[str, list[Any]]:
    """The index map ``value`` with every record that ``ok`` refuses (or that is not a list
    under a text key) dropped."""
    if not isinstance(value, dict):
        return {}
    return {k: v for k, v in value.items()
            if isinstance(k, str) and isinstance(v, list) and ok(v)}


def _file_record(rec: list[Any]) -> bool:
    """[size, mtime_ns, sha256, ctime_ns, inode] of ``files``."""
    return (len(rec) == 5 and isinstance(rec[2], str)
            and all(type(rec[i]) is int for i in (0, 1, 3, 4)))


def _entry_location(loc: list[Any]) -> bool:
    """[pack, offset, length, crc32] of ``entries``, the pack a name towtank gives."""
    return (len(loc) == 4 and isinstance(loc[0], str) and bool(_PACK_NAME.fullmatch(loc[0]))
            and all(type(loc[i]) is int and loc[i] >= 0 for i in (1, 2, 3)))


class RunCache:
    """Per-run reductions on disk; a missing, damaged or unexpected entry is simply a miss.

    Parameters
    ----------
    directory : path
        The cache folder (``.cache`` in the output folder).
    kind : type
        The dataclass of the entries (:class:`towtank.reduce.run.RunReduction`): every entry
        read back is checked against its fields' types (:func:`towtank.runtime.records.
        from_bytes`).
    check : callable, optional
        A further check of an entry read back, of its values (finite means, sample tables of
        float64 columns of one length...: :func:`towtank.reduce.sanity.sane_reduction`);
        False is a miss, and the entry put for the same run then replaces it.
    """

    def __init__(self, directory: str | Path, kind: type[Any], check: Any = None):
        self.dir = Path(directory)
        self.kind = kind
        self._check = check
        self._runs = self.dir / "runs"
        self._index_path = self.dir / "files.json"
        self._files: dict[str, list[Any]] = {}
        self._entries: dict[str, list[Any]] = {}
        #: why the cache is not used (a sentence), or None
        self.problem: str | None = None
        if os.path.lexists(self.dir) and not is_real_dir(self.dir):
            self.problem = (f"{self.dir} is not a folder (or is a link to one): the per-run "
                            "cache is not used; remove it to have one again.")
        elif os.path.lexists(self._runs) and not is_real_dir(self._runs):
            self.problem = (f"{self._runs} is not a folder (or is a link to one): the per-run "
                            "cache is not used; remove it to have one again.")
        else:
            try:
                data = json.loads(read_regular(self._index_path, MAX_INDEX_BYTES) or b"null")
            except (ValueError, RecursionError, UnicodeDecodeError):
                data = None
            if isinstance(data, dict) and data.get("format") == INDEX_FORMAT:
                self._files = _valid_records(data.get("files"), _file_record)
                self._entries = _valid_records(data.get("entries"), _entry_location)
        self._pending: list[tuple[str, bytes]] = []
        self._packs: dict[str, bytes | None] = {}  # pack name -> its bytes, read on first use
        self._real_dirs: dict[str, str] = {}
        self._dirty = False
        self._last_write = time.monotonic()

    @property
    def usable(self) -> bool:
        return self.problem is None

    # ----------------------------------------------------------------------------- files
    def _stat(self, path: Path) -> tuple[str, os.stat_result] | None:
        """The file's index key (its real path, as ``Path.resolve``) and its stat."""
        name = os.fspath(path)
        try:
            st = os.lstat(name)
        except OSError:
            return None
        if stat.S_ISLNK(st.st_mode):
            try:
                return str(Path(name).resolve()), os.stat(name)
            except (OSError, RuntimeError):
                return None
        head, tail = os.path.split(name)
        real = self._real_dirs.get(head)
        if real is None:
            real = self._real_dirs[head] = os.path.realpath(head or ".")
        return os.path.join(real, tail), st

    def known_file(self, path: Path) -> tuple[str, tuple[int, int, int, int]] | None:
        """The file's sha256 and its (size, mtime_ns, ctime_ns, inode) if those are the ones
        recorded with it (the file as the reduction cached for it read it), else None.

        The ctime (set by the system on every write, not settable by ``touch``) and the inode
        catch a file rewritten at the same size with its mtime put back. One stat.
        """
        found = self._stat(path)
        if found is None:
            return None
        key, st = found
        rec = self._files.get(key)
        stamp = (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)
        if rec and (rec[0], rec[1], rec[3], rec[4]) == stamp:
            return str(rec[2]), stamp
        return None

    def hit(self, path: Path, file: str, key: str, run: int) -> Any | None:
        """The reduction cached for the run file at ``path`` (named ``file`` in the sheet)
        under settings key ``key``, as run ``run`` with the file's stamp as it was read; None
        for a miss: the file not known as it is now, no entry, or an entry that is not this
        file's (another sha256 or file name).

        The entries are dataclasses with fields ``run``, ``file``, ``sha256`` and
        ``file_stamp`` (:class:`towtank.reduce.run.RunReduction`).
        """
        known = self.known_file(path)
        if known is None:
            return None
        sha, stamp = known
        entry = self.get(sha, key)
        if entry is None or entry.sha256 != sha or entry.file != file:
            return None
        return replace(entry, run=run, file_stamp=stamp)

    def known_sha(self, path: Path) -> str | None:
        """The file's sha256 if :meth:`known_file` knows the file as it is."""
        known = self.known_file(path)
        return known[0] if known is not None else None

    def remember_sha(self, path: Path, sha: str,
                     stamp: tuple[int, int, int, int] | None | bool = True) -> None:
        """Remember that ``path`` holds the bytes of ``sha``.

        ``stamp`` is (size, mtime_ns, ctime_ns, inode) of the file as those bytes were read
        (:func:`towtank.ingest.runfile.file_bytes_stamped`): the file is remembered only if
        it is still that file, so a file changed after it was read is read again next time.
        None (the file changed while it was read) remembers nothing; True (no stamp known)
        takes the file as it is now.
        """
        found = self._stat(path)
        if found is None or stamp is None or stamp is False:
            return
        key, st = found
        now = (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)
        if stamp is not True and tuple(stamp) != now:
            return
        self._files[key] = [st.st_size, st.st_mtime_ns, sha, st.st_ctime_ns, st.st_ino]
        self._dirty = True

    # --------------------------------------------------------------------------- entries
    @staticmethod
    def _name(sha: str, key: str) -> str:
        return f"{sha[:32]}-{key}"

    def _pack_bytes(self, pack: str) -> bytes | None:
        if pack not in self._packs:
            self._packs[pack] = read_regular(self._runs / pack, MAX_PACK_BYTES)
        return self._packs[pack]

    def _blob(self, name: str) -> bytes | None:
        loc = self._entries.get(name)
        if loc is None:
            return None
        pack, offset, length, crc = loc
        data = self._pack_bytes(pack)
        if data is None or offset + length > len(data):
            return None
        blob = data[offset : offset + length]
        return blob if zlib.crc32(blob) == crc else None

    def get(self, sha: str, key: str) -> Any | None:
        """The entry stored for (file sha256, settings key), checked; None for a miss."""
        if not self.usable:
            return None
        name = self._name(sha, key)
        blob = next((b for n, b in self._pending if n == name), None)
        if blob is None:
            blob = self._blob(name)
        if blob is None:
            return None
        try:
            value: Any = records.from_bytes(blob, self.kind)
        except records.RecordError:
            return None
        if self._check is not None and not self._check(value):
            return None
        return value

    def put(self, sha: str, key: str, value: Any) -> None:
        """Store a reduction (encoded now; written with the next pack)."""
        if not self.usable:
            return
        self._pending.append((self._name(sha, key), records.to_bytes(value)))
        self._dirty = True
        if (len(self._pending) >= PACK_ENTRIES
                and time.monotonic() - self._last_write >= PACK_SECONDS):
            self._guarded(self._write_pack_and_index)

    def _write_pack_and_index(self) -> None:
        self._write_pack()
        self._write_index()

    # ----------------------------------------------------------------------------- disk
    def _guarded(self, write: Any) -> None:
        """Run a write of the cache; a failure (full disk, a folder in a file's place) turns
        the cache off for the rest of the day with a sentence in :attr:`problem`: the cache
        only saves time, it never stops a day."""
        try:
            write()
        except OSError as exc:
            self.problem = (f"the per-run cache in {self.dir} could not be written "
                            f"({exc.strerror or type(exc).__name__}); the day was processed "
                            "without it.")
            self._pending.clear()

    def _write_pack(self) -> None:
        if not self._pending:
            return
        pack = f"pack-{time.time_ns():x}-{os.getpid()}.bin"
        parts, offset = [], 0
        locs: dict[str, list[Any]] = {}
        for name, blob in self._pending:
            parts.append(blob)
            locs[name] = [pack, offset, len(blob), zlib.crc32(blob)]
            offset += len(blob)
        data = b"".join(parts)
        _atomic_write(self._runs / pack, data)
        self._entries.update(locs)
        self._pending.clear()
        self._last_write = time.monotonic()

    def _write_index(self) -> None:
        payload = {"format": INDEX_FORMAT, "files": self._files, "entries": self._entries}
        _atomic_write(self._index_path, json.dumps(payload, separators=(",", ":")).encode())

    def _merge_packs(self) -> None:
        """Rewrite every indexed entry into one pack; remove the packs merged (and old orphans)."""
        packs = {str(loc[0]) for loc in self._entries.values()}
        if len(packs) <= MAX_PACKS:
            return
        for name in list(self._entries):
            blob = self._blob(name)
            del self._entries[name]
            if blob is not None:
                self._pending.append((name, blob))
        self._write_pack()
        self._write_index()
        keep = {str(loc[0]) for loc in self._entries.values()}
        now = time.time()
        for path in self._runs.glob("pack-*.bin"):
            try:
                old = now - path.lstat().st_mtime > ORPHAN_AGE_S
                if (path.name not in keep and (path.name in packs or old)
                        and _PACK_NAME.fullmatch(path.name) and path.is_file()
                        and not path.is_symlink()):
                    path.unlink()
                    self._packs.pop(path.name, None)
            except OSError:
                pass

    def flush(self) -> None:
        """Write the pending entries and the index."""
        if self._dirty and self.usable:
            def write() -> None:
                self._write_pack()
                self._write_index()
                self._merge_packs()

            self._guarded(write)
            self._dirty = False


# ================================================================================ the day
DAY_FORMAT = 2  # 2: outputs by their stat, inputs as every file the day opened
#: The exit statuses a completed day records and replays: every run used (0), some rejected (1).
REPLAY_CODES = (0, 1)


def _stamp(path: Path) -> tuple[int, int, int, int] | None:
    """(size, mtime_ns, ctime_ns, inode) of a file now, or None if it cannot be stat'ed."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino)


def _sha_file(path: Path) -> str | None:
    return sha256_regular(path)


def _lstamp(path: Path) -> list[int] | None:
    """[size, mtime_ns, ctime_ns, inode] of a regular file (not a link), else None."""
    try:
        st = os.lstat(path)
    except OSError:
        return None
    if not stat.S_ISREG(st.st_mode):
        return None
    return [st.st_size, st.st_mtime_ns, st.st_ctime_ns, st.st_ino]


MAX_DAY_BYTES = 64 << 20  # a larger day.json is not read


def _tree(root: Path, skip: tuple[str, ...] = ()) -> list[tuple[str, int, int, int]]:
    """(relative path, size, mtime_ns, ctime_ns) of every file under ``root``, sorted."""
    out = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if d not in skip and d != "__pycache__")
        for name in filenames:
            p = os.path.join(dirpath, name)
            try:
                st = os.stat(p)
            except OSError:
                continue
            out.append((os.path.relpath(p, root), st.st_size, st.st_mtime_ns, st.st_ctime_ns))
    return sorted(out)


def _installed() -> list[str]:
    """Names (with versions) of the distributions installed on sys.path: a library upgraded
    changes the outputs' provenance, so it changes the fingerprint. One listing per folder."""
    out: list[str] = []
    for entry in sys.path:
        try:
            names = os.listdir(entry or ".")
        except OSError:
            continue
        out.extend(n for n in names if n.endswith((".dist-info", ".egg-info")))
    return sorted(out)


class DayStamp:
    """Fingerprint of everything a day's outputs depend on, kept with them (``.cache/day.json``).

    The fingerprint covers towtank's own code (its files' sizes and modification times) and
    version, the libraries' versions, the protocol and the run sheet (their bytes), a reference
    file named by the protocol, the data folder (every file's name, size and modification time,
    as the run cache's index does: nothing is read), the output folder and the options that
    change the outputs. The record of a run adds every other file the day read, whatever
    named it (tare table, hull table, zeros files, run files outside the data folder: all the
    files opened, :mod:`towtank.runtime.reads`), with its stat. :meth:`replay` returns the
    exit code and the summary recorded by the last complete run when its fingerprint is this
    one, every file it read is as it was, and every output the manifest lists is still there
    untouched (same size, mtime, ctime and inode); the caller can then stop. Anything else,
    including any error while checking, is "not unchanged".
    """

    def __init__(self, cache_dir: str | Path, protocol: Any, out_dir: str | Path,
                 options: dict[str, Any] | None = None):
        self.path = Path(cache_dir) / "day.json"
        self.out_dir = Path(out_dir).resolve()
        self._protocol = protocol
        self._options = dict(options or {})
        self._key: str | None = None

    @property
    def key(self) -> str:
        if self._key is None:
            c = self._protocol.campaign
            ref = Path(str(c.reference))
            payload = {
                "format": DAY_FORMAT,
                "version": __version__,
                "code": _tree(Path(towtank.__file__).parent),
                "python": platform.python_version(),
                "libraries": _installed(),
                "protocol": [str(self._protocol.path), _sha_file(Path(self._protocol.path))],
                "run_sheet": [str(c.run_sheet), _sha_file(Path(c.run_sheet))],
                "reference": [str(ref), _sha_file(ref) if ref.is_file() else None],
                "data": [str(c.data_dir), _tree(Path(c.data_dir))],
                "out": str(self.out_dir),
                "options": self._options,
            }
            text = json.dumps(payload, sort_keys=True, default=str)
            self._key = hashlib.sha256(text.encode()).hexdigest()
        return self._key

    def _outputs(self) -> dict[str, list[int] | None]:
        """(size, mtime_ns, ctime_ns, inode) of every file the output folder's manifest says
        towtank wrote: stat only, nothing read (a FIFO or a 12 GB file the user put beside the
        outputs is not towtank's, and not looked at); a link or a non-file is None."""
        data = read_manifest(self.out_dir)
        files = sorted(data["files"]) if data else []
        return {rel: _lstamp(self.out_dir / rel) for rel in files}

    def replay(self) -> tuple[int, str] | None:
        """(exit code, summary) of the last run if nothing changed since, else None.

        The fingerprint is taken here, before the day is read: :meth:`record` compares it with
        the inputs as they are at the end, so that a sheet edited while the day was being
        processed is never recorded as the one the outputs came from.
        """
        try:
            key = self.key  # first: the fingerprint of the inputs before the day is read
            if not is_real_dir(self.path.parent):
                return None
            rec = json.loads(read_regular(self.path, MAX_DAY_BYTES) or b"null")
            if not isinstance(rec, dict) or rec.get("key") != key:
                return None
            outputs, inputs = rec.get("outputs"), rec.get("inputs")
            code, summary = rec.get("exit_code"), rec.get("summary")
            if (not isinstance(outputs, dict) or not outputs or not isinstance(inputs, dict)
                    or type(code) is not int or code not in REPLAY_CODES
                    or not isinstance(summary, str)):
                return None
            if outputs != self._outputs():
                return None
            for path, stamp in inputs.items():
                if stamp is None or list(_stamp(Path(path)) or ()) != list(stamp):
                    return None  # a file the day read (run file, tare table, ...) changed
            return code, summary
        except Exception:  # noqa: BLE001 - any doubt: process the day
            return None

    def record(self, exit_code: int, summary: str,
               inputs: dict[str, tuple[int, int, int, int] | None] | None = None) -> str | None:
        """Remember a completed run (call once its outputs are in place).

        ``inputs`` maps every file the day read (run files wherever they are, side files) to
        its (size, mtime_ns, ctime_ns, inode) as it was read. Nothing is remembered (and the
        returned sentence says why) when the protocol, the sheet, the data folder or one of
        ``inputs`` changed while the day was processed: the next run then processes it again.
        """
        if exit_code not in REPLAY_CODES:
            self.forget()
            return None
        fresh = DayStamp(self.path.parent, self._protocol, self.out_dir, self._options).key
        changed = [p for p, st in (inputs or {}).items() if st is None or _stamp(Path(p)) != st]
        if fresh != self.key or changed:
            self.forget()
            what = (f"{Path(changed[0]).name}{' and others' if len(changed) > 1 else ''}"
                    if changed else "the protocol, the run sheet or the data folder")
            return (f"{what} changed while towtank was working: the outputs may mix the old "
                    "and the new version; run process again.")
        rec = {"key": self.key, "exit_code": int(exit_code), "summary": summary,
               "outputs": self._outputs(),
               "inputs": {p: list(st) for p, st in (inputs or {}).items() if st is not None}}
        if os.path.lexists(self.path.parent) and not is_real_dir(self.path.parent):
            return None  # a link or a file in the cache's place: nothing is written through it
        try:
            _atomic_write(self.path, json.dumps(rec, indent=1).encode())
        except OSError:  # a folder in day.json's place, a full disk: the next run re-processes
            self.forget()
        return None

    def forget(self) -> None:
        """Drop the record (only if it is a file: a folder or link of that name is left)."""
        with contextlib.suppress(OSError):
            if stat.S_ISREG(os.lstat(self.path).st_mode):
                self.path.unlink()
