"""Ingest: read one run file, map and calibrate its channels, and check it is sound.

Run files (docs/formats.md §3) are CSV, CSV.gz or LabVIEW TDMS. The file is read once as bytes (the
same bytes give its sha256 for the cache and the provenance), parsed with pyarrow (CSV) or npTDMS
(TDMS) into float64 arrays, mapped to the canonical channels with value = gain·(raw − offset),
and checked: truncated last line, non-numeric or malformed rows, missing and infinite values,
several acquisitions appended in one file (:mod:`towtank.ingest.segments`: the run's is read
when the sheet's ``segment`` or ``[read] segment`` names it), time not increasing (duplicated
blocks, glitches), an implausible or irregular sample rate,
lost samples, channels clipped flat at a rail, spikes. Repairs that are safe (a few bad rows
dropped, a few lost samples and short gaps interpolated, isolated spikes replaced) are made and
counted in ``notes``; anything else raises :class:`~towtank.errors.RunError` with one sentence
that names the file and says what is wrong and where. Rows are counted as a spreadsheet or a
text editor counts them (the header is row 1); TDMS data are counted in samples from 1.

Raw files are only ever opened for reading. Every check is vectorised (no per-sample loop).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from towtank.errors import RunError
from towtank.ingest.calibration import UNITS, calibrate, unit_source  # noqa: F401 - re-exported
from towtank.ingest.columns import (  # noqa: F401 - the file primitives, importable here too
    fallback_time,
    file_bytes,
    file_bytes_stamped,
    read_columns,
    sha256_bytes,
)
from towtank.ingest.plaincsv import INVALID_KEY as _INVALID_KEY
from towtank.ingest.plaincsv import ROWS_KEY as _ROWS_KEY
from towtank.ingest.plaincsv import read_csv_columns  # noqa: F401 - importable here too
from towtank.ingest.protocol_types import (
    CAPTIVE_CHANNELS,
    CAPTIVE_TESTS,
    PMM_TESTS,
    Balance,
    ChannelMap,
    channel_map,
)
from towtank.ingest.readers import (  # noqa: F401 - MAX_RUN_FILE_BYTES: importable here too
    FS_ERROR_KEY,
    FS_KEY,
    LVM_HEADERS_KEY,
    MAX_RUN_FILE_BYTES,
    TIME_COLUMN_KEY,
    WF_TIME_KEY,
    ReadOptions,
    name_list,
    stated_units,
)
from towtank.ingest.segments import find_segments, human_duration, segment_error
from towtank.ingest.speedlog import speed_on_run_time
from towtank.ingest.timing import time_source_text, timing_note
from towtank.signal.masks import runs_of_true
from towtank.stats.robust import blocks, quantile, quantiles, robust_scale

REQUIRED_CHANNELS = ("time", "speed", "drag")
#: What a file without a speed channel needs (docs/formats.md §3.2): its column, a log, or none.
_NO_SPEED_HINT = ("; map its column in [channels] speed, give the carriage's log in "
                  "[speed_log], or, with no speed recorded, set [processing] speed_source = "
                  "\"nominal\" (each run at the run sheet's speed_nominal)")
OPTIONAL_CHANNELS = ("accel", "lift")
FORCE_CHANNELS = ("drag", "lift")

#: Words in a column's name (lower case, blanks and separators ignored) that name a captive
#: channel when [channels] does not map it: the channel's own name first.
CAPTIVE_GUESSES = {
    "fx": ("fx", "xforce", "forcex", "surgeforce"),
    "fy": ("fy", "yforce", "forcey", "swayforce", "sideforce"),
    "mz": ("mz", "nz", "yawmoment", "momentz", "zmoment"),
    "sway": ("sway", "pmmy", "ypmm", "swayposition", "swaydisplacement"),
    "yaw": ("yaw", "psi", "pmmyaw", "yawangle", "heading"),
}
#: Largest |value| of a captive channel that a rig records (a larger one is another unit).
CAPTIVE_LIMITS = {"sway": (5.0, "is it in mm?"), "yaw": (90.0, "a wrong unit or gain?")}

MIN_SAMPLES = 10
MIN_FS_HZ = 10.0  # below this the time channel is not in seconds (ms? sample numbers?)
MAX_FS_HZ = 1.0e6
JITTER_TOLERANCE = 0.2  # largest departure of one time step from the sample interval [-]
SPIKE_THRESHOLD = 8.0  # robust standard deviations (see despike)
MAX_SPEED = 50.0  # [m/s] no towing carriage is faster: a larger value is a unit or gain error
MAX_VALUE = 1.0e9  # [SI] larger values are corrupted numbers (and would overflow the filters)
MAX_TIME = 1.0e11  # [s] over 3000 years: not a time in seconds

_LABEL_KEY = "__label__"


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
    #: the notes (among ``notes``) the engineer must also see: non-numeric rows dropped
    warnings: tuple[str, ...] = ()
    #: drag and lift zeros [N] from the run's zeros file (``[zeros]``), else None
    zero_levels: dict[str, float] | None = None
    #: the run sheet's set speed [m/s] of a run without a measured speed (``speed_source =
    #: "nominal"``; ``speed`` then holds 0), else NaN
    speed_nominal: float = math.nan
    #: where the time comes from, said for a person: "the column 'Time (s)'", "LabVIEW
    #: waveform timing (wf_increment)", "[read] sample_rate_hz = 200 Hz" ...
    time_source: str = ""
    #: per channel read: (its unit in the file, where that came from: "file", "protocol",
    #: "assumed" or "unknown", see :func:`towtank.ingest.calibration.unit_source`)
    units: dict[str, tuple[str, str]] = field(default_factory=dict)
    #: a captive run's channels (:data:`towtank.ingest.protocol_types.CAPTIVE_CHANNELS` found in the
    #: file): fx, fy [N], mz [N m], sway [m], yaw [deg]; empty for other runs
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    #: the file's columns that ``extra`` was read from (so no note calls them unmapped)
    extra_columns: tuple[str, ...] = ()
    #: the optional channels (lift, accel, ...) whose column holds no numbers, each with the
    #: column it was read from: left out of the run (``lift`` is None) with a note; a fin
    #: run, which needs its lift, is rejected for it (:func:`towtank.reduce.run.reduce_read`)
    blank: dict[str, str] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(self.time.size)


# --------------------------------------------------------------------------- row bookkeeping
class _Where:
    """Where a sample sits in the file: its row (CSV, header = row 1) or sample number (TDMS)."""

    def __init__(self, rows: np.ndarray, label: str = "row"):
        self.rows = rows
        self.label = label

    def __call__(self, i: int) -> str:
        i = min(max(int(i), 0), self.rows.size - 1)
        return f"{self.label} {int(self.rows[i])}"

    def span(self, i0: int, i1: int) -> str:
        """Rows i0..i1 (inclusive sample indices)."""
        if i1 <= i0:
            return self(i0)
        r0 = int(self.rows[min(max(i0, 0), self.rows.size - 1)])
        r1 = int(self.rows[min(max(i1, 0), self.rows.size - 1)])
        return f"{self.label}s {r0}–{r1}"

    def many(self, idx: np.ndarray, limit: int = 5) -> str:
        """'rows 12, 40, 77' (at most ``limit``, then an ellipsis)."""
        idx = np.asarray(idx, dtype=int)
        shown = ", ".join(str(int(self.rows[i])) for i in idx[:limit])
        more = ", …" if idx.size > limit else ""
        return f"{self.label}{'s' if idx.size > 1 else ''} {shown}{more}"

    def subset(self, keep: np.ndarray) -> _Where:
        return _Where(self.rows[keep], self.label)


# ------------------------------------------------------------------------------------ readers
def _to_float_array(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Float64 array and a mask of entries that hold text that is not a number."""
    if values.dtype.kind in "fiub":
        return values.astype(np.float64, copy=False), np.zeros(values.size, dtype=bool)
    # loaded on use: pandas for text in a numeric column only: the reduction's workers
    # never load it
    import pandas as pd

    s = pd.Series(values, dtype=object)
    as_text = s.astype("string").str.strip()
    empty = as_text.isna() | (as_text == "") | as_text.str.lower().isin(["nan", "na", "null"])
    num = pd.to_numeric(as_text.where(~empty), errors="coerce")
    bad = num.isna().to_numpy(dtype=bool, na_value=True) & ~empty.to_numpy(
        dtype=bool, na_value=True
    )
    return num.to_numpy(dtype=np.float64, na_value=np.nan), bad


