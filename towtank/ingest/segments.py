"""Acquisitions appended in one run file (docs/formats.md §3, "Appended acquisitions").

A DAQ program told to append writes a second acquisition under the first: LabVIEW adds a
segment header to an LVM file (or none at all, the rows simply continue), a text logger keeps
writing its rows. The file then holds several blocks of rows, each a recording of its own,
that towtank calls *segments*. They are found on the time column:

* at an LVM segment header where the time does not continue (it goes back, or steps forward
  by more than ``max_gap_s``, the gap that lost samples may fill);
* anywhere, where the time **restarts** (goes back to or before the start of the current
  segment, with new data: not a copy of the rows at its start), or **jumps** forward by at
  least :data:`SEGMENT_GAP_S` and at least :data:`SEGMENT_GAP_STEPS` sample intervals (a DAQ
  restarted by hand; a few lost samples are far shorter).

The run sheet's ``segment`` column (per run) or ``[read] segment`` (the day's default) says
which segment, counted from 1, is the run; a file with more than one and no choice is
rejected in one sentence that lists them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from towtank.errors import RunError

#: A forward time step of at least this long [s] (and :data:`SEGMENT_GAP_STEPS` sample
#: intervals) starts a new segment: a DAQ restarted by hand, not samples lost in a buffer.
SEGMENT_GAP_S = 1.0
#: ... and at least this many sample intervals (time written in ms is not split at every row).
SEGMENT_GAP_STEPS = 20.0
#: Segments listed in a message before "…".
MAX_LISTED = 6


def human_duration(seconds: float) -> str:
    """A duration in the unit a person reads it in: ms below 1 s, s below 120 s, min above.

    ``human_duration(77.0005)`` is ``'77 s'``, ``human_duration(0.205)`` is ``'205 ms'``,
    ``human_duration(300)`` is ``'5 min'`` (three significant digits).
    """
    x = float(seconds)
    if not math.isfinite(x):
        return f"{x} s"
    if abs(x) < 1.0:
        return f"{x * 1e3:.3g} ms"
    if abs(x) < 120.0:
        return f"{x:.3g} s"
    return f"{x / 60.0:.3g} min"


@dataclass(frozen=True)
class Segment:
    """One acquisition of a file: rows ``start`` to ``stop`` (sample indices, stop excluded),
    how its first row follows the previous segment (``kind``: ``"restart"``, ``"jump"``, or
    ``""`` for the first) and the time of the previous segment's last row (``t_before`` [s])."""

    start: int
    stop: int
    kind: str = ""
    t_before: float = math.nan

    @property
    def n(self) -> int:
        return self.stop - self.start

    def how(self, t: np.ndarray, where: str) -> str:
        """'the time restarts at row 2292, t = 0.0000 s after 11.4450 s' ('' for the first
        segment); ``where`` names the segment's first row."""
        t_next = float(t[self.start])
        if self.kind == "jump":
            return (f"the time jumps by {human_duration(t_next - self.t_before)} at {where}, "
                    f"from t = {self.t_before:.4f} s to {t_next:.4f} s")
        if self.kind == "restart":
            return f"the time restarts at {where}, t = {t_next:.4f} s after {self.t_before:.4f} s"
        return ""


def _typical_step(t: np.ndarray) -> float:
    with np.errstate(invalid="ignore", over="ignore"):
        dt = np.diff(t)
        pos = dt[np.isfinite(dt) & (dt > 0)]
        return float(np.median(pos)) if pos.size else 0.0


