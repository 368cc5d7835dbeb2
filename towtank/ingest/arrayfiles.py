"""Run files that hold arrays: MATLAB .mat (v4–v7 with scipy.io, v7.3 with h5py) and HDF5.

The columns come back as from the text readers of :mod:`towtank.ingest.readers` (``name ->
float64 array`` and the private ``__units__``, ``__fs__``, ``__fs_error__`` entries). Before any
array is read, the sizes the file *declares* are checked against the run-file cap
(:data:`towtank.ingest.readers.MAX_RUN_FILE_BYTES`): a compressed MATLAB variable or an
unwritten HDF5 dataset holds far more than the file's size (docs/formats.md §3.1, "Size").
A sample rate stated as an attribute or a scalar may be text with its unit (``"200 Hz"``);
one that is not a rate gives the reason, used only if the time must come from it. An HDF5
file without either may state its rate in a group's or dataset's name (``/200.05 Hz``).
"""

from __future__ import annotations

import io
import math
import re
import struct
import zlib
from typing import Any

import numpy as np

from towtank.errors import RunError
from towtank.ingest import readers
from towtank.ingest.readers import (
    DT_NAMES,
    FS_ERROR_KEY,
    FS_KEY,
    FS_NAMES,
    HDF5_SIGNATURE,
    LABEL_KEY,
    UNITS_KEY,
    ReadOptions,
    name_list,
    units_entry,
)

#: Private column entry: where a sample rate read from a group's or dataset's name stands
#: (0-d object array holding text such as ``'200.05 Hz' in the name of the group
#: '/200.05 Hz'``); present
#: only when ``__fs__`` comes from a name (:func:`rate_from_names`).
FS_NAME_KEY = "__fs_name__"


def _size_cap() -> int:
    """The largest run file [bytes], also the most its arrays may declare as float64 numbers
    (:data:`towtank.ingest.readers.MAX_RUN_FILE_BYTES`: a .mat or HDF5 file holds far more
    than its size when it is compressed or leaves a dataset unwritten)."""
    return int(readers.MAX_RUN_FILE_BYTES)


def _too_much(name: str, what: str, nbytes: int) -> RunError:
    cap = _size_cap()
    return RunError(
        f"{name} is too large for one run: {what} declares {_amount(nbytes)} of numbers, and "
        f"towtank reads up to {_amount(cap)} from one run file (checked before reading): split "
        "the recording into its runs"
    )


def _amount(nbytes: int) -> str:
    if nbytes >= 1 << 30:
        return f"{nbytes / 2**30:.1f} GiB"
    return f"{nbytes / 2**20:.0f} MiB" if nbytes >= 1 << 20 else f"{nbytes:,} bytes"


# MAT-file v5 element types (the MAT-File Format, MathWorks): a variable is an miMATRIX
# element, stored as is or inside an miCOMPRESSED (zlib) element.
_MI_INT8, _MI_INT32, _MI_UINT32, _MI_MATRIX, _MI_COMPRESSED = 1, 5, 6, 14, 15
_MAT5_MAX_DEPTH = 32


def _mat5_tag(buf: bytes | bytearray | memoryview, pos: int,
              order: str) -> tuple[int, int, int, int]:
    """(type, byte count, data offset, next element offset) of the element at ``pos``; the
    small-element form (type and count in one word, data in the next four bytes) too."""
    word, count = struct.unpack_from(order + "II", buf, pos)
    if word >> 16:  # small data element
        return word & 0xFFFF, word >> 16, pos + 4, pos + 8
    return word, count, pos + 8, pos + 8 + count + (-count % 8)


