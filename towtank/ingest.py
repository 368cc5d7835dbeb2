"""Ingest: read one run file, map and calibrate its channels, and check it is sound.

Run files (FORMATS.md §3) are CSV, CSV.gz or LabVIEW TDMS. The file is read once as bytes (the
same bytes give its sha256 for the cache and the provenance), parsed with pyarrow (CSV) or npTDMS
(TDMS) into float64 arrays, mapped to the canonical channels with value = gain·(raw − offset),
and checked: truncated last line, non-numeric rows, NaN gaps, time running backwards or at an
irregular rate, channels clipped flat at a rail, spikes. Repairs that are safe (a few bad rows
dropped, short gaps interpolated, spikes replaced) are made and counted in ``notes``; anything
else raises :class:`~towtank.errors.RunError` with one sentence. Raw files are only ever read.
"""

from __future__ import annotations

import gzip
import hashlib
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from towtank.errors import RunError
from towtank.protocol import ChannelMap, channel_map

REQUIRED_CHANNELS = ("time", "speed", "drag")
OPTIONAL_CHANNELS = ("accel", "lift")
FORCE_CHANNELS = ("drag", "lift")


@dataclass
class RawRun:
    """A run's calibrated channels [SI units], before zeroing and filtering."""

    time: np.ndarray
    speed: np.ndarray
    drag: np.ndarray
    lift: np.ndarray | None = None
    accel: np.ndarray | None = None
    fs: float = 0.0
    sha256: str = ""
    columns: tuple[str, ...] = ()
    notes: list[str] = field(default_factory=list)

    @property
    def n(self) -> int:
        return int(self.time.size)


def file_bytes(path: Path) -> bytes:
    """The file's bytes, read-only; a missing or unreadable file is a RunError."""
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except FileNotFoundError:
        raise RunError(f"the data file {path.name} is not found in {path.parent}") from None
    except OSError as exc:
        raise RunError(f"{path.name} cannot be read ({exc.strerror})") from None