def find_segments(
    t: np.ndarray,
    *,
    headers: np.ndarray | None = None,
    values: np.ndarray | None = None,
    max_gap_s: float = 0.05,
) -> list[Segment]:
    """The acquisitions of a file, from its time column ``t`` [s] (module docstring).

    Parameters
    ----------
    t : numpy.ndarray
        Time of each row [s] (NaN where missing: no boundary is found there).
    headers : numpy.ndarray of int, optional
        Sample indices where an LVM segment header starts a new block of rows.
    values : numpy.ndarray, optional
        A data channel on the same rows: a restart whose first rows repeat the segment's
        first rows, time and data alike, is a duplicated block, not a new acquisition.
    max_gap_s : float
        At an LVM segment header, a forward step longer than this [s] starts a segment.

    Returns
    -------
    list of Segment
        In file order; together they cover every row exactly once (one segment, all rows, for
        a file recorded in one go; an empty list for an empty ``t``).
    """
    t = np.asarray(t, dtype=np.float64).ravel()
    n = t.size
    if n == 0:
        return []
    med = _typical_step(t)
    with np.errstate(invalid="ignore", over="ignore"):
        dt = np.diff(t)
        jump = (dt >= SEGMENT_GAP_S) & (dt >= SEGMENT_GAP_STEPS * med) if med > 0 else \
            np.zeros(dt.size, dtype=bool)
        back = dt < 0
    at_header = np.zeros(dt.size, dtype=bool)
    if headers is not None:
        h = np.asarray(headers, dtype=np.int64).ravel()
        h = h[(h >= 1) & (h < n)]
        at_header[h - 1] = True
    with np.errstate(invalid="ignore"):
        header_break = at_header & ((dt <= 0) | (dt > max(max_gap_s, 1.5 * med)))
    candidates = np.flatnonzero(jump | back | header_break)
    segments: list[Segment] = []
    start, kind, before = 0, "", math.nan
    for i in candidates.tolist():
        b = i + 1  # first row of the new segment
        t_prev, t_next = float(t[i]), float(t[b])
        if not (header_break[i] or jump[i]):  # time goes back: a restart only to (or before)
            t0 = float(t[start])               # the segment's own start, with new data
            if not t_next <= t0 + 2.0 * med or _repeats_start(t, values, start, b):
                continue
        segments.append(Segment(start, b, kind, before))
        start, kind, before = b, ("jump" if t_next > t_prev else "restart"), t_prev
    segments.append(Segment(start, n, kind, before))
    return segments


def _repeats_start(t: np.ndarray, values: np.ndarray | None, start: int, b: int) -> bool:
    """Rows from ``b`` repeat the rows from ``start`` (time and data): a duplicated block."""
    if values is None:
        return False
    v = np.asarray(values)
    if v.size != t.size:
        return False
    m = min(b - start, t.size - b, 3)
    if m < 2:
        return False
    return bool(np.array_equal(t[b:b + m], t[start:start + m], equal_nan=True) and
                np.array_equal(v[b:b + m], v[start:start + m], equal_nan=True))


def describe_segments(t: np.ndarray, segments: list[Segment], rows: np.ndarray | None = None,
                      label: str = "row") -> list[str]:
    """One line per segment: its rows, samples, duration (samples × the file's typical time
    step) and times."""
    out = []
    step = _typical_step(np.asarray(t, dtype=np.float64))
    for k, s in enumerate(segments, start=1):
        r0, r1 = (int(rows[s.start]), int(rows[s.stop - 1])) if rows is not None else \
            (s.start + 1, s.stop)
        t0, t1 = float(t[s.start]), float(t[s.stop - 1])
        span = f"{label}s {r0}–{r1}" if r1 != r0 else f"{label} {r0}"
        out.append(f"segment {k}: {span}, {s.n} samples, {human_duration(s.n * step)} "
                   f"(t = {t0:.4f}–{t1:.4f} s)")
    return out


def segment_error(name: str, t: np.ndarray, segments: list[Segment],
                  rows: np.ndarray | None = None, label: str = "row",
                  chosen: int | None = None) -> RunError:
    """The one sentence of a file with several acquisitions and no (or no such) choice."""
    n = len(segments)
    if chosen is None and n > 2 and n - 1 > 0.5 * (len(t) - 1):
        # most steps go back in time: one reversed acquisition, not thousands of restarts
        return RunError(
            f"{name}: the time runs backwards (it goes back at {n - 1} of its {len(t) - 1} "
            f"steps, from t = {float(t[0]):.4f} s to {float(t[-1]):.4f} s): are the rows in "
            "reverse order, or is the time column another channel?")
    lines = describe_segments(t, segments, rows, label)
    listed = "; ".join(lines[:MAX_LISTED]) + ("; …" if len(lines) > MAX_LISTED else "")
    if chosen is not None:
        head = f"{name}: segment {chosen} is chosen, but the file holds {n} segment" + \
            ("s" if n > 1 else "")
    else:
        second = segments[1]
        r = int(rows[second.start]) if rows is not None else second.start + 1
        more = f", and {n - 2} more time{'s' if n > 3 else ''}" if n > 2 else ""
        head = (f"{name} holds {n} segments ({second.how(t, f'{label} {r}')}{more}: a clock "
                "reset, or acquisitions appended to one file)")
    return RunError(
        f"{head}: {listed}; say which one is the run in the run sheet's 'segment' column "
        "(1 = the first) or with [read] segment = N"
    )