def _mat5_matrix_head(buf: bytes | bytearray | memoryview, pos: int, end: int,
                      order: str) -> tuple[int, list[int], str, int]:
    """(class, dims, name, offset of what follows the name) of an miMATRIX's contents at
    ``pos`` (its array flags, dimensions and name sub-elements)."""
    mtype, count, data, nxt = _mat5_tag(buf, pos, order)
    if mtype != _MI_UINT32 or count < 4 or nxt > end:
        raise ValueError("no array flags")
    cls = struct.unpack_from(order + "I", buf, data)[0] & 0xFF
    mtype, count, data, nxt2 = _mat5_tag(buf, nxt, order)
    if mtype != _MI_INT32 or nxt2 > end:
        raise ValueError("no dimensions")
    dims = list(struct.unpack_from(f"{order}{count // 4}i", buf, data))
    mtype, count, data, nxt3 = _mat5_tag(buf, nxt2, order)
    if nxt3 > end:
        raise ValueError("no name")
    name = bytes(buf[data : data + count]).decode("latin-1") if mtype == _MI_INT8 else ""
    return cls, dims, name, nxt3


class _Mat5Budget:
    """The values a MAT v5 file declares, summed over its (nested) variables and checked
    against :func:`_size_cap` as float64 numbers (a cell or struct array holds one object
    per element)."""

    def __init__(self, name: str):
        self.name = name
        self.values = 0
        self.cap = _size_cap()

    def add(self, var: str, dims: list[int]) -> None:
        n = 1
        for d in dims:
            n *= max(int(d), 0)
        self.values += n
        if 8 * self.values > self.cap:
            shape = "×".join(str(max(int(d), 0)) for d in dims)
            raise _too_much(self.name, f"its MATLAB variable '{var}' ({shape})", 8 * n)

    def walk(self, buf: bytes | bytearray | memoryview, pos: int, end: int, order: str,
             labels: Any = None, depth: int = 0) -> None:
        """Every miMATRIX element in buf[pos:end], nested ones (struct fields, cells) too;
        ``labels(i, name)`` names the i-th (the variable's own name, a field, a cell)."""
        if depth > _MAT5_MAX_DEPTH:
            raise RunError(f"{self.name} is not a readable MATLAB file (variables nested more "
                           f"than {_MAT5_MAX_DEPTH} deep)")
        i = 0
        while pos + 8 <= end:
            mtype, count, data, nxt = _mat5_tag(buf, pos, order)
            if mtype == _MI_MATRIX and count:
                stop = min(data + count, end)
                try:
                    cls, dims, var, after = _mat5_matrix_head(buf, data, stop, order)
                    label = labels(i, var) if labels is not None else var or "?"
                    self.add(label, dims)
                    self._children(buf, cls, after, stop, order, label, depth)
                except (ValueError, struct.error):
                    return  # a damaged variable: scipy's reader says what is wrong
                i += 1
            pos = nxt

    def _children(self, buf: bytes | bytearray | memoryview, cls: int, pos: int, end: int,
                  order: str, label: str, depth: int) -> None:
        """The arrays inside a cell (class 1), struct (2) or object (3) array."""
        if cls == 1:
            self.walk(buf, pos, end, order, lambda i, _: f"{label}{{{i + 1}}}", depth + 1)
        elif cls in (2, 3):
            if cls == 3:  # the class name comes first
                pos = _mat5_tag(buf, pos, order)[3]
            _, _, data, pos = _mat5_tag(buf, pos, order)
            width = struct.unpack_from(order + "i", buf, data)[0]
            mtype, count, data, pos = _mat5_tag(buf, pos, order)
            raw = bytes(buf[data : data + count])
            fields = [raw[k : k + width].split(b"\0", 1)[0].decode("latin-1")
                      for k in range(0, len(raw), width)] if width > 0 else []
            fields = fields or ["?"]
            self.walk(buf, pos, end, order,
                      lambda i, _: f"{label}.{fields[i % len(fields)]}", depth + 1)


