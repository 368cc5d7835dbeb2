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

from towtank.ingest.arrayfiles import FS_NAME_KEY
from towtank.ingest.protocol_types import CAPTIVE_CHANNELS
from towtank.ingest.readers import (
    FS_ERROR_KEY,
    FS_KEY,
    LVM_HEADERS_KEY,
    ROWS_KEY,
    TIME_COLUMN_KEY,
    WF_TIME_KEY,
    ReadOptions,
    column_unit,
    file_format,
    name_list,
    stated_units,
    text_layout,
    unit_factor,
)
from towtank.ingest.runfile import captive_guess, file_bytes, read_columns
from towtank.ingest.segments import describe_segments, find_segments
from towtank.ingest.timing import stated_rate

#: Words in a column name that suggest a canonical channel (lower case, first match wins).
_GUESSES = (
    ("time", ("time", "zeit", "temps", "x_value", "t (s)", "t [s]")),
    ("speed", ("speed", "velocity", "vel", "geschw", "vitesse", "carriage", "u (m")),
    ("accel", ("accel", "acc", "beschl")),
    ("drag", ("drag", "fx", "resistance", "widerstand", "x force", "force x", "axial")),
    ("lift", ("lift", "fy", "side", "y force", "force y", "fz", "normal")),
)


#: Most channels ``towtank inspect`` lists one a line (then the count of the rest).
CHANNELS_LISTED = 64


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
    #: forces whose load cells are summed (``drag`` → ``["DragL", "DragR"]``)
    parts: dict[str, list[str]] = field(default_factory=dict)
    #: the acquisitions of a file holding several one after another, one line each
    #: (:func:`towtank.ingest.segments.describe_segments`); empty for a file recorded in one go
    segments: list[str] = field(default_factory=list)
    #: the channel that is the file's time ("" when none), and what it is
    time_column: str = ""
    time_what: str = ""
    #: the rate the block must state in ``[read] sample_rate_hz`` (the protocol's) [Hz], or 0
    stated_rate_hz: float = 0.0
    #: channels that are digital inputs (:func:`digital_channel`), proposed as no channel
    digital: list[str] = field(default_factory=list)

    def lines(self) -> list[str]:
        """The account printed by ``towtank inspect``."""
        out = [f"{self.name}: {self.format} file"]
        if self.layout:
            lay = self.layout
            out.append(f"  text: separator '{lay['delimiter']}', decimal '{lay['decimal']}', "
                       f"header on line {lay['header_line']}"
                       + (", units row under it" if lay["units_row"] == "True" else ""))
        out.append(f"  timing: {self.timing}")
        if self.segments:
            out.append(f"  segments: {len(self.segments)} acquisitions one after another "
                       "(the run sheet's 'segment' column, or [read] segment, says which is "
                       "the run):")
            out += [f"    {line}" for line in self.segments]
        out.append("  channels:")
        for name, unit, n in self.channels[:CHANNELS_LISTED]:
            what = "   <- the time" if name == self.time_column and self.time_what else ""
            out.append(f"    {name!r:<40s} {unit or '(no unit)':<10s} {n} samples{what}")
        rest = len(self.channels) - CHANNELS_LISTED
        if rest > 0:
            out.append(f"    ... and {rest:,} more channels (not listed)")
        return out


