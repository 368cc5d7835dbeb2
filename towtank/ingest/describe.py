"""What a run file holds, said for a person setting up a protocol (``towtank inspect``).

:func:`describe_file` reads a file as towtank would and reports its format, its channels with
their units and lengths, where the time comes from, and (for text) the separator, decimal mark
and header line it found; :func:`protocol_block` turns that into ``[read]`` and ``[channels]``
tables to paste into a protocol, with the channels guessed from the lab's names.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from towtank.ingest.readers import (
    FS_ERROR_KEY,
    FS_KEY,
    WF_TIME_KEY,
    ReadOptions,
    column_unit,
    file_format,
    stated_units,
    text_layout,
)

#: Words in a column name that suggest a canonical channel (lower case, first match wins).
_GUESSES = (
    ("time", ("time", "zeit", "temps", "x_value", "t (s)", "t [s]")),
    ("speed", ("speed", "velocity", "vel", "geschw", "vitesse", "carriage", "u (m")),
    ("accel", ("accel", "acc", "beschl")),
    ("drag", ("drag", "fx", "resistance", "widerstand", "x force", "force x", "axial")),
    ("lift", ("lift", "fy", "side", "y force", "force y", "fz", "normal")),
)


@dataclass
class FileDescription:
    """What :func:`describe_file` found in one run file."""

    name: str
    format: str
    channels: list[tuple[str, str, int]] = field(default_factory=list)  # name, unit, samples
    timing: str = ""
    fs: float = float("nan")
    layout: dict[str, str] | None = None
    guesses: dict[str, str] = field(default_factory=dict)

    def lines(self) -> list[str]:
        """The account printed by ``towtank inspect``."""
        out = [f"{self.name}: {self.format} file"]
        if self.layout:
            lay = self.layout
            out.append(f"  text: separator '{lay['delimiter']}', decimal '{lay['decimal']}', "
                       f"header on line {lay['header_line']}"
                       + (", units row under it" if lay["units_row"] == "True" else ""))
        out.append(f"  timing: {self.timing}")
        out.append("  channels:")
        for name, unit, n in self.channels:
            out.append(f"    {name!r:<40s} {unit or '(no unit)':<10s} {n} samples")
        return out


def describe_file(path: Path, options: ReadOptions | None = None) -> FileDescription:
    """Read ``path`` and say what it holds (raises RunError as the readers do)."""
    from towtank.ingest.runfile import file_bytes, read_columns

    data = file_bytes(path)
    fmt, gz = file_format(path, data, options)
    cols, _ = read_columns(path, data, options)
    units = stated_units(cols)
    names = [c for c in cols if not c.startswith("__")
             and not (fmt == "tdms" and "/" in c and c.split("/", 1)[1] in cols)]
    desc = FileDescription(name=path.name, format=fmt + (" (gzip)" if gz else ""),
                           layout=text_layout(cols))
    for c in names:
        arr = np.asarray(cols[c])
        desc.channels.append((c, column_unit(c, units) or "", int(arr.size)))
    time_col = next((c for c in names if _guess(c) == "time"), None)
    if time_col is not None:
        t = np.asarray(cols[time_col], dtype=float)
        dt = np.diff(t[np.isfinite(t)])
        desc.fs = 1.0 / float(np.median(dt)) if dt.size and np.median(dt) > 0 else float("nan")
        desc.timing = f"time column '{time_col}' ({desc.fs:g} Hz)"
    elif WF_TIME_KEY in cols:
        t = cols[WF_TIME_KEY]
        desc.fs = 1.0 / float(t[1] - t[0]) if t.size > 1 else float("nan")
        desc.timing = f"LabVIEW waveform timing (wf_increment), {desc.fs:g} Hz; no time channel"
    elif FS_KEY in cols:
        desc.fs = float(cols[FS_KEY][0])
        desc.timing = f"sample rate stated in the file, {desc.fs:g} Hz; no time channel"
    elif FS_ERROR_KEY in cols:
        desc.timing = (f"none usable: {cols[FS_ERROR_KEY].item()}; give [read] sample_rate_hz "
                       "or map a time column")
    else:
        desc.timing = "none found: give [read] sample_rate_hz or map a time column"
    for c in names:
        canon = _guess(c)
        if canon and canon not in desc.guesses:
            desc.guesses[canon] = c
    return desc


def _guess(column: str) -> str | None:
    low = column.lower()
    for canon, words in _GUESSES:
        if any(w in low for w in words):
            return canon
    return None


def _toml_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def protocol_block(desc: FileDescription) -> str:
    """``[read]`` and ``[channels]`` tables for a protocol, from what the file holds.

    Channels in volts get a ``gain`` placeholder to fill in (N per V); channels not recognised
    by name are listed as comments.
    """
    lines = ["[read]", f"format = {_toml_string(desc.format.split(' ')[0])}"]
    if desc.layout:
        delim = {"tab": "\\t"}.get(desc.layout["delimiter"], desc.layout["delimiter"])
        lines.append(f"delimiter = {_toml_string(delim)}")
        lines.append(f"decimal = {_toml_string(desc.layout['decimal'])}")
    if "time" not in desc.guesses and desc.timing.startswith("none"):
        lines.append("sample_rate_hz = 1000.0   # <- the rate the file was recorded at")
    lines += ["", "[channels]"]
    units = {name: unit for name, unit, _ in desc.channels}
    for canon in ("time", "speed", "accel", "drag", "lift"):
        col = desc.guesses.get(canon)
        if col is None:
            continue
        entry = f"column = {_toml_string(col)}"
        if re.fullmatch(r"m?V", units.get(col, "")):
            entry += ", gain = 1.0, offset = 0.0   # <- N per V from the calibration"
            lines.append(f"{canon} = {{ {entry.split('   #')[0]} }}   #{entry.split('   #')[1]}")
            continue
        lines.append(f"{canon} = {{ {entry} }}")
    rest = [n for n, _, _ in desc.channels if n not in desc.guesses.values()]
    if rest:
        lines.append("# not recognised: " + ", ".join(repr(n) for n in rest))
    return "\n".join(lines) + "\n"