# ------------------------------------------------------------------------------ checks/repairs
def fill_gaps(
    x: np.ndarray,
    t: np.ndarray,
    max_gap_samples: int,
    name: str,
    *,
    file: str = "",
    where: _Where | None = None,
) -> tuple[np.ndarray, int]:
    """Interpolate NaN gaps up to ``max_gap_samples`` long; a longer gap is a RunError."""
    nan = np.isnan(x)
    if not nan.any():
        return x, 0
    head = f"{file}: " if file else ""
    if nan.all():
        raise RunError(f"{head}the {name} channel holds no numbers")
    starts, lengths = runs_of_true(nan)
    worst = int(np.argmax(lengths))
    if lengths[worst] > max_gap_samples:
        i0, n = int(starts[worst]), int(lengths[worst])
        dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
        rows = f", {where.span(i0, i0 + n - 1)}" if where is not None else ""
        raise RunError(
            f"{head}the {name} channel has a gap of {n} missing values ({n * dt:.2f} s) from "
            f"t = {t[i0]:.2f} s{rows}, longer than the {max_gap_samples * dt:.2f} s that may "
            "be interpolated"
        )
    good = ~nan
    out = x.copy()
    out[nan] = np.interp(t[nan], t[good], x[good])
    return out, int(nan.sum())


@dataclass
class TimeBase:
    """The result of the time checks: sample rate and the lost samples to put back."""

    fs: float
    steps: np.ndarray  # samples per time step (1 everywhere unless samples were lost)

    @property
    def n_lost(self) -> int:
        return int(self.steps.sum() - self.steps.size)


def _not_increasing(
    t: np.ndarray,
    dt: np.ndarray,
    i: int,
    file: str,
    where: _Where,
    values: np.ndarray | None,
) -> RunError:
    """The sentence for the first step i where time does not increase.

    A duplicated block repeats earlier rows, time and data alike; a clock reset starts time
    again from (or before) the start of the file with new data; anything else goes backwards.
    """
    t_prev, t_next = float(t[i]), float(t[i + 1])
    pos = dt[dt > 0]
    med = float(np.median(pos)) if pos.size else 0.0
    j = int(np.searchsorted(t[: i + 1], t_next, side="left"))
    if j <= i and t[j] == t_next:
        m = min(t.size - (i + 1), i + 1 - j)
        eq = t[i + 1 : i + 1 + m] == t[j : j + m]
        k = int(np.argmin(eq)) if not eq.all() else m
        same = values is None or np.array_equal(
            values[i + 1 : i + 1 + k], values[j : j + k], equal_nan=True
        )
        if same and k > 1:
            return RunError(
                f"{file}: time repeats itself from {where(i + 1)}: {where.span(i + 1, i + k)} "
                f"duplicate {where.span(j, j + k - 1)} (t = {t[j]:.4f}–{t[j + k - 1]:.4f} s), "
                f"a duplicated block of {k} rows"
            )
        if same:
            return RunError(
                f"{file}: time repeats at {where(i + 1)} (t = {t_next:.4f} s twice): a "
                "duplicated row"
            )
    if t_next <= float(t[0]) + 2.0 * med:
        return RunError(
            f"{file}: time restarts at {where(i + 1)} (t = {t_next:.4f} s after {t_prev:.4f} s):"
            " a clock reset in the middle of the run"
        )
    return RunError(
        f"{file}: time goes backwards at {where(i + 1)} (t = {t_next:.4f} s after "
        f"{t_prev:.4f} s)"
    )


