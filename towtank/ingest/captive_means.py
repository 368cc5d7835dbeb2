"""A lab's table of static captive-test means (``[captive] means``, docs/formats.md "Captive
manoeuvring tests").

One row per run as a lab delivers it (a CSV, ``,`` ``;`` or tab separated, or an .xlsx
workbook's first visible worksheet): the run number, drift angle, rudder angle, arm radius,
speed and the forces and yaw moment, in columns named by ``[captive] means_columns`` or
guessed from the lab's names (``Run No.``, ``beta(deg)``, ``delta(deg)``, ``Speed(m/s)``,
``X'``, ``Y'``, ``N'``). Cells may carry stray blanks (``30 ,``); a run listed in several
test-type blocks is kept once when its rows agree and stops the protocol when they do not.
With ``means_prime`` the forces are primes over ½ρL²U² and the moment over ½ρL³U²
(:func:`means_in_si` converts them):

    F = F'·½ρL²U²,   N = N'·½ρL³U²                                               (1)

Every fault is a :class:`~towtank.errors.ProtocolError` with one sentence: the table is the
whole day, read before anything is written.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from towtank.errors import ProtocolError
from towtank.ingest.protocol_types import MEANS_COLUMNS, Captive, Protocol
from towtank.ingest.runsheet import read_csv_grid
from towtank.ingest.schema import check_table_size
from towtank.ingest.sheetlayout import SheetOptions
from towtank.reference.water import water_at

__all__ = ["MAX_DRIFT_DEG", "MAX_MEANS_SPEED", "captive_means", "check_prime_names",
           "means_in_si", "prime_magnitude_warning", "read_means_table"]

#: Largest |drift angle| and |rudder angle| of a captive run [deg].
MAX_DRIFT_DEG = 90.0
#: Fastest speed a means table may give [m/s] (no towing carriage is faster).
MAX_MEANS_SPEED = 50.0
#: The lab's names of each canonical column (lower case, blanks removed), first match wins.
_GUESSES: dict[str, tuple[str, ...]] = {
    "run": ("run", "runno.", "runno", "run#", "runnumber", "runnr", "run_no", "testno.",
            "testno"),
    "drift_deg": ("drift_deg", "beta", "drift", "driftangle", "β"),
    "rudder_deg": ("rudder_deg", "delta", "rudder", "rudderangle", "δ", "dr"),
    "radius_m": ("radius_m", "radius", "armradius", "r_arm"),
    "speed": ("speed", "u", "velocity", "carriagespeed"),
    "fx": ("fx", "x", "x'", "xforce"),
    "fy": ("fy", "y", "y'", "yforce"),
    "mz": ("mz", "n", "n'", "yawmoment"),
}
#: The lab's names of its test-type column (kept as ``test_type``).
_TEST_TYPE_NAMES = ("testtype", "test", "type", "test_type")
#: Factors to the canonical unit of a unit written in brackets after a column's name.
_UNITS = {
    "drift_deg": {"deg": 1.0, "°": 1.0, "degree": 1.0, "degrees": 1.0, "rad": 180.0 / math.pi},
    "rudder_deg": {"deg": 1.0, "°": 1.0, "degree": 1.0, "degrees": 1.0,
                   "rad": 180.0 / math.pi},
    "radius_m": {"m": 1.0, "mm": 1e-3, "cm": 1e-2},
    "speed": {"m/s": 1.0, "mm/s": 1e-3, "cm/s": 1e-2, "kn": 0.514444, "knots": 0.514444},
    "fx": {"n": 1.0, "kn": 1e3}, "fy": {"n": 1.0, "kn": 1e3},
    "mz": {"nm": 1.0, "n m": 1.0, "n.m": 1.0, "n·m": 1.0, "knm": 1e3, "kn m": 1e3},
}
_UNIT_IN_NAME = re.compile(r"^(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]\s*$")
#: Canonical numeric columns a run's rows must agree in to be the same run.
_VALUES = ("drift_deg", "rudder_deg", "radius_m", "speed", "fx", "fy", "mz")


def _key(text: str) -> str:
    return re.sub(r"\s+", "", text.strip().lower())


def _split_unit(name: str) -> tuple[str, str]:
    m = _UNIT_IN_NAME.match(name)
    return (m.group(1), m.group(2)) if m else (name, "")


def _grid(path: Path, src: str) -> list[list[Any]]:
    """The table's cells (text or numbers), header first; blank rows dropped."""
    check_table_size(path, "means table", src)
    try:
        if path.suffix.lower() == ".xlsx":
            # loaded on use: openpyxl only for a workbook
            import openpyxl

            wb = openpyxl.load_workbook(path, read_only=True, data_only=True)
            try:
                ws = next(w for w in wb.worksheets if w.sheet_state == "visible")
                rows = [list(r) for r in ws.iter_rows(values_only=True)]
            finally:
                wb.close()
        else:
            rows = read_csv_grid(path, SheetOptions())
    except ProtocolError:
        raise
    except Exception as exc:  # noqa: BLE001 - any reader failure is the table's fault
        raise ProtocolError(f"{src}: the means table {path.name} cannot be read ({exc}).") \
            from None
    return [r for r in rows if any(c is not None and str(c).strip() for c in r)]


