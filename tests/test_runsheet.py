"""The run sheet reader (FORMATS.md §2): .csv and .xlsx alike, sheet-level faults stop the day
with a ProtocolError naming rows and columns, a fault in one row only rejects that row."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path

import pandas as pd
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from towtank.errors import ProtocolError
from towtank.ingest.runsheet import read_run_sheet
from towtank.testing import synthetic as syn

DEFAULT_T = 17.5  # [°C] the protocol's water temperature

ROWS = [
    {"run": 1, "file": "run_001.csv", "config": "sting", "test": "steady", "angle_deg": 0,
     "speed_nominal": 0.8, "accel_nominal": 0.5, "tare_group": "A", "water_temp_C": 18.1,
     "status": "ok", "remarks": ""},
    {"run": 2, "file": "run_002.csv", "config": "hull", "test": "steady", "angle_deg": 0,
     "speed_nominal": 1.2, "accel_nominal": 0.5, "tare_group": "A", "water_temp_C": "",
     "status": "", "remarks": "first hull run"},
    {"run": 3, "file": "run_003.csv", "config": "hull", "test": "accel", "angle_deg": 10.5,
     "speed_nominal": 2.0, "accel_nominal": 1.0, "tare_group": "B", "water_temp_C": 18.3,
     "status": "void", "remarks": "carriage stopped early"},
    {"run": 4, "file": "sub/run_004.csv", "config": "hull", "test": "", "angle_deg": 90,
     "speed_nominal": "", "accel_nominal": "", "tare_group": "", "water_temp_C": "",
     "status": "ok", "remarks": "transverse, comma, \"quoted\""},
]


def _write(path: Path, rows: list[dict], columns=None) -> Path:
    columns = columns or list(rows[0])
    return syn.write_run_sheet(rows, path, columns=columns)


def _read(path: Path) -> pd.DataFrame:
    return read_run_sheet(path, DEFAULT_T)


def test_csv_and_xlsx_give_the_same_frame(tmp_path):
    rows = [dict(r, operator="MS" if r["run"] % 2 else "AK") for r in ROWS]
    a = _read(_write(tmp_path / "s.csv", rows))
    b = _read(_write(tmp_path / "s.xlsx", rows))
    pd.testing.assert_frame_equal(a, b)
    assert list(a["run"]) == [1, 2, 3, 4]
    assert a["run"].dtype.kind == "i"
    assert list(a["operator"]) == ["MS", "AK", "MS", "AK"]  # extra columns are kept


def test_generated_day_sheets_agree(tmp_path):
    plan = syn.hull_day_plan()[:14]
    syn.make_hull_day(tmp_path / "x", seed=1, fs=50.0, runs=plan, sheet_format="xlsx",
                      noise=syn.Noise.quiet())
    truth = syn.load_truth(tmp_path / "x")
    rows = [{c: truth["runs"][str(i + 1)][c] for c in syn.SHEET_COLUMNS}
            for i in range(len(plan))]
    a = _read(_write(tmp_path / "s.csv", rows, syn.SHEET_COLUMNS))
    b = _read(tmp_path / "x" / "run_sheet.xlsx")
    pd.testing.assert_frame_equal(a, b)


def test_typed_columns_and_defaults(tmp_path):
    df = _read(_write(tmp_path / "s.csv", ROWS)).set_index("run")
    assert df.loc[3, "angle_deg"] == 10.5
    assert df.loc[1, "water_temp_C"] == 18.1
    assert df.loc[2, "water_temp_C"] == DEFAULT_T  # default from the protocol
    assert df.loc[4, "water_temp_C"] == DEFAULT_T
    assert df.loc[2, "status"] == "ok"  # blank status is ok
    assert df.loc[4, "tare_group"] == "default"
    assert math.isnan(df.loc[4, "speed_nominal"]) and math.isnan(df.loc[4, "accel_nominal"])
    assert df.loc[4, "file"] == "sub/run_004.csv"
    assert df.loc[4, "remarks"] == 'transverse, comma, "quoted"'
    assert list(df["sheet_row"]) == [2, 3, 4, 5]
    assert (df["sheet_error"] == "").all()


def test_void_runs(tmp_path):
    df = _read(_write(tmp_path / "s.csv", ROWS)).set_index("run")
    assert df.loc[3, "status"] == "void"
    assert df.loc[3, "sheet_error"] == ""
    assert df.loc[3, "remarks"] == "carriage stopped early"
    rows = [dict(r) for r in ROWS]
    rows[1]["status"] = "VOID "
    df = _read(_write(tmp_path / "t.csv", rows)).set_index("run")
    assert df.loc[2, "status"] == "void"


def test_duplicated_run_numbers_name_both_rows(tmp_path):
    rows = [dict(r) for r in ROWS]
    rows[3]["run"] = 2
    for suffix in ("csv", "xlsx"):
        with pytest.raises(ProtocolError) as info:
            _read(_write(tmp_path / f"s.{suffix}", rows))
        msg = str(info.value)
        assert "duplicated" in msg and "run 2" in msg
        assert "rows 3, 5" in msg  # header is row 1
        assert f"s.{suffix}" in msg


@pytest.mark.parametrize("missing", ["run", "file", "config", "angle_deg"])
def test_missing_required_column(tmp_path, missing):
    columns = [c for c in ROWS[0] if c != missing]
    with pytest.raises(ProtocolError) as info:
        _read(_write(tmp_path / "s.csv", ROWS, columns))
    msg = str(info.value)
    assert f"required column(s) {missing}" in msg
    assert "columns found: " + ", ".join(columns) in msg


def test_misspelt_required_column_lists_what_is_there(tmp_path):
    rows = [{("heading" if k == "angle_deg" else k): v for k, v in r.items()} for r in ROWS]
    with pytest.raises(ProtocolError, match=r"angle_deg .*columns found: .*heading"):
        _read(_write(tmp_path / "s.xlsx", rows))


def test_typo_in_one_row_only_rejects_that_row(tmp_path):
    rows = [dict(r) for r in ROWS]
    rows[1]["config"] = "hul"
    df = _read(_write(tmp_path / "s.csv", rows)).set_index("run")
    err = df.loc[2, "sheet_error"]
    assert "row 3" in err and "'hul'" in err and "s.csv" in err
    assert "hull" in err  # the valid values are named
    for run in (1, 3, 4):
        assert df.loc[run, "sheet_error"] == ""


@pytest.mark.parametrize(
    "column, value, words",
    [("angle_deg", "ten", "angle_deg 'ten' is not a number"),
     ("angle_deg", "", "angle_deg '' is not a number"),
     ("speed_nominal", "1,2", "speed_nominal '1,2' is not a number"),
     ("test", "stedy", "test 'stedy'"),
     ("status", "maybe", "status 'maybe'"),
     ("file", "", "no data file")],
)
def test_row_faults(tmp_path, column, value, words):
    rows = [dict(r) for r in ROWS]
    rows[0][column] = value
    df = _read(_write(tmp_path / "s.csv", rows)).set_index("run")
    assert words in df.loc[1, "sheet_error"]
    assert (df.drop(index=1)["sheet_error"] == "").all()


def test_run_number_not_whole_stops_the_sheet(tmp_path):
    rows = [dict(r) for r in ROWS]
    rows[1]["run"] = "2b"
    with pytest.raises(ProtocolError, match="row 3 has run number '2b'"):
        _read(_write(tmp_path / "s.csv", rows))


def test_a_void_row_or_a_total_row_without_a_run_number_is_left_aside(tmp_path):
    """docs/formats.md §2: a void row is never an error, even with a typo in a cell. Run 3
    (void) with its number typed '3b', and a total line at the bottom ('Total' and a sum of
    the speeds, no file): both are left aside with a note, and the other runs read; they
    stopped the whole day (exit 2). A run row with a file and no whole run number still
    stops it (test above)."""
    rows = [dict(r) for r in ROWS]
    rows[2]["run"] = "3b"
    total = {k: "" for k in ROWS[0]} | {"run": "Total", "speed_nominal": 4.0}
    sheet = _read(_write(tmp_path / "s.csv", [*rows, total]))
    assert sheet["run"].tolist() == [1, 2, 4]
    notes = sheet.attrs["notes"]
    assert "row 4 is left aside: its run number '3b' is not a whole number and it is void" \
        in notes
    assert any(n.startswith("row 6 is left aside: its run number 'Total'") for n in notes)
    only = [dict(ROWS[2], run="x")]
    with pytest.raises(ProtocolError, match="has no runs"):
        _read(_write(tmp_path / "v.csv", only))


@pytest.mark.parametrize(("angles", "warned"), [
    ([0, 0.0873, 0.1745, 0.2618, 1.5708], True),  # 0, 5, 10, 15, 90° typed in radians
    ([0, 0.087, 0.175, 0.262, 1.571], True),  # the same rounded to 3 decimals
    ([0, 5, 10, 15, 90], False),
    ([0, 0.5, 1.0, 1.5, 1.0], False),  # small angles in degrees: whole or half degrees
    ([0, 0.1, 0.2, 0.3, 0.4], False),  # 5.73°, 11.46°... are no whole degrees
    ([0, 0.0873, 0.0873, 0, 0], False),  # one angle: not enough to tell
])
def test_angles_typed_in_radians_are_named(tmp_path, angles, warned):
    """A sheet whose angle_deg column holds radians (a hull day's 0–90° as 0–1.5708): read
    as degrees, X_uv and X_v|v| came out 4 orders off without a word. One sentence when
    every angle is within ±π/2 and a whole or half degree as radians; none for degrees, nor
    with the unit in the header (converted)."""
    rows = [dict(r, angle_deg=a) for r, a in zip(ROWS * 2, angles, strict=False)]
    for i, r in enumerate(rows):
        r["run"], r["file"] = i + 1, f"run_{i + 1:03d}.csv"
    sheet = _read(_write(tmp_path / "s.csv", rows))
    said = [w for w in sheet.attrs["warnings"] if "typed in radians" in w]
    assert len(said) == int(warned), sheet.attrs["warnings"]
    if warned:
        assert "angle_deg" in said[0] and "= 90.0" in said[0]
        renamed = [{("Angle [rad]" if k == "angle_deg" else k): v for k, v in r.items()}
                   for r in rows]
        named = _read(_write(tmp_path / "r.csv", renamed))
        assert not [w for w in named.attrs["warnings"] if "radians" in w]
        assert named["angle_deg"].max() == pytest.approx(90.0, abs=0.05)


def test_manual_window_columns(tmp_path):
    rows = [dict(r, window_start_s="", window_end_s="") for r in ROWS]
    rows[1].update(window_start_s="6.5", window_end_s=" 10.25")
    rows[2].update(window_start_s="7", window_end_s="")
    rows[3].update(window_start_s="9", window_end_s="8")
    for suffix in ("csv", "xlsx"):
        df = _read(_write(tmp_path / f"s.{suffix}", rows)).set_index("run")
        assert df.loc[2, "window_start_s"] == 6.5 and df.loc[2, "window_end_s"] == 10.25
        assert df.loc[2, "sheet_error"] == ""
        assert math.isnan(df.loc[1, "window_start_s"]) and df.loc[1, "sheet_error"] == ""
        assert "together" in df.loc[3, "sheet_error"]
        assert "must be after" in df.loc[4, "sheet_error"]


def test_blank_trailing_rows_ignored(tmp_path):
    path = _write(tmp_path / "s.csv", ROWS)
    path.write_text(path.read_text() + ",,,,,,,,,,\n,,,,,,,,,,\n")
    assert len(_read(path)) == 4


def test_empty_or_unreadable_sheet(tmp_path):
    empty = tmp_path / "empty.csv"
    empty.write_text("run,file,config,angle_deg\n")
    with pytest.raises(ProtocolError, match="no runs"):
        _read(empty)
    broken = tmp_path / "broken.xlsx"
    broken.write_bytes(b"PK\x03\x04 not really a workbook")
    with pytest.raises(ProtocolError, match="cannot be read"):
        _read(broken)


# ------------------------------------------------------------------------------- fuzzing
OPTIONAL = ("test", "speed_nominal", "accel_nominal", "tare_group", "water_temp_C", "status",
            "remarks", "window_start_s", "window_end_s", "depth_mm")
_cell = st.one_of(
    st.text(max_size=10),
    st.sampled_from(["", " ", "nan", "NaN", "inf", "-inf", "1e999", "0", "-1", "1.5",
                     "void", "OK", "steady", "accel", "1,5", "NA", "null", "None", "#N/A",
                     "TRUE", "1_000", "٣", "\t", "\x00"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-(10**20), 10**20).map(str),
)


@pytest.mark.heavy
@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cells=st.lists(st.fixed_dictionaries({c: _cell for c in OPTIONAL}), min_size=1,
                      max_size=4))
@example(cells=[dict.fromkeys(OPTIONAL, ""), dict(dict.fromkeys(OPTIONAL, ""),
                                                   depth_mm="\x0c0")])  # found by hypothesis
def test_fuzz_optional_cells(tmp_path, cells):
    """Random content in the optional columns: the reader returns a frame (faults confined to
    their rows' sheet_error) or raises ProtocolError, never anything else."""
    rows = [{"run": i + 1, "file": f"run_{i + 1:03d}.csv", "config": "hull", "angle_deg": 5,
             **c} for i, c in enumerate(cells)]
    path = tmp_path / "fuzz.csv"
    # saved as Excel saves a CSV (CRLF): a cell holding a line break is quoted. With bare
    # "\n" ends a cell's lone "\r" is a line break of the file itself, which the reader
    # rightly reads as one more row (with its own sheet_error)
    pd.DataFrame(rows).to_csv(path, index=False, lineterminator="\r\n")
    try:
        df = _read(path)
    except ProtocolError as exc:
        assert str(exc).strip()
        return
    assert list(df["run"]) == [r["run"] for r in rows]
    for _, row in df.iterrows():
        assert row["status"] in ("ok", "void") or row["sheet_error"]
        assert isinstance(row["sheet_error"], str)
        assert isinstance(row["water_temp_C"], float)


@pytest.mark.heavy
@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cells=st.lists(
    st.fixed_dictionaries({c: st.one_of(
        st.none(), st.booleans(), st.integers(-(10**6), 10**6),
        st.floats(allow_nan=False, allow_infinity=False),
        st.text(alphabet=st.characters(min_codepoint=0x20, max_codepoint=0x2FF), max_size=8),
        st.datetimes(min_value=dt.datetime(1990, 1, 1),
                     max_value=dt.datetime(2100, 1, 1)),
    ) for c in OPTIONAL}), min_size=1, max_size=3))
def test_fuzz_optional_cells_xlsx(tmp_path, cells):
    """The same with typed Excel cells (numbers, booleans, dates, text)."""
    import openpyxl

    wb = openpyxl.Workbook()
    ws = wb.active
    header = ["run", "file", "config", "angle_deg", *OPTIONAL]
    ws.append(header)
    for i, c in enumerate(cells):
        ws.append([i + 1, f"run_{i + 1:03d}.csv", "hull", 5.0, *(c[k] for k in OPTIONAL)])
    path = tmp_path / "fuzz.xlsx"
    wb.save(path)
    try:
        df = _read(path)
    except ProtocolError:
        return
    assert len(df) == len(cells)


def test_a_bare_carriage_return_in_a_csv_is_a_line_break_with_its_own_row_error(tmp_path):
    """A cell ending in a lone CR, written unquoted, splits the line: the reader keeps the
    runs before it and gives the stray line a sheet_error naming its row, never a crash."""
    path = tmp_path / "cr.csv"
    path.write_bytes(b"run,file,config,angle_deg,depth_mm\n1,run_001.csv,hull,5,\n"
                     b"2,run_002.csv,hull,5,\r0\n")
    df = _read(path)
    assert list(df["run"])[:2] == [1, 2] and list(df["sheet_error"])[:2] == ["", ""]
    assert len(df) == 3 and "row 4 of cr.csv" in df["sheet_error"].iloc[2]


@pytest.mark.parametrize("char", ["\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85",
                                  "\u2028", "\u2029"])
def test_a_cell_with_a_character_python_calls_a_line_break_stays_in_its_row(tmp_path, char):
    """A form feed, vertical tab, file/group/record separator, NEL or Unicode line separator
    pasted into a cell is not where a CSV line ends: the sheet keeps its rows (no phantom run 0)
    and the cell its text."""
    rows = [dict(r) for r in ROWS[:2]]
    rows[1]["remarks"] = f"gauge{char}0"
    df = _read(_write(tmp_path / "s.csv", rows))
    assert list(df["run"]) == [1, 2]
    assert df["remarks"].iloc[1] == f"gauge{char}0"