def time_base(
    t: np.ndarray,
    file: str,
    *,
    where: _Where | None = None,
    max_gap_samples: int = 0,
    max_lost: int = 0,
    values: np.ndarray | None = None,
    max_gap_s: float | None = None,
) -> TimeBase:
    """Check the time channel and find the sample rate.

    Time must increase; its median step must give a plausible rate (MIN_FS_HZ..MAX_FS_HZ);
    every step must be the sample interval to within JITTER_TOLERANCE (or to the resolution the
    times are written with), or a whole multiple of it where samples were lost. Lost samples
    are accepted (and reported in ``steps``) up to ``max_gap_samples`` in one place (or, when
    given, as many as fit in ``max_gap_s`` seconds at the rate found) and ``max_lost`` in all;
    anything else is a RunError. ``values`` (a data channel on the same rows) tells a
    duplicated block from a clock reset.
    """
    where = where or _Where(np.arange(t.size) + 2)
    if t.size < MIN_SAMPLES:
        raise RunError(f"{file} has only {t.size} samples")
    dt = np.diff(t)
    bad = np.flatnonzero(~(dt > 0))
    if bad.size:
        raise _not_increasing(t, dt, int(bad[0]), file, where, values)
    med = quantile(blocks(dt), 0.5)  # the typical step (of at most a few thousand)
    fs_med = 1.0 / med
    if not MIN_FS_HZ <= fs_med <= MAX_FS_HZ:
        hint = (
            "is time recorded in ms or as sample numbers rather than in s?"
            if fs_med < MIN_FS_HZ
            else "is time recorded in µs rather than in s?"
        )
        raise RunError(
            f"{file}: the time channel steps by {med:.6g} per sample, a sample rate of "
            f"{fs_med:.3g} Hz: {hint}"
        )
    if max_gap_s is not None:
        max_gap_samples = max(1, int(round(max_gap_s * fs_med)))
    k = np.rint(dt / med)
    tol = JITTER_TOLERANCE * med
    off = (k < 1) | (np.abs(dt - k * med) > tol)
    if off.any():
        # times written with a coarse resolution (ms at 300 Hz: steps of 3 and 4 ms) jitter by
        # one resolution step: that is rounding, not an irregular clock
        distinct = np.unique(dt)
        gaps = np.diff(distinct)
        gaps = gaps[gaps > 1e-6 * med]
        resolution = float(gaps.min()) if gaps.size else 0.0
        if resolution < 0.5 * med:
            tol = max(tol, 1.01 * resolution)
            off = (k < 1) | (np.abs(dt - k * med) > tol)
    if off.any():
        worst = int(np.argmax(np.where(off, np.abs(dt - np.maximum(k, 1) * med), -1.0)))
        n_off = int(off.sum())
        raise RunError(
            f"{file}: the sample rate is irregular: a step of {human_duration(dt[worst])} at "
            f"{where(worst + 1)} (t = {t[worst + 1]:.3f} s) where the rate is {fs_med:.1f} Hz "
            f"({n_off} of {dt.size} steps off by more than {100 * tol / med:.0f} %)"
        )
    lost = k - 1
    if lost.any():
        i = int(np.argmax(lost))
        total = int(lost.sum())
        if lost[i] > max_gap_samples or total > max_lost:
            n_gaps = int(np.count_nonzero(lost))
            raise RunError(
                f"{file}: {int(lost[i])} samples are missing after {where(i)} (t = "
                f"{t[i]:.3f}–{t[i + 1]:.3f} s, a step of {human_duration(dt[i])} where the rate is "
                f"{fs_med:.1f} Hz; {total} lost in {n_gaps} place(s), more than can be "
                "interpolated)"
            )
    regular = k == 1
    exact = np.all(np.abs(dt[regular] - med) <= 1e-9 * med) if regular.any() else True
    fs = fs_med if exact else float(np.count_nonzero(regular) / np.sum(dt[regular]))
    return TimeBase(fs=fs, steps=k.astype(np.int64))


