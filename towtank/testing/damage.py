"""Damaged run files, made on purpose: for testing that bad input never crashes a day.

One function per kind of damage a towing-tank run file suffers in practice. Each takes a good
run file's bytes (CSV, or gzip-compressed CSV) or its table as a :class:`pandas.DataFrame` and
returns a damaged copy (the input is never changed); randomness comes only from ``seed``, so a
seed gives the same damage, byte for byte.

========================  ===============================================  ================
function                  damage                                           returns
========================  ===============================================  ================
:func:`empty`             a file with nothing in it                        bytes
:func:`truncate`          the file cut in the middle of a line             bytes
:func:`insert_text_rows`  lines of text among the numbers                  bytes
:func:`drop_channel`      a column missing                                 like the input
:func:`nan_gap`           a stretch of one channel's values missing        like the input
:func:`duplicate_block`   a block of rows written twice                    like the input
:func:`time_reset`        the clock restarting in the middle of the run    like the input
:func:`irregular_rate`    time stamps jittered (an unsteady sample clock)  like the input
:func:`clip`              a channel saturated flat at a rail               like the input
:func:`spikes`            isolated one-sample spikes on a channel          like the input
:func:`no_plateau`        a carriage profile that never settles            like the input
========================  ===============================================  ================

Channels are found by their canonical name (``time``, ``speed``, ``drag``, ...), or by a
column name, or by a keyword in the lab's column names (``Fx load cell (V)`` is the drag).

:func:`make_damaged_day` writes a whole synthetic hull day (:mod:`towtank.testing.synthetic`) with
enough good runs for every coefficient, plus one damaged copy of a good run per kind, a model
run whose tare group has no sting runs, a sheet row whose file does not exist and a stray file
in ``data/`` that the sheet does not name; it returns what each damaged run should come to.
"""

from __future__ import annotations

import functools
import gzip
import io
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import pandas as pd

from towtank.testing import synthetic
from towtank.testing.numbertext import csv_text

__all__ = [
    "read_frame",
    "frame_bytes",
    "find_column",
    "empty",
    "truncate",
    "insert_text_rows",
    "drop_channel",
    "nan_gap",
    "duplicate_block",
    "time_reset",
    "irregular_rate",
    "clip",
    "spikes",
    "no_plateau",
    "DamagedDay",
    "make_damaged_day",
]

Run = TypeVar("Run", bytes, pd.DataFrame)

_KEYWORDS = {
    "time": ("time",),
    "speed": ("speed",),
    "accel": ("accel",),
    "drag": ("drag", "fx"),
    "lift": ("lift", "fy"),
}
_TEXT_ROWS = ("ERROR", "#N/A", "overflow", "--", "buffer overrun", "NaN?")


# ------------------------------------------------------------------------------ conversions
def _is_gzip(data: bytes) -> bool:
    return data[:2] == b"\x1f\x8b"


def read_frame(data: bytes) -> pd.DataFrame:
    """A run file's table from its CSV (or gzip CSV) bytes, values exactly as written."""
    if _is_gzip(data):
        data = gzip.decompress(data)
    return pd.read_csv(io.BytesIO(data))


def frame_bytes(frame: pd.DataFrame) -> bytes:
    """CSV bytes as :mod:`towtank.testing.synthetic` writes them ('\\n' line ends, empty =
    missing)."""
    return csv_text(frame).encode("utf-8")


def _as_bytes(run: bytes | pd.DataFrame) -> tuple[bytes, bool]:
    """(uncompressed CSV bytes, whether the input was gzip)."""
    if isinstance(run, pd.DataFrame):
        return frame_bytes(run), False
    data = bytes(run)
    if _is_gzip(data):
        return gzip.decompress(data), True
    return data, False


def _frame_level(func: Callable[..., pd.DataFrame]) -> Callable[..., Any]:
    """Let a DataFrame-level damage take and give bytes too (gzip stays gzip)."""

    @functools.wraps(func)
    def wrapper(run: Any, *args: Any, **kwargs: Any) -> Any:
        if isinstance(run, pd.DataFrame):
            return func(run.copy(), *args, **kwargs)
        data = bytes(run)
        out = frame_bytes(func(read_frame(data), *args, **kwargs))
        return gzip.compress(out, mtime=0) if _is_gzip(data) else out

    return wrapper