def _mat5_inflated(data: bytes, name: str) -> bytes:  # noqa: C901 - one pass, in order
    """A MAT v5 file with each compressed variable decompressed, its declared size checked
    first: the miMATRIX element a compressed variable starts with declares its byte count,
    read from the first bytes of the stream; a variable that alone, or with those before
    it, declares more than :func:`_size_cap` rejects the run before anything is decompressed.
    A stream is decompressed to its declared size at most (a longer one is cut there, and
    scipy then reads a bounded buffer). The uncompressed file is then walked for the
    dimensions of every (nested) variable (:class:`_Mat5Budget`). Files that are not MAT v5
    (v4, v7.3) are returned as they are."""
    if len(data) < 136 or data[126:128] not in (b"IM", b"MI"):
        return data
    order = "<" if data[126:128] == b"IM" else ">"
    if struct.unpack_from(order + "H", data, 124)[0] != 0x0100:
        return data
    cap = _size_cap()
    budget = _Mat5Budget(name)
    view = memoryview(data)
    out: bytearray | None = None
    declared = 0
    pos = 128
    while pos + 8 <= len(data):
        mtype, count, start, nxt = _mat5_tag(data, pos, order)
        if mtype != _MI_COMPRESSED:
            if out is not None:
                out += view[pos : min(nxt, len(data))]
            pos = nxt
            continue
        nxt = start + count  # a compressed element is not padded
        stream = zlib.decompressobj()
        try:
            head = stream.decompress(view[start : min(nxt, len(data))], 256)
        except zlib.error as exc:
            raise RunError(f"{name} is not a readable MATLAB file (a compressed variable: "
                           f"{exc})") from None
        if len(head) < 8:
            break  # scipy says what is wrong
        inner, size, _, _ = _mat5_tag(head, 0, order)
        var, shape = "?", ""
        if inner == _MI_MATRIX:
            try:
                _, dims, var, _ = _mat5_matrix_head(head, 8, len(head), order)
                shape = " (" + "×".join(str(max(d, 0)) for d in dims) + ")"
            except (ValueError, struct.error):
                pass
        declared += 8 + size
        if declared > cap:
            raise _too_much(name, f"its compressed MATLAB variable '{var}'{shape}", 8 + size)
        if out is None:
            out = bytearray(view[:pos])
        begin = len(out)
        out += head[: 8 + size]
        while len(out) - begin < 8 + size:
            try:
                chunk = stream.decompress(stream.unconsumed_tail,
                                          min(8 + size - (len(out) - begin), 1 << 24))
            except zlib.error as exc:
                raise RunError(f"{name} is not a readable MATLAB file (the compressed variable "
                               f"'{var}': {exc})") from None
            if not chunk:
                break
            out += chunk
        pos = nxt
    if out is None:
        budget.walk(data, 128, len(data), order)
        return data
    budget.walk(out, 128, len(out), order)
    return bytes(out)


def _vector(value: Any) -> np.ndarray | None:
    arr = np.asarray(value)
    if arr.dtype.kind not in "fiub" or arr.ndim > 2:
        return None
    if arr.ndim == 2 and min(arr.shape) != 1:
        return None
    with np.errstate(invalid="ignore", over="ignore"):
        return arr.astype(np.float64).ravel()


#: Units of a sample rate or interval written as text (``fs = "200 Hz"``), to Hz or s.
_RATE_UNITS = {"Hz": 1.0, "kHz": 1e3, "MHz": 1e6, "S/s": 1.0, "Sa/s": 1.0, "sps": 1.0,
               "samples/s": 1.0, "1/s": 1.0}
_INTERVAL_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9}
_RATE_TEXT = re.compile(r"^([-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S.*)?$")