def describe_file(path: Path, options: ReadOptions | None = None) -> FileDescription:
    """Read ``path`` and say what it holds (raises RunError as the readers do)."""
    data = file_bytes(path)
    fmt, gz = file_format(path, data, options)
    cols, _ = read_columns(path, data, options)
    units = stated_units(cols)
    names = [c for c in cols if not c.startswith("__")
             and not (fmt == "tdms" and "/" in c and c.split("/", 1)[1] in cols)]
    desc = FileDescription(name=path.name, format=fmt + (" (gzip)" if gz else ""),
                           layout=text_layout(cols))
    own = cols[TIME_COLUMN_KEY].item() if TIME_COLUMN_KEY in cols else None
    is_digital = {c: digital_channel(c, cols[c]) for c in names}
    desc.digital = [c for c in names if is_digital[c]]
    analog = [c for c in names if not is_digital[c]]
    time_col = own[0] if own is not None and own[0] in cols else \
        next((c for c in analog if _guess(c) == "time"), None)
    for c in names:
        arr = np.asarray(cols[c])
        unit = column_unit(c, units, "time" if c == time_col else None)
        desc.channels.append((c, unit or "", int(arr.size)))
    given = float(getattr(options, "sample_rate_hz", 0.0) or 0.0)
    fs, source = stated_rate(cols, given)
    if time_col is not None:
        # the time in s: a unit in its name or stated by the file (ms, us) converted
        unit = column_unit(time_col, units, "time")
        t = np.asarray(cols[time_col], dtype=float) * unit_factor("time", unit, time_col,
                                                                  path.name)
        dt = np.diff(t[np.isfinite(t)])
        desc.fs = 1.0 / float(np.median(dt)) if dt.size and np.median(dt) > 0 else float("nan")
        desc.time_column = time_col
        if own is not None and own[0] == time_col:
            desc.time_what = own[1]
            desc.timing = (f"the column '{time_col}' ({own[1]}), {desc.fs:g} Hz; the file has "
                           "no channel named time")
        else:
            desc.timing = f"time column '{time_col}' ({desc.fs:g} Hz)"
        desc.segments = _segments(cols, t)
    elif WF_TIME_KEY in cols:
        t = cols[WF_TIME_KEY]
        desc.fs = 1.0 / float(t[1] - t[0]) if t.size > 1 else float("nan")
        desc.timing = f"LabVIEW waveform timing (wf_increment), {desc.fs:g} Hz; no time channel"
    elif fs > 0:
        desc.fs = fs
        if source.startswith("[read]"):
            desc.stated_rate_hz = fs
            named = (f"; {cols[FS_NAME_KEY].item()} says {float(cols[FS_KEY][0]):g} Hz"
                     if FS_NAME_KEY in cols else "")
            desc.timing = f"{source} (the protocol's), no time channel{named}"
        elif FS_NAME_KEY in cols:
            desc.timing = f"{fs:g} Hz from {source}; no time channel"
        else:
            desc.timing = f"sample rate stated in the file, {fs:g} Hz; no time channel"
    elif FS_ERROR_KEY in cols:
        desc.timing = (f"none usable: {cols[FS_ERROR_KEY].item()}; give [read] sample_rate_hz "
                       "or map a time column")
    else:
        desc.timing = "none found: give [read] sample_rate_hz or map a time column"
    captive = captive_columns(analog)
    desc.parts = force_parts([c for c in analog if c not in captive.values()])
    in_parts = {c for cells in desc.parts.values() for c in cells}
    desc.guesses.update(captive)
    for c in analog:  # a digital line is proposed as no channel
        if c in captive.values():
            continue
        canon = next((k for k, cells in desc.parts.items() if c in cells), None)
        if canon is None and c not in in_parts:
            canon = _guess(c)
        if canon and canon not in desc.guesses:
            desc.guesses[canon] = c
    return desc


def captive_columns(names: list[str]) -> dict[str, str]:
    """A captive balance's channels among a file's columns, by name
    (:func:`towtank.ingest.runfile.captive_guess`): ``{"fx": "Fx (N)", "fy": "Fy (N)", "mz":
    "Mz (N m)", "sway": "PMM y", ...}`` when the file has both a side force fy and a yaw
    moment mz (the first column of each name), else empty: a hull balance's ``Fx`` (with or
    without ``Fy``) stays the drag and lift."""
    found: dict[str, str] = {}
    for c in names:
        canon = captive_guess(c)
        if canon is not None and canon not in found:
            found[canon] = c
    return found if "fy" in found and "mz" in found else {}


#: A digital input in a channel's name: ``Digital in``, ``TTL``, ``DI3``, ``DIO``,
#: ``Dev1_port3_line7``, ``Dev1/port0/line2`` (NI-DAQmx's names of a port's lines).
_DIGITAL_NAME = re.compile(r"(?i)digital|\b(ttl|dio|di\d+)\b|port\s*\d+\W*_?\W*line\s*\d+")
#: Most different values of a channel read as the states of a digital line or port.
DIGITAL_STATES = 4
#: Fewest samples from which a channel's values can say it is digital.
DIGITAL_MIN_SAMPLES = 8