def _columns(header: list[str], given: dict[str, str], path: Path, src: str
             ) -> tuple[dict[str, int], dict[str, float], int | None]:
    """Each canonical column's index in ``header`` (``given`` first, then guessed), its
    factor to the canonical unit, and the test-type column's index (None without one)."""
    keys = [_key(h) for h in header]
    bare = [_key(_split_unit(h)[0]) for h in header]
    index: dict[str, int] = {}
    for canon, name in given.items():
        if _key(name) not in keys:
            raise ProtocolError(
                f"{src}: [captive] means_columns maps {canon} to the column {name!r}, which "
                f"the means table {path.name} does not have (its columns: "
                f"{', '.join(header)}).")
        index[canon] = keys.index(_key(name))
    for canon in MEANS_COLUMNS:
        if canon in index:
            continue
        for guess in _GUESSES[canon]:
            hits = [i for i, b in enumerate(bare) if b == guess and i not in index.values()]
            if len(hits) == 1:
                index[canon] = hits[0]
                break
    factors = {}
    for canon, i in index.items():
        unit = _split_unit(header[i])[1].strip().lower()
        if not unit or canon == "run":
            factors[canon] = 1.0
            continue
        table = _UNITS[canon]
        if unit not in table:
            raise ProtocolError(
                f"{src}: the means table's column {header[i]!r} ({canon}) is in {unit!r}, "
                f"which towtank cannot convert (known: {', '.join(table)}).")
        factors[canon] = table[unit]
    taken = set(index.values())
    test = next((i for i, b in enumerate(bare) if b in _TEST_TYPE_NAMES and i not in taken),
                None)
    return index, factors, test


def _number(cell: Any) -> float:
    """A cell as a number (blanks around it ignored); NaN when blank; ValueError for text."""
    if cell is None:
        return math.nan
    if isinstance(cell, bool):
        raise ValueError(cell)
    text = str(cell).strip()
    if not text:
        return math.nan
    value = float(text.replace(" ", ""))
    if math.isinf(value):
        raise ValueError(cell)
    return value


