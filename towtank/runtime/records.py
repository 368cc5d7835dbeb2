"""A dataclass record as bytes that cannot execute anything when read back (the run cache).

A record is written as an uncompressed ``.npz`` archive (:func:`numpy.savez`): its numeric
arrays as ``.npy`` members and every other field in one JSON member (``__record__.json``).
Reading it back never unpickles (``allow_pickle=False``), checks every member's declared size
against the bytes it has before anything is allocated, and checks every field against the
record class's type hints: a missing or extra field, a value of another type, an array of
another kind or dimension, a member that is compressed or that is not a plain array is a
:class:`RecordError`, which the cache treats as a miss.
"""

from __future__ import annotations

import dataclasses
import io
import json
import types
import typing
import zipfile
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

__all__ = ["RecordError", "to_bytes", "from_bytes", "check_value", "table_length"]

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

T = TypeVar("T", bound="DataclassInstance")

#: The JSON member of a record.
HEADER = "__record__.json"
#: Largest JSON member read back [bytes]; a run's notes are a few kB.
MAX_HEADER_BYTES = 4 << 20
#: Largest record read back [bytes] (a run's decimated samples and thumbnail are < 10 MB).
MAX_RECORD_BYTES = 1 << 30
#: Kinds of array a record may hold: bool, signed and unsigned integers, floats.
ARRAY_KINDS = "biuf"


class RecordError(ValueError):
    """A stored record that is not a record of the expected class."""


def to_bytes(record: Any) -> bytes:
    """The dataclass ``record`` as the bytes of an uncompressed npz archive.

    Arrays (fields typed ``np.ndarray``, or values of ``dict[str, np.ndarray]`` fields) become
    ``.npy`` members; every other field goes into the JSON member (NaN written as ``NaN``).
    """
    if not dataclasses.is_dataclass(record) or isinstance(record, type):
        raise TypeError("to_bytes takes a dataclass instance")
    arrays: dict[str, Any] = {}
    header: dict[str, Any] = {}

    def ref(arr: np.ndarray) -> dict[str, str]:
        name = f"a{len(arrays)}"
        arrays[name] = np.asarray(arr)
        return {"__array__": name}

    for f in dataclasses.fields(record):
        value = getattr(record, f.name)
        if isinstance(value, np.ndarray):
            header[f.name] = ref(value)
        elif isinstance(value, dict) and value and all(
                isinstance(v, np.ndarray) for v in value.values()):
            header[f.name] = {str(k): ref(v) for k, v in value.items()}
        else:
            header[f.name] = _plain(value)
    buf = io.BytesIO()
    # stored, not deflated: sizes are what they say (the names a0, a1, ... are never savez's
    # own keyword allow_pickle)
    np.savez(buf, **arrays)
    with zipfile.ZipFile(buf, "a", compression=zipfile.ZIP_STORED) as zf:
        zf.writestr(HEADER, json.dumps(header, allow_nan=True))
    return buf.getvalue()


def _plain(value: Any) -> Any:
    """``value`` with tuples as lists and numpy scalars as Python numbers (for JSON)."""
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, np.generic):
        return value.item()
    return value


