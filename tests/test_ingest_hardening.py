"""Issue 20 (adversarial review), the ingest part: files built to mislead or to exhaust the
readers are either read as the lab meant them or refused in one sentence, through the real
pipeline (exit status, the sentence, the other runs still processed).

- item 8: which worksheet of a run-sheet workbook is read (never a hidden one unless named),
  and a formula whose saved value is the empty string;
- item 9: a text run file cut in the middle of a line (CSV, LVM, European text, whitespace
  text) is refused with the same sentence, never read with a value "interpolated";
- item 6: the declared size of .mat and HDF5 arrays is checked before anything is read (a
  compression bomb, an unwritten 2³¹-element dataset), under an address-space limit so that a
  regression fails instead of eating the machine; huge reference CSVs and tare tables;
- item 11: HDF5 sample-rate attributes that are text, zero, empty, and soft-link loops.
"""

from __future__ import annotations

import re
import zipfile
from pathlib import Path

import pandas as pd
import pytest

from towtank.commands.cli import main
from towtank.ingest.runsheet import read_run_sheet
from towtank.testing import synthetic as syn
from towtank.testing.layouts import layout_channels, protocol_sections

SEED = 20
REPO = Path(__file__).resolve().parents[1]


def _day(root: Path, file_format: str = "csv", sheet_format: str = "csv",
         **sections: dict) -> Path:
    """A synthetic hull day in ``root`` (run files in ``file_format``); its protocol."""
    syn.make_hull_day(root, seed=SEED, file_format=file_format, sheet_format=sheet_format)
    channels = layout_channels(file_format, syn.LabChannels())
    sec = syn.hull_protocol_sections(".", "out", sheet_format=sheet_format, channels=channels)
    sec = protocol_sections(file_format, sec)
    for name, values in sections.items():
        sec.setdefault(name, {}).update(values)
    return syn.write_protocol(root / "protocol.toml", **sec)


def _process(protocol: Path) -> int:
    return main(["process", str(protocol), "--out", str(protocol.parent / "out"),
                 "--no-report", "-q"])


def _runs(protocol: Path) -> pd.DataFrame:
    return pd.read_csv(protocol.parent / "out" / "runs.csv").set_index("run")


def _only_rejected(protocol: Path, run: int) -> str:
    """The reason of ``run``, after checking that it is the day's only rejected run."""
    runs = _runs(protocol)
    rejected = runs.index[runs["status"] == "rejected"].tolist()
    assert rejected == [run], runs.loc[rejected, "reason"].to_dict()
    assert (runs["status"] == "ok").sum() > 30  # the rest of the day is processed
    return str(runs.loc[run, "reason"])


def _one_sentence(text: str) -> None:
    assert "\n" not in text.strip() and "Traceback" not in text
    assert "internal error" not in text and "please report" not in text


# =============================================================== item 8: which worksheet
def _xlsx_day(root: Path) -> tuple[Path, Path]:
    protocol = _day(root, sheet_format="xlsx")
    return protocol, root / "run_sheet.xlsx"


def _copy_sheet(wb, title: str, index: int, angle_21: float):  # noqa: ANN001, ANN202
    """A copy of the run table as worksheet ``title`` at ``index``, run 21's angle changed."""
    src = wb.worksheets[0]
    rows = [list(r) for r in src.iter_rows(values_only=True)]
    ws = wb.create_sheet(title, index)
    col = rows[0].index("angle_deg")
    for r in rows:
        if r[0] == 21:
            r[col] = angle_21
        ws.append(r)
    return ws


def test_a_hidden_first_worksheet_is_not_the_run_sheet(tmp_path, capsys):
    """An old copy of the table hidden in the first tab (run 21 at 0°): the visible sheet
    (run 21 at 5°) is read; named in [sheet] name, the hidden one is."""
    import openpyxl

    protocol, path = _xlsx_day(tmp_path)
    wb = openpyxl.load_workbook(path)
    hidden = _copy_sheet(wb, "old runs", 0, 0.0)
    hidden.sheet_state = "hidden"
    wb.active = 1
    wb.save(path)
    assert read_run_sheet(path, 18.0).set_index("run").loc[21, "angle_deg"] == 5.0
    assert _process(protocol) == 0
    assert _runs(protocol).loc[21, "angle_deg"] == 5.0

    named = read_run_sheet(path, 18.0, _sheet_options(name="old runs"))
    assert named.set_index("run").loc[21, "angle_deg"] == 0.0
    for state in ("hidden", "veryHidden"):
        wb = openpyxl.load_workbook(path)
        wb.worksheets[0].sheet_state = state
        wb.active = 1
        wb.save(path)
        assert read_run_sheet(path, 18.0).set_index("run").loc[21, "angle_deg"] == 5.0


def _sheet_options(**kw):  # noqa: ANN003, ANN202
    from towtank.ingest.sheetlayout import parse_sheet_options

    return parse_sheet_options(kw, "p.toml")


def test_the_sheet_name_key_picks_a_worksheet_through_the_pipeline(tmp_path, capsys):
    import openpyxl

    protocol, path = _xlsx_day(tmp_path)
    wb = openpyxl.load_workbook(path)
    _copy_sheet(wb, "old runs", 0, 0.0).sheet_state = "hidden"
    wb.active = 1
    wb.save(path)
    text = protocol.read_text(encoding="utf-8")
    protocol.write_text(text + '\n[sheet]\nname = "old runs"\n', encoding="utf-8")
    assert _process(protocol) == 0
    assert _runs(protocol).loc[21, "angle_deg"] == 0.0

    protocol.write_text(text + '\n[sheet]\nname = "Runs 2024"\n', encoding="utf-8")
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    assert "[sheet] name = 'Runs 2024', but the workbook has no worksheet of that name" in err
    assert "'old runs' (hidden)" in err
    _one_sentence(err)