def sample_rate_value(value: Any, key: str) -> tuple[float | None, str | None]:
    """A sample rate [Hz] from a rate (``fs``, ``sample_rate``…) or interval (``dt``,
    ``wf_increment``…) the file states, as (rate, None), or (None, the reason it is not one).

    A number, or text holding a number and, optionally, its unit (``"200 Hz"``, ``"2 kHz"``;
    ``"5 ms"`` for an interval); a one-element array, or one whose values are all equal. The
    rate must be a finite positive number. The reason is a clause for a sentence: "its sample
    rate attribute fs = 'fast' is not a number".
    """
    interval = key.lower() in DT_NAMES
    what = f"its sample {'interval' if interval else 'rate'} attribute {key}"
    if value is None:
        return None, f"{what} cannot be read as one value"
    if isinstance(value, bytes | np.bytes_):
        value = value.decode("utf-8", "replace")
    arr = np.asarray(value)
    if arr.dtype.kind in "SUO" and arr.size == 1:
        item = arr.ravel()[0]
        text = (item.decode("utf-8", "replace") if isinstance(item, bytes) else str(item)).strip()
        if not text:
            return None, f"{what} is empty"
        m = _RATE_TEXT.match(text)
        if m is None:
            return None, f"{what} = {text!r} is not a number"
        number = float(m.group(1))
        if m.group(2):
            units = _INTERVAL_UNITS if interval else _RATE_UNITS
            unit = m.group(2).strip().replace(" ", "")
            folded = {k.lower(): v for k, v in units.items() if k != "MHz"}  # not mHz
            factor = units.get(unit, folded.get(unit.lower()))
            if factor is None:
                return None, (f"{what} = {text!r} is in a unit towtank does not know (it "
                              f"reads {', '.join(units)})")
            number *= factor
        shown = repr(text)
    elif arr.dtype.kind in "fiu":
        flat = arr.ravel().astype(np.float64)
        if flat.size == 0:
            return None, f"{what} is empty"
        if flat.size > 1 and not (flat == flat[0]).all():
            return None, f"{what} holds {flat.size} different values"
        number = float(flat[0])
        shown = f"{number:g}"
    else:
        return None, f"{what} is not a number ({arr.dtype.kind!r} data)"
    if not math.isfinite(number) or number <= 0:
        return None, f"{what} = {shown} is not a positive number"
    return (1.0 / number if interval else number), None


#: A rate written in a name: a number and a rate unit (``200.05 Hz``, ``200Hz``, ``1 kHz``,
#: ``500 S/s``), or a rate or interval name, ``=`` or ``:``, a number and optionally its unit
#: (``fs=200``, ``sample_rate: 1 kHz``, ``dt=5 ms``). The number stands alone: no letter,
#: digit or point just before it.
_NAME_NUMBER = r"(\d+(?:\.\d*)?|\.\d+)(?:[eE]([-+]?\d{1,3}))?"
_NAME_RATE = re.compile(
    r"(?<![0-9A-Za-z.])" + _NAME_NUMBER
    + r"\s*(MHz|[kK]Hz|[hH][zZ]|S/s|Sa/s|sps|samples/s)(?![0-9A-Za-z/])")
_NAME_KEYED = re.compile(
    r"(?<![0-9A-Za-z])(" + "|".join(sorted((*FS_NAMES, *DT_NAMES), key=len, reverse=True))
    + r")\s*[=:]\s*" + _NAME_NUMBER
    + r"(?:\s*(MHz|[kK]Hz|[hH][zZ]|S/s|Sa/s|sps|samples/s|ms|us|µs|ns|s)(?![0-9A-Za-z/]))?",
    re.IGNORECASE)


def _name_number(whole: str, exponent: str | None) -> float:
    return float(f"{whole}e{exponent}" if exponent else whole)  # inf when too large