def find_column(frame: pd.DataFrame, channel: str) -> str:
    """The column holding ``channel``: a column name, or a canonical channel by keyword."""
    if channel in frame.columns:
        return channel
    for word in _KEYWORDS.get(channel, (channel.lower(),)):
        hits = [c for c in frame.columns if word in str(c).lower()]
        if hits:
            return hits[0]
    raise KeyError(f"no column for the {channel!r} channel among {list(frame.columns)}")


def _fs(frame: pd.DataFrame) -> float:
    t = frame[find_column(frame, "time")].to_numpy(dtype=float)
    return 1.0 / float(np.median(np.diff(t)))


def _middle_index(n: int, rng: np.random.Generator, lo: float = 0.4, hi: float = 0.7) -> int:
    return int(rng.integers(int(lo * n), max(int(hi * n), int(lo * n) + 1)))


# ------------------------------------------------------------------------- byte-level damage
def empty(run: bytes | pd.DataFrame | None = None) -> bytes:
    """An empty file (0 bytes)."""
    return b""


def truncate(run: bytes | pd.DataFrame, seed: int = 0, *, line: int | None = None) -> bytes:
    """The file cut in the middle of a data line, before its last field (a copy interrupted).

    Parameters
    ----------
    run : bytes or DataFrame
        A good run file (gzip input gives gzip output, cut in the uncompressed text).
    seed : int
        Chooses the line (between 50 % and 90 % of the file) and the cut within it.
    line : int, optional
        The file row to cut (header = row 1) instead of a random one.

    The last row of the result, as a text editor counts, is ``result.count(b"\\n") + 1``.
    """
    data, gz = _as_bytes(run)
    rng = np.random.default_rng(seed)
    starts = np.concatenate(([0], np.flatnonzero(np.frombuffer(data, np.uint8) == 10) + 1))
    n_lines = starts.size - 1 if data.endswith(b"\n") else starts.size
    row = line if line is not None else _middle_index(n_lines, rng, 0.5, 0.9) + 1
    row = min(max(row, 2), n_lines)
    begin = int(starts[row - 1])
    text = data[begin : int(starts[row]) if row < starts.size else len(data)]
    last_delim = text.rfind(b",")
    cut = begin + int(rng.integers(1, max(last_delim, 1) + 1))
    out = data[:cut]
    return gzip.compress(out, mtime=0) if gz else out


def insert_text_rows(run: bytes | pd.DataFrame, n: int, seed: int = 0) -> bytes:
    """``n`` lines of text inserted among the data lines (a logger writing messages or headers).

    Each inserted line has the header's number of fields; some repeat the header, the others
    hold words such as ``ERROR`` or ``#N/A``. They go at distinct random places after the
    first data line.
    """
    data, gz = _as_bytes(run)
    rng = np.random.default_rng(seed)
    lines = data.split(b"\n")
    trailing = lines[-1] == b""
    if trailing:
        lines = lines[:-1]
    header = lines[0]
    n_fields = header.count(b",") + 1
    n_data = len(lines) - 1
    where = np.sort(rng.choice(np.arange(2, n_data + 1), size=min(n, n_data - 1), replace=False))
    texts = []
    for _ in range(where.size):
        if rng.random() < 0.25:
            texts.append(header)
        else:
            word = _TEXT_ROWS[int(rng.integers(len(_TEXT_ROWS)))].encode()
            texts.append(b",".join([word] * n_fields))
    out_lines: list[bytes] = []
    prev = 0
    for pos, txt in zip(where.tolist(), texts, strict=True):
        out_lines.extend(lines[prev:pos])
        out_lines.append(txt)
        prev = pos
    out_lines.extend(lines[prev:])
    out = b"\n".join(out_lines) + (b"\n" if trailing else b"")
    return gzip.compress(out, mtime=0) if gz else out


# -------------------------------------------------------------------- table-level damage
@_frame_level
def drop_channel(frame: pd.DataFrame, channel: str = "drag") -> pd.DataFrame:
    """The channel's column removed (a cable not plugged in, a column not exported)."""
    return frame.drop(columns=[find_column(frame, channel)])