def sha256_bytes(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def file_kind(path: Path) -> str:
    """'csv', 'csv.gz' or 'tdms' from the file name."""
    name = path.name.lower()
    if name.endswith(".csv.gz"):
        return "csv.gz"
    if name.endswith(".csv"):
        return "csv"
    if name.endswith(".tdms"):
        return "tdms"
    raise RunError(f"{path.name} is neither .csv, .csv.gz nor .tdms")


# ------------------------------------------------------------------------------------ readers
def _to_float_array(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Float64 array and a mask of entries that were text but not numbers."""
    import pandas as pd

    if values.dtype.kind in "fiu":
        return values.astype(np.float64, copy=False), np.zeros(values.size, dtype=bool)
    s = pd.Series(values, dtype=object)
    as_text = s.astype("string").str.strip()
    empty = as_text.isna() | (as_text == "") | as_text.str.lower().isin(["nan", "na", "null"])
    num = pd.to_numeric(as_text.where(~empty), errors="coerce")
    bad = num.isna().to_numpy() & ~empty.to_numpy()
    return num.to_numpy(dtype=np.float64, na_value=np.nan), bad


def read_csv_columns(data: bytes, name: str) -> tuple[dict[str, np.ndarray], list[str]]:
    """Parse CSV text (already decompressed) into float64 columns.

    Returns the columns and notes. Rows with the wrong number of fields are skipped by pyarrow's
    invalid-row handler and reported; a last line cut short is reported as a truncated file.
    """
    import pyarrow as pa
    import pyarrow.csv as pacsv

    if not data.strip():
        raise RunError(f"{name} is empty")
    notes: list[str] = []
    truncated_tail = not data.endswith((b"\n", b"\r"))
    invalid: list[int] = []

    def handler(row: pacsv.InvalidRow) -> str:
        invalid.append(row.number if row.number is not None else -1)
        return "skip"

    try:
        table = pacsv.read_csv(
            pa.BufferReader(data),
            read_options=pacsv.ReadOptions(block_size=1 << 22),
            parse_options=pacsv.ParseOptions(invalid_row_handler=handler),
            convert_options=pacsv.ConvertOptions(
                strings_can_be_null=True, null_values=["", "NaN", "nan", "NA", "null"]
            ),
        )
    except pa.ArrowInvalid as exc:
        raise RunError(f"{name} is not a readable CSV table ({str(exc).splitlines()[0]})") from None
    n_lines = table.num_rows + len(invalid) + 1  # + header
    if truncated_tail:
        last_row = n_lines
        raise RunError(f"{name} ends mid-line at row {last_row} (truncated file)")
    if invalid:
        last = max(invalid)
        if last >= n_lines and len(invalid) == 1:
            raise RunError(f"{name} ends mid-line at row {last} (truncated file)")
        notes.append(
            f"{len(invalid)} row(s) with the wrong number of fields skipped "
            f"(first at row {min(invalid)})"
        )
    if table.num_columns == 0 or table.num_rows == 0:
        raise RunError(f"{name} has a header but no data rows")
    cols: dict[str, np.ndarray] = {}
    for col_name, column in zip(table.column_names, table.columns, strict=True):
        if pa.types.is_floating(column.type) or pa.types.is_integer(column.type):
            cols[col_name] = column.to_numpy(zero_copy_only=False).astype(np.float64, copy=False)
        elif pa.types.is_null(column.type):
            cols[col_name] = np.full(table.num_rows, np.nan)
        else:
            cols[col_name] = column.to_numpy(zero_copy_only=False)
    if invalid:
        cols["__invalid_rows__"] = np.asarray(invalid)
    return cols, notes


def read_tdms_columns(data: bytes, name: str) -> tuple[dict[str, np.ndarray], list[str]]:
    """All channels of a TDMS file as float64 arrays, keyed by channel name (and group/channel)."""
    from nptdms import TdmsFile

    if not data:
        raise RunError(f"{name} is empty")
    try:
        tdms = TdmsFile.read(io.BytesIO(data))
    except Exception as exc:  # noqa: BLE001 - nptdms raises many types for damaged files
        raise RunError(f"{name} is not a readable TDMS file ({exc})") from None
    cols: dict[str, np.ndarray] = {}
    for group in tdms.groups():
        for channel in group.channels():
            arr = np.asarray(channel[:])
            if arr.dtype.kind not in "fiu":
                continue
            arr = arr.astype(np.float64, copy=False)
            cols.setdefault(channel.name, arr)
            cols[f"{group.name}/{channel.name}"] = arr
    if not cols:
        raise RunError(f"{name} holds no numeric channels")
    return cols, []


def read_columns(path: Path, data: bytes | None = None) -> tuple[dict[str, np.ndarray], list[str]]:
    """Read a run file's columns (raw units) from its bytes."""
    kind = file_kind(path)
    if data is None:
        data = file_bytes(path)
    if kind == "tdms":
        return read_tdms_columns(data, path.name)
    if kind == "csv.gz":
        try:
            data = gzip.decompress(data)
        except (OSError, EOFError) as exc:
            msg = "truncated gzip file" if isinstance(exc, EOFError) else str(exc)
            raise RunError(f"{path.name} cannot be decompressed ({msg})") from None
    return read_csv_columns(data, path.name)


# ------------------------------------------------------------------------------ checks/repairs
def _runs_of_true(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start indices and lengths of the runs of True in a boolean array."""
    if mask.size == 0:
        return np.array([], dtype=int), np.array([], dtype=int)
    m = np.concatenate(([False], mask, [False])).astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1)
    return starts, ends - starts


def fill_gaps(
    x: np.ndarray, t: np.ndarray, max_gap_samples: int, name: str
) -> tuple[np.ndarray, int]:
    """Interpolate NaN gaps up to ``max_gap_samples`` long; a longer gap is a RunError."""
    nan = np.isnan(x)
    if not nan.any():
        return x, 0
    starts, lengths = _runs_of_true(nan)
    worst = int(np.argmax(lengths))
    if lengths[worst] > max_gap_samples or nan.all():
        i0 = starts[worst]
        span = lengths[worst] * (np.median(np.diff(t)) if t.size > 1 else 0.0)
        raise RunError(
            f"the {name} channel has a gap of {lengths[worst]} missing values ({span:.2f} s) "
            f"from t = {t[i0]:.2f} s, too long to interpolate"
        )
    good = ~nan
    out = x.copy()
    out[nan] = np.interp(t[nan], t[good], x[good])
    return out, int(nan.sum())


def check_time(t: np.ndarray, name: str) -> float:
    """Check the time channel increases at a regular rate; return the sample rate [Hz]."""
    if t.size < 10:
        raise RunError(f"{name} has only {t.size} samples")
    dt = np.diff(t)
    bad = np.flatnonzero(~(dt > 0))
    if bad.size:
        i = int(bad[0])
        what = "repeats" if dt[i] == 0 else "goes backwards"
        raise RunError(
            f"time {what} at row {i + 3} (t = {t[i + 1]:.4f} s after {t[i]:.4f} s): "
            "a duplicated block or a clock reset"
        )
    med = float(np.median(dt))
    worst = int(np.argmax(np.abs(dt - med)))
    if abs(dt[worst] - med) > 0.5 * med:
        raise RunError(
            f"the sample rate is irregular: a step of {dt[worst] * 1e3:.2f} ms at row {worst + 3} "
            f"(t = {t[worst]:.3f} s) where the rate is {1.0 / med:.1f} Hz (samples lost?)"
        )
    return 1.0 / med


def check_clipping(x: np.ndarray, t: np.ndarray, fs: float, name: str) -> None:
    """A channel stuck at its extreme value for ≥ 20 samples (and ≥ 20 ms) is saturated."""
    min_len = max(20, int(0.02 * fs))
    if x.size < min_len:
        return
    for rail, label in ((np.max(x), "upper"), (np.min(x), "lower")):
        at = x == rail
        if at.sum() < min_len:
            continue
        starts, lengths = _runs_of_true(at)
        k = int(np.argmax(lengths))
        if lengths[k] >= min_len:
            raise RunError(
                f"the {name} channel is clipped flat at {rail:g} ({label} rail) for "
                f"{lengths[k] / fs:.2f} s from t = {t[starts[k]]:.2f} s (saturated)"
            )


def despike(x: np.ndarray, window: int = 7, threshold: float = 10.0) -> tuple[np.ndarray, int]:
    """Replace isolated spikes by the running median (Hampel filter).

    A sample is a spike when it departs from the running median of ``window`` samples by more
    than ``threshold`` robust standard deviations (1.4826·MAD of the departures). Pearson, R. K.
    (2002), Outliers in process modeling and identification, IEEE Trans. Control Syst. Technol.
    """
    from scipy.ndimage import median_filter

    if x.size < 3 * window:
        return x, 0
    med = median_filter(x, size=window, mode="nearest")
    dev = x - med
    mad = 1.4826 * np.median(np.abs(dev - np.median(dev)))
    if not mad > 0:
        return x, 0
    spikes = np.abs(dev) > threshold * mad
    n = int(spikes.sum())
    if n == 0:
        return x, 0
    out = x.copy()
    out[spikes] = med[spikes]
    return out, n


# ------------------------------------------------------------------------------------ mapping
def map_channels(
    cols: dict[str, np.ndarray], mapping: dict[str, ChannelMap], name: str
) -> dict[str, np.ndarray]:
    """Canonical channels from raw columns: value = gain·(raw − offset).

    The required channels (time, speed, drag) must be present; accel and lift are optional
    unless the protocol maps them explicitly.
    """
    full = channel_map(mapping)
    out: dict[str, np.ndarray] = {}
    found = [c for c in cols if not c.startswith("__")]
    for canon, cm in full.items():
        if cm.column in cols:
            out[canon] = cols[cm.column]  # calibrated after numeric conversion
        elif canon in REQUIRED_CHANNELS or canon in mapping:
            how = (
                f"mapped from column '{cm.column}' in [channels]"
                if canon in mapping
                else f"expected as column '{canon}' (no [channels] mapping)"
            )
            raise RunError(
                f"the {canon} channel is missing from {name}: {how}; "
                f"columns found: {', '.join(found) or 'none'}"
            )
    return out


def load_run(
    path: Path,
    mapping: dict[str, ChannelMap],
    *,
    max_nan_gap_s: float = 0.05,
    max_bad_row_fraction: float = 0.01,
    do_despike: bool = True,
    data: bytes | None = None,
) -> RawRun:
    """Read a run file and return its calibrated, checked channels.

    Parameters
    ----------
    path : Path
        The run file (.csv, .csv.gz or .tdms).
    mapping : dict
        Protocol [channels] mapping (canonical name → column, gain, offset).
    max_nan_gap_s : float
        Longest gap of missing values that is interpolated [s]; longer gaps reject the run.
    max_bad_row_fraction : float
        Largest fraction of non-numeric or malformed rows that is dropped with a warning;
        more rejects the run.
    do_despike : bool
        Replace isolated spikes in speed and forces by the running median.
    data : bytes, optional
        The file's bytes when already read (for hashing).
    """
    if data is None:
        data = file_bytes(path)
    digest = sha256_bytes(data)
    cols, notes = read_columns(path, data)
    invalid = cols.pop("__invalid_rows__", np.array([], dtype=int))
    chans = map_channels(cols, mapping, path.name)
    full = channel_map(mapping)
    n_rows = next(iter(chans.values())).size
    bad_rows = np.zeros(n_rows, dtype=bool)
    numeric: dict[str, np.ndarray] = {}
    for canon, raw in chans.items():
        arr, bad = _to_float_array(np.asarray(raw))
        bad_rows |= bad
        numeric[canon] = arr
    n_bad = int(bad_rows.sum()) + int(len(invalid))
    total = n_rows + int(len(invalid))
    if n_bad:
        frac = n_bad / max(total, 1)
        if frac > max_bad_row_fraction:
            raise RunError(
                f"{n_bad} of {total} rows of {path.name} are not numeric or malformed "
                f"({100 * frac:.1f} %, more than the {100 * max_bad_row_fraction:g} % that "
                "may be dropped)"
            )
        if bad_rows.any():
            numeric = {k: v[~bad_rows] for k, v in numeric.items()}
            notes.append(f"{int(bad_rows.sum())} non-numeric row(s) dropped")
    for canon, arr in numeric.items():
        cm = full[canon]
        if cm.gain != 1.0 or cm.offset != 0.0:
            numeric[canon] = cm.gain * (arr - cm.offset)

    t = numeric["time"]
    if np.isnan(t).any():
        good = ~np.isnan(t)
        if good.sum() < 10:
            raise RunError(f"the time channel of {path.name} holds no numbers")
        idx = np.arange(t.size)
        t = np.interp(idx, idx[good], t[good])
        notes.append(f"{int((~good).sum())} missing time value(s) interpolated")
    fs = check_time(t, path.name)
    max_gap = max(1, int(round(max_nan_gap_s * fs)))
    for canon in ("speed",) + FORCE_CHANNELS + ("accel",):
        if canon not in numeric:
            continue
        arr, n_filled = fill_gaps(numeric[canon], t, max_gap, canon)
        if n_filled:
            notes.append(f"{n_filled} missing {canon} value(s) interpolated")
        check_clipping(arr, t, fs, canon)
        if do_despike:
            arr, n_spikes = despike(arr)
            if n_spikes:
                notes.append(f"{n_spikes} spike(s) removed from {canon}")
        numeric[canon] = arr
    return RawRun(
        time=t,
        speed=numeric["speed"],
        drag=numeric["drag"],
        lift=numeric.get("lift"),
        accel=numeric.get("accel"),
        fs=fs,
        sha256=digest,
        columns=tuple(c for c in cols if not c.startswith("__")),
        notes=notes,
    )
