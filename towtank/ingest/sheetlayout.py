"""Run sheets as labs type them: the ``[sheet]`` section and the lab's column names.

A hand-typed sheet has a title (and a date, an operator) above its header, notes below its
table, the lab's own column names with units (``Run #``, ``Angle (deg)``, ``Speed (m/s)``,
``Water temp (°C)``), a ``;`` separator and decimal commas when it is a European CSV, and
status words of its own (``x``, ``bad``, ``good``). This module names the contract's columns
(docs/formats.md §2) in such a header and gives the factor to SI of a column in other units:

    value_contract = factor·value_sheet + offset                                      (1)

(e.g. mm/s → m/s: factor 1e-3; °F → °C: factor 5/9, offset −32·5/9).
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from typing import Any

from towtank.errors import ProtocolError
from towtank.ingest.schema import check_keys
from towtank.reference.constants import STANDARD_GRAVITY

__all__ = ["SheetOptions", "parse_sheet_options", "header_names", "STATUS_WORDS", "TEST_WORDS",
           "CONTRACT_COLUMNS"]

#: The contract's sheet columns a [sheet] ``columns`` table may map (and ``date``).
CONTRACT_COLUMNS = ("run", "file", "config", "test", "angle_deg", "speed_nominal",
                    "accel_nominal", "tare_group", "water_temp_C", "status", "remarks",
                    "window_start_s", "window_end_s", "date", "drift_deg", "rudder_deg",
                    "radius_m", "pmm_amplitude_m", "pmm_frequency_hz", "plane")

#: Status words: each means ``ok`` or ``void`` (case-insensitive).
STATUS_WORDS = {
    "ok": "ok", "good": "ok", "valid": "ok", "yes": "ok", "y": "ok", "✓": "ok", "✔": "ok",
    "done": "ok", "pass": "ok",
    "void": "void", "voided": "void", "x": "void", "✗": "void", "bad": "void", "skip": "void",
    "skipped": "void", "excluded": "void", "exclude": "void", "invalid": "void",
    "discard": "void", "discarded": "void", "no": "void", "n": "void", "fail": "void",
    "failed": "void", "aborted": "void",
}
#: Test words: each means ``steady``, ``accel`` or a captive test (``drift``, ``rudder``,
#: ``arm``, ``sway``, ``yaw``, ``yaw_drift``).
TEST_WORDS = {
    "steady": "steady", "steady state": "steady", "steady-state": "steady",
    "constant": "steady", "const": "steady", "resistance": "steady",
    "accel": "accel", "acceleration": "accel", "acc": "accel", "accelerated": "accel",
    "static drift": "drift", "drift angle": "drift", "oblique tow": "drift",
    "rudder angle": "rudder", "drift + rudder angle": "rudder", "drift and rudder": "rudder",
    "rotating arm": "arm", "circular motion": "arm",
    "pure sway": "sway", "pmm sway": "sway", "pmm pure sway": "sway",
    "pure yaw": "yaw", "pmm yaw": "yaw", "pmm pure yaw": "yaw",
    "yaw and drift": "yaw_drift", "yaw with drift": "yaw_drift", "yaw-drift": "yaw_drift",
    "yaw drift": "yaw_drift", "pure yaw with drift": "yaw_drift", "pmm yaw drift": "yaw_drift",
}

# the lab's names of each contract column (normalised: lower case, words separated by a blank)
_ALIASES = {
    "run": ("run", "run #", "#", "run no", "run nr", "run number", "run id", "test no",
            "test number", "run num"),
    "file": ("file", "file name", "filename", "data file", "datafile", "recording",
             "run file"),
    "config": ("config", "configuration", "setup", "set up", "set-up"),
    "test": ("test", "test type", "run type", "type"),
    "angle_deg": ("angle", "angle deg", "alpha", "aoa", "angle of attack", "drift angle",
                  "yaw angle", "incidence"),
    "speed_nominal": ("speed", "nominal speed", "set speed", "carriage speed", "tow speed",
                      "velocity", "speed nominal"),
    "accel_nominal": ("accel", "acceleration", "set acceleration", "nominal acceleration",
                      "accel nominal"),
    "water_temp_C": ("water temp", "water temperature", "temperature", "temp", "water temp c",
                     "t water"),
    "tare_group": ("tare group", "tare"),
    "status": ("status", "state"),
    "remarks": ("remarks", "comment", "comments"),
    "window_start_s": ("window start", "steady start", "window start s"),
    "window_end_s": ("window end", "steady end", "window end s"),
    "date": ("date", "test date"),
    "drift_deg": ("drift deg", "beta", "drift_deg"),
    "rudder_deg": ("rudder", "rudder angle", "delta", "rudder deg"),
    "radius_m": ("radius", "arm radius", "turning radius"),
    "pmm_amplitude_m": ("pmm amplitude", "sway amplitude", "pmm amplitude m"),
    "pmm_frequency_hz": ("pmm frequency", "pmm frequency hz", "pmm freq"),
    "plane": ("plane",),
}
_BY_ALIAS = {a: canon for canon, names in _ALIASES.items() for a in names}

# units of the numeric columns: unit (lower case) -> (factor, offset) to the contract's unit
_UNITS: dict[str, dict[str, tuple[float, float]]] = {
    "angle_deg": {"deg": (1.0, 0.0), "°": (1.0, 0.0), "degree": (1.0, 0.0),
                  "degrees": (1.0, 0.0), "rad": (57.29577951308232, 0.0)},
    "speed_nominal": {"m/s": (1.0, 0.0), "mm/s": (1e-3, 0.0), "cm/s": (1e-2, 0.0),
                      "km/h": (1 / 3.6, 0.0), "kn": (0.514444, 0.0), "knots": (0.514444, 0.0),
                      "kt": (0.514444, 0.0), "ms-1": (1.0, 0.0), "m s-1": (1.0, 0.0)},
    "accel_nominal": {"m/s²": (1.0, 0.0), "m/s^2": (1.0, 0.0), "m/s2": (1.0, 0.0),
                      "mm/s²": (1e-3, 0.0), "mm/s^2": (1e-3, 0.0), "g": (STANDARD_GRAVITY, 0.0),
                      "m s-2": (1.0, 0.0)},
    "water_temp_C": {"°c": (1.0, 0.0), "c": (1.0, 0.0), "degc": (1.0, 0.0),
                     "deg c": (1.0, 0.0), "celsius": (1.0, 0.0), "k": (1.0, -273.15),
                     "°f": (5 / 9, -32 * 5 / 9), "f": (5 / 9, -32 * 5 / 9)},
    "drift_deg": {"deg": (1.0, 0.0), "°": (1.0, 0.0), "rad": (57.29577951308232, 0.0)},
    "rudder_deg": {"deg": (1.0, 0.0), "°": (1.0, 0.0), "rad": (57.29577951308232, 0.0)},
    "radius_m": {"m": (1.0, 0.0), "mm": (1e-3, 0.0), "cm": (1e-2, 0.0)},
    "pmm_amplitude_m": {"m": (1.0, 0.0), "mm": (1e-3, 0.0), "cm": (1e-2, 0.0)},
    "pmm_frequency_hz": {"hz": (1.0, 0.0), "rad/s": (0.15915494309189535, 0.0)},
    "window_start_s": {"s": (1.0, 0.0), "ms": (1e-3, 0.0)},
    "window_end_s": {"s": (1.0, 0.0), "ms": (1e-3, 0.0)},
}
_UNIT_IN_NAME = re.compile(r"^(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]\s*$")


@dataclass(frozen=True)
class SheetOptions:
    """The protocol's ``[sheet]`` (docs/formats.md §2.1).

    Parameters
    ----------
    header_row : int
        1-based row of the header; 0 finds it (the first row, within the first 30, that names
        the required columns: title rows above it are skipped).
    columns : dict
        Contract column -> the lab's column name (``{ run = "Run #" }``).
    delimiter : str
        CSV sheets: ``auto``, ``","``, ``";"`` or ``"\\t"``.
    decimal : str
        CSV sheets: ``auto`` (a decimal comma in ``;`` or tab separated sheets), ``"."``, ``","``.
    name : str
        .xlsx sheets: the worksheet holding the runs ("" = chosen as docs/formats.md §2
        says: the active worksheet if it is visible and has the columns, else the first
        visible one that has them; never a hidden one unless named here).
    """

    header_row: int = 0
    columns: dict[str, str] = field(default_factory=dict)
    delimiter: str = "auto"
    decimal: str = "auto"
    name: str = ""


def parse_sheet_options(data: Any, src: str) -> SheetOptions:
    """The ``[sheet]`` table checked (defaults when the protocol has none)."""
    if data is None:
        return SheetOptions()
    check_keys(data, ("header_row", "columns", "delimiter", "decimal", "name"), "sheet", src)
    row = data.get("header_row", 0)
    if isinstance(row, bool) or not isinstance(row, int) or not 0 <= row <= 1000:
        raise ProtocolError(f"{src}: 'header_row' in [sheet] must be a whole number 0–1000 "
                            f"(0: found automatically), but it is {row!r}.")
    columns = data.get("columns", {})
    if not isinstance(columns, dict):
        raise ProtocolError(f"{src}: 'columns' in [sheet] must be a table "
                            "{ run = \"Run #\", ... }, but it is {columns!r}.")
    for canon, name in columns.items():
        if canon not in CONTRACT_COLUMNS:
            near = difflib.get_close_matches(canon, CONTRACT_COLUMNS, n=1, cutoff=0.5)
            hint = (f"; did you mean '{near[0]}'?" if near
                    else f"; the columns are {', '.join(CONTRACT_COLUMNS)}")
            raise ProtocolError(f"{src}: [sheet] columns maps '{canon}', which is not a run "
                                f"sheet column{hint}")
        if not isinstance(name, str) or not name.strip():
            raise ProtocolError(f"{src}: [sheet] columns: '{canon}' must name a column of the "
                                f"sheet (text), but it is {name!r}.")
    if len(set(columns.values())) != len(columns):
        raise ProtocolError(f"{src}: [sheet] columns maps one column of the sheet twice.")
    delimiter = data.get("delimiter", "auto")
    if delimiter not in ("auto", ",", ";", "\t", "tab"):
        raise ProtocolError(f"{src}: 'delimiter' in [sheet] must be auto, \",\", \";\" or "
                            f"\"\\t\", but it is {delimiter!r}.")
    decimal = data.get("decimal", "auto")
    if decimal not in ("auto", ".", ","):
        raise ProtocolError(f"{src}: 'decimal' in [sheet] must be auto, \".\" or \",\", but "
                            f"it is {decimal!r}.")
    name = data.get("name", "")
    if not isinstance(name, str) or ("name" in data and not name.strip()):
        raise ProtocolError(f"{src}: 'name' in [sheet] must name a worksheet of the workbook "
                            f"(text), but it is {name!r}.")
    return SheetOptions(header_row=row, columns=dict(columns),
                        delimiter="\t" if delimiter == "tab" else delimiter, decimal=decimal,
                        name=name)


def _norm(text: str) -> str:
    return re.sub(r"[^0-9a-z#°²^/]+", " ", text.lower()).strip()


def header_names(cells: list[Any], options: SheetOptions | None,
                 src: str) -> tuple[list[str], dict[str, tuple[float, float]]]:
    """The header's columns as the contract names them, and (factor, offset) of eq. 1 for the
    numeric ones in other units.

    A cell the ``[sheet] columns`` table names is that column; else a cell whose words (its unit
    in brackets aside) are a common name of a contract column (``Run #``, ``Angle (deg)``,
    ``Speed (mm/s)``, ``Water temp (°C)``, ``Date``) is that column, if no other cell is; other
    cells keep their text (extra columns, or contract names handled by the reader). A unit that
    cannot be converted stops the day with a sentence naming it.
    """
    texts = ["" if c is None else str(c).strip() for c in cells]
    mapped = {v.strip(): k for k, v in (options.columns if options else {}).items()}
    out: list[str] = list(texts)
    units: dict[str, tuple[float, float]] = {}
    taken = {t for t in texts if t in CONTRACT_COLUMNS}
    guesses: dict[str, list[int]] = {}
    for i, text in enumerate(texts):
        if not text:
            continue
        if text in mapped:
            out[i] = mapped[text]
            taken.add(mapped[text])
            m = _UNIT_IN_NAME.match(text)
            if m and mapped[text] in _UNITS:
                units[mapped[text]] = _unit(mapped[text], m.group(2), text, src)
            continue
        if text in CONTRACT_COLUMNS:
            continue
        m = _UNIT_IN_NAME.match(text)
        base, unit = (m.group(1), m.group(2)) if m else (text, "")
        canon = _BY_ALIAS.get(_norm(base))
        if canon is None and not unit:
            canon = _BY_ALIAS.get(_norm(text))
        if canon is not None:
            guesses.setdefault(canon, []).append(i)
    for canon, idx in guesses.items():
        if canon in taken or len(idx) != 1:
            continue  # the contract's own column is there, or two cells could be it
        i = idx[0]
        m = _UNIT_IN_NAME.match(texts[i])
        if m and m.group(2) and canon in _UNITS:
            units[canon] = _unit(canon, m.group(2), texts[i], src)
        elif m and m.group(2) and canon not in _UNITS and canon != "run":
            continue  # a unit on a text column: not this column after all
        out[i] = canon
        taken.add(canon)
    return out, units


def _unit(canon: str, unit: str, text: str, src: str) -> tuple[float, float]:
    table = _UNITS[canon]
    key = unit.strip().lower().replace(" ", "") if unit.strip().lower() not in table else \
        unit.strip().lower()
    if key in table:
        return table[key]
    if key.replace("deg", "°") in table:
        return table[key.replace("deg", "°")]
    raise ProtocolError(
        f"{src}: the run sheet's column {text!r} is in {unit!r}, which towtank cannot convert "
        f"to {canon}'s unit (known: {', '.join(table)}); convert it or map it in [sheet] "
        "columns."
    )


def words(value: str, table: dict[str, str]) -> str:
    """A status or test word as the contract spells it (unknown words unchanged)."""
    key = value.strip().lower()
    return table.get(key, key)