@_frame_level
def nan_gap(
    frame: pd.DataFrame,
    duration: float,
    channel: str = "drag",
    seed: int = 0,
    *,
    start: float | None = None,
) -> pd.DataFrame:
    """``duration`` seconds of one channel's values missing (empty cells).

    The gap starts at ``start`` [s] or at a random time between 40 % and 70 % of the record;
    it is round(duration · fs) samples long (at least one).
    """
    rng = np.random.default_rng(seed)
    col = find_column(frame, channel)
    t = frame[find_column(frame, "time")].to_numpy(dtype=float)
    n = max(1, int(round(duration * _fs(frame))))
    i0 = int(np.searchsorted(t, start)) if start is not None else _middle_index(t.size, rng)
    values = frame[col].to_numpy(dtype=float).copy()
    values[i0 : i0 + n] = np.nan
    frame[col] = values
    return frame


@_frame_level
def duplicate_block(
    frame: pd.DataFrame, seed: int = 0, *, length: int | None = None
) -> pd.DataFrame:
    """A block of rows written twice in a row (a logger re-sending a buffer).

    ``length`` rows (default 0.5 s worth) ending at a random row between 40 % and 70 % of the
    record are repeated right after themselves.
    """
    rng = np.random.default_rng(seed)
    n = len(frame)
    k = length if length is not None else max(2, int(round(0.5 * _fs(frame))))
    i = max(_middle_index(n, rng), k)
    return pd.concat([frame.iloc[:i], frame.iloc[i - k : i], frame.iloc[i:]], ignore_index=True)


@_frame_level
def time_reset(frame: pd.DataFrame, seed: int = 0) -> pd.DataFrame:
    """The time channel restarting from the file's first time at a random row (40–70 %)."""
    rng = np.random.default_rng(seed)
    col = find_column(frame, "time")
    t = frame[col].to_numpy(dtype=float).copy()
    i = _middle_index(t.size, rng)
    t[i:] = t[i:] - t[i] + t[0]
    frame[col] = np.round(t, 9) + 0.0
    return frame


@_frame_level
def irregular_rate(frame: pd.DataFrame, seed: int = 0, *, jitter: float = 0.3) -> pd.DataFrame:
    """Time stamps jittered by up to ±``jitter`` of the sample interval (an unsteady clock).

    The times stay increasing for ``jitter`` < 0.5; steps vary by up to ±2·jitter.
    """
    rng = np.random.default_rng(seed)
    col = find_column(frame, "time")
    t = frame[col].to_numpy(dtype=float)
    dt = float(np.median(np.diff(t)))
    frame[col] = np.round(t + rng.uniform(-jitter, jitter, t.size) * dt, 9) + 0.0
    return frame


@_frame_level
def time_in_ms(frame: pd.DataFrame, seed: int = 0) -> pd.DataFrame:
    """The time channel written in milliseconds under its seconds header (a wrong sample rate:
    200 Hz read as 0.2 Hz, a 15 s run as 4 hours)."""
    col = find_column(frame, "time")
    frame[col] = np.round(frame[col].to_numpy(dtype=float) * 1000.0, 6) + 0.0
    return frame


@_frame_level
def clip(
    frame: pd.DataFrame,
    channel: str = "drag",
    level: float | None = None,
    *,
    rail: str = "upper",
) -> pd.DataFrame:
    """The channel saturated flat at ``level`` (in the file's units, volts for a lab file).

    ``rail="upper"`` caps the values at ``level`` (default: the channel's 90th percentile, so
    that about a tenth of the record sits on the rail); ``rail="lower"`` floors them (default
    level: the 10th percentile).
    """
    col = find_column(frame, channel)
    x = frame[col].to_numpy(dtype=float)
    if rail not in ("upper", "lower"):
        raise ValueError(f"rail must be 'upper' or 'lower', not {rail!r}")
    if level is None:
        level = float(np.percentile(x, 90.0 if rail == "upper" else 10.0))
    frame[col] = np.minimum(x, level) if rail == "upper" else np.maximum(x, level)
    return frame


@_frame_level
def spikes(
    frame: pd.DataFrame,
    n: int,
    channel: str = "drag",
    seed: int = 0,
    *,
    amplitude: float | None = None,
) -> pd.DataFrame:
    """``n`` isolated one-sample spikes of random sign on one channel (electrical glitches).

    Spikes are at least 20 samples apart and from the ends of the record; their height is
    ``amplitude`` (file units; default half the channel's 0.5–99.5 % range).
    """
    rng = np.random.default_rng(seed)
    col = find_column(frame, channel)
    x = frame[col].to_numpy(dtype=float).copy()
    if amplitude is None:
        lo, hi = np.percentile(x, [0.5, 99.5])
        amplitude = 0.5 * float(hi - lo)
    slots = np.arange(20, x.size - 20, 20)
    at = np.sort(rng.choice(slots, size=min(n, slots.size), replace=False))
    at = at + rng.integers(0, 10, size=at.size)
    x[at] += amplitude * rng.choice([-1.0, 1.0], size=at.size)
    frame[col] = x
    return frame