def _read_arrays(zf: zipfile.ZipFile) -> dict[str, np.ndarray]:
    """Every ``.npy`` member of ``zf``, each checked before it is read: stored (not
    compressed), a plain numeric dtype, and a declared shape that its bytes hold."""
    out = {}
    for info in zf.infolist():
        if info.filename == HEADER:
            continue
        if not info.filename.endswith(".npy") or info.compress_type != zipfile.ZIP_STORED:
            raise RecordError(f"unexpected member {info.filename!r}")
        with zf.open(info) as fh:
            version = np.lib.format.read_magic(fh)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
            elif version == (2, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
            else:
                raise RecordError(f"npy version {version} in {info.filename!r}")
            if dtype.hasobject or dtype.kind not in ARRAY_KINDS or len(shape) != 1:
                raise RecordError(f"{info.filename!r} is not a 1-D numeric array")
            if shape[0] * dtype.itemsize > info.file_size:
                raise RecordError(f"{info.filename!r} declares more than it holds")
            fh.seek(0)
            arr = np.lib.format.read_array(fh, allow_pickle=False)
        out[info.filename[: -len(".npy")]] = arr
    return out


def from_bytes(blob: bytes, cls: type[T]) -> T:
    """The record of class ``cls`` that :func:`to_bytes` wrote into ``blob``.

    Raises :class:`RecordError` for anything that is not exactly such a record.
    """
    if not isinstance(blob, bytes | bytearray | memoryview) or len(blob) > MAX_RECORD_BYTES:
        raise RecordError("not a record")
    try:
        with zipfile.ZipFile(io.BytesIO(blob)) as zf:
            info = zf.getinfo(HEADER)
            if info.file_size > MAX_HEADER_BYTES or info.compress_type != zipfile.ZIP_STORED:
                raise RecordError("record header too large")
            header = json.loads(zf.read(info))
            arrays = _read_arrays(zf)
    except RecordError:
        raise
    except (zipfile.BadZipFile, KeyError, ValueError, OSError, EOFError,
            RecursionError, MemoryError, UnicodeDecodeError) as exc:
        raise RecordError(f"not a record ({type(exc).__name__})") from None
    if not isinstance(header, dict):
        raise RecordError("record header is not a table")
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    if set(header) != names:
        raise RecordError("record fields differ from the class's")
    used: set[str] = set()

    def arrays_in(value: Any) -> Any:
        if isinstance(value, dict):
            if set(value) == {"__array__"}:
                name = value["__array__"]
                if not isinstance(name, str) or name not in arrays or name in used:
                    raise RecordError("record names an array it does not hold")
                used.add(name)
                return arrays[name]
            return {k: arrays_in(v) for k, v in value.items()}
        return value

    values = {}
    for name in names:
        values[name] = check_value(arrays_in(header[name]), hints[name], name)
    if used != set(arrays):
        raise RecordError("record holds arrays it does not name")
    return cls(**values)


def check_value(value: Any, tp: Any, where: str = "value") -> Any:
    """``value`` converted to type ``tp`` (JSON lists to tuples, ints to floats), or
    RecordError. Types: bool, int, float, str, None, np.ndarray, ``X | Y``, ``tuple[X, ...]``,
    ``tuple[X, Y]``, ``list[X]``, ``dict[str, X]``."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        for option in typing.get_args(tp):
            try:
                return check_value(value, option, where)
            except RecordError:
                continue
        raise RecordError(f"{where}: {type(value).__name__} is none of {tp}")
    if tp is type(None) or tp is None:
        if value is None:
            return None
    elif tp is bool:
        if isinstance(value, bool):
            return value
    elif tp is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif tp is float:
        if isinstance(value, int | float) and not isinstance(value, bool):
            return float(value)
    elif tp is str:
        if isinstance(value, str):
            return value
    elif tp is np.ndarray:
        if isinstance(value, np.ndarray):
            return value
    elif origin is tuple:
        args = typing.get_args(tp)
        if isinstance(value, list):
            if len(args) == 2 and args[1] is Ellipsis:
                return tuple(check_value(v, args[0], where) for v in value)
            if len(value) == len(args):
                return tuple(check_value(v, a, where) for v, a in zip(value, args, strict=True))
    elif origin is list:
        (arg,) = typing.get_args(tp)
        if isinstance(value, list):
            return [check_value(v, arg, where) for v in value]
    elif origin is dict:
        key_t, val_t = typing.get_args(tp)
        if isinstance(value, dict) and key_t is str:
            return {k: check_value(v, val_t, f"{where}[{k}]") for k, v in value.items()}
    else:
        raise RecordError(f"{where}: type {tp} cannot be read back")
    raise RecordError(f"{where}: {type(value).__name__} is not {tp}")


def table_length(table: Any, floats: tuple[str, ...], ints: tuple[str, ...] = ()) -> int | None:
    """The length of ``table`` when it is a sample table of a record, else None.

    A sample table maps exactly the column names ``floats`` to 1-D float64 arrays and ``ints``
    to 1-D arrays of a signed integer type, all of one length > 0 (what a record may hold
    otherwise, a bool or integer array where floats belong, an empty or a ragged table, is
    not one).
    """
    if not isinstance(table, dict) or set(table) != set(floats) | set(ints):
        return None
    arrays = list(table.values())
    if not all(isinstance(a, np.ndarray) and a.ndim == 1 for a in arrays):
        return None
    if not (all(table[k].dtype == np.float64 for k in floats)
            and all(table[k].dtype.kind == "i" for k in ints)):
        return None
    lengths = {a.shape[0] for a in arrays}
    return lengths.pop() if len(lengths) == 1 and 0 not in lengths else None