def rates_in_name(name: str) -> list[tuple[float, str]]:
    """The sample rates [Hz] a group or dataset name states, with the text that states each.

    A number with a rate unit, ``"200.05 Hz"`` → 200.05, ``"200Hz"``, ``"1 kHz"`` → 1000,
    ``"500 S/s"``; or a rate or interval name with ``=`` or ``:`` (:data:`FS_NAMES`,
    :data:`DT_NAMES`), ``"fs=200"`` → 200, ``"dt = 5 ms"`` → 200 (a bare number is in Hz for
    a rate, in s for an interval). Only finite positive rates are returned; any text gives a
    list (empty when it states none), never an error.

    Parameters
    ----------
    name : str
        One component of an HDF5 path (a group's or a dataset's name).

    Returns
    -------
    list of (float, str)
        (rate [Hz], the matched text), in the order they stand in the name.
    """
    found: list[tuple[int, float, str]] = []
    taken: list[tuple[int, int]] = []
    for m in _NAME_KEYED.finditer(name):
        key, unit = m.group(1).lower(), m.group(4)
        value = _name_number(m.group(2), m.group(3))
        if unit and _rate_factor(unit):  # a rate unit, whatever the key
            rate = value * _rate_factor(unit)
        elif key in DT_NAMES:  # an interval: s when no unit is written
            step = value * (_INTERVAL_UNITS.get(unit.lower(), 0.0) if unit else 1.0)
            rate = 1.0 / step if step > 0 else math.nan
        else:  # a rate: Hz when no unit is written (an interval unit is not a rate)
            rate = math.nan if unit else value
        taken.append(m.span())
        found.append((m.start(), rate, m.group(0)))
    for m in _NAME_RATE.finditer(name):
        if any(a <= m.start() < b for a, b in taken):
            continue
        rate = _name_number(m.group(1), m.group(2)) * _rate_factor(m.group(3))
        found.append((m.start(), rate, m.group(0)))
    return [(rate, text) for _, rate, text in sorted(found)
            if math.isfinite(rate) and rate > 0]


def _rate_factor(unit: str | None) -> float:
    """Hz per unit of a rate unit in a name (``MHz`` as written; ``kHz``, ``Hz`` in any case;
    ``mHz`` is not a rate towtank reads: 0)."""
    if not unit or unit.lower() not in {"hz", "khz", "mhz", "s/s", "sa/s", "sps", "samples/s"}:
        return 0.0
    if unit.lower() == "mhz":
        return 1e6 if unit == "MHz" else 0.0
    return 1e3 if unit.lower() == "khz" else 1.0


def rate_from_names(names: list[tuple[str, str]]) -> tuple[float | None, str | None,
                                                          str | None]:
    """(rate [Hz], where it is stated, None), or (None, None, why not) when the names state
    different rates, or (None, None, None) when they state none.

    ``names`` holds (what, path) pairs, ``("group", "/200.05 Hz")``, ``("dataset",
    "/200.05 Hz/C.SPEED")``: :func:`rates_in_name` reads the last component of each path. The
    same rate stated twice is one rate (equal within 1e-9 relative); two different rates are
    refused, as a clause for a sentence: "its group and dataset names state different sample
    rates (200 Hz in the name of the group '/200 Hz', 100Hz in the name of the dataset
    '/200 Hz/Fx 100Hz')".
    """
    seen: list[tuple[float, str, str]] = []
    for what, path in names:
        for rate, text in rates_in_name(path.rstrip("/").rsplit("/", 1)[-1]):
            seen.append((rate, text, f"the name of the {what} '{path}'"))
    if not seen:
        return None, None, None
    first = seen[0][0]
    other = next((s for s in seen if abs(s[0] - first) > 1e-9 * first), None)
    if other is not None:
        return None, None, (
            f"its group and dataset names state different sample rates ({seen[0][1]} in "
            f"{seen[0][2]}, {other[1]} in {other[2]})")
    return first, f"'{seen[0][1]}' in {seen[0][2]}", None


def _text_entry(text: str) -> np.ndarray:
    holder = np.empty((), dtype=object)
    holder[()] = text
    return holder


def _rate_entries(cols: dict[str, np.ndarray], fs: list[float], errors: list[str]) -> None:
    """``__fs__`` from the first rate the file states, else ``__fs_error__`` (the reason the
    rate it states is not one: the run is rejected with it only if the time must come from
    it, see :func:`towtank.ingest.runfile.map_channels`)."""
    if fs:
        cols[FS_KEY] = np.array([fs[0]])
    elif errors:
        holder = np.empty((), dtype=object)
        holder[()] = errors[0]
        cols[FS_ERROR_KEY] = holder