def read_means_table(path: str | Path, columns: dict[str, str] | None = None, *,
                     src: str = "", prime: bool | None = None
                     ) -> tuple[pd.DataFrame, list[str]]:
    """Read a lab's table of static captive means, in the table's own units.

    Parameters
    ----------
    path : str or Path
        The table (.csv or .xlsx).
    columns : dict, optional
        ``[captive] means_columns``: canonical name -> the table's column; the rest guessed.
    src : str
        The protocol's name, for the messages.
    prime : bool, optional
        ``[captive] means_prime``: the loads' column names must agree with it
        (:func:`check_prime_names`); None: not checked.

    Returns
    -------
    (pandas.DataFrame, list of str)
        One row per run, in the table's order (a run listed in several blocks kept where it
        is first): ``run``, ``drift_deg`` [deg], ``rudder_deg`` [deg], ``radius_m`` [m] (NaN:
        no arm), ``speed`` [m/s], ``fx``, ``fy`` [N, or primes], ``mz`` [N m, or prime],
        ``row`` (the row in the table, header = 1) and, when the table has one, ``test_type``
        (the lab's words, of the run's first row). And the notes: repeated runs kept once,
        columns not read.

    Raises
    ------
    ProtocolError
        Unreadable table, required column (speed, fy, mz) not found, a cell that is not a
        number, a run listed twice with different values, a drift or rudder angle beyond
        ±90°, a speed not in 0–50 m/s, load columns named as primes (X', Y', N') without
        ``prime`` or with a unit (N) with it.
    """
    path = Path(path)
    src = src or path.name
    grid = _grid(path, src)
    if len(grid) < 2:
        raise ProtocolError(f"{src}: the means table {path.name} has no rows under its header.")
    header = ["" if c is None else str(c).strip() for c in grid[0]]
    index, factors, test = _columns(header, columns or {}, path, src)
    missing = [c for c in ("speed", "fy", "mz") if c not in index]
    if prime is not None:
        check_prime_names([header[index[c]] for c in ("fx", "fy", "mz") if c in index],
                          prime, path.name, src)
    if missing:
        raise ProtocolError(
            f"{src}: the means table {path.name} has no column for {', '.join(missing)} "
            f"(its columns: {', '.join(header)}); name them in [captive] means_columns = "
            "{ speed = \"...\", fy = \"...\", mz = \"...\" }.")
    records = []
    for k, row in enumerate(grid[1:], start=2):
        row = list(row) + [None] * (len(header) - len(row))
        rec: dict[str, Any] = {"row": k}
        for canon in MEANS_COLUMNS:
            if canon not in index:
                continue
            cell = row[index[canon]]
            try:
                value = _number(cell)
            except (ValueError, OverflowError):
                raise ProtocolError(
                    f"{src}: row {k} of the means table {path.name} has {cell!r} in the column "
                    f"{header[index[canon]]!r} ({canon}), which is not a number.") from None
            if math.isnan(value) and canon in ("run", "speed", "fy", "mz"):
                raise ProtocolError(f"{src}: row {k} of the means table {path.name} has no "
                                    f"{canon} (column {header[index[canon]]!r}).")
            rec[canon] = value * factors[canon]
        if test is not None:
            rec["test_type"] = "" if row[test] is None else str(row[test]).strip()
        records.append(rec)
    table = pd.DataFrame(records)
    if "run" not in table:
        table["run"] = np.arange(1, len(table) + 1)
    for canon, default in (("drift_deg", 0.0), ("rudder_deg", 0.0), ("radius_m", math.nan),
                           ("fx", math.nan)):
        if canon not in table:
            table[canon] = default
    table["radius_m"] = table["radius_m"].where(table["radius_m"] != 0.0)  # 0: no arm
    _check_values(table, path.name, src)
    table, notes = _unique_runs(table, path.name, src)
    unread = [h for i, h in enumerate(header) if h and i not in index.values() and i != test]
    if unread:
        notes.append(f"the means table {path.name}'s column(s) {', '.join(unread)} are not "
                     "read (towtank reads " + ", ".join(MEANS_COLUMNS) + ").")
    cols = ["run", *_VALUES, "row"] + (["test_type"] if "test_type" in table else [])
    table = table[cols].reset_index(drop=True)
    table["run"] = table["run"].astype(int)
    return table, notes


#: The marks a lab writes after a load's name for its prime (X', Y′).
PRIME_MARKS = ("'", "′", "’")