def despike(
    x: np.ndarray, window: int = 7, threshold: float = SPIKE_THRESHOLD
) -> tuple[np.ndarray, int]:
    """Replace isolated spikes (one or two samples wide) by interpolation from their neighbours.

    A sample is a spike when it departs by more than ``threshold`` robust standard deviations
    both from the running median of ``window`` samples (Hampel filter; Pearson, R. K. 2002,
    IEEE Trans. Control Syst. Technol. 10(1)) and from the straight-line extrapolations of the
    two samples on either side. The second test keeps real signal: at a kink (the end of a
    constant-acceleration stretch, say) the running median cuts the corner, but one side's
    extrapolation always runs through it. Robust scales come from
    :func:`towtank.stats.robust.robust_scale`, never below 1e-4 of the channel's range (noise-free
    synthetic data).
    """
    n = x.size
    if n < 3 * window:
        return x, 0
    lo, hi = quantiles(blocks(x), (0.005, 0.995))
    floor = 1e-4 * float(hi - lo) + 1e-12 * float(np.max(np.abs(x)))
    if not floor > 0:
        return x, 0
    with np.errstate(over="ignore", invalid="ignore"):
        d2 = x[2:] - 2.0 * x[1:-1] + x[:-2]  # d2[i - 2]: sample i from its two left neighbours
    s_e = robust_scale(blocks(d2), floor, centred=True)
    big = np.abs(d2) > threshold * s_e
    # sample i departs from both extrapolations: d2[i - 2] (left) and d2[i] (right) are big;
    # the first two and last two samples have one side only
    cand = np.empty(n, dtype=bool)
    cand[:2] = big[:2]
    cand[2:-2] = big[:-2] & big[2:]
    cand[-2:] = big[-2:]
    if not cand.any():
        return x, 0
    # loaded on use: scipy.ndimage only when a channel holds spikes to replace
    from scipy.ndimage import median_filter

    med = median_filter(x, size=window, mode="nearest")
    dev = x - med
    s_d = robust_scale(blocks(dev), floor)
    spikes = cand & (np.abs(dev) > threshold * s_d)
    n_spikes = int(spikes.sum())
    if n_spikes == 0:
        return x, 0
    idx = np.arange(n)
    good = ~spikes
    out = x.copy()
    out[spikes] = np.interp(idx[spikes], idx[good], x[good])
    return out, n_spikes


def check_clipping(
    x: np.ndarray,
    t: np.ndarray,
    fs: float,
    name: str,
    *,
    file: str = "",
    where: _Where | None = None,
    calibration: tuple[float, float] = (1.0, 0.0),
) -> None:
    """Reject a channel that sits flat on a rail (its extreme value): a saturated sensor.

    Clipped means: at least max(20 samples, 20 ms) inside the record (stretches that touch its
    start or end are a reading at rest) exactly at the channel's maximum or minimum, at least
    4 times as many as at any other single value, while off the rail the channel is noisy (the
    robust spread of its second differences is over 4 quantisation steps), so that noise would
    have moved a genuine reading off any one value. A healthy quantised channel repeats values
    but never piles up at its extreme; a noise-free or coarsely quantised channel, whose still
    windows and plateaus are flat anyway, cannot be told from a clipped one and is let through;
    an exact 0 is a reading at rest or zeroed, never a rail. ``calibration`` (gain, offset)
    lets the message give the rail as written in the file too.
    """
    min_len = max(20, int(0.02 * fs))
    if x.size < min_len:
        return
    x_max, x_min = float(np.max(x)), float(np.min(x))
    if x_max == x_min:
        return  # a constant channel: dead or absent, not clipped (the phases will tell)
    head = f"{file}: " if file else ""
    for rail, label in ((x_max, "upper"), (x_min, "lower")):
        if rail == 0.0:
            continue
        at = x == rail
        if np.count_nonzero(at) < min_len:
            continue
        inner = at.copy()
        if at[0]:
            inner[: int(np.argmin(at))] = False
        if at[-1]:
            inner[x.size - int(np.argmin(at[::-1])) :] = False
        n_at = int(np.count_nonzero(inner))
        if n_at < min_len:
            continue
        off = ~at
        pairs = off[1:] & off[:-1]
        steps = np.abs(np.diff(x))[pairs]
        steps = steps[steps > 0]
        quantum = float(steps.min()) if steps.size else 0.0
        triples = off[2:] & off[1:-1] & off[:-2]
        with np.errstate(over="ignore", invalid="ignore"):
            d2 = (x[2:] - 2.0 * x[1:-1] + x[:-2])[triples]
        noise = robust_scale(d2, 0.0) if d2.size >= min_len else 0.0
        if not noise > 4.0 * quantum:
            continue
        _, counts = np.unique(x[off], return_counts=True)
        if n_at < 4 * int(counts.max(initial=1)):
            continue
        idx = np.flatnonzero(inner)
        i0, i1 = int(idx[0]), int(idx[-1])
        rows = f", {where.span(i0, i1)}" if where is not None else ""
        gain, offset = calibration
        raw = f", {rail / gain + offset:.6g} in the file" if (gain, offset) != (1.0, 0.0) else ""
        raise RunError(
            f"{head}the {name} channel is clipped flat at {rail:.6g} {UNITS.get(name, '')} "
            f"({label} rail{raw}) for {n_at} samples ({n_at / fs:.2f} s) between t = {t[i0]:.2f} s "
            f"and {t[i1]:.2f} s{rows}: the sensor or its amplifier saturated"
        )


def _check_range(x: np.ndarray, t: np.ndarray, name: str, file: str, where: _Where) -> None:
    """Reject values no towing tank records: a wrong unit or gain, or corrupted numbers."""
    limit = {"speed": MAX_SPEED, "time": MAX_TIME,
             **{k: v[0] for k, v in CAPTIVE_LIMITS.items()}}.get(name, MAX_VALUE)
    big = np.abs(x) > limit
    if not big.any():
        return
    i = int(np.argmax(np.abs(x)))
    hint = {
        "speed": "a wrong unit or gain in [channels]?",
        "time": "is time recorded in ms or µs rather than in s?",
        **{k: v[1] for k, v in CAPTIVE_LIMITS.items()},
    }.get(name, "corrupted numbers?")
    raise RunError(
        f"{file}: the {name} channel reaches {x[i]:.4g} {UNITS.get(name, '')} at {where(i)} "
        f"(t = {t[i]:.2f} s; {int(big.sum())} value(s) beyond ±{limit:g}): {hint}"
    )