def _collect(items: dict[str, Any], cols: dict[str, np.ndarray], fs: list[float],
             errors: list[str] | None = None) -> None:
    """Vectors of a MATLAB/HDF5 namespace as columns; a sample rate or interval noted (a
    scalar, or text such as ``"200 Hz"``, named as in ``FS_NAMES``/``DT_NAMES``), or why
    it is not one (in ``errors``)."""
    for key, value in items.items():
        low = key.lower()
        is_rate = low in FS_NAMES or low in DT_NAMES
        if is_rate and (isinstance(value, str | bytes) or np.size(value) <= 1):
            rate, why = sample_rate_value(value, key)
            if rate is not None:
                fs.append(rate)
            elif errors is not None and why:
                errors.append(why)
            continue
        vec = _vector(value)
        if vec is None or vec.size == 1:
            continue
        cols[key] = vec


def read_mat_columns(
    data: bytes, name: str, options: ReadOptions | None = None
) -> tuple[dict[str, np.ndarray], list[str]]:
    """Vectors of a MATLAB .mat file (v4–v7 with scipy.io, v7.3 with h5py) as columns.

    The channels are the file's vectors, or the fields of the struct ``[read] group`` (default:
    the struct holding the most vectors when the top level holds none). A scalar ``fs``,
    ``sample_rate`` or ``dt`` gives the sample rate of a file without a time vector.
    """
    if data[512:520] == HDF5_SIGNATURE or data[:8] == HDF5_SIGNATURE:
        return read_hdf5_columns(data, name, options, matlab=True)
    # loaded on use: scipy.io only for a MATLAB file
    import scipy.io

    opts = options or ReadOptions()
    data = _mat5_inflated(data, name)
    try:
        mat = scipy.io.loadmat(io.BytesIO(data), squeeze_me=True, struct_as_record=False)
    except NotImplementedError:  # v7.3 without the usual header offset
        return read_hdf5_columns(data, name, options, matlab=True)
    except Exception as exc:  # noqa: BLE001 - scipy raises many types for damaged files
        raise RunError(f"{name} is not a readable MATLAB file ({type(exc).__name__}: {exc})") \
            from None
    top = {k: v for k, v in mat.items() if not k.startswith("__")}
    structs = {k: v for k, v in top.items() if hasattr(v, "_fieldnames")}
    cols: dict[str, np.ndarray] = {}
    fs: list[float] = []
    errors: list[str] = []
    if opts.group:
        if opts.group not in structs:
            found = name_list(structs)
            raise RunError(f"{name} has no struct '{opts.group}' (structs: {found})")
        chosen = [opts.group]
    else:
        _collect(top, cols, fs, errors)
        chosen = [] if len(cols) >= 2 else list(structs)
    for key in chosen:
        s = structs[key]
        _collect({f: getattr(s, f) for f in s._fieldnames}, cols, fs, errors)
    if not cols:
        raise RunError(f"{name} holds no numeric vectors (variables: "
                       f"{name_list(top, quoted=False)})")
    _rate_entries(cols, fs, errors)
    cols[LABEL_KEY] = np.array([], dtype=float)
    return cols, []


def _h5_members(group: Any, name: str) -> dict[str, Any]:
    """The objects a group's links lead to, without following a link out of the file: an
    external link (it names another file) and a soft link to nothing are left out; a soft
    link that leads back into itself rejects the run."""
    # loaded on use: h5py only for an HDF5 file
    import h5py

    out = {}
    for key in group.keys():  # the link names: nothing is resolved yet
        link = group.get(key, getlink=True)
        if isinstance(link, h5py.ExternalLink):
            continue
        try:
            out[key] = group[key]
        except RuntimeError:  # HDF5: "special link traversal failed (too many links)"
            target = getattr(link, "path", "?")
            raise RunError(
                f"{name}: the link '{group.name.rstrip('/')}/{key}' points back into itself "
                f"(through '{target}', a loop of soft links), so the file cannot be read"
            ) from None
        except KeyError:
            continue  # a soft link to nothing
    return out


