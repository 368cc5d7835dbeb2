"""Hand-typed run sheets (docs/formats.md §2.1): a title above the header, notes below it, the
lab's column names with units, its status and test words, ``;`` and decimal commas; read as
typed, they give the plain sheet's runs and the plain day's coefficients."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import towtank
from towtank.errors import ProtocolError
from towtank.ingest.runsheet import read_run_sheet
from towtank.ingest.sheetlayout import SheetOptions, parse_sheet_options
from towtank.testing import synthetic as syn
from towtank.testing.handsheet import HAND_NOTES, write_hand_typed_sheet

SEED = 5
T_DEFAULT = 18.0  # [°C]
COLUMNS = ("run", "file", "config", "test", "angle_deg", "speed_nominal", "accel_nominal",
           "tare_group", "water_temp_C", "status", "remarks")


def _day(root: Path, style: str | None) -> Path:
    plain = "xlsx" if style == "hand-xlsx" else "csv"
    syn.make_hull_day(root, seed=SEED, file_format="csv", sheet_format=plain, date="2024-05-21")
    if style:
        write_hand_typed_sheet(root / f"run_sheet.{plain}", style, root / f"run_sheet.{plain}")
    sections = syn.hull_protocol_sections(".", "out", sheet_format=plain)
    return syn.write_protocol(root / "protocol.toml", **sections)


@pytest.fixture(scope="session")
def plain(tmp_path_factory):
    root = tmp_path_factory.mktemp("plain")
    return towtank.process_day(_day(root, None), jobs=1)


@pytest.mark.heavy
@pytest.mark.parametrize("style", ["hand-xlsx", "hand-csv"])
def test_a_hand_typed_sheet_gives_the_plain_days_coefficients(style, plain, tmp_path):
    day = towtank.process_day(_day(tmp_path, style), jobs=1)
    got = day.coefficients.set_index("symbol")["value"]
    ref = plain.coefficients.set_index("symbol")["value"]
    assert np.allclose(got, ref, rtol=1e-3, atol=0), ((got - ref) / ref).to_dict()
    assert len(day.rejected) == len(plain.rejected) == 0
    # the same runs, the void one still void, the notes below the table not runs
    cols = ["run", "file", "config", "test", "angle_deg", "speed_nominal", "status"]
    assert day.sheet[cols].equals(plain.sheet[cols])
    assert any("read as notes, not runs" in w and "wavemaker" in w for w in map(str, day.warnings))
    assert set(day.sheet["status"]) == {"ok", "void"}


def test_hand_typed_csv_is_read_as_typed(tmp_path):
    """';', decimal commas, Latin-1, title rows, speed in mm/s: every value as in the plain
    sheet, the row numbers those of the file."""
    syn.make_hull_day(tmp_path, seed=SEED, file_format="csv", sheet_format="csv")
    plain = read_run_sheet(tmp_path / "run_sheet.csv", T_DEFAULT)
    hand = write_hand_typed_sheet(tmp_path / "run_sheet.csv", "hand-csv", tmp_path / "hand.csv")
    assert hand.read_bytes().count(b";") > 10 and b"0,15" in hand.read_bytes()
    got = read_run_sheet(hand, T_DEFAULT)
    for col in ("run", "config", "test", "status", "tare_group"):
        assert list(got[col]) == list(plain[col]), col
    for col in ("angle_deg", "speed_nominal", "accel_nominal", "water_temp_C"):
        assert np.allclose(got[col], plain[col], rtol=1e-12), col
    # the header is on line 4 (title, operator line, blank line above it)
    assert list(got["sheet_row"]) == list(range(5, 5 + len(plain)))
    assert got.attrs["notes"] == list(HAND_NOTES)


def _lab_sheet(path: Path, header: list[str], rows: list[list], top=(), bottom=()) -> Path:
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        for r in [*top, header, *rows, *bottom]:
            w.writerow(r)
    return path


ROW = ["1", "run_001.csv", "hull", "steady", "0", "1.2"]


def test_lab_names_and_units_are_mapped(tmp_path):
    path = _lab_sheet(tmp_path / "s.csv", ["Run #", "File", "Config", "Type", "Angle (deg)",
                                           "Speed (mm/s)", "Water temp (°F)", "Date"],
                      [[*ROW[:5], "1200", "64.4", "2024-05-21"]])
    sheet = read_run_sheet(path, T_DEFAULT)
    assert sheet.loc[0, "speed_nominal"] == pytest.approx(1.2)  # the cross-check is on
    assert sheet.loc[0, "water_temp_C"] == pytest.approx(18.0)
    assert sheet.loc[0, "date"] == "2024-05-21"  # a 'Date' column is the test date
    assert "Speed (mm/s)" not in sheet.columns


def test_a_unit_towtank_cannot_convert_is_named(tmp_path):
    path = _lab_sheet(tmp_path / "s.csv", ["Run #", "File", "Config", "Angle (deg)",
                                           "Speed (furlong/fortnight)"], [[*ROW[:3], "0", "1"]])
    with pytest.raises(ProtocolError, match="'Speed \\(furlong/fortnight\\)' is in "
                                            "'furlong/fortnight'"):
        read_run_sheet(path, T_DEFAULT)


def test_sheet_section_maps_the_labs_own_names(tmp_path):
    """The docs/formats.md §2.1 example."""
    path = _lab_sheet(tmp_path / "s.csv", ["Lauf", "Datei", "Konfig", "Winkel (°)",
                                           "v_soll (cm/s)"],
                      [[*ROW[:3], "10", "80"]], top=[["Schlepptank Versuch 12"]])
    options = parse_sheet_options({"columns": {"run": "Lauf", "file": "Datei",
                                               "config": "Konfig", "angle_deg": "Winkel (°)",
                                               "speed_nominal": "v_soll (cm/s)"}}, "p.toml")
    sheet = read_run_sheet(path, T_DEFAULT, options)
    assert sheet.loc[0, "angle_deg"] == 10.0 and sheet.loc[0, "speed_nominal"] == 0.8
    assert sheet.loc[0, "sheet_row"] == 3
    # an explicit header row: the same
    explicit = read_run_sheet(path, T_DEFAULT, SheetOptions(header_row=2,
                                                            columns=options.columns))
    assert explicit.loc[0, "angle_deg"] == 10.0
    with pytest.raises(ProtocolError, match="did you mean 'speed_nominal'"):
        parse_sheet_options({"columns": {"speed_nominl": "v"}}, "p.toml")
    with pytest.raises(ProtocolError, match="unknown key 'header'"):
        parse_sheet_options({"header": 2}, "p.toml")


@pytest.mark.parametrize("word,status", [("x", "void"), ("OK", "ok"), ("Bad", "void"),
                                         ("✓", "ok"), ("excluded", "void"), ("", "ok")])
def test_status_words(tmp_path, word, status):
    path = _lab_sheet(tmp_path / "s.csv", ["run", "file", "config", "angle_deg", "status"],
                      [[*ROW[:3], "0", word]])
    assert read_run_sheet(path, T_DEFAULT).loc[0, "status"] == status


def test_a_note_below_the_table_is_not_a_run_but_a_bad_row_still_is(tmp_path):
    path = _lab_sheet(tmp_path / "s.csv", ["run", "file", "config", "angle_deg"],
                      [ROW[:4], ["2", "run_002.csv", "hull", "ten"]],
                      bottom=[[], ["run 2: check the angle"]])
    sheet = read_run_sheet(path, T_DEFAULT)
    assert list(sheet["run"]) == [1, 2]
    assert "angle_deg 'ten'" in sheet.loc[1, "sheet_error"]
    assert sheet.loc[1, "sheet_row"] == 3
    assert sheet.attrs["notes"] == ["run 2: check the angle"]


_ALIASES = {
    "run": ["run", "Run #", "Run no", "Run number", "RUN"],
    "file": ["file", "File name", "Data file", "Filename"],
    "config": ["config", "Configuration", "Setup"],
    "angle_deg": ["angle_deg", "Angle (deg)", "Angle [°]", "AoA", "Drift angle (deg)"],
    "speed_nominal": ["speed_nominal", "Speed (m/s)", "Carriage speed [m/s]", "Speed (cm/s)"],
}
_TITLE = st.lists(st.text(st.characters(codec="utf-8", categories=("L", "Zs")), min_size=1,
                          max_size=30).filter(lambda t: t.strip()), min_size=0, max_size=2)


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(titles=st.lists(_TITLE, max_size=5),
       names=st.fixed_dictionaries({k: st.sampled_from(v) for k, v in _ALIASES.items()}),
       order=st.permutations(list(_ALIASES)),
       sep=st.sampled_from([",", ";", "\t"]),
       speed=st.floats(0.05, 5.0).map(lambda v: round(v, 3)))
def test_header_is_found_under_any_title_rows(tmp_path, titles, names, order, sep, speed):
    """Title rows of text above the header (one or two cells each, or blank) never hide it; any
    of the lab's names of each column in any order is read; the speed in its unit."""
    factor = 100.0 if "cm/s" in names["speed_nominal"] else 1.0
    cells = {"run": "7", "file": "run_007.csv", "config": "hull", "angle_deg": "4",
             "speed_nominal": repr(speed * factor)}
    if sep != ",":
        cells["speed_nominal"] = cells["speed_nominal"].replace(".", ",")
    path = tmp_path / "hyp.csv"
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, delimiter=sep)
        for t in titles:
            w.writerow(t)
        w.writerow([names[k] for k in order])
        w.writerow([cells[k] for k in order])
    sheet = read_run_sheet(path, T_DEFAULT)
    assert list(sheet["run"]) == [7]
    assert sheet.loc[0, "file"] == "run_007.csv"
    assert sheet.loc[0, "angle_deg"] == 4.0
    assert math.isclose(sheet.loc[0, "speed_nominal"], speed, rel_tol=1e-9)
    assert sheet.loc[0, "sheet_row"] == len(titles) + 2