# ------------------------------------------------------------------------------------ mapping
def _squeezed(text: str) -> str:
    """A column's name for guessing: lower case, its unit in brackets and separators gone."""
    text = re.sub(r"[\(\[][^\)\]]*[\)\]]\s*$", "", text.strip().lower())
    return re.sub(r"[\s_\-./]+", "", text)


def captive_guess(column: str) -> str | None:
    """The captive channel (fx, fy, mz, sway, yaw) a column's name is, by
    :data:`CAPTIVE_GUESSES` (``Fy (N)`` → fy, ``Yaw moment`` → mz, ``PMM y`` → sway), or
    None."""
    squeezed = _squeezed(column)
    return next((canon for canon, words in CAPTIVE_GUESSES.items() if squeezed in words), None)


def _found(cols: dict[str, np.ndarray], canon: str) -> str | None:
    """The column named as the canonical channel ``canon`` (blanks and case aside), or None."""
    names = [c for c in cols if not c.startswith("__")]
    return next((c for c in names if c.strip() == canon), None)


def captive_mapping(cols: dict[str, np.ndarray], mapping: dict[str, ChannelMap], name: str,
                    test: str) -> dict[str, ChannelMap]:
    """``mapping`` with a captive run's channels found in the file's columns.

    A channel [channels] does not map is the column of its own name, else the one column whose
    name holds one of :data:`CAPTIVE_GUESSES` (``Fy (N)``, ``Yaw moment``, ``PMM y``). A
    captive run needs mz, and fy (or, for a drift run, lift); a PMM run (sway, yaw, yaw_drift)
    sway; a yaw run (yaw, yaw_drift) yaw; else a RunError in one sentence names the channel.
    """
    out = dict(mapping)
    names = [c for c in cols if not c.startswith("__")]
    taken = {m.column for m in mapping.values()} | {c for m in mapping.values()
                                                     for c in m.columns}
    for canon, words in CAPTIVE_GUESSES.items():
        if canon in out:
            continue
        own = _found(cols, canon)
        hits = [own] if own is not None else [
            c for c in names if c not in taken and _squeezed(c) in words]
        if len(hits) == 1:
            out[canon] = ChannelMap(column=hits[0])
            taken.add(hits[0])
    lift = "lift" in mapping or _found(cols, "lift") is not None
    need = ["mz"] + ([] if test == "drift" and lift else ["fy"])
    need += ["sway"] if test in PMM_TESTS else []
    need += ["yaw"] if test in ("yaw", "yaw_drift") else []
    missing = [c for c in need if c not in out]
    if missing:
        raise RunError(
            f"{name}: the {' and '.join(missing)} channel{'s are' if len(missing) > 1 else ' is'}"
            f" missing, which a {test} run needs (map {'them' if len(missing) > 1 else 'it'} "
            f"in [channels]); columns found: {name_list(names)}", kind="missing_channel")
    return out


