"""Inputs are never touched and never misread (issue 7 follow-ups).

The output folder can never be the data folder nor overwrite an input; a bad reference CSV or
a misspelt sheet column stops the day before anything is written; the per-run cache cannot be
fooled by a file rewritten at the same size with its mtime put back; odd files get a reason
that says what they are; a killed run's temporary folders are swept.
"""

from __future__ import annotations

import dataclasses
import gzip
import hashlib
import json
import os
import time
from pathlib import Path

import pandas as pd
import pytest
from conftest import draw_only_pages, write_hull_protocol

from towtank.commands import cli
from towtank.errors import ProtocolError, RunError
from towtank.ingest.protocol import (
    check_output_dir,
    load_protocol,
    read_reference_csv,
    with_output_dir,
)
from towtank.ingest.runfile import read_columns
from towtank.ingest.runsheet import read_run_sheet
from towtank.report.outputs import sweep_stale_temporaries
from towtank.runtime import manifest, outfolder
from towtank.testing import synthetic as syn

HIGH = 0.5
PLAN = [syn.RunSpec("sting", 0.0, v, HIGH) for v in (0.8, 1.6)] + [
    syn.RunSpec("hull", 0.0, v, HIGH) for v in (0.8, 1.2, 1.6)
]


def _day(root: Path) -> Path:
    syn.make_hull_day(root, seed=8, runs=PLAN, sheet_format="csv", file_format="csv",
                      channel_style="canonical")
    return write_hull_protocol(root, sheet_format="csv", channel_style="canonical")


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _tree_hashes(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): _sha(p) for p in sorted(root.rglob("*")) if p.is_file()}


def _process(protocol: Path, out: Path, *extra: str) -> int:
    return cli.main(["process", str(protocol), "--out", str(out), "--quiet", "--no-report",
                     "--jobs", "1", *extra])


# ------------------------------------------------------------------------- output folder
def test_output_folder_may_not_be_or_hold_the_data(tmp_path, capsys):
    protocol = _day(tmp_path)
    before = _tree_hashes(tmp_path)
    for out in (tmp_path / "data", tmp_path / "data" / "out", tmp_path):
        assert _process(protocol, out) == 2, out
        assert "raw run files" in capsys.readouterr().err
    assert _tree_hashes(tmp_path) == before


def test_outputs_put_back_are_said_by_a_new_protocol_the_frozen_one_unchanged(tmp_path):
    """An interrupted run left no output folder, only its last complete set beside it: the
    check puts it back and says so in a new protocol (dataclasses.replace); the protocol given
    is never changed in place."""
    loaded = load_protocol(_day(tmp_path))
    before = loaded.warnings
    out = tmp_path / "out"

    def interrupted(name: str) -> None:
        old = tmp_path / f".out.old-{name}"
        old.mkdir()
        (old / "runs.csv").write_text("run\n1\n", encoding="utf-8")
        manifest.write_manifest(old, manifest.describe(old, outfolder.OUTPUT_NAMES))

    interrupted("1")
    new, folder = with_output_dir(loaded, out)
    assert folder == out.resolve() and (out / "runs.csv").read_text() == "run\n1\n"
    assert loaded.warnings == before  # untouched
    assert new is not loaded and len(new.warnings) == len(before) + 1
    assert "interrupted run" in new.warnings[-1] and ".out.old-1" in new.warnings[-1]
    assert dataclasses.replace(new, warnings=before) == loaded
    again, _ = with_output_dir(new, out)  # nothing to put back: the protocol as given
    assert again is new
    # the folder-only check says it as a Python warning, the protocol still untouched
    out.rename(tmp_path / ".out.moved")
    interrupted("2")
    with pytest.warns(UserWarning, match="interrupted run"):
        assert check_output_dir(out, loaded) == out.resolve()
    assert loaded.warnings == before
    assert outfolder.check_output_dir(out, loaded.campaign.data_dir).recovered is None


