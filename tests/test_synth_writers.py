"""The generator's text writers (towtank.testing.numbertext) write the very bytes pandas'
``to_csv`` and the per-value formats write: for any frame (property tests) and for whole
generated days in every layout (the per-value writers kept here as the reference)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from conftest import _real_make_hull_day
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from towtank.testing import captive, damage, instruments, layouts
from towtank.testing.captive import CAPTIVE_LAYOUTS, make_captive_day
from towtank.testing.days import RunSpec
from towtank.testing.numbertext import column_texts, csv_text, rows_text

#: Values where the text of a float changes form: signs of zero, the exponent switches of
#: ``repr`` (1e-05, 1e16), extremes, subnormals, non-finite.
CORNERS = [0.0, -0.0, 1.0, -1.5, 1e-4, 1e-05, 9.999999999999999e-05, 1e15, 1e16,
           9999999999999998.0, 1e22, -1e300, 1.7976931348623157e308, 5e-324,
           2.2250738585072014e-308, 0.1, 1 / 3, 123456.789, np.nan, np.inf, -np.inf]

floats = st.one_of(st.sampled_from(CORNERS), st.floats(allow_nan=True, allow_infinity=True),
                   st.floats(-1e3, 1e3).map(lambda x: round(x, 6)))
names = st.text(st.characters(exclude_categories=["Cs"]), max_size=6)


@st.composite
def frames(draw: Any) -> pd.DataFrame:
    """Frames of 0-40 rows and 1-5 columns of float64 (corner values included), int64, bool,
    float32 or strings, named by any text (commas, quotes, line ends, duplicates)."""
    n = draw(st.integers(0, 40))
    k = draw(st.integers(1, 5))
    columns = {}
    for j in range(k):
        kind = draw(st.sampled_from(["f8", "f8", "f8", "i8", "bool", "f4", "str"]))
        if kind == "f8":
            values: Any = np.array(draw(st.lists(floats, min_size=n, max_size=n)), np.float64)
        elif kind == "i8":
            values = draw(hnp.arrays(np.int64, n))
        elif kind == "bool":
            values = draw(hnp.arrays(np.bool_, n))
        elif kind == "f4":
            values = draw(hnp.arrays(np.float32, n))
        else:
            values = draw(st.lists(names, min_size=n, max_size=n))
        columns[j] = values
    frame = pd.DataFrame(columns)
    frame.columns = draw(st.lists(names, min_size=k, max_size=k))
    return frame


@pytest.mark.heavy
@settings(max_examples=300)
@given(frame=frames(), header=st.booleans(),
       float_format=st.sampled_from([None, "%.7g", "%.3f"]))
def test_csv_text_is_pandas_text(frame: pd.DataFrame, header: bool,
                                 float_format: str | None) -> None:
    expected = frame.to_csv(index=False, header=header, lineterminator="\n",
                            float_format=float_format)
    assert csv_text(frame, header=header, float_format=float_format) == expected


def test_csv_text_corner_values_in_bytes() -> None:
    frame = pd.DataFrame({"a,b": CORNERS, 'say "x"': np.arange(len(CORNERS)) - 3,
                          "c": np.array(CORNERS)[::-1]})
    expected = frame.to_csv(index=False, lineterminator="\n").encode("utf-8")
    assert csv_text(frame).encode("utf-8") == expected
    assert instruments.csv_bytes(frame) == expected
    assert damage.frame_bytes(frame) == expected


def _per_value(v: float, fmt: str | None) -> str:
    """One value as the layouts wrote it value by value (LVM: repr, txt-eu: ``:.9g``)."""
    if not np.isfinite(v):
        return ""
    return repr(float(v)) if fmt is None else f"{v:{fmt[1:]}}"


@given(values=st.lists(floats, max_size=30), fmt=st.sampled_from([None, "%.9g", "%.7g"]))
def test_column_texts_are_per_value_texts(values: list[float], fmt: str | None) -> None:
    column = np.array(values, np.float64)
    assert column_texts(column, fmt, blank_infinite=True) == [_per_value(v, fmt) for v in column]


@given(columns=st.lists(st.lists(names, min_size=3, max_size=3), min_size=1, max_size=4),
       sep=st.sampled_from([",", "\t", ";"]), row_end=st.sampled_from(["", "\t"]))
def test_rows_text_is_rows_joined(columns: list[list[str]], sep: str, row_end: str) -> None:
    rows = zip(*columns, strict=True)
    assert rows_text(columns, sep, row_end) == "".join(sep.join(r) + row_end + "\n"
                                                       for r in rows)


# ------------------------------------------------------------ whole days, old writers kept here
def _pandas_csv_text(frame: pd.DataFrame, *, header: bool = True,
                     float_format: str | None = None) -> str:
    return frame.to_csv(index=False, header=header, lineterminator="\n",
                        float_format=float_format)


def _number(x: float) -> str:
    return "" if not np.isfinite(x) else repr(float(x))


def _old_lvm_rows(columns: list[np.ndarray]) -> str:
    block = np.column_stack(columns)
    return "".join("\t".join(_number(v) for v in row) + "\t\n" for row in block)


def _old_eu_rows(columns: list[np.ndarray]) -> str:
    table = np.column_stack(columns)
    return "\n".join(";".join("" if not np.isfinite(v) else f"{v:.9g}".replace(".", ",")
                              for v in row) for row in table) + "\n"


def _old_writers(monkeypatch: pytest.MonkeyPatch) -> None:
    """The generator's writers as they formatted value by value (pandas for CSV)."""
    for module in (instruments, layouts, captive):
        monkeypatch.setattr(module, "csv_text", _pandas_csv_text)
    monkeypatch.setattr(layouts, "_lvm_rows", _old_lvm_rows)
    monkeypatch.setattr(layouts, "_eu_rows", _old_eu_rows)