def map_channels(
    cols: dict[str, np.ndarray],
    mapping: dict[str, ChannelMap],
    name: str,
    *,
    fallback_time: np.ndarray | None = None,
    used: dict[str, str] | None = None,
    balance: Balance | None = None,
    external: tuple[str, ...] = (),
) -> dict[str, np.ndarray]:
    """Canonical channels from raw columns (not yet calibrated).

    The required channels (time, speed, drag) must be present; accel and lift are optional
    unless the protocol maps them explicitly. Column names are matched exactly, then with
    surrounding blanks ignored. ``fallback_time`` (waveform timing or a stated sample rate, see
    :func:`fallback_time`) stands in for a time column that is neither mapped nor found;
    ``used`` receives the column each channel came from. A channel with ``columns`` is the
    sum of those load cells; the outputs of ``balance`` are its matrix times its inputs.
    Channels in ``external`` come from another file (``[speed_log]``) and are skipped.
    """
    full = {k: v for k, v in channel_map(mapping).items() if k not in external}
    out: dict[str, np.ndarray] = {}
    found = [c for c in cols if not c.startswith("__")]
    stripped = {c.strip(): c for c in found}

    def column(col: str, canon: str) -> np.ndarray:
        key = col if col in cols else stripped.get(col.strip())
        if key is None:
            listed = name_list(found)
            raise RunError(f"{name}: the column '{col}' of the {canon} channel is missing; "
                           f"columns found: {listed}", kind="missing_channel")
        arr, _ = _to_float_array(np.asarray(cols[key]))
        return arr

    for canon, cm in full.items():
        if cm.columns:  # load cells summed
            out[canon] = np.sum([column(c, canon) for c in cm.columns], axis=0)
            if used is not None:
                used[canon] = cm.column
            continue
        if balance is not None and canon in balance.outputs:
            i = balance.outputs.index(canon)
            inputs = [column(c, canon) for c in balance.inputs]
            out[canon] = np.sum([m * x for m, x in zip(balance.matrix[i], inputs, strict=True)],
                                axis=0)
            if used is not None:
                used[canon] = "[balance]"
            continue
        key = cm.column if cm.column in cols else stripped.get(cm.column.strip())
        if key is None and canon == "time" and "time" not in mapping and \
                TIME_COLUMN_KEY in cols:  # the file's time under its own name (LVM X_Value)
            key = cols[TIME_COLUMN_KEY].item()[0]
        if key is None and canon == "time" and "time" not in mapping and \
                fallback_time is not None:
            out["time"] = fallback_time
            if used is not None:
                used["time"] = "time (from the file's timing)"
            continue
        if key is not None and used is not None:
            used[canon] = key
        if key is not None:
            if f"{key} (duplicate)" in cols:
                raise RunError(
                    f"{name}: the column '{key}' for the {canon} channel appears more than once"
                )
            out[canon] = cols[key]
        elif canon in REQUIRED_CHANNELS or canon in mapping:
            how = (
                f"mapped from the column '{cm.column}' in [channels]"
                if canon in mapping
                else f"expected as the column '{canon}' (no [channels] mapping)"
            )
            listed = name_list(found)
            if canon == "time" and "time" not in mapping and FS_ERROR_KEY in cols:
                raise RunError(
                    f"{name} has no time column, and {cols[FS_ERROR_KEY].item()}, so the time "
                    "cannot be built from it (write it as a number in Hz, fs = 200 or "
                    "'200 Hz', or give [read] sample_rate_hz)"
                )
            if canon == "time" and "time" not in mapping:
                how += (", no LabVIEW waveform timing (wf_increment) and no [read] "
                        "sample_rate_hz")
            raise RunError(
                f"{name}: the {canon} channel is missing ({how}); columns found: {listed}"
                + (_NO_SPEED_HINT if canon == "speed" else ""), kind="missing_channel"
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
    options: ReadOptions | None = None,
    balance: Balance | None = None,
    speed_log: tuple[np.ndarray, np.ndarray, str] | None = None,
    speed_nominal: float | None = None,
    segment: int | None = None,
    test: str = "",
) -> RawRun:
    """Read a run file and return its calibrated, checked channels.

    Parameters
    ----------
    path : Path
        The run file (.csv, .csv.gz or .tdms).
    mapping : dict
        Protocol [channels] mapping (canonical name → column, gain, offset).
    max_nan_gap_s : float
        Longest gap of missing values (or of lost samples) that is interpolated [s]; longer
        gaps reject the run.
    max_bad_row_fraction : float
        Largest fraction of non-numeric or malformed rows (and of lost samples) that is
        dropped (re-interpolated) with a note; more rejects the run.
    do_despike : bool
        Replace isolated spikes in speed, forces and accel by interpolation.
    data : bytes, optional
        The file's bytes when already read (for hashing).
    options : ReadOptions, optional
        The protocol's ``[read]`` section (format, separator, decimal, group, sample rate).
    balance : Balance, optional
        The protocol's ``[balance]``: force channels from a calibration matrix.
    speed_log : tuple, optional
        (time on the run's clock [s], carriage speed [m/s], file name) of the run's speed log
        (:mod:`towtank.ingest.speedlog`): the speed comes from it, not from the run file.
    speed_nominal : float, optional
        The run sheet's set speed [m/s] for a run without a measured speed (``[processing]
        speed_source = "nominal"``): no speed channel is read; ``RawRun.speed`` holds 0 and
        ``RawRun.speed_nominal`` this value.
    segment : int, optional
        Which acquisition of a file holding several one after another is the run, counted
        from 1 (the run sheet's ``segment``; default ``[read] segment``, see
        :mod:`towtank.ingest.segments`). A file with several and no choice is a RunError.
    test : str
        The run sheet's test. A captive test (:data:`towtank.ingest.protocol_types.
        CAPTIVE_TESTS`) also reads the balance's and the PMM's channels into
        ``RawRun.extra`` (:func:`captive_mapping`); its ``drag`` is −fx when the file has fx
        and no drag (a captive file with neither is a RunError).

    Raises
    ------
    RunError
        One sentence naming the file, what is wrong and where (row, time).
    """
    if data is None:
        data = file_bytes(path)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return _load_run(path, mapping, data, max_nan_gap_s, max_bad_row_fraction, do_despike,
                         options or ReadOptions(), balance, speed_log, speed_nominal,
                         segment, test)