def test_output_may_not_overwrite_the_run_sheet(tmp_path, capsys):
    protocol = _day(tmp_path)
    sheets = tmp_path / "sheets"
    sheets.mkdir()
    (tmp_path / "run_sheet.csv").rename(sheets / "runs.csv")
    text = protocol.read_text(encoding="utf-8").replace('"./run_sheet.csv"',
                                                        '"./sheets/runs.csv"')
    protocol.write_text(text, encoding="utf-8")
    sheet_sha = _sha(sheets / "runs.csv")
    assert _process(protocol, sheets) == 2
    assert "would overwrite the input" in capsys.readouterr().err
    assert _sha(sheets / "runs.csv") == sheet_sha


def test_output_folder_that_is_a_file_stops_before_any_work(tmp_path, capsys):
    protocol = _day(tmp_path)
    target = tmp_path / "report.txt"
    target.write_text("not a folder", encoding="utf-8")
    assert _process(protocol, target) == 2
    assert "is a file, not a folder" in capsys.readouterr().err
    assert target.read_text(encoding="utf-8") == "not a folder"


# ------------------------------------------------------------------------ reference CSV
@pytest.mark.parametrize(
    ("content", "words"),
    [
        ("", "is empty"),
        ("# only a comment\n", "is empty"),
        ("name,value\nX_udot,-0.0008\n", "needs the columns symbol and prime"),
        ("symbol,prime\nX_udot,minus one\n", "line 2 needs a symbol and a finite prime"),
        ("symbol,prime\nX_udot,-0.0008\nX_udot,-0.0009\n", "repeats the symbol"),
        ("symbol,prime\n", "no coefficient rows"),
    ],
)
def test_bad_reference_csv_stops_the_day_before_anything_is_written(tmp_path, capsys,
                                                                    content, words):
    protocol = _day(tmp_path)
    (tmp_path / "ref.csv").write_text(content, encoding="utf-8")
    text = protocol.read_text(encoding="utf-8")
    protocol.write_text(text.replace('reference = "remus"', 'reference = "ref.csv"'),
                        encoding="utf-8")
    out = tmp_path / "out"
    assert _process(protocol, out) == 2
    assert words in capsys.readouterr().err
    assert not out.exists()


def test_good_reference_csv_is_read_and_hashed_in_provenance(tmp_path):
    protocol = _day(tmp_path)
    ref = tmp_path / "ref.csv"
    ref.write_text("# my vehicle\nSymbol , Prime, note\nX_u|u|,-0.0031,towed 2023\n"
                   "X_udot,-0.0008,\n", encoding="utf-8")
    assert read_reference_csv(ref) == {"X_u|u|": -0.0031, "X_udot": -0.0008}
    text = protocol.read_text(encoding="utf-8")
    protocol.write_text(text.replace('reference = "remus"', 'reference = "ref.csv"'),
                        encoding="utf-8")
    out = tmp_path / "out"
    assert _process(protocol, out) == 0
    prov = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    hashes = {Path(i["path"]).name: i["sha256"] for i in prov["inputs"]}
    assert hashes["ref.csv"] == _sha(ref)
    coef = pd.read_csv(out / "coefficients.csv").set_index("symbol")
    assert coef.loc["X_u|u|", "reference_prime"] == pytest.approx(-0.0031)