def test_only_a_hidden_worksheet_with_the_columns_stops_the_day(tmp_path, capsys):
    import openpyxl

    protocol, path = _xlsx_day(tmp_path)
    wb = openpyxl.load_workbook(path)
    notes = wb.create_sheet("notes", 0)
    notes["A1"] = "operator notes"
    wb.worksheets[1].sheet_state = "hidden"
    wb.active = 0
    wb.save(path)
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    assert "no visible worksheet has the required columns" in err
    assert "the hidden worksheet 'Sheet' has them" in err or "hidden worksheet" in err
    assert "[sheet] name" in err
    _one_sentence(err)
    assert not (tmp_path / "out").exists()


def test_two_visible_worksheets_with_the_columns_give_one_warning(tmp_path, capsys):
    """The active worksheet is read (here the second tab), and the day says so."""
    import openpyxl

    protocol, path = _xlsx_day(tmp_path)
    wb = openpyxl.load_workbook(path)
    first = wb.worksheets[0].title
    _copy_sheet(wb, "copy", 1, 7.5)
    wb.active = 1
    wb.save(path)
    assert main(["process", str(protocol), "--out", str(tmp_path / "out"), "--no-report"]) == 0
    captured = capsys.readouterr()
    assert _runs(protocol).loc[21, "angle_deg"] == 7.5
    line = next(ln for ln in (captured.out + captured.err).splitlines()
                if "visible worksheets" in ln)
    assert f"('{first}', 'copy'); 'copy' is used (the active one)" in line
    assert "[sheet] name" in line

    wb = openpyxl.load_workbook(path)
    wb.active = 2  # past both: a third tab, without the columns
    wb.create_sheet("chart data")
    wb.active = 2
    wb.save(path)
    sheet = read_run_sheet(path, 18.0)
    assert sheet.set_index("run").loc[21, "angle_deg"] == 5.0  # the first of the two
    assert f"'{first}' is used (the first)" in sheet.attrs["warnings"][0]


def test_a_sheet_name_with_a_csv_sheet_stops_the_day(tmp_path, capsys):
    protocol = _day(tmp_path)
    protocol.write_text(protocol.read_text(encoding="utf-8") + '\n[sheet]\nname = "runs"\n',
                        encoding="utf-8")
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    assert "names a worksheet, but the run sheet is a CSV file" in err


def _set_cell_xml(path: Path, coordinate: str, cell_xml: bytes) -> None:
    """Replace cell ``coordinate`` of the first worksheet by ``cell_xml`` (as Excel or a
    program writes it)."""
    with zipfile.ZipFile(path) as zin:
        parts = [(i, zin.read(i)) for i in zin.infolist()]
    pattern = re.compile(rb'<c r="' + coordinate.encode() + rb'"[^>]*?(/>|>.*?</c>)', re.S)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zout:
        for info, data in parts:
            if info.filename == "xl/worksheets/sheet1.xml":
                data, n = pattern.subn(cell_xml, data, count=1)
                assert n == 1, coordinate
            zout.writestr(info, data)


def _remarks_cell(path: Path, run: int) -> str:
    """The coordinate of run ``run``'s remarks cell, given a text for the XML to hold."""
    import openpyxl

    wb = openpyxl.load_workbook(path)
    ws = wb.worksheets[0]
    header = [c.value for c in ws[1]]
    col = header.index("remarks") + 1
    row = next(r for r in range(2, ws.max_row + 1) if ws.cell(r, 1).value == run)
    ws.cell(row, col).value = "placeholder"
    wb.save(path)
    return ws.cell(row, col).coordinate


@pytest.mark.parametrize("cell", [
    b'<c r="{ref}" t="str"><f>IF(A2&gt;0,"","repeat")</f><v></v></c>',  # Excel
    b'<c r="{ref}" s="0" t="str"><f>IF(A2&gt;0,"","repeat")</f><v/></c>',  # LibreOffice
])
def test_a_formula_whose_saved_value_is_empty_text_is_an_empty_cell(tmp_path, cell):
    protocol, path = _xlsx_day(tmp_path)
    ref = _remarks_cell(path, 21)
    _set_cell_xml(path, ref, cell.replace(b"{ref}", ref.encode()))
    assert read_run_sheet(path, 18.0).set_index("run").loc[21, "remarks"] == ""
    assert _process(protocol) == 0


@pytest.mark.parametrize("cell", [
    b'<c r="{ref}"><f>IF(A2&gt;0,"","repeat")</f><v/></c>',  # openpyxl: never computed
    b'<c r="{ref}"><f>IF(A2&gt;0,"","repeat")</f></c>',
    b'<c r="{ref}" t="n"><f>1+1</f><v></v></c>',
])
def test_a_formula_with_no_saved_value_still_stops_the_day(tmp_path, capsys, cell):
    protocol, path = _xlsx_day(tmp_path)
    ref = _remarks_cell(path, 21)
    _set_cell_xml(path, ref, cell.replace(b"{ref}", ref.encode()))
    assert _process(protocol) == 2
    err = capsys.readouterr().err
    assert f"the cell(s) {ref} hold formulas with no saved value" in err
    _one_sentence(err)