def _load_run(
    path: Path,
    mapping: dict[str, ChannelMap],
    data: bytes,
    max_nan_gap_s: float,
    max_bad_row_fraction: float,
    do_despike: bool,
    options: ReadOptions,
    balance: Balance | None = None,
    speed_log: tuple[np.ndarray, np.ndarray, str] | None = None,
    speed_nominal: float | None = None,
    segment: int | None = None,
    test: str = "",
) -> RawRun:
    """read (:func:`read_columns`) -> map (:func:`map_channels`) -> drop bad rows -> calibrate
    (:func:`calibrate`) -> the run's segment -> time base -> gaps, clipping, spikes,
    ranges."""
    name = path.name
    digest = sha256_bytes(data)
    cols, notes = read_columns(path, data, options)
    headers = cols.pop(LVM_HEADERS_KEY, None)
    invalid = cols.pop(_INVALID_KEY, np.array([], dtype=int))
    rows = cols.pop(_ROWS_KEY, None)
    label = "sample" if cols.pop(_LABEL_KEY, None) is not None else "row"
    used: dict[str, str] = {}
    nominal = speed_nominal is not None
    external: tuple[str, ...] = ("speed",) if speed_log is not None or nominal else ()
    if test in CAPTIVE_TESTS:
        mapping = captive_mapping(cols, mapping, name, test)
        if "drag" not in mapping and _found(cols, "drag") is None and \
                (balance is None or "drag" not in balance.outputs):
            external += ("drag",)  # −fx (below)
    else:
        external += CAPTIVE_CHANNELS
    chans = map_channels(cols, mapping, name, used=used, balance=balance, external=external,
                         fallback_time=fallback_time(cols, mapping, options.sample_rate_hz))
    full = channel_map(mapping)
    if FS_ERROR_KEY in cols and used.get("time") in cols:
        notes.append(f"{cols[FS_ERROR_KEY].item()}: ignored (the time column gives the time)")
    if used.get("time") == "time (from the file's timing)":
        timing = timing_note(cols, options.sample_rate_hz)
        notes.extend([timing] if timing else [])
    time_source = time_source_text(cols, used, channel_map(mapping)["time"].column,
                                   options.sample_rate_hz)
    if speed_log is not None or nominal:  # a placeholder until the time base is known
        chans["speed"] = np.zeros(np.asarray(chans["time"]).size)
        used["speed"] = "[speed_log]" if speed_log is not None else "[nominal]"

    sizes = {k: int(np.asarray(v).size) for k, v in chans.items()}
    if len(set(sizes.values())) > 1:
        listed = ", ".join(f"{k} {v}" for k, v in sizes.items())
        raise RunError(
            f"{name}: the channels have different lengths ({listed} samples): the file is "
            "incomplete"
        )
    n_rows = sizes["time"]
    if rows is None or rows.size != n_rows:
        rows = np.arange(n_rows) + (2 if label == "row" else 1)
    where = _Where(rows, label)
    header_rows = rows[headers[headers < n_rows]] if headers is not None else None

    n_notes = len(notes)
    numeric, where = _drop_bad_rows(chans, rows, invalid, where, name, max_bad_row_fraction,
                                    notes)
    dropped = tuple(notes[n_notes:])  # rows dropped: said to the engineer, not only noted

    units: dict[str, tuple[str, str]] = {}
    numeric = calibrate(numeric, full, used, stated_units(cols), name, notes, units)
    if "drag" not in numeric:  # a captive run's file without drag
        if "fx" not in numeric:
            raise RunError(f"{name}: the file has no fx channel (the balance's axial force) "
                           "nor a drag channel, which a captive run needs beside fy and mz",
                           kind="missing_channel")
        numeric["drag"] = -numeric["fx"]
        notes.append("drag taken as −fx (the file has no drag channel)")
    if used.get("time", "").startswith("time (from the file") and FS_KEY not in cols and \
            WF_TIME_KEY not in cols:
        units["time"] = ("s", "protocol")  # [read] sample_rate_hz

    t = _fill_missing_times(numeric, where, name, max_nan_gap_s, notes)
    chosen = segment if segment is not None else (options.segment or None)
    t, where = _run_segment(numeric, t, where, name, chosen, header_rows, max_nan_gap_s, notes)

    n = t.size
    if n < MIN_SAMPLES:
        raise RunError(f"{name} has only {n} usable samples")
    _check_range(t, t, "time", name, where)
    tb = time_base(
        t,
        name,
        where=where,
        max_gap_s=max_nan_gap_s,
        max_lost=int(max_bad_row_fraction * (n + 1)),
        values=numeric["drag"],
    )
    fs = tb.fs
    max_gap = max(1, int(round(max_nan_gap_s * fs)))
    if tb.n_lost:
        t, where = _put_back_lost(numeric, tb, where, notes)
    if speed_log is not None:
        numeric["speed"] = speed_on_run_time(t, *speed_log)
        notes.append(f"carriage speed from the speed log {speed_log[2]}")

    blank = _repair_and_check(numeric, t, fs, full, tb.n_lost, max_gap, do_despike, name,
                              where, notes)
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
        warnings=dropped,
        speed_nominal=float(speed_nominal) if speed_nominal is not None else math.nan,
        time_source=time_source,
        units=units,
        extra={c: numeric[c] for c in CAPTIVE_CHANNELS if c in numeric},
        extra_columns=tuple(col for c in CAPTIVE_CHANNELS if c in mapping and c in numeric
                            for col in (mapping[c].columns or (mapping[c].column,))),
        blank={c: used.get(c, c) for c in blank},
    )


def _drop_bad_rows(
    chans: dict[str, np.ndarray], rows: np.ndarray, invalid: np.ndarray, where: _Where,
    name: str, max_bad_row_fraction: float, notes: list[str],
) -> tuple[dict[str, np.ndarray], _Where]:
    """Channels as floats with non-numeric and malformed rows dropped (a few, with a note) or
    the run rejected (more than ``max_bad_row_fraction`` of them)."""
    n_rows = len(rows)
    bad_rows = np.zeros(n_rows, dtype=bool)
    numeric: dict[str, np.ndarray] = {}
    for canon, raw in chans.items():
        arr, bad = _to_float_array(np.asarray(raw))
        bad_rows |= bad
        numeric[canon] = arr
    n_text = int(bad_rows.sum())
    n_bad = n_text + int(invalid.size)
    total = n_rows + int(invalid.size)
    if n_bad:
        frac = n_bad / max(total, 1)
        if frac > max_bad_row_fraction:
            all_bad = np.sort(np.concatenate([rows[bad_rows], invalid[invalid > 0]]))
            first = f"first at row {int(all_bad[0])}; " if all_bad.size else ""
            raise RunError(
                f"{name}: {n_bad} of {total} rows are not numeric or malformed ({first}"
                f"{100 * frac:.1f} %, more than the {100 * max_bad_row_fraction:g} % that may "
                "be dropped)"
            )
        if n_text:
            notes.append(
                f"{n_text} non-numeric row(s) dropped ({where.many(np.flatnonzero(bad_rows))})"
            )
            keep = ~bad_rows
            numeric = {k: v[keep] for k, v in numeric.items()}
            where = where.subset(keep)
    return numeric, where


