"""Numbers as text for the generator's text files, a whole column at a time.

The run files' text is pandas' ``DataFrame.to_csv`` text (and, for other labs' layouts, the
text of Python's ``repr`` or ``%`` formats), written here from each column's ``tolist()``
with one C-level ``map`` per column instead of a conversion per value: the same bytes in
about half the time. Frames with other dtypes or shapes go through pandas itself.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence

import numpy as np
import pandas as pd

#: The numpy dtypes :func:`csv_text` writes itself; other columns go through pandas.
_FAST_DTYPES = (np.dtype(np.float64), np.dtype(np.int64))


def column_texts(values: np.ndarray, fmt: str | None = None, *,
                 blank_infinite: bool = False) -> list[str]:
    """A float64 or int64 column as text: ``str`` (Python's shortest round-trip ``repr``), or
    ``fmt % value`` for floats; NaN (and, with ``blank_infinite``, ±inf) as ``""``."""
    items = values.tolist()
    if values.dtype.kind != "f":
        return list(map(str, items))
    texts = list(map(str if fmt is None else fmt.__mod__, items))
    blank = ~np.isfinite(values) if blank_infinite else np.isnan(values)
    for i in np.flatnonzero(blank).tolist():
        texts[i] = ""
    return texts


def rows_text(columns: Sequence[list[str]], sep: str, row_end: str = "") -> str:
    """Columns of texts as rows: the fields joined by ``sep``, each row ended by
    ``row_end + "\\n"``; no rows, no text."""
    if not columns or not columns[0]:
        return ""
    end = row_end + "\n"
    return end.join(map(sep.join, zip(*columns, strict=True))) + end


def _header_text(names: Sequence[str]) -> str:
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerow(names)
    return out.getvalue()


def csv_text(frame: pd.DataFrame, *, header: bool = True, float_format: str | None = None) -> str:
    """``frame.to_csv(index=False, lineterminator="\\n", header=header,
    float_format=float_format)``, the same text: float64 and int64 columns written by
    :func:`column_texts`; any other frame (other dtypes, fewer than two columns, no rows,
    names other than strings) by pandas."""
    names = list(frame.columns)
    simple = (
        frame.shape[0] > 0
        and len(names) >= 2
        and all(isinstance(c, str) for c in names)
        and all(isinstance(d, np.dtype) and d in _FAST_DTYPES for d in frame.dtypes)
    )
    if not simple:
        return frame.to_csv(index=False, header=header, lineterminator="\n",
                            float_format=float_format)
    body = rows_text([column_texts(s.to_numpy(), float_format) for _, s in frame.items()], ",")
    return (_header_text(names) if header else "") + body