def check_prime_names(names: list[str], prime: bool, name: str, src: str) -> None:
    """ProtocolError when the load columns ``names`` of the means table ``name`` contradict
    ``[captive] means_prime`` (``prime``): a column named as a prime (X', Y′) read as newtons,
    or a column with a unit (``Y (N)``) read as a prime; a slip of 10^4 either way."""
    primed = [n for n in names if _split_unit(n)[0].strip().endswith(PRIME_MARKS)]
    if primed and not prime:
        raise ProtocolError(
            f"{src}: the means table {name}'s load column(s) {', '.join(primed)} are named "
            "as primes (X' = X/(½ρL²U²)), but [captive] means_prime is not true, so they "
            "would be read as newtons: set means_prime = true.")
    united = [n for n in names if _split_unit(n)[1].strip()]
    if united and prime:
        raise ProtocolError(
            f"{src}: the means table {name}'s load column(s) {', '.join(united)} carry a "
            "unit, but [captive] means_prime = true reads them as primes: remove "
            "means_prime, or give the primes' columns.")


#: Largest |Y'| and |N'| of a table's loads below which loads given in N and N m are primes
#: after all: a captive programme's largest drift or rudder gives primes of 10^-3 to 10^-1;
#: below 10^-5 a 2 m model at 1 m/s would feel less than 0.02 N.
MIN_PLAUSIBLE_PRIME = 1e-5
#: Largest |Y'| and |N'| above which loads given as primes are newtons after all (a
#: slender body's Y' at 90° drift is about 0.5).
MAX_PLAUSIBLE_PRIME = 2.0


def prime_magnitude_warning(table: pd.DataFrame, *, prime: bool, rho: float, length_m: float,
                            name: str) -> str | None:
    """One sentence when the loads' size contradicts ``[captive] means_prime``: every |Y'|
    and |N'| below :data:`MIN_PLAUSIBLE_PRIME` read as newtons (primes read as N), or any
    above :data:`MAX_PLAUSIBLE_PRIME` read as primes (newtons read as primes); else None.
    ``table`` in SI (:func:`means_in_si`), ``rho`` [kg/m³], ``length_m`` L [m]."""
    q = 0.5 * rho * table["speed"].to_numpy(float) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        primes = np.abs(np.concatenate([table["fy"].to_numpy(float) / (q * length_m**2),
                                        table["mz"].to_numpy(float) / (q * length_m**3)]))
    primes = primes[np.isfinite(primes)]
    if primes.size == 0 or not primes.any():
        return None
    top = float(primes.max())
    if not prime and top < MIN_PLAUSIBLE_PRIME:
        return (f"the means table {name}'s loads are at most {top:.2g} as primes (Y/(½ρL²U²), "
                f"N/(½ρL³U²)), below the {MIN_PLAUSIBLE_PRIME:g} of any captive test: are they "
                "primes? Then set [captive] means_prime = true.")
    if prime and top > MAX_PLAUSIBLE_PRIME:
        return (f"the means table {name}'s primes reach {top:.3g}, above the "
                f"{MAX_PLAUSIBLE_PRIME:g} of any captive test: are they in N and N m? Then "
                "remove [captive] means_prime.")
    return None


def _check_values(table: pd.DataFrame, name: str, src: str) -> None:
    """Runs are whole numbers, angles within ±90°, speeds in 0–50 m/s (else units or a typo)."""
    run = table["run"].to_numpy(float)
    bad = ~((run == np.round(run)) & (run >= 0))
    checks = [
        (bad, "run", "is not a whole number from 0"),
        (~(np.abs(table["drift_deg"]) <= MAX_DRIFT_DEG), "drift_deg",
         f"is beyond ±{MAX_DRIFT_DEG:g}° (in radians, or a typo?)"),
        (~(np.abs(table["rudder_deg"]) <= MAX_DRIFT_DEG), "rudder_deg",
         f"is beyond ±{MAX_DRIFT_DEG:g}°"),
        (~((table["speed"] > 0) & (table["speed"] < MAX_MEANS_SPEED)), "speed",
         f"is not a speed in 0–{MAX_MEANS_SPEED:g} m/s (another unit?)"),
    ]
    for mask, canon, what in checks:
        mask = np.asarray(mask, dtype=bool)
        if mask.any():
            i = int(np.flatnonzero(mask)[0])
            raise ProtocolError(f"{src}: row {int(table['row'].iloc[i])} of the means table "
                                f"{name}: {canon} = {table[canon].iloc[i]:g} {what}.")


