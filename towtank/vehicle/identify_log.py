"""A manoeuvre record for ``towtank identify``: read, checked, never modified (docs/formats.md).

The record has the columns ``towtank simulate`` writes (``t_s``, the states ``x_m ... r_deg_s``,
``rudder_deg``, ``sternplane_deg``); any subset of the 12 states, the time and both controls
are required. Other column names are mapped by a ``[channels]`` table
(``r_deg_s = { column = "yaw_rate", gain = 57.29578, offset = 0.0 }``: towtank's value is
``gain * column + offset``). Each problem that makes the record unusable is one sentence
(:class:`LogError`).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from towtank.errors import ProtocolError

__all__ = ["STATE_COLUMNS", "CONTROL_COLUMNS", "MAX_ROWS", "MAX_ROWS_MINUTES", "MIN_ROWS",
           "MAX_GAP_S", "SHORT_NAMES", "LogError", "ManoeuvreLog", "read_log", "log_from_frame",
           "noise_sd", "noise_entry", "parse_noise", "noise_floor", "exact_states",
           "white_noise_ratio", "NOISE_FREE_RATIO", "noise_free_states"]

#: The state columns in the order of the simulation's state vector and their scale to SI.
STATE_COLUMNS = ("x_m", "y_m", "z_m", "phi_deg", "theta_deg", "psi_deg", "u_m_s", "v_m_s",
                 "w_m_s", "p_deg_s", "q_deg_s", "r_deg_s")
CONTROL_COLUMNS = ("rudder_deg", "sternplane_deg")
#: The states' short names (``u``, ``psi``) -> their columns.
SHORT_NAMES = {c.split("_", 1)[0]: c for c in STATE_COLUMNS}
_TO_SI = tuple(math.pi / 180.0 if c.endswith(("_deg", "_deg_s")) else 1.0
               for c in STATE_COLUMNS)
#: Most rows towtank identifies from (a longer record: resample it, 20 Hz is plenty).
MAX_ROWS = 30_000
#: About how long identify takes at most on :data:`MAX_ROWS` rows [min]: three coefficients,
#: the unscented filter and the least-squares cross-check on a two-core machine
#: (tests/benchmarks/test_bench_identify.py: 40 000 rows took 424 s of CPU with 2 of the
#: filter's 4 passes; docs/formats.md, "Why 30 000 rows").
MAX_ROWS_MINUTES = 10
#: Fewest rows with a measured state.
MIN_ROWS = 20
#: Longest step of the time from one row to the next [s]: the filter predicts across a step
#: open loop, and a vehicle's sway and yaw settle within about a second (REMUS: Prestero
#: 2001), so that past a few seconds the record after the gap is another manoeuvre; the work
#: of the prediction grows with the step (Runge-Kutta steps of at most 0.05 s).
MAX_GAP_S = 5.0


class LogError(ValueError):
    """The record cannot be used; the message is one sentence naming the file."""


@dataclass
class ManoeuvreLog:
    """A checked manoeuvre record in SI units (angles in rad).

    Attributes
    ----------
    t : ndarray
        Time [s] from the first sample, increasing
    z : ndarray
        (n, 12) states in the order of :data:`STATE_COLUMNS`, SI [m, rad, m/s, rad/s]; NaN
        where not measured; the heading unwrapped
    rudder, sternplane : ndarray
        Control angles [rad], NaN filled by linear interpolation
    measured : list of int
        Indices of the states that have at least one value
    name : str
        The file's name, for the sentences
    notes : list of str
        What was done to read it (gaps, filled controls)
    """

    t: np.ndarray
    z: np.ndarray
    rudder: np.ndarray
    sternplane: np.ndarray
    measured: list[int]
    name: str = "log"
    notes: list[str] = field(default_factory=list)

    def frame(self) -> pd.DataFrame:
        """The record in the columns and units of manoeuvre.csv."""
        out = {"t_s": self.t}
        for i, col in enumerate(STATE_COLUMNS):
            out[col] = self.z[:, i] / _TO_SI[i]
        out["rudder_deg"] = np.degrees(self.rudder)
        out["sternplane_deg"] = np.degrees(self.sternplane)
        return pd.DataFrame(out)


def read_log(path: Any, channels: dict[str, Any] | None = None) -> ManoeuvreLog:
    """Read a manoeuvre record (CSV) for identification; the file is only read.

    Parameters
    ----------
    path : path-like
        The CSV file
    channels : dict, optional
        ``[channels]``-style mapping: towtank's column name -> the file's column name, or a
        table ``{column, gain, offset}`` (value = gain * column + offset)

    Raises
    ------
    LogError
        One sentence naming the file and the reason.
    """
    name = Path(path).name
    try:
        with open(path, "rb") as fh:
            head = fh.read(1 << 16)
            if b"\0" in head:
                raise LogError(f"{name}: is not a text CSV file (it holds NUL bytes).")
            fh.seek(0)
            lines = sum(1 for _ in fh)
        if lines - 1 > MAX_ROWS:
            raise LogError(_too_long(name, lines - 1))
        raw = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except LogError:
        raise
    except FileNotFoundError:
        raise LogError(f"{name}: no such file.") from None
    except (OSError, ValueError, UnicodeDecodeError, pd.errors.ParserError,
            pd.errors.EmptyDataError, csv_error()) as exc:
        why = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise LogError(f"{name}: cannot be read as a CSV manoeuvre record ({why}).") from None
    return log_from_frame(raw, name, channels)


def _too_long(name: str, rows: int) -> str:
    """The sentence of a record longer than :data:`MAX_ROWS`."""
    return (f"{name}: has {rows} rows, more than the {MAX_ROWS} identify reads (about "
            f"{MAX_ROWS_MINUTES:g} minutes of work at that length); resample the record (20 Hz "
            "is plenty for a manoeuvre) and try again.")


def csv_error() -> type[Exception]:
    return csv.Error


def _column(raw: pd.DataFrame, key: str, spec: Any, name: str) -> np.ndarray | None:
    gain, offset, col = 1.0, 0.0, key
    if spec is not None:
        if isinstance(spec, str):
            col = spec
        elif isinstance(spec, dict) and isinstance(spec.get("column"), str):
            col = spec["column"]
            try:
                gain = float(spec.get("gain", 1.0))
                offset = float(spec.get("offset", 0.0))
            except (TypeError, ValueError):
                raise LogError(f"{name}: [channels] {key} has a gain or offset that is not a "
                               "number.") from None
            if not (math.isfinite(gain) and math.isfinite(offset)) or gain == 0:
                raise LogError(f"{name}: [channels] {key} needs a finite gain other than 0 and "
                               "a finite offset.")
        else:
            raise LogError(f"{name}: [channels] {key} must be a column name or a table "
                           "{ column = \"...\", gain = ..., offset = ... }.")
        if col not in raw.columns:
            raise LogError(f"{name}: [channels] maps {key} to the column {col!r}, which the "
                           "file does not have.")
    if col not in raw.columns:
        return None
    values = pd.to_numeric(raw[col].astype(str).str.strip().replace("", "nan"),
                           errors="coerce").to_numpy(dtype=float, copy=True)
    values[~np.isfinite(values)] = np.nan
    return gain * values + offset


def log_from_frame(raw: pd.DataFrame, name: str = "log",
                   channels: dict[str, Any] | None = None) -> ManoeuvreLog:
    """:func:`read_log` on a table already in memory (strings or numbers); see there."""
    raw = raw.copy()
    raw.columns = [str(c).strip() for c in raw.columns]
    channels = dict(channels or {})
    unknown = sorted(set(channels) - set(STATE_COLUMNS) - set(CONTROL_COLUMNS) - {"t_s"})
    if unknown:
        raise LogError(f"{name}: [channels] names {', '.join(unknown)}, which identify does not "
                       f"use (it uses t_s, {', '.join(STATE_COLUMNS)}, rudder_deg, "
                       "sternplane_deg).")
    n = len(raw)
    if n > MAX_ROWS:
        raise LogError(_too_long(name, n))
    cols = {k: _column(raw, k, channels.get(k), name)
            for k in ("t_s",) + STATE_COLUMNS + CONTROL_COLUMNS}
    missing = [k for k in ("t_s",) + CONTROL_COLUMNS if cols[k] is None]
    if missing:
        raise LogError(f"{name}: the column{'s' if len(missing) > 1 else ''} "
                       f"{', '.join(missing)} {'are' if len(missing) > 1 else 'is'} missing "
                       "(the time and both controls are required; map other names in the "
                       "protocol's [channels]).")
    t = cols["t_s"]
    assert t is not None
    good_t = np.isfinite(t)
    if good_t.sum() < MIN_ROWS:
        raise LogError(f"{name}: has {int(good_t.sum())} rows with a time, fewer than the "
                       f"{MIN_ROWS} identification needs.")
    notes = []
    if not good_t.all():
        notes.append(f"{int((~good_t).sum())} rows without a time left out")
    keep = np.nonzero(good_t)[0]
    t = t[keep]
    dt = np.diff(t)
    if (dt <= 0).any():
        i = int(np.nonzero(dt <= 0)[0][0])
        raise LogError(f"{name}: the time goes back or repeats at row {keep[i + 1] + 2} "
                       f"({t[i]:g} s then {t[i + 1]:g} s); identify needs a time that "
                       "increases from row to row.")
    if np.median(dt) > MAX_GAP_S:  # every step long: not a gap, the time's unit
        raise LogError(f"{name}: the time steps by {float(np.median(dt)):.4g} s from row to "
                       f"row (median), more than the {MAX_GAP_S:g} s identify predicts "
                       "across: is t_s in ms?")
    if (dt > MAX_GAP_S).any():
        i = int(np.nonzero(dt > MAX_GAP_S)[0][0])
        raise LogError(f"{name}: the time jumps by {dt[i]:.4g} s at row {keep[i + 1] + 2} "
                       f"({t[i]:g} s then {t[i + 1]:g} s), more than the {MAX_GAP_S:g} s "
                       "identify predicts across; split the record at the gap and identify "
                       "from each part.")
    z = np.full((len(t), len(STATE_COLUMNS)), np.nan)
    for i, col in enumerate(STATE_COLUMNS):
        v = cols[col]
        if v is not None:
            z[:, i] = v[keep] * _TO_SI[i]
    measured = [i for i in range(len(STATE_COLUMNS)) if np.isfinite(z[:, i]).any()]
    if not measured:
        raise LogError(f"{name}: has no state column with a number ({', '.join(STATE_COLUMNS)})"
                       "; identify compares the model's motion with measured states.")
    for i in measured:
        if np.isfinite(z[:, i]).sum() < MIN_ROWS:
            raise LogError(f"{name}: {STATE_COLUMNS[i]} has fewer than {MIN_ROWS} numbers; "
                           "leave the column out or give a longer record.")
    psi = z[:, 5]
    ok = np.isfinite(psi)
    if ok.any():
        psi[ok] = np.unwrap(psi[ok])
    controls = []
    for col in CONTROL_COLUMNS:
        v = cols[col]
        assert v is not None
        v = v[keep] * math.pi / 180.0
        fin = np.isfinite(v)
        if fin.sum() < 2:
            raise LogError(f"{name}: {col} has fewer than 2 numbers; both controls are needed "
                           "(a column of zeros for a surface that does not move).")
        if not fin.all():
            notes.append(f"{int((~fin).sum())} {col} values missing, interpolated")
            v = np.interp(t, t[fin], v[fin])
        if np.abs(v).max() > math.radians(90.0):
            raise LogError(f"{name}: {col} reaches {math.degrees(np.abs(v).max()):.4g} deg; "
                           "control angles are in degrees within ±90.")
        controls.append(v)
    if all(np.ptp(c) == 0 for c in controls):
        r0, s0 = (math.degrees(c[0]) for c in controls)
        raise LogError(f"{name}: the rudder and stern plane stay at {r0:g} and {s0:g} deg over "
                       "the whole record, which cannot tell the damping from the control terms; "
                       "record a manoeuvre that "
                       "moves a control surface (simulate --manoeuvre sine or zigzag).")
    step = float(np.median(dt))
    gaps = dt > 10.0 * step
    if gaps.any():
        notes.append(f"{int(gaps.sum())} gaps in the time (longest {dt.max():.3g} s), "
                     "predicted across")
    rows_bad = ~np.isfinite(z[:, measured]).any(axis=1)
    if rows_bad.any():
        notes.append(f"{int(rows_bad.sum())} rows without any measured state")
    return ManoeuvreLog(t=t - t[0], z=z, rudder=controls[0], sternplane=controls[1],
                        measured=measured, name=name, notes=notes)


def noise_sd(log: ManoeuvreLog) -> np.ndarray:
    """Each measured state's noise standard deviation [SI], estimated from the record.

    ``sigma = 1.4826 MAD(d2) / sqrt(6)`` with ``d2_k = y_{k+1} - 2 y_k + y_{k-1}`` the
    second differences (white noise of variance s^2 gives var d2 = 6 s^2; a smooth signal's
    second difference ``y'' dt^2`` is far smaller at manoeuvre sample rates), MAD the median
    absolute deviation (robust to the odd spike). Floored at 1e-6 of the channel's range
    (a noise-free record still gives a usable filter). NaN for states not measured.
    """
    out = np.full(len(STATE_COLUMNS), np.nan)
    for i in log.measured:
        y = log.z[:, i]
        y = y[np.isfinite(y)]
        d2 = y[2:] - 2.0 * y[1:-1] + y[:-2]
        mad = float(np.median(np.abs(d2 - np.median(d2)))) if len(d2) else 0.0
        out[i] = max(1.4826 * mad / math.sqrt(6.0), noise_floor(y))
    return out


def noise_floor(y: np.ndarray) -> float:
    """The least noise sd :func:`noise_sd` gives a state [its unit]: 1e-6 of its range (of at
    least 1e-3)."""
    fin = y[np.isfinite(y)]
    return 1e-6 * max(float(np.ptp(fin)) if len(fin) else 0.0, 1e-3)


def exact_states(log: ManoeuvreLog, sd: np.ndarray) -> list[int]:
    """The measured states whose noise sd ``sd`` [SI] is at :func:`noise_floor`: written
    without noise (``simulate`` writes the states it adds no ``--noise`` to exactly)."""
    return [i for i in log.measured if sd[i] <= noise_floor(log.z[:, i]) * (1 + 1e-9)]


#: A measured state whose :func:`white_noise_ratio` is below this carries no white noise [-]
#: (measured: 0.96-1.06 on white noise of u, v, r, psi, x, y; 0.001-0.09 on the noise-free
#: states of the sine record at 10 and 20 Hz).
NOISE_FREE_RATIO = 0.5


def white_noise_ratio(y: np.ndarray) -> float:
    """The noise sd estimated from fourth differences over that from second differences [-].

    Each is ``1.4826 MAD(d_k) / sqrt(C(2k, k))`` (white noise of variance s^2 gives
    var d_k = C(2k, k) s^2, so both estimate s and the ratio is about 1); a smooth signal's
    k-th difference is about ``y^(k) dt^k``, so without noise the ratio falls to about
    ``(omega dt)^2``. 0 when the second differences vanish (a column written exactly or
    interpolated linearly) or there are fewer than 5 values.
    """
    fin = np.asarray(y, dtype=float)
    fin = fin[np.isfinite(fin)]
    if len(fin) < 5:
        return 0.0
    d2, d4 = np.diff(fin, 2), np.diff(fin, 4)
    s2 = float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0)
    s4 = float(np.median(np.abs(d4 - np.median(d4)))) / math.sqrt(70.0)
    return s4 / s2 if s2 > noise_floor(fin) else 0.0


def noise_free_states(log: ManoeuvreLog) -> list[int]:
    """The measured states whose :func:`white_noise_ratio` is below :data:`NOISE_FREE_RATIO`:
    written without noise, derived, smoothed or interpolated (their differences are the
    signal's, not noise)."""
    return [i for i in log.measured if white_noise_ratio(log.z[:, i]) < NOISE_FREE_RATIO]


def noise_entry(state: Any, value: Any, positive: bool = True) -> tuple[str, float]:
    """One ``state=sd`` of ``--noise``: the state's column and the standard deviation [the
    column's unit: m, deg, m/s, deg/s].

    Parameters
    ----------
    state : str
        A short name (``u``, ``psi``) or a column (``u_m_s``); anything else is read as its
        text
    value : str or float
        The standard deviation
    positive : bool
        True: it must be above 0 (identify's measurement noise); False: 0 is allowed

    Raises
    ------
    ValueError
        An unknown state or a value that is not a finite number in range (one sentence).
    """
    state = str(state).strip()
    col = SHORT_NAMES.get(state, state)
    if col not in STATE_COLUMNS:
        raise ValueError(f"--noise: {state!r} is not a state (states: "
                         f"{', '.join(SHORT_NAMES)}, or their columns such as u_m_s).")
    try:
        sd = float(value)
    except (TypeError, ValueError):
        sd = math.nan
    if not (math.isfinite(sd) and (sd > 0 if positive else sd >= 0)):
        raise ValueError(f"--noise: the standard deviation of {state} must be a finite "
                         f"number {'> 0' if positive else '>= 0'}, not "
                         f"{str(value).strip()!r}.")
    return col, sd


def parse_noise(text: str | None, positive: bool = False) -> dict[str, float]:
    """``--noise u=0.01,r=0.2,psi=0.5``: standard deviation per state, in the state's column
    unit (m, deg, m/s, deg/s); short names (``u``, ``psi``) or the columns (``u_m_s``), each
    state once; ``positive``: every value above 0, else 0 allowed
    (:func:`noise_entry`).

    Raises
    ------
    ProtocolError
        One sentence naming the part that is wrong.
    """
    out: dict[str, float] = {}
    for part in (text or "").split(","):
        if not part.strip():
            continue
        key, sep, val = part.partition("=")
        if not sep:
            raise ProtocolError(f"--noise: {part.strip()!r} is not state=sd (states: "
                                f"{', '.join(SHORT_NAMES)}).")
        try:
            col, sd = noise_entry(key, val, positive)
        except ValueError as exc:
            raise ProtocolError(str(exc)) from None
        if col in out:
            raise ProtocolError(f"--noise names the state {col} twice ({text!r}); give "
                                "each state once.")
        out[col] = sd
    return out