def _files(folder: Path) -> dict[str, bytes]:
    """A day's files by relative name (the MATLAB v5 files without scipy's clock header)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            data = p.read_bytes()
            out[p.relative_to(folder).as_posix()] = data[116:] if p.suffix == ".mat" else data
    return out


#: A short day: a tare run and a hull run.
RUNS = [RunSpec("sting", 0.0, 0.6, 0.3), RunSpec("hull", 10.0, 1.2, 0.5)]


@pytest.mark.parametrize("file_format", ["csv", "csv.gz", *layouts.LAYOUTS])
def test_days_are_byte_identical_to_the_old_writers(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, file_format: str
) -> None:
    kw: dict[str, Any] = {"file_format": file_format, "runs": RUNS, "sheet_format": "csv"}
    _real_make_hull_day(tmp_path / "new", **kw)
    with monkeypatch.context() as m:
        _old_writers(m)
        _real_make_hull_day(tmp_path / "old", **kw)
    new, old = _files(tmp_path / "new"), _files(tmp_path / "old")
    assert len(new) >= 4
    assert new == old


@pytest.mark.heavy
@pytest.mark.parametrize("layout", list(CAPTIVE_LAYOUTS))
def test_captive_days_are_byte_identical_to_the_old_writers(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, layout: str
) -> None:
    make_captive_day(tmp_path / "new", layout=layout)
    with monkeypatch.context() as m:
        _old_writers(m)
        make_captive_day(tmp_path / "old", layout=layout)
    assert _files(tmp_path / "new") == _files(tmp_path / "old")


def test_number_frames_are_written_without_pandas(monkeypatch: pytest.MonkeyPatch) -> None:
    """float64 and int64 frames take the column-wise writer (the property test above then
    compares it with pandas), other frames pandas' own."""
    numbers = pd.DataFrame({"t": [0.0, 0.005], "n": [1, 2], "x": [np.nan, -0.0]})
    strings = pd.DataFrame({"run": ["1", "2"], "x": [1.0, 2.0]})
    expected = _pandas_csv_text(numbers)

    def no_pandas(*args: Any, **kwargs: Any) -> str:
        raise AssertionError("written by pandas")

    monkeypatch.setattr(pd.DataFrame, "to_csv", no_pandas)
    assert csv_text(numbers) == expected == "t,n,x\n0.0,1,\n0.005,2,-0.0\n"
    with pytest.raises(AssertionError, match="written by pandas"):
        csv_text(strings)