def _values_elsewhere(dataset: Any, name: str) -> RunError | None:
    """The run's rejection when an HDF5 dataset keeps its values in other files (external
    raw storage, or a virtual dataset mapping other datasets), else None. Read from the
    dataset's creation property list: nothing of its values, nor of those files, is read."""
    # loaded on use: h5py only for an HDF5 file
    import h5py

    plist = dataset.id.get_create_plist()
    if plist.get_layout() == h5py.h5d.VIRTUAL:
        files = [plist.get_virtual_filename(i) for i in range(plist.get_virtual_count())]
        how = f"a virtual dataset mapped from {name_list(dict.fromkeys(files), 3)}"
    elif plist.get_external_count():
        files = [plist.get_external(i)[0] for i in range(plist.get_external_count())]
        how = "HDF5 external storage in " + name_list(
            dict.fromkeys(f.decode("utf-8", "replace") if isinstance(f, bytes) else str(f)
                          for f in files), 3)
    else:
        return None
    return RunError(
        f"{name}: the dataset '{dataset.name}' keeps its values outside the file ({how}), and "
        "towtank reads a run only from its own file (as it never follows an external link): "
        "write the values into the dataset itself"
    )


def _vector_shape(shape: tuple[int, ...]) -> bool:
    """A shape :func:`_vector` takes: a scalar, a vector or a one-row/one-column matrix."""
    return len(shape) <= 1 or (len(shape) == 2 and min(shape) == 1)