# ------------------------------------------------------------------------------ cache
def test_cache_sees_a_file_rewritten_at_the_same_size_with_its_mtime_put_back(tmp_path):
    protocol = _day(tmp_path)
    out = tmp_path / "out"
    assert _process(protocol, out) == 0
    run_file = tmp_path / "data" / "run_005.csv"
    st = run_file.stat()
    original = run_file.read_text(encoding="utf-8")
    # the same bytes with the last digit of every drag value changed: same size
    lines = original.splitlines(keepends=True)
    header = lines[0].rstrip("\n").split(",")
    k = header.index("drag")
    new_lines = [lines[0]]
    for line in lines[1:]:
        cells = line.rstrip("\n").split(",")
        v = cells[k]
        digit = next(i for i in range(len(v) - 1, -1, -1) if v[i].isdigit())
        cells[k] = v[:digit] + str((int(v[digit]) + 5) % 10) + v[digit + 1:]
        new_lines.append(",".join(cells) + "\n")
    changed = "".join(new_lines)
    assert len(changed) == len(original) and changed != original
    run_file.write_text(changed, encoding="utf-8")
    os.utime(run_file, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert run_file.stat().st_size == st.st_size
    assert run_file.stat().st_mtime_ns == st.st_mtime_ns
    assert _process(protocol, out, "--date", "2024-01-01") == 0  # not a replay: options differ
    prov = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    hashes = {Path(i["path"]).name: i["sha256"] for i in prov["inputs"]}
    assert hashes["run_005.csv"] == _sha(run_file)


# ----------------------------------------------------------------------------- run sheet
def test_misspelt_optional_sheet_column_stops_the_day(tmp_path):
    _day(tmp_path)
    sheet = tmp_path / "run_sheet.csv"
    frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
    frame.rename(columns={"tare_group": "tare_grp"}).to_csv(sheet, index=False)
    with pytest.raises(ProtocolError, match="'tare_grp' looks like a misspelling of 'tare_group'"):
        read_run_sheet(sheet, 18.0)


def test_sheet_columns_in_another_case_are_the_contract_columns(tmp_path):
    _day(tmp_path)
    sheet = tmp_path / "run_sheet.csv"
    frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
    frame.loc[frame.index[-1], "status"] = "void"
    frame.columns = [c.capitalize() if c in ("status", "run", "remarks") else c
                     for c in frame.columns]
    frame.to_csv(sheet, index=False)
    runs = read_run_sheet(sheet, 18.0)
    assert runs["status"].iloc[-1] == "void"
    assert list(runs["run"]) == list(range(1, len(PLAN) + 1))


def test_protocol_with_a_byte_order_mark_loads(tmp_path):
    protocol = _day(tmp_path)
    protocol.write_bytes(b"\xef\xbb\xbf" + protocol.read_bytes())
    assert load_protocol(protocol).campaign.name


# ------------------------------------------------------------------------------ odd files
def test_gzip_file_named_csv_and_nul_file_get_their_own_reason(tmp_path):
    _day(tmp_path)
    src = tmp_path / "data" / "run_003.csv"
    zipped = tmp_path / "zipped.csv"
    zipped.write_bytes(gzip.compress(src.read_bytes(), mtime=0))
    with pytest.raises(RunError, match="gzip-compressed although its name does not end in .gz"):
        read_columns(zipped)
    nul = tmp_path / "nul.csv"
    nul.write_bytes(src.read_bytes()[:200] + b"\x00" * 4096)
    with pytest.raises(RunError, match="holds NUL bytes"):
        read_columns(nul)


def test_few_dropped_rows_are_warned_on_the_terminal(tmp_path, capsys):
    protocol = _day(tmp_path)
    run_file = tmp_path / "data" / "run_004.csv"
    lines = run_file.read_text(encoding="utf-8").splitlines(keepends=True)
    lines[500] = "n/a,n/a,n/a,n/a\n"
    run_file.write_text("".join(lines), encoding="utf-8")
    code = cli.main(["process", str(protocol), "--out", str(tmp_path / "out"), "--no-report",
                     "--jobs", "1"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "run 4:" in printed and "non-numeric row(s) dropped" in printed


def test_a_killed_runs_temporary_folders_are_swept(tmp_path):
    out = tmp_path / "out"
    old_tmp = tmp_path / ".out.tmp-abc123"
    fresh_tmp = tmp_path / ".out.tmp-def456"
    for d in (old_tmp, fresh_tmp):
        (d / "figures").mkdir(parents=True)
        (d / "runs.csv").write_text("x\n", encoding="utf-8")
    hour_ago = time.time() - 3600
    os.utime(old_tmp, (hour_ago, hour_ago))
    assert sweep_stale_temporaries(out) == [old_tmp]
    assert not old_tmp.exists() and fresh_tmp.exists()  # a run writing now keeps its folder


def test_a_file_listed_for_two_runs_is_one_run(tmp_path):
    protocol = _day(tmp_path)
    sheet = tmp_path / "run_sheet.csv"
    frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
    frame.loc[frame["run"] == "5", "file"] = "./run_004.csv"  # the same file, written otherwise
    frame.to_csv(sheet, index=False)
    from conftest import process

    result = process(protocol)
    assert set(result.rejected) == {5}
    assert str(result.rejected[5]) == ("run 5: ./run_004.csv is also the file of run 4 in the "
                                       "sheet; a recording is one run (a copied cell?)")
    assert result.runs.set_index("run").loc[4, "status"] == "ok"


def test_merged_cells_of_an_xlsx_sheet_fill_the_cells_they_cover(tmp_path):
    import openpyxl

    syn.make_hull_day(tmp_path, seed=8, runs=PLAN, sheet_format="xlsx", file_format="csv",
                      channel_style="canonical")
    path = tmp_path / "run_sheet.xlsx"
    wb = openpyxl.load_workbook(path)
    ws = wb.worksheets[0]
    header = [c.value for c in ws[1]]
    col = header.index("tare_group") + 1
    for r in range(2, 2 + len(PLAN)):
        ws.cell(r, col).value = "A" if r == 2 else None
    ws.merge_cells(start_row=2, start_column=col, end_row=1 + len(PLAN), end_column=col)
    temp = header.index("water_temp_C") + 1
    ws.cell(2, temp).value = 17.25
    ws.merge_cells(start_row=2, start_column=temp, end_row=3, end_column=temp)
    wb.save(path)
    runs = read_run_sheet(path, 18.0)
    assert list(runs["tare_group"]) == ["A"] * len(PLAN)
    assert list(runs["water_temp_C"][:2]) == [17.25, 17.25]


def test_a_named_pipe_in_place_of_a_run_file_is_rejected_not_read(tmp_path):
    protocol = _day(tmp_path)
    fifo = tmp_path / "data" / "run_004.csv"
    fifo.unlink()
    os.mkfifo(fifo)
    from conftest import process

    result = process(protocol, jobs=1)
    assert {r: str(x) for r, x in result.rejected.items()} == {
        4: "run 4: run_004.csv is not a regular file (a pipe, socket or device)"}


def test_outputs_may_not_replace_a_run_file_outside_the_data_folder(tmp_path, capsys):
    protocol = _day(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (tmp_path / "data" / "run_004.csv").rename(out / "fins.csv")
    sheet = tmp_path / "run_sheet.csv"
    frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
    frame.loc[frame["run"] == "4", "file"] = "../out/fins.csv"
    frame.to_csv(sheet, index=False)
    raw = _sha(out / "fins.csv")
    assert _process(protocol, out) == 2
    err = capsys.readouterr().err
    assert "would overwrite the input" in err or "towtank did not write" in err
    assert _sha(out / "fins.csv") == raw


def test_a_file_named_in_another_case_is_suggested(tmp_path):
    from conftest import process

    protocol = _day(tmp_path)
    (tmp_path / "data" / "run_004.csv").rename(tmp_path / "data" / "RUN_004.CSV")
    result = process(protocol, jobs=1)
    assert set(result.rejected) == {4}
    assert str(result.rejected[4]).endswith("is not found in "
                                       f"{tmp_path / 'data'}; did you mean 'RUN_004.CSV'?")


@pytest.mark.parametrize(("extra", "words"), [
    (["air_temp_C", "start_s", "operator", "notes", "file name"], None),
    (["water_temp_F"], "looks like 'water_temp_C' in another unit"),
    (["remark"], "looks like a misspelling of 'remarks'"),
    (["status", "Status"], "has the column 'status' twice"),
])
def test_sheet_column_names_a_lab_uses(tmp_path, extra, words):
    from towtank.ingest.runsheet import known_columns

    base = ["run", "file", "config", "angle_deg"]
    if words is None:
        assert known_columns(base + extra, "s.csv") == base + extra
    else:
        with pytest.raises(ProtocolError, match=words):
            known_columns(base + extra, "s.csv")


def _xlsx_day(tmp_path: Path):
    import openpyxl

    syn.make_hull_day(tmp_path, seed=8, runs=PLAN, sheet_format="xlsx", file_format="csv",
                      channel_style="canonical")
    path = tmp_path / "run_sheet.xlsx"
    return path, openpyxl.load_workbook(path)


def test_the_run_sheet_worksheet_need_not_be_the_first(tmp_path):
    path, wb = _xlsx_day(tmp_path)
    notes = wb.create_sheet("Operator notes", 0)
    notes["A1"] = "Operator notes"
    notes["A2"] = "carriage squeaked after run 3"
    wb.save(path)
    assert list(read_run_sheet(path, 18.0)["run"]) == list(range(1, len(PLAN) + 1))
    only_notes = tmp_path / "notes.xlsx"
    del wb[wb.sheetnames[1]]
    wb.save(only_notes)
    with pytest.raises(ProtocolError, match="no worksheet has the required columns.*"
                                            "'Operator notes'"):
        read_run_sheet(only_notes, 18.0)


def test_formulas_without_a_saved_value_stop_the_day(tmp_path):
    path, wb = _xlsx_day(tmp_path)
    ws = wb.worksheets[0]
    header = [c.value for c in ws[1]]
    col = header.index("water_temp_C") + 1
    ws.cell(2, col).value = "=17.5+0.5"  # written by a program: no value saved with it
    wb.save(path)
    with pytest.raises(ProtocolError, match=r"cell\(s\) [A-Z]+2 hold formulas with no saved"):
        read_run_sheet(path, 18.0)


@pytest.mark.heavy
def test_dollars_and_carets_from_the_inputs_never_break_the_report(tmp_path, monkeypatch):
    """Names, remarks, file names and cells typed by people reach the PDF as text; matplotlib
    would parse '$…$' as mathtext (and fail on '$\\frac$'): they must be drawn literally.

    The pages that print the inputs' text are drawn (title, summary, runs, quality, the
    thumbnails and every page's header); the fits' figures, which print none, are blank."""
    from pypdf import PdfReader

    from towtank.report import figures

    draw_only_pages(monkeypatch, lambda page: page.kind != "figure")
    monkeypatch.setattr(figures, "write_figures", lambda day, folder: None)

    protocol = _day(tmp_path)
    text = protocol.read_text(encoding="utf-8")
    name_line = next(line for line in text.splitlines() if line.startswith("name = "))
    protocol.write_text(text.replace(name_line, 'name = "Tank $A_1$ day, cost $\\\\frac$"', 1),
                        encoding="utf-8")
    sheet = tmp_path / "run_sheet.csv"
    frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
    frame.loc[frame["run"] == "3", "remarks"] = "probe $x^2$ moved"
    frame.loc[frame["run"] == "4", "config"] = "hu$_$ll"
    frame.loc[frame["run"] == "5", "file"] = "tank$A_run^8.csv"
    frame.to_csv(sheet, index=False)
    out = tmp_path / "out"
    code = cli.main(["process", str(protocol), "--out", str(out), "--quiet", "--jobs", "1"])
    assert code == 1  # runs 4 and 5 rejected, the report written
    pages = " ".join(p.extract_text() for p in PdfReader(out / "report.pdf").pages)
    assert "Tank $A_1$ day" in pages and "tank$A_run^8.csv" in pages