def digital_channel(name: str, values: np.ndarray) -> bool:
    """Whether a channel is a digital input (a trigger, a switch, one line of a DAQ port)
    rather than a measured signal: its name says so (:data:`_DIGITAL_NAME`), or it holds
    booleans, or its values are whole numbers taking 2 to :data:`DIGITAL_STATES` different
    values (0 and 1, a port's few states) over :data:`DIGITAL_MIN_SAMPLES` samples at least.
    A constant channel (a speed of 0 all along) is not called digital by its values.

    Parameters
    ----------
    name : str
        The channel's name in the file.
    values : numpy.ndarray
        Its values (any units; text is never digital by its values).
    """
    if _DIGITAL_NAME.search(name):
        return True
    arr = np.asarray(values)
    if arr.dtype.kind == "b":
        return arr.size > 0
    if arr.dtype.kind not in "fiu":
        return False
    finite = arr[np.isfinite(arr)] if arr.dtype.kind == "f" else arr
    if finite.size < DIGITAL_MIN_SAMPLES:
        return False
    for part in (finite[:4096], finite):  # most analog channels show it in their first values
        if not np.array_equal(part, np.round(part)):
            return False
    return 2 <= np.unique(finite).size <= DIGITAL_STATES


def _segments(cols: dict[str, np.ndarray], t: np.ndarray) -> list[str]:
    """One line per acquisition of a file holding several (none for one)."""
    segs = find_segments(t, headers=cols.get(LVM_HEADERS_KEY))
    if len(segs) < 2:
        return []
    rows = cols.get(ROWS_KEY)
    rows = np.asarray(rows) if rows is not None and np.asarray(rows).size == t.size else \
        np.arange(t.size) + 2
    return describe_segments(t, segs, rows)


#: Words that mark one load cell of several carrying one force: a pair (left/right, port/
#: starboard, fore/aft, a/b) or numbered cells (Fx1, Fx2 ...). Families [lower case].
_SIDE_FAMILIES = (
    ("l", "r"), ("left", "right"), ("lh", "rh"), ("port", "stbd", "starboard"), ("ps", "sb"),
    ("fwd", "aft", "fore"), ("front", "rear", "back"), ("a", "b"), ("upper", "lower"),
)
_SIDE_WORDS = sorted({w for fam in _SIDE_FAMILIES for w in fam}, key=len, reverse=True)
_SIDE_TOKEN = re.compile(r"(?i)(" + "|".join(_SIDE_WORDS) + r"|\d+)")


def _side_tokens(name: str) -> list[tuple[str, str]]:
    """(base with the token taken out, token) for each place in ``name`` where a word marking
    one cell of several stands (``DragL`` → (``drag\0``, ``l``)); the unit in brackets is
    left out of the base. A token stands alone: between separators, at a change from lower to
    upper case (``DragL``, ``LeftDrag``), or, for a number, after letters (``Fx1``)."""
    core = re.sub(r"[\(\[][^\)\]]*[\)\]]\s*$", "", name).rstrip()
    out = []
    for m in _SIDE_TOKEN.finditer(core):
        i, j, tok = m.start(), m.end(), m.group()
        before = core[i - 1] if i > 0 else ""
        after = core[j] if j < len(core) else ""
        if tok.isdigit():
            ok_before = before == "" or not before.isdigit()
            ok_after = after == "" or not after.isalnum()
        else:
            ok_before = before == "" or not before.isalnum() or (
                before.islower() and tok[0].isupper())
            ok_after = after == "" or not after.isalnum() or (
                len(tok) > 1 and after.isupper())
        if ok_before and ok_after:
            out.append(((core[:i] + "\0" + core[j:]).lower(), tok.lower()))
    return out


def _one_family(tokens: set[str]) -> bool:
    if all(t.isdigit() for t in tokens):
        return True
    return any(tokens <= set(fam) for fam in _SIDE_FAMILIES)


def force_parts(names: list[str]) -> dict[str, list[str]]:
    """Channels that look like the load cells of one force, by force: ``{"drag": ["DragL",
    "DragR"]}`` for a file holding ``DragL`` and ``DragR`` (or ``Fx1``/``Fx2``, ``Fx port``/
    ``Fx stbd``, ``Drag_a``/``Drag_b`` ...). Names that differ only in one such word of one
    family, and whose common part names a force (drag or lift by :func:`guess`), are one
    force's parts, in the file's order; the first group found per force is kept."""
    groups: dict[str, list[tuple[str, str]]] = {}
    for name in names:
        for base, tok in _side_tokens(name):
            groups.setdefault(base, []).append((name, tok))
    out: dict[str, list[str]] = {}
    for base, members in groups.items():
        cells = list(dict.fromkeys(n for n, _ in members))
        tokens = {t for _, t in members}
        if len(cells) < 2 or len(tokens) != len(cells) or not _one_family(tokens):
            continue
        canon = guess(base.replace("\0", " "))
        if canon in ("drag", "lift") and canon not in out and \
                not any(c in v for v in out.values() for c in cells):
            out[canon] = sorted(cells, key=names.index)
    return out


