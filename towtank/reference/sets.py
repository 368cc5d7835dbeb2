"""The packaged reference coefficient sets, by name (``[campaign] reference``).

- ``"remus"``: the REMUS column of the SUT-2 report's Table 4 (Sadeghzadeh Parapari, Seif &
  Mahdigholi), prime values as printed (``data/sut2_table4.csv``);
- ``"remus-prestero2001"``: Prestero's (2001) REMUS coefficients in SI, normalised here with his
  rho = 1030 kg/m^3 and L = 1.33 m (``data/remus_prestero2001.csv``). The added masses agree with
  "remus" (0.2 %, 1 %), the damping primes do not (X_u|u|' -0.00178 against -0.00344, Y_v|v|'
  -0.144 against -0.100): the SUT-2 table's REMUS damping is not Prestero's.

Beside the sets, ``data/auv_design_tool_table1.csv`` (:func:`design_tool_table1`): a MATLAB AUV
concept-design tool's Table 1, REMUS 100 coefficients predicted from geometry with the tool's
error against Prestero's (2001) values, which its ``prestero2001`` column repeats (SI units).

A lab's own set is a CSV of ``symbol`` and ``prime`` columns named by ``[campaign] reference``
(:func:`read_reference_csv`).
"""

from __future__ import annotations

import csv
import math
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from towtank.errors import ProtocolError
from towtank.runtime.safefile import check_table_size, text_lines

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["BUILTIN_REFERENCES", "REFERENCE_NAMES", "builtin_reference", "design_tool_table1",
           "read_reference_csv", "reference_name", "reference_table"]

#: Name -> (file in data/, column of the prime values, where it comes from).
BUILTIN_REFERENCES: dict[str, tuple[str, str, str]] = {
    "remus": ("sut2_table4.csv", "remus_prime",
              "REMUS column of the SUT-2 report's Table 4, primes as printed"),
    "remus-prestero2001": ("remus_prestero2001.csv", "prime",
                           "Prestero (2001) REMUS coefficients, primes with rho = 1030 kg/m^3, "
                           "L = 1.33 m"),
}


#: What a reader is shown for each built-in set (the key is what the protocol names).
REFERENCE_NAMES: dict[str, str] = {
    "remus": "REMUS 100 (SUT-2 report, Table 4)",
    "remus-prestero2001": "REMUS 100 (Prestero 2001)",
}


def reference_name(reference: str) -> str:
    """The name a reader sees for ``[campaign] reference``: the built-in set's display name
    ("REMUS 100 (SUT-2 report, Table 4)" for ``remus``), else the user CSV's file name."""
    if reference in REFERENCE_NAMES:
        return REFERENCE_NAMES[reference]

    return f"{Path(str(reference)).name} (user reference CSV)"


def reference_table(name: str) -> pd.DataFrame:
    """The packaged CSV of the built-in set ``name`` (comments dropped)."""
    # loaded on use: pandas only for the tables: towtank.ingest.protocol imports this
    # module
    import pandas as pd

    file, _, _ = BUILTIN_REFERENCES[name]
    with resources.files("towtank.reference").joinpath("data", file).open() as fh:
        return pd.read_csv(fh, comment="#")


def builtin_reference(name: str) -> dict[str, float]:
    """Prime values by symbol of the built-in set ``name`` (KeyError for an unknown name)."""
    _, column, _ = BUILTIN_REFERENCES[name]
    df = reference_table(name)
    return dict(zip(df["symbol"], df[column].astype(float), strict=True))


def design_tool_table1() -> pd.DataFrame:
    """The design tool's Table 1 (``data/auv_design_tool_table1.csv``), indexed by symbol.

    Columns: printed_exp, printed_value (the two numbers as printed, SI), error_pct_printed (the
    tool's error [%]) and prestero2001 (Prestero's 2001 value where the row has one, SI).
    """
    # loaded on use: pandas only for the tables: towtank.ingest.protocol imports this
    # module
    import pandas as pd

    with resources.files("towtank.reference").joinpath(
            "data", "auv_design_tool_table1.csv").open() as fh:
        return pd.read_csv(fh, comment="#").set_index("symbol")


def read_reference_csv(path: str | Path) -> dict[str, float]:
    """Reference prime values of a user CSV with the columns ``symbol`` and ``prime`` [-].

    Lines starting with ``#`` are comments; column names are matched without regard to case
    or surrounding spaces; other columns are ignored.

    Raises
    ------
    ProtocolError
        The file cannot be read, lacks a column, holds no row, repeats a symbol or has a prime
        that is not a finite number (one sentence naming the file and the row).
    """
    path = Path(path)
    check_table_size(path, "reference CSV", str(path))
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise ProtocolError(f"{path}: the reference CSV cannot be read ({exc}).") from None
    lines = [(n, line) for n, line in enumerate(text_lines(text), start=1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise ProtocolError(f"{path}: the reference CSV is empty (it needs the columns symbol "
                            "and prime and one row per coefficient).")
    rows = list(csv.reader([line for _, line in lines]))
    header = [h.strip().lower() for h in rows[0]]
    if "symbol" not in header or "prime" not in header:
        raise ProtocolError(
            f"{path}: a reference CSV needs the columns symbol and prime "
            f"(found {', '.join(repr(h) for h in rows[0])})."
        )
    i_sym, i_prime = header.index("symbol"), header.index("prime")
    out: dict[str, float] = {}
    for (lineno, _), row in zip(lines[1:], rows[1:], strict=True):
        cells = row + [""] * (len(header) - len(row))
        sym, raw = cells[i_sym].strip(), cells[i_prime].strip()
        try:
            value = float(raw)
        except ValueError:
            value = math.nan
        if not sym or not math.isfinite(value):
            raise ProtocolError(
                f"{path}: line {lineno} needs a symbol and a finite prime value "
                f"(found symbol {sym!r}, prime {raw!r})."
            )
        if sym in out:
            raise ProtocolError(f"{path}: line {lineno} repeats the symbol {sym!r}.")
        out[sym] = value
    if not out:
        raise ProtocolError(f"{path}: the reference CSV has a header but no coefficient rows.")
    return out