@_frame_level
def no_plateau(frame: pd.DataFrame, seed: int = 0) -> pd.DataFrame:
    """The carriage speed replaced by a ramp up and straight back down: it never settles.

    The motion keeps its start, end and peak speed; the speed rises at constant acceleration
    to the peak at mid-run and falls at once (a triangle), with recorded-speed noise (0.5 mm/s)
    quantised to 0.1 mm/s. An accel channel, if any, becomes the triangle's acceleration.
    """
    rng = np.random.default_rng(seed)
    col = find_column(frame, "speed")
    t = frame[find_column(frame, "time")].to_numpy(dtype=float)
    u = frame[col].to_numpy(dtype=float)
    peak = float(np.max(u))
    moving = np.flatnonzero(u > 0.02 * peak)
    t0, t1 = float(t[moving[0]]), float(t[moving[-1]])
    half = 0.5 * (t1 - t0)
    tri = np.clip(peak * (1.0 - np.abs(t - (t0 + half)) / half), 0.0, None)
    noisy = tri + 0.0005 * rng.standard_normal(t.size)
    frame[col] = np.round(noisy / 1e-4) * 1e-4 + 0.0
    try:
        acol = find_column(frame, "accel")
    except KeyError:
        return frame
    a = np.where((t > t0) & (t < t1), np.sign(t0 + half - t) * peak / half, 0.0)
    frame[acol] = np.round(a, 5) + 0.0
    return frame


# ------------------------------------------------------------------------------- the day
@dataclass
class DamagedDay:
    """What :func:`make_damaged_day` wrote and what processing it must give.

    Unpacks as ``expected, ok_with_note = make_damaged_day(...)``.

    Attributes
    ----------
    expected : dict
        Run number → a keyword of the reason it must be rejected for (in runs.csv ``reason``).
    ok_with_note : list of int
        Runs whose damage is repaired: they must be ``ok`` with a note.
    notes : dict
        Run number → a keyword of that note (runs.csv ``notes``).
    kinds : dict
        Run number → the kind of damage done to it.
    protocol : Path
        The day's protocol (output folder ``output`` beside it).
    stray_file : str
        The file in ``data/`` that the sheet does not name.
    root : Path
        The day's folder (``data/``, ``run_sheet.csv``, ``truth.json``, ``protocol.toml``).
    """

    expected: dict[int, str]
    ok_with_note: list[int]
    notes: dict[int, str] = field(default_factory=dict)
    kinds: dict[int, str] = field(default_factory=dict)
    protocol: Path = Path()
    stray_file: str = ""
    root: Path = Path()

    def __iter__(self):  # noqa: ANN204 - unpacking into (expected, ok_with_note)
        yield self.expected
        yield self.ok_with_note


# kind -> (index of the good run copied in hull_day_plan, reason or note keyword, repaired?)
_DAMAGE_PLAN: tuple[tuple[str, int, str, bool], ...] = (
    ("empty", 12, "empty", False),
    ("truncate", 13, "truncated", False),
    ("text_rows_many", 14, "not numeric", False),
    ("text_rows_few", 13, "non-numeric row", True),
    ("drop_channel", 15, "missing", False),
    ("nan_gap_long", 12, "gap", False),
    ("nan_gap_short", 21, "interpolated", True),
    ("duplicate_block", 13, "duplicated", False),
    ("time_reset", 14, "reset", False),
    ("irregular_rate", 15, "irregular", False),
    ("time_in_ms", 21, "sample rate", False),
    ("clip", 13, "clipped", False),
    ("spikes", 14, "spike", True),
    ("no_plateau", 13, "plateau", False),
    ("no_tare_group", 13, "tare", False),
    ("missing_file", 12, "not found", False),
)


