"""Protocol sections for real labs' set-ups: ``[tare]`` (sting runs, a tare table or none),
``[balance]`` (a dynamometer's interaction matrix), ``[read]`` (how run files are read),
``[speed_log]`` (the carriage's own log), ``[zeros]`` (a zeros file per run), and the
plausibility of ``[model] mass_kg`` (docs/formats.md).

Each parser takes the section's TOML table and returns the type of
:mod:`towtank.ingest.protocol_types` it describes (ProtocolError with one sentence otherwise);
none reads a run file.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

from towtank.errors import ProtocolError
from towtank.ingest.protocol_types import (
    CAPTIVE_TESTS,
    MEANS_COLUMNS,
    MOMENT_REFS,
    Balance,
    Captive,
    ChannelMap,
    Model,
    SpeedLog,
    TareSource,
    ZeroFile,
)
from towtank.ingest.readers import DELIMITERS, FORMATS, ReadOptions
from towtank.ingest.schema import check_keys, check_table_size, checked_section
from towtank.ingest.values import finite_number, shown
from towtank.reference.geometry import displaced_volume

__all__ = ["CAPTIVE_TESTS", "MASS_RATIO_RANGE", "TARE_TABLE_COLUMNS", "Balance", "TareSource",
           "captive_model_missing", "check_captive_runs", "check_mass", "parse_balance",
           "parse_captive",
           "parse_read_options", "parse_speed_log", "parse_tare", "parse_zero_file"]

#: The tare table's columns (docs/formats.md §3.3): speed [m/s], drag and lift [N].
TARE_TABLE_COLUMNS = ("speed_m_s", "drag_N", "lift_N")


def _table_columns(data: Any, keys: tuple[str, ...], label: str, table: str,
                   src: str) -> dict[str, str]:
    """A table of ``canonical = "the lab's column"`` (``[tare] columns``, ``[captive]
    means_columns``; ``label`` its dotted name, ``table`` the table's name in words), checked:
    known canonical names, each a non-empty text, no column named twice."""
    check_keys(data, keys, label, src)
    section, key = label.split(".")
    where = f"[{section}] {key}"
    for canon, name in data.items():
        if not isinstance(name, str) or not name.strip():
            raise ProtocolError(f"{src}: {where}: '{canon}' must name a column of the "
                                f"{table} (text), but it is {name!r}.")
    if len({v.strip().lower() for v in data.values()}) != len(data):
        raise ProtocolError(f"{src}: {where} maps one column of the {table} twice.")
    return dict(data)


def _tare_columns(data: Any, src: str) -> dict[str, str]:
    """``[tare] columns``: each table column's name in the lab's table (``{ speed_m_s =
    "tow_speed", drag_N = "tare_drag" }``), checked; the contract's own names by default."""
    given = _table_columns(data, TARE_TABLE_COLUMNS, "tare.columns", "tare table", src)
    return {c: given.get(c, c) for c in TARE_TABLE_COLUMNS}


def parse_tare(data: Any, base: Path, src: str, check_paths: bool) -> TareSource:
    """``[tare]``: sting runs, a tare table (read and checked here) or none."""
    t = checked_section(data, "tare", "tare", src)
    source = t.get("source", "sting")
    if source not in ("sting", "table", "none"):
        raise ProtocolError(
            f"{src}: 'source' in [tare] is {source!r}; it must be 'sting', 'table' or 'none'."
        )
    if source != "table":
        for key in ("table", "columns"):
            if key in t:
                raise ProtocolError(f"{src}: '{key}' in [tare] needs source = \"table\".")
        return TareSource(source=source)
    if "table" not in t:
        raise ProtocolError(f"{src}: [tare] source = \"table\" needs 'table' (a CSV file).")
    names = _tare_columns(t.get("columns", {}), src)
    path = base / t["table"]
    if not check_paths:
        return TareSource(source="table", table=str(path))
    check_table_size(path, "tare table", src)
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            rows = [r for r in csv.DictReader(line for line in fh if not line.startswith("#"))]
    except OSError as exc:
        raise ProtocolError(f"{src}: the tare table {path} cannot be read ({exc.strerror}).") \
            from None
    header = {k.strip().lower(): k for k in (rows[0] if rows else {}) if k is not None}
    cols = {c: header.get(names[c].strip().lower()) for c in TARE_TABLE_COLUMNS}
    if cols["speed_m_s"] is None or cols["drag_N"] is None:
        given = t.get("columns", {})
        need = " and ".join(f"'{names[c]}'" + (f" ({c} in [tare] columns)" if c in given else "")
                            for c in ("speed_m_s", "drag_N"))
        raise ProtocolError(
            f"{src}: the tare table {path.name} needs the columns {need} (and optionally "
            f"'{names['lift_N']}'); it has {', '.join(header) or 'none'}. Name the table's "
            "own columns in [tare] columns = { speed_m_s = \"...\", drag_N = \"...\" }."
        )
    try:
        u = [float(r[cols["speed_m_s"]]) for r in rows]
        d = [float(r[cols["drag_N"]]) for r in rows]
        lift = [float(r[cols["lift_N"]]) for r in rows] if cols["lift_N"] is not None else []
    except (TypeError, ValueError):
        raise ProtocolError(f"{src}: the tare table {path.name} holds a value that is not a "
                            "number.") from None
    if len(u) < 2 or any(b <= a for a, b in zip(u, u[1:], strict=False)) or \
            not all(math.isfinite(v) for v in u + d + lift):
        raise ProtocolError(
            f"{src}: the tare table {path.name} needs two or more rows with finite values and "
            "speeds increasing from row to row."
        )
    return TareSource(source="table", table=str(path), speeds_m_s=tuple(u), drag_N=tuple(d),
                      lift_N=tuple(lift))


def parse_balance(data: Any, channels: dict[str, ChannelMap], src: str) -> Balance:
    """``[balance]``: the interaction matrix of a multi-component dynamometer, checked."""
    b = checked_section(data, "balance", "balance", src)
    inputs, outputs, matrix = b["inputs"], b["outputs"], b["matrix"]
    if len(matrix) != len(outputs) or any(len(row) != len(inputs) for row in matrix):
        raise ProtocolError(
            f"{src}: 'matrix' in [balance] must have one row per output ({len(outputs)}) and one "
            f"number per input ({len(inputs)}) in each row."
        )
    for out in outputs:
        if out not in ("drag", "lift"):
            raise ProtocolError(
                f"{src}: the [balance] output '{out}' is not a force channel (drag, lift)."
            )
        if out in channels:
            raise ProtocolError(
                f"{src}: '{out}' is given both by [balance] and by [channels.{out}]; keep one."
            )
    if len(set(outputs)) != len(outputs) or len(set(inputs)) != len(inputs):
        raise ProtocolError(f"{src}: [balance] names an input or output twice.")
    return Balance(inputs=inputs, outputs=outputs, matrix=matrix)


def parse_read_options(values: dict[str, Any], src: str) -> ReadOptions:
    """``[read]``: how run files are read (docs/formats.md, "Run files as recorded")."""
    choices = {"format": FORMATS, "delimiter": tuple(DELIMITERS), "decimal": ("auto", ".", ",")}
    for key, allowed in choices.items():
        if key in values and values[key] not in allowed:
            listed = ", ".join(repr(a) for a in allowed)
            raise ProtocolError(
                f"{src}: '{key}' in [read] is {values[key]!r}; it must be one of {listed}."
            )
    if values.get("skip_rows", 0) < 0:
        raise ProtocolError(f"{src}: 'skip_rows' in [read] must be 0 or more.")
    if values.get("segment", 1) < 1:
        raise ProtocolError(f"{src}: 'segment' in [read] counts a file's acquisitions from 1; "
                            f"it cannot be {values['segment']}.")
    rate = values.get("sample_rate_hz")
    if rate is not None and not 1.0 <= rate <= 1.0e6:
        raise ProtocolError(
            f"{src}: 'sample_rate_hz' in [read] must lie in 1–1e6 Hz, but it is {rate:g}."
        )
    return ReadOptions(**values)


#: [model] mass_kg against the displaced mass ρV (ρ ≈ 1000 kg/m³): outside this range of
#: ratios it is in other units (grams give ~1000, tonnes ~0.001); a solid steel body is ~8.
MASS_RATIO_RANGE = (0.05, 20.0)


def check_mass(model: Model, src: str) -> None:
    """Stop on a weighed mass that no body of this size can have (a unit slip)."""
    if not 0.05 <= model.length_m <= 20.0 or not 0.005 <= (model.diameter_m or 0.05) <= 3.0:
        return  # a length or diameter in other units: the unit warnings name it
    volume = displaced_volume(model.length_m, model.diameter_m, model.volume_m3)
    if volume is None:
        return
    disp = 1000.0 * volume
    ratio = model.mass_kg / disp
    lo, hi = MASS_RATIO_RANGE
    if not lo <= ratio <= hi:
        unit = "grams" if ratio > hi else "tonnes, or the geometry in other units"
        raise ProtocolError(
            f"{src}: [model] mass_kg = {model.mass_kg:g} is {ratio:.3g} times the mass of the "
            f"water the hull displaces (about {disp:.3g} kg for its "
            f"{'given' if model.volume_m3 else 'estimated'} volume {volume:.3g} m³); a towed "
            f"model weighs {lo:g}–{hi:g} times that: was it given in {unit}?"
        )


_SPEED_LOG_KEYS = ("file", "time", "speed", "position", "offset_s")


def _log_column(value: Any, key: str, src: str) -> tuple[str, float, float]:
    """``{ column = "...", gain = 1.0, offset = 0.0 }`` (or a bare column name)."""
    where = f"'{key}' in [speed_log]"
    if isinstance(value, str):
        value = {"column": value}
    if not isinstance(value, dict) or not isinstance(value.get("column"), str) \
            or not value["column"].strip():
        raise ProtocolError(f"{src}: {where} must be {{ column = \"...\" }} (with optional gain "
                            f"and offset), but it is {value!r}.")
    extra = set(value) - {"column", "gain", "offset"}
    if extra:
        raise ProtocolError(f"{src}: {where} has the unknown key '{sorted(extra)[0]}'; it takes "
                            "column, gain and offset.")
    out = []
    for k, default in (("gain", 1.0), ("offset", 0.0)):
        v = value.get(k, default)
        number = finite_number(v)
        if number is None:
            raise ProtocolError(f"{src}: '{k}' of {where} must be a number, but it is "
                                f"{shown(v)}.")
        out.append(number)
    if out[0] == 0.0:
        raise ProtocolError(f"{src}: the gain of {where} is 0.")
    return value["column"], out[0], out[1]


def _file_pattern(data: dict[str, Any], section: str, what: str, example: str, src: str) -> str:
    """The ``file`` name pattern of a side-file section ([speed_log], [zeros]): a non-empty
    string whose only fields are {stem}, {name}, {dir} and {run}; else one sentence."""
    pattern = data.get("file")
    if not isinstance(pattern, str) or not pattern.strip():
        raise ProtocolError(f"{src}: [{section}] needs 'file', {what} name pattern (e.g. "
                            f"\"{example}\").")
    try:
        pattern.format(stem="s", name="n", dir=".", run=1)
    except (KeyError, IndexError, ValueError) as exc:
        raise ProtocolError(f"{src}: 'file' in [{section}] is {pattern!r}: only {{stem}}, "
                            f"{{name}}, {{dir}} and {{run}} can be filled in ({exc}).") from None
    return pattern


def parse_speed_log(data: Any, src: str) -> SpeedLog | None:
    """The ``[speed_log]`` table checked (None when the protocol has none)."""
    if data is None:
        return None
    check_keys(data, _SPEED_LOG_KEYS, "speed_log", src)
    pattern = _file_pattern(data, "speed_log", "the log's", "{stem}_carriage.csv", src)
    if ("speed" in data) == ("position" in data):
        raise ProtocolError(f"{src}: [speed_log] needs either 'speed' or 'position' (one of "
                            "them).")
    offset = finite_number(data.get("offset_s", 0.0))
    if offset is None or abs(offset) > 3600.0:
        raise ProtocolError(f"{src}: 'offset_s' in [speed_log] must be a number of seconds "
                            f"(within ±3600), but it is {shown(data.get('offset_s'))}.")
    return SpeedLog(
        file=pattern,
        time=_log_column(data["time"], "time", src) if "time" in data else None,
        speed=_log_column(data["speed"], "speed", src) if "speed" in data else None,
        position=_log_column(data["position"], "position", src) if "position" in data else None,
        offset_s=offset,
    )


def parse_zero_file(data: Any, src: str) -> ZeroFile | None:
    """The ``[zeros]`` table checked (None when the protocol has none)."""
    if data is None:
        return None
    check_keys(data, ("file",), "zeros", src)
    pattern = _file_pattern(data, "zeros", "the zeros file's", "{stem}_zero.csv", src)
    return ZeroFile(file=pattern)

#: Largest |roll_deg| departure from ±90° [deg]: the rig's axes are the model's rolled a
#: quarter turn, nothing in between.
ROLL_TOLERANCE_DEG = 1e-6


def _means_columns(data: Any, src: str) -> dict[str, str]:
    """``[captive] means_columns``: canonical name -> the means table's column, checked."""
    given = _table_columns(data, MEANS_COLUMNS, "captive.means_columns", "means table", src)
    return {k: v.strip() for k, v in given.items()}


def parse_captive(data: Any, base: Path, src: str, check_paths: bool) -> Captive:
    """``[captive]`` checked; with ``check_paths`` its means table is read once (a bad one
    stops the protocol: :func:`towtank.ingest.captive_means.read_means_table`)."""
    c = checked_section(data, "captive", "captive", src)
    moment_ref = c.get("moment_ref", "origin")
    if moment_ref not in MOMENT_REFS:
        raise ProtocolError(f"{src}: 'moment_ref' in [captive] is {moment_ref!r}; it must be "
                            f"one of {', '.join(MOMENT_REFS)}.")
    roll = c.get("roll_deg", 90.0)
    if abs(abs(roll) - 90.0) > ROLL_TOLERANCE_DEG:
        raise ProtocolError(f"{src}: 'roll_deg' in [captive] is {roll:g}; a model rolled onto "
                            "its side for the vertical plane is at +90 (starboard side down) "
                            "or -90.")
    cycles = c.get("min_cycles", 3)
    if not 3 <= cycles <= 1000:
        raise ProtocolError(f"{src}: 'min_cycles' in [captive] is {cycles}; a PMM run needs at "
                            "least 3 whole steady cycles (3–1000).")
    tol = c.get("amplitude_tolerance", 0.05)
    if not 0.0 < tol <= 0.5:
        raise ProtocolError(f"{src}: 'amplitude_tolerance' in [captive] is {tol:g}; it is a "
                            "fraction, above 0 and at most 0.5 (0.05 is 5 %).")
    columns = _means_columns(c.get("means_columns", {}), src)
    if "means" not in c:
        for key in ("means_prime", "means_columns"):
            if key in c:
                raise ProtocolError(f"{src}: '{key}' in [captive] describes the means table, "
                                    "but [captive] names none (means = \"...\").")
    means = base / c["means"] if "means" in c else None
    if means is not None and check_paths:
        # loaded on use: the means table's reader (pandas) only for a protocol naming one
        from towtank.ingest.captive_means import read_means_table

        read_means_table(means, columns, src=src, prime=c.get("means_prime", False))
    return Captive(moment_ref=moment_ref, means=means, means_prime=c.get("means_prime", False),
                   means_columns=columns, roll_deg=float(math.copysign(90.0, roll)),
                   min_cycles=cycles, amplitude_tolerance=tol)


def captive_model_missing(model: Model | None, captive: Captive | None,
                          planes: tuple[str, ...] = ("horizontal",)) -> list[str]:
    """The [model] keys captive tests need that the protocol leaves out.

    ``planes``: the planes (``horizontal``, ``vertical``) of the day's captive runs, whose
    balance loads carry the model's inertia: xg_m, izz_kg_m2 for the horizontal plane and
    iyy_kg_m2 (or, failing it, izz_kg_m2) for the vertical; () for a means table (inertia
    already removed). Always, with ``moment_ref = "origin"`` (the default), balance_x_m for
    the moment's transfer to O.
    """
    if model is None:
        return ["[model]"]
    out = []
    horizontal, vertical = "horizontal" in planes, "vertical" in planes
    if (horizontal or vertical) and model.izz_kg_m2 is None and \
            (horizontal or model.iyy_kg_m2 is None):
        out.append("izz_kg_m2" if horizontal or not vertical else "iyy_kg_m2")
    if (horizontal or vertical) and model.xg_m is None:
        out.append("xg_m")
    if (captive is None or captive.moment_ref == "origin") and model.balance_x_m is None:
        out.append("balance_x_m")
    return out


def check_captive_runs(sheet: Any, model: Model | None, captive: Captive | None,
                       src: str) -> None:
    """Stop a day whose run sheet has captive runs (status ok) that the protocol's [model]
    cannot reduce: one sentence naming the missing keys (:func:`captive_model_missing`) and
    the first runs that need them. ``sheet``: :func:`towtank.ingest.runsheet.read_run_sheet`'s
    table."""
    rows = sheet[sheet["test"].isin(CAPTIVE_TESTS) & (sheet["status"] == "ok")]
    if rows.empty:
        return
    planes = tuple(sorted(set(rows["plane"]) if "plane" in rows else {"horizontal"}))
    missing = captive_model_missing(model, captive, planes)
    if not missing:
        return
    runs = [str(r) for r in rows["run"].tolist()]
    listed = ", ".join(runs[:5]) + (f" and {len(runs) - 5} more" if len(runs) > 5 else "")
    need = "a [model] section" if model is None else \
        f"{' and '.join(missing)} in [model]"
    raise ProtocolError(
        f"{src}: the run sheet has {len(runs)} captive run(s) (runs {listed}), which need "
        f"{need} (the model's inertia is removed from the balance's loads and its moment "
        "transferred to the origin).")