def _unique_runs(table: pd.DataFrame, name: str, src: str) -> tuple[pd.DataFrame, list[str]]:
    """Each run once: rows of one run that agree in every value are kept at the first; rows
    that differ stop the protocol, naming the run and its rows."""
    values = table[list(_VALUES)].to_numpy(float)
    keep = np.ones(len(table), dtype=bool)
    first: dict[int, int] = {}
    for i, run in enumerate(table["run"].to_numpy(float).astype(int)):
        j = first.setdefault(run, i)
        if j == i:
            continue
        if not np.allclose(values[i], values[j], rtol=1e-9, atol=0.0, equal_nan=True):
            differ = [c for c, a, b in zip(_VALUES, values[i], values[j], strict=True)
                      if not (a == b or (math.isnan(a) and math.isnan(b)))]
            raise ProtocolError(
                f"{src}: run {run} is listed twice in the means table {name} with different "
                f"{', '.join(differ)} (rows {int(table['row'].iloc[j])} and "
                f"{int(table['row'].iloc[i])}); keep the right one.")
        keep[i] = False
    notes = []
    n_repeat = int((~keep).sum())
    if n_repeat:
        notes.append(f"the means table {name} lists {n_repeat} run(s) again in another block "
                     f"with the same values; each is read once ({int(keep.sum())} runs).")
    return table[keep], notes


def means_in_si(table: pd.DataFrame, *, prime: bool, rho: float, length_m: float
                ) -> pd.DataFrame:
    """The table's loads in N and N m: from primes by eq. (1) (``prime``), else as they are.

    Parameters
    ----------
    table : DataFrame
        :func:`read_means_table`'s table.
    prime : bool
        The loads are primes (``[captive] means_prime``).
    rho : float
        Water density [kg/m³].
    length_m : float
        The model's length L [m].
    """
    if not prime:
        return table.copy()
    out = table.copy()
    q = 0.5 * rho * out["speed"].to_numpy(float) ** 2
    for canon, power in (("fx", 2), ("fy", 2), ("mz", 3)):
        out[canon] = out[canon].to_numpy(float) * q * length_m**power
    return out


def captive_means(protocol: Protocol) -> tuple[pd.DataFrame, list[str]]:
    """The protocol's ``[captive] means`` table read (:func:`read_means_table`), its loads in
    N and N m (:func:`means_in_si` at the protocol's water density and model length).

    Raises
    ------
    ProtocolError
        The protocol has no means table, or the table is unusable.
    """
    captive: Captive | None = protocol.captive
    if captive is None or captive.means is None or protocol.model is None:
        raise ProtocolError(f"{protocol.path.name}: the protocol names no [captive] means "
                            "table.")
    table, notes = read_means_table(captive.means, captive.means_columns,
                                    src=protocol.path.name, prime=captive.means_prime)
    w = protocol.water
    rho = float(water_at(w.temperature_C, w.type, w.salinity_g_kg, w.pressure_Pa,
                         w.relative_humidity_pct)[0])
    out = means_in_si(table, prime=captive.means_prime, rho=rho,
                      length_m=protocol.model.length_m)
    said = prime_magnitude_warning(out, prime=captive.means_prime, rho=rho,
                                   length_m=protocol.model.length_m, name=Path(captive.means).name)
    notes += [said] if said else []
    out.attrs["prime"] = captive.means_prime
    return out, notes