def _damage(kind: str, data: bytes, seed: int) -> bytes | None:
    """The damaged bytes for one kind (None: leave the file as it is, or delete it)."""
    if kind == "empty":
        return empty(data)
    if kind == "truncate":
        return truncate(data, seed)
    if kind == "text_rows_many":
        n_rows = data.count(b"\n")
        return insert_text_rows(data, max(50, n_rows // 20), seed)  # ~5 %
    if kind == "text_rows_few":
        return insert_text_rows(data, 3, seed)
    if kind == "drop_channel":
        return drop_channel(data, "drag")
    if kind == "nan_gap_long":
        return nan_gap(data, 0.5, "drag", seed)
    if kind == "nan_gap_short":
        return nan_gap(data, 0.02, "drag", seed)
    if kind == "duplicate_block":
        return duplicate_block(data, seed)
    if kind == "time_reset":
        return time_reset(data, seed)
    if kind == "irregular_rate":
        return irregular_rate(data, seed)
    if kind == "time_in_ms":
        return time_in_ms(data, seed)
    if kind == "clip":
        return clip(data, "drag")
    if kind == "spikes":
        return spikes(data, 6, "drag", seed)
    if kind == "no_plateau":
        return no_plateau(data, seed)
    return None


def make_damaged_day(out_dir: str | Path, seed: int = 1, *, fs: float = 200.0) -> DamagedDay:
    """Write a synthetic hull day with damaged runs among good ones.

    The good runs are :func:`towtank.testing.synthetic.hull_day_plan` (enough for every
    coefficient).
    After them come copies of good runs' specs with new run numbers (43 on), each damaged in
    one way (``_DAMAGE_PLAN``): empty, truncated, many and few text rows, the drag column
    dropped, a long and a short gap, a duplicated block, a clock reset, an irregular clock, time
    in milliseconds (a wrong sample rate), drag clipped, spikes, no plateau; then a hull run in
    tare group "B" that has no sting runs and a sheet row whose file is deleted. A copy of a
    good file, ``run_099.csv``, is left in ``data/`` without a sheet row. Files are CSV in the
    lab's channel names (forces in volts), the sheet is ``run_sheet.csv`` and the protocol
    ``protocol.toml``.

    Parameters
    ----------
    out_dir : str or Path
        The day's folder (created).
    seed : int
        Seed of the day (the good runs' noise) and of every damage.
    fs : float
        Sample rate [Hz].

    Returns
    -------
    DamagedDay
        Unpacks as ``expected, ok_with_note``: run → rejection keyword, and the runs that must
        stay ok with a note.
    """
    out_dir = Path(out_dir)
    plan = synthetic.hull_day_plan()
    base = [replace(spec, run=i + 1) for i, spec in enumerate(plan)]
    extra = []
    kinds: dict[int, str] = {}
    number = len(base) + 1
    for kind, copy_of, _, _ in _DAMAGE_PLAN:
        spec = base[copy_of]
        group = "B" if kind == "no_tare_group" else spec.tare_group
        extra.append(
            replace(spec, run=number, tare_group=group, remarks=f"damaged: {kind}", status="ok")
        )
        kinds[number] = kind
        number += 1
    synthetic.make_hull_day(
        out_dir,
        seed=seed,
        fs=fs,
        file_format="csv",
        sheet_format="csv",
        runs=base + extra,
    )
    data_dir = out_dir / "data"
    expected: dict[int, str] = {}
    ok_with_note: list[int] = []
    notes: dict[int, str] = {}
    for (kind, _, keyword, repaired), run in zip(_DAMAGE_PLAN, sorted(kinds), strict=True):
        path = data_dir / f"run_{run:03d}.csv"
        if kind == "missing_file":
            path.unlink()
        else:
            damaged = _damage(kind, path.read_bytes(), seed * 1000 + run)
            if damaged is not None:
                path.write_bytes(damaged)
        if repaired:
            ok_with_note.append(run)
            notes[run] = keyword
        else:
            expected[run] = keyword
    stray = "run_099.csv"
    (data_dir / stray).write_bytes((data_dir / "run_014.csv").read_bytes())
    protocol = synthetic.write_protocol(
        out_dir / "protocol.toml",
        header="Synthetic hull day with damaged runs (towtank.testing.damage.make_damaged_day).",
        **synthetic.hull_protocol_sections(".", "output", sheet_format="csv"),
    )
    return DamagedDay(
        expected=expected,
        ok_with_note=ok_with_note,
        notes=notes,
        kinds=kinds,
        protocol=protocol,
        stray_file=stray,
        root=out_dir,
    )
