"""Raw columns to SI channels, and where each channel's unit came from.

A channel's value is gain·(raw − offset) where ``[channels]`` gives a calibration, else its
column converted to SI from its unit: ``unit`` in ``[channels]``, else the unit the file states
(a units row, TDMS ``unit_string``, LVM ``Y_Unit_Label``, an HDF5/.mat attribute) or writes in
the column's name (``Speed (mm/s)``); with none of them the SI unit is assumed, and recorded as
assumed (docs/formats.md §3.1, "Where each unit came from").
"""

from __future__ import annotations

import numpy as np

from towtank.ingest.protocol_types import ChannelMap
from towtank.ingest.readers import column_unit, converts, is_volts, unit_factor

__all__ = ["UNITS", "calibrate", "unit_source"]

#: The SI unit of each canonical channel.
UNITS = {"time": "s", "speed": "m/s", "accel": "m/s²", "drag": "N", "lift": "N",
         "fx": "N", "fy": "N", "mz": "N m", "sway": "m", "yaw": "deg"}


def calibrate(
    numeric: dict[str, np.ndarray],
    full: dict[str, ChannelMap],
    used: dict[str, str],
    units: dict[str, str],
    name: str,
    notes: list[str],
    sources: dict[str, tuple[str, str]] | None = None,
) -> dict[str, np.ndarray]:
    """Raw columns to SI channels: value = gain·(raw − offset) where ``[channels]`` gives a
    calibration, else the column's unit (``unit`` in ``[channels]``, else stated by the file
    or in its name, ``Speed (mm/s)``) converted to SI
    (:func:`towtank.ingest.readers.unit_factor`); infinities become missing. ``sources``
    receives, per channel, (its unit, where the unit came from: :func:`unit_source`)."""
    out = {}
    for canon, arr in numeric.items():
        cm = full[canon]
        column = used.get(canon, cm.column)
        in_file = column_unit(column, units, canon) or _cells_unit(cm, units)
        stated = cm.unit or in_file
        if cm.unit and in_file and in_file.lower() != cm.unit.lower():
            notes.append(f"{canon}: the file states {in_file}; [channels] unit = "
                         f"\"{cm.unit}\" is used")
        if sources is not None and column not in ("[speed_log]", "[nominal]"):
            sources[canon] = unit_source(canon, cm, column, stated, cm.unit != "")
        if cm.gain != 1.0 or cm.offset != 0.0:
            with np.errstate(all="ignore"):
                arr = cm.gain * (arr - cm.offset)
        else:
            unit = stated
            if cm.calibrated and is_volts(unit):  # a stated gain of 1 N per V (or V per V)
                notes.append(f"{canon} taken from {unit} with the stated gain 1.0 "
                             f"(1 SI unit per {unit})")
                factor = 1.0
            else:
                factor = unit_factor(canon, unit, column, name)
            if factor != 1.0:
                arr = arr * factor
                notes.append(f"{canon} converted from {unit} to SI (×{factor:g})")
        inf = np.isinf(arr)
        if inf.any():
            arr = np.where(inf, np.nan, arr)
            notes.append(f"{int(inf.sum())} infinite {canon} value(s) treated as missing")
        out[canon] = arr
    return out


def _cells_unit(cm: ChannelMap, units: dict[str, str]) -> str | None:
    """The unit of a sum of load cells (``columns``): the one unit all its cells state."""
    if not cm.columns:
        return None
    found = {column_unit(c, units) for c in cm.columns}
    return found.pop() if len(found) == 1 else None


def unit_source(canon: str, cm: ChannelMap, column: str, stated: str | None,
                from_protocol: bool = False) -> tuple[str, str]:
    """(unit, source) of one channel read from ``column``.

    ``"protocol"`` when [channels] gives a ``unit`` (``from_protocol``: that unit), a gain or
    an offset, or the channel is a [balance] output (the SI unit of ``canon``: the calibration
    gives it); ``"file"`` when the file states the unit (a units row or header, TDMS
    ``unit_string``, LVM ``Y_Unit_Label``, an HDF5/.mat attribute, ``Speed (mm/s)``) or the
    time comes from the file's own timing; ``"unknown"`` for a label towtank does not convert
    (``lb``, ``-``: the values are taken in the SI unit, with the label kept); else
    ``"assumed"``: no label anywhere, the SI unit of ``canon`` is taken.
    """
    si = UNITS.get(canon, "")
    if from_protocol or cm.calibrated or column.startswith("["):
        return (stated or si) if from_protocol else si, "protocol"
    if column.startswith("time (from the file"):
        return "s", "file"
    if stated and not converts(canon, stated):
        return stated, "unknown"  # a label towtank does not convert: the values taken as SI
    if stated:
        return stated, "file"
    return si, "assumed"