def _fill_missing_times(numeric: dict[str, np.ndarray], where: _Where, name: str,
                        max_nan_gap_s: float, notes: list[str]) -> np.ndarray:
    """The time channel with a short stretch of missing times interpolated by row (the clock
    is regular; the time checks still see any irregularity around it); a long one rejects
    the run."""
    t = numeric["time"]
    no_t = np.isnan(t)
    if not no_t.any():
        return t
    if np.count_nonzero(~no_t) < MIN_SAMPLES:
        raise RunError(f"{name}: the time channel holds no numbers")
    starts, lengths = runs_of_true(no_t)
    tt = t[~no_t]
    dt_est = float(np.median(np.diff(tt))) if tt.size > 1 else 0.0
    gap_max = max(1, int(round(max_nan_gap_s / dt_est))) if dt_est > 0 else 1
    k = int(np.argmax(lengths))
    if lengths[k] > gap_max:
        i0, n = int(starts[k]), int(lengths[k])
        raise RunError(
            f"{name}: the time channel is empty for {n} rows ({where.span(i0, i0 + n - 1)}), "
            f"longer than the {max_nan_gap_s:g} s that may be interpolated"
        )
    idx = np.arange(t.size)
    t = np.interp(idx, idx[~no_t], t[~no_t])
    numeric["time"] = t
    notes.append(f"{int(no_t.sum())} missing time value(s) interpolated")
    return t


def _run_segment(numeric: dict[str, np.ndarray], t: np.ndarray, where: _Where, name: str,
                 chosen: int | None, header_rows: np.ndarray | None, max_gap_s: float,
                 notes: list[str]) -> tuple[np.ndarray, _Where]:
    """The rows of the run's acquisition (``chosen``, from 1) of a file holding several one
    after another (:func:`towtank.ingest.segments.find_segments`; ``numeric`` is cut to
    them); a file with several and no choice, or fewer than chosen, is a RunError."""
    headers = (np.searchsorted(where.rows, header_rows) if header_rows is not None
               and header_rows.size else None)
    segs = find_segments(t, headers=headers, values=numeric.get("drag"), max_gap_s=max_gap_s)
    if len(segs) <= 1 and chosen in (None, 1):
        return t, where
    if chosen is None or not 1 <= chosen <= len(segs):
        raise segment_error(name, t, segs, where.rows, where.label, chosen)
    seg = segs[chosen - 1]
    keep = np.zeros(t.size, dtype=bool)
    keep[seg.start:seg.stop] = True
    for canon in list(numeric):
        numeric[canon] = numeric[canon][keep]
    span = where.span(seg.start, seg.stop - 1)
    notes.append(f"segment {chosen} of {len(segs)} read ({span}, t = {t[seg.start]:.4f}–"
                 f"{t[seg.stop - 1]:.4f} s; the file holds {len(segs)} acquisitions)")
    return t[keep], where.subset(keep)


def _put_back_lost(numeric: dict[str, np.ndarray], tb: TimeBase, where: _Where,
                   notes: list[str]) -> tuple[np.ndarray, _Where]:
    """Lost samples put back as missing values on a regular time base (in ``numeric``)."""
    pos = np.concatenate(([0], np.cumsum(tb.steps)))
    m = int(pos[-1]) + 1
    grid = np.interp(np.arange(m), pos, numeric["time"])
    for canon in list(numeric):
        full_arr = np.full(m, np.nan)
        full_arr[pos] = numeric[canon]
        numeric[canon] = full_arr
    numeric["time"] = grid
    rows_full = np.zeros(m, dtype=np.int64)
    rows_full[pos] = where.rows
    notes.append(f"{tb.n_lost} lost sample(s) put back by interpolation")
    return grid, _Where(np.maximum.accumulate(rows_full), where.label)  # a lost one: row before


def _repair_and_check(
    numeric: dict[str, np.ndarray], t: np.ndarray, fs: float, full: dict[str, ChannelMap],
    n_lost: int, max_gap: int, do_despike: bool, name: str, where: _Where, notes: list[str],
) -> list[str]:
    """Per channel (in ``numeric``): gaps filled, clipping checked, spikes removed, range
    checked; an optional channel without numbers dropped (the dropped ones are returned)."""
    blank = []
    for canon in ("speed",) + FORCE_CHANNELS + ("accel",) + CAPTIVE_CHANNELS:
        if canon not in numeric:
            continue
        arr = numeric[canon]
        if np.isnan(arr).all() and canon not in REQUIRED_CHANNELS:
            del numeric[canon]
            notes.append(f"the {canon} column holds no numbers; the channel is ignored")
            blank.append(canon)
            continue
        arr, n_filled = fill_gaps(arr, t, max_gap, canon, file=name, where=where)
        if n_filled and not n_lost:
            notes.append(f"{n_filled} missing {canon} value(s) interpolated")
        elif n_filled > n_lost:
            notes.append(f"{n_filled - n_lost} missing {canon} value(s) interpolated")
        cm = full[canon]
        check_clipping(
            arr, t, fs, canon, file=name, where=where, calibration=(cm.gain, cm.offset)
        )
        if do_despike:
            arr, n_spikes = despike(arr)
            if n_spikes:
                notes.append(f"{n_spikes} spike(s) removed from {canon}")
        _check_range(arr, t, canon, name, where)
        numeric[canon] = arr
    return blank