def unmapped_forces(columns: list[str] | tuple[str, ...], used: set[str]) -> list[str]:
    """Channels of a file that look like a force, or a part of one, and are mapped to nothing:
    a cell of a split force (:func:`force_parts`) beside a mapped one, and any channel named as
    a drag (``DragR`` when only ``DragL`` is mapped). ``used`` holds the mapped column names
    (each cell of a ``columns`` sum); TDMS ``group/channel`` aliases are left out."""
    names = [c for c in columns if not c.startswith("__")
             and not ("/" in c and c.split("/", 1)[1] in columns)]
    used_s = {u.strip() for u in used}
    free = [c for c in names if c.strip() not in used_s]
    parts = force_parts(names)
    out = []
    for c in free:
        sibling = any(c in cells and any(x.strip() in used_s for x in cells)
                      for cells in parts.values())
        if sibling or guess(c) == "drag":
            out.append(c)
    return out


def guess(column: str) -> str | None:
    """The canonical channel a column's name suggests (:data:`_GUESSES`), or None."""
    return _guess(column)


#: A time column named ``t`` with its unit: ``t (min)``, ``t [ms]``, ``t_us``.
_T_WITH_UNIT = re.compile(r"t(\s*[\(\[][^\)\]]*[\)\]]|_[a-zµ]+)")


def _guess(column: str) -> str | None:
    low = column.lower()
    if _T_WITH_UNIT.fullmatch(low.strip()):
        return "time"
    for canon, words in _GUESSES:
        if any(w in low for w in words):
            return canon
    return None


def _toml_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def protocol_block(desc: FileDescription) -> str:
    """``[read]`` and ``[channels]`` tables for a protocol, from what the file holds.

    Channels in volts get a ``gain = 1.0`` placeholder to fill in (N per V: as it stands the
    block reads the run with forces in volts); the load cells of one force (``DragL``,
    ``DragR``) are summed with ``columns = [...]``; channels not recognised by name are listed
    as comments. Pasted into a protocol, the block reads the file as it is.
    """
    lines = ["[read]", f"format = {_toml_string(desc.format.split(' ')[0])}"]
    if desc.layout:
        delim = {"tab": "\\t"}.get(desc.layout["delimiter"], desc.layout["delimiter"])
        lines.append(f"delimiter = {_toml_string(delim)}")
        lines.append(f"decimal = {_toml_string(desc.layout['decimal'])}")
    if desc.stated_rate_hz > 0:
        lines.append(f"sample_rate_hz = {desc.stated_rate_hz!r}")
    elif "time" not in desc.guesses and desc.timing.startswith("none"):
        lines.append("sample_rate_hz = 1000.0   # <- the rate the file was recorded at")
    if desc.segments:
        lines.append(f"segment = 1   # <- which of the file's {len(desc.segments)} "
                     "acquisitions is the run (per run: the run sheet's 'segment' column)")
    lines += ["", "[channels]"]
    units = {name: unit for name, unit, _ in desc.channels}
    for canon in ("time", "speed", "accel", "drag", "lift", *CAPTIVE_CHANNELS):
        col = desc.guesses.get(canon)
        if col is None:
            continue
        cells = desc.parts.get(canon)
        if cells:
            entry = "columns = [" + ", ".join(_toml_string(c) for c in cells) + "]"
        else:
            entry = f"column = {_toml_string(col)}"
        volts = [u for u in (units.get(c, "") for c in (cells or [col]))
                 if re.fullmatch(r"[mµu]?V", u)]
        comment = f"   # the sum of {len(cells)} load cells" if cells else ""
        if volts:
            entry += ", gain = 1.0, offset = 0.0"
            comment = (f"   # <- N per {volts[0]} from the calibration (1.0: forces in "
                       f"{volts[0]})" + (f"; the sum of {len(cells)} load cells" if cells
                                         else ""))
        lines.append(f"{canon} = {{ {entry} }}{comment}")
    mapped = {c for canon in desc.guesses for c in desc.parts.get(canon, [])} | set(
        desc.guesses.values())
    digital = set(desc.digital)
    rest = [n for n, _, _ in desc.channels if n not in mapped and n not in digital]
    if desc.digital:
        lines.append("# digital inputs, mapped to no channel: " + name_list(desc.digital))
    if rest:
        lines.append("# not recognised: " + name_list(rest))
    return "\n".join(lines) + "\n"