def read_hdf5_columns(  # noqa: C901 - one pass over the file's groups and attributes
    data: bytes, name: str, options: ReadOptions | None = None, *, matlab: bool = False
) -> tuple[dict[str, np.ndarray], list[str]]:
    """Datasets of an HDF5 file (or a MATLAB v7.3 file) as columns.

    The channels are the 1-D datasets of ``[read] group`` or, by default, of the group (root
    first) holding the most of them. Units come from a ``unit``/``units`` attribute; the sample
    rate from an ``fs``/``sample_rate`` attribute or scalar dataset, or ``wf_increment``
    (:func:`sample_rate_value`: a number, or text such as ``"200 Hz"``); without one, from a
    rate written in the name of the chosen group, a group above it or a channel's dataset
    (``/200.05 Hz/C.SPEED``, as MARIN's exports write it: :func:`rate_from_names`; where it
    stands is kept in ``__fs_name__``, and two different rates in names are
    ``__fs_error__``).

    Before a dataset is read, the values it declares (its shape: an unwritten dataset or a
    compressed one holds far more than the file's size) are added up and checked against the
    run-file cap as float64 numbers. External links are not followed; a loop of soft links
    rejects the run.
    """
    # loaded on use: h5py only for an HDF5 file
    import h5py

    opts = options or ReadOptions()
    what = "MATLAB v7.3" if matlab else "HDF5"
    try:  # the bytes as an in-memory file image (no Python call per read)
        fh = h5py.File(h5py.h5f.open_file_image(data), "r")
    except Exception as exc:  # noqa: BLE001 - h5py raises OSError and others for bad files
        raise RunError(f"{name} is not a readable {what} file ({type(exc).__name__}: {exc})") \
            from None
    cap = _size_cap()
    with fh:
        groups: dict[str, Any] = {"/": fh}
        members: dict[str, dict[str, Any]] = {}

        def datasets(key: str) -> dict[str, Any]:
            """The datasets of a group; one keeping its values in other files rejects the
            run before anything of it (its shape, its values) is asked for."""
            if key not in members:
                members[key] = {k: v for k, v in _h5_members(groups[key], name).items()
                                if isinstance(v, h5py.Dataset)}
                for dataset in members[key].values():
                    refused = _values_elsewhere(dataset, name)
                    if refused is not None:
                        raise refused
            return members[key]

        def vectors(key: str) -> int:
            return sum(1 for v in datasets(key).values()
                       if len(v.shape or ()) in (1, 2) and max(v.shape or (0,)) > 1)

        def attribute(owner: Any, key: str) -> Any:
            """An attribute's value when it is small (a rate, a unit), else None."""
            try:
                shape = owner.attrs.get_id(key).shape
                if int(np.prod(shape or (1,))) > 64:
                    return None
                return owner.attrs[key]
            except (OSError, KeyError, TypeError, ValueError):
                return None  # an attribute h5py cannot read: not a rate, not a unit

        try:
            if opts.group or vectors("/") < 2:
                def note_group(key: str, obj: Any) -> None:  # None: h5py visits on
                    if isinstance(obj, h5py.Group) and not key.startswith("#"):
                        groups.setdefault(key, obj)

                fh.visititems(note_group)  # every group, nested ones too
            if opts.group:
                group_key = opts.group.strip("/") or "/"
                if group_key not in groups:
                    found = name_list(groups)
                    raise RunError(f"{name} has no group '{opts.group}' (groups: {found})")
            else:
                counts = {k: vectors(k) for k in groups}
                group_key = max(counts, key=lambda k: (counts[k], k == "/"))
            chosen = groups[group_key]
            cols: dict[str, np.ndarray] = {}
            units: dict[str, str] = {}
            fs: list[float] = []
            errors: list[str] = []
            items = {}
            declared = 0
            for key, obj in datasets(group_key).items():
                shape = tuple(obj.shape or ())
                rate = key.lower() in FS_NAMES or key.lower() in DT_NAMES
                if not _vector_shape(shape) or (obj.dtype.kind not in "fiub" and not (
                        rate and int(np.prod(shape)) <= 1)):
                    continue  # not a channel: never read
                n = int(np.prod(shape))
                declared += n
                if 8 * declared > cap:
                    dims = "×".join(str(d) for d in shape)
                    raise _too_much(name, f"its {what} dataset '{obj.name}' ({dims})", 8 * n)
                items[key] = obj[()]
                names = set(obj.attrs.keys())
                unit = attribute(obj, "unit") if "unit" in names else \
                    attribute(obj, "units") if "units" in names else None
                if unit is not None:
                    units[key] = unit.decode() if isinstance(unit, bytes) else str(unit)
                if "wf_increment" in names:
                    rate_hz, why = sample_rate_value(attribute(obj, "wf_increment"),
                                                     "wf_increment")
                    fs.extend([rate_hz] if rate_hz else [])
                    errors.extend([why] if why else [])
            for owner in (chosen, fh):
                for key in owner.attrs.keys():
                    if key.lower() in FS_NAMES or key.lower() in DT_NAMES:
                        rate_hz, why = sample_rate_value(attribute(owner, key), key)
                        fs.extend([rate_hz] if rate_hz else [])
                        errors.extend([why] if why else [])
        except (OSError, KeyError, ValueError, TypeError) as exc:  # damaged inside
            raise RunError(f"{name} is not a readable {what} file ({type(exc).__name__}: "
                           f"{exc})") from None
        _collect(items, cols, fs, errors)
    if not cols:
        raise RunError(f"{name} holds no numeric datasets")
    if not fs:  # no rate attribute or scalar: a rate written in the group's or a dataset's name
        parts = [] if group_key == "/" else group_key.strip("/").split("/")
        owners = [("group", "/" + "/".join(parts[:i])) for i in range(len(parts), 0, -1)]
        base = "/" + "/".join(parts) if parts else ""
        rate_hz, where, why = rate_from_names(
            [*owners, *(("dataset", f"{base}/{k}") for k in cols)])
        if rate_hz is not None and where is not None:  # a rate comes with where it is stated
            fs.append(rate_hz)
            cols[FS_NAME_KEY] = _text_entry((where or "") + (f" ({errors[0]}: not used)" if errors
                                                     else ""))
        elif why:
            errors.append(why)
    _rate_entries(cols, fs, errors)
    cols[UNITS_KEY] = units_entry(units)
    cols[LABEL_KEY] = np.array([], dtype=float)
    return cols, []
