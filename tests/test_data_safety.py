"""Issue 14: never lose a user's files, never run their text as formulas, never let one bad
value take the day down. One test (or more) per numbered item of the issue."""

from __future__ import annotations

import csv
import os
import stat
from pathlib import Path

import pandas as pd
import pytest

from towtank.commands.cli import main
from towtank.testing import synthetic as syn

SEED = 11
EVIL = '=HYPERLINK("http://evil.example","c")'


def _day(root: Path, name: str | None = None, sheet_edit=None, *, workbook_only: bool = False,
         **model) -> Path:
    """A hull day in ``root`` (CSV run files and sheet), its protocol path. ``workbook_only``:
    the report is the workbook alone (``[report] pdf = false, figures = false``)."""
    syn.make_hull_day(root, seed=SEED, file_format="csv", sheet_format="csv")
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv")
    if name is not None:
        sections["campaign"]["name"] = name
    if workbook_only:
        sections["report"] = {"pdf": False, "figures": False}
    sections["model"].update(model)
    if sheet_edit is not None:
        sheet = root / "run_sheet.csv"
        frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
        sheet_edit(frame)
        frame.to_csv(sheet, index=False)
    return syn.write_protocol(root / "protocol.toml", **sections)


# ------------------------------------------------------------------ 3. formula injection
def _evil_sheet(frame: pd.DataFrame) -> None:
    frame.loc[0, "remarks"] = "=2*3"
    frame.loc[5, "remarks"] = "@SUM(A1:A9)"
    frame.loc[19, "remarks"] = EVIL  # the void run: its remark becomes its reason
    frame["operator"] = "+cmd|' /C calc'!A0"
    frame.loc[7, "remarks"] = "bell\x07 and \ufffe in a remark"


def test_no_text_becomes_a_formula_in_the_workbook_or_the_csv(tmp_path):
    import openpyxl

    # the workbook and the CSVs are what could hold a formula: the PDF and PNGs are not drawn
    protocol = _day(tmp_path, name=EVIL + "\x01", sheet_edit=_evil_sheet, workbook_only=True)
    assert main(["process", str(protocol), "--out", str(tmp_path / "out"), "-q"]) in (0, 1)
    wb = openpyxl.load_workbook(tmp_path / "out" / "report.xlsx")  # valid XML
    formulas = [(ws.title, c.coordinate, c.value) for ws in wb.worksheets
                for row in ws.iter_rows() for c in row if c.data_type == "f"]
    assert formulas == []
    texts = {c.value for ws in wb.worksheets for row in ws.iter_rows() for c in row
             if isinstance(c.value, str)}
    assert "=2*3" in texts and any(t.startswith(EVIL) for t in texts)
    with open(tmp_path / "out" / "runs.csv", newline="", encoding="utf-8") as fh:
        cells = [c for row in csv.reader(fh) for c in row]
    assert "=2*3" not in cells and "'=2*3" in cells
    assert "'@SUM(A1:A9)" in cells and "'+cmd|' /C calc'!A0" in cells
    assert not any(c.startswith(("=", "+", "@")) for c in cells)
    numbers = pd.read_csv(tmp_path / "out" / "coefficients.csv")["value"]
    assert (numbers < 0).any()  # negative numbers stay numbers
    method = pd.read_csv(tmp_path / "out" / "coefficients.csv").set_index("symbol")["method"]
    assert method["Z_wdot"].startswith("same as Y_vdot")  # no more '= Y_vdot' formula cells


# ------------------------------------------------------ 1. the user's files are never deleted
@pytest.fixture(scope="session")
def day(tmp_path_factory) -> Path:
    return _day(tmp_path_factory.mktemp("day"))


def _process(protocol: Path, out: Path, *extra: str) -> int:
    return main(["process", str(protocol), "--out", str(out), "-q", "--jobs", "1", *extra])


def test_files_with_output_names_that_towtank_did_not_write_stop_the_day(day, tmp_path, capsys):
    out = tmp_path / "out"
    (out / "figures").mkdir(parents=True)
    (out / "figures" / "model_photo.jpg").write_bytes(b"x")
    (out / "report.pdf").write_text("mine")
    (out / "notes.txt").write_text("n")
    assert _process(day, out, "--no-report") == 2
    err = capsys.readouterr().err
    assert "figures/model_photo.jpg, report.pdf, which towtank did not write" in err
    assert (out / "figures" / "model_photo.jpg").read_bytes() == b"x"
    assert (out / "report.pdf").read_text() == "mine"
    assert sorted(p.name for p in out.iterdir()) == ["figures", "notes.txt", "report.pdf"]
    # moved away, the day is written beside notes.txt, and again over its own outputs
    (out / "report.pdf").unlink()
    (out / "figures" / "model_photo.jpg").unlink()
    (out / "figures").rmdir()
    for _ in range(2):
        assert _process(day, out, "--no-report") == 0
        assert (out / "notes.txt").read_text() == "n"
    assert not (out / "OUTPUTS-INCOMPLETE.txt").exists()
    # an output the user edited afterwards is theirs now: not replaced either
    (out / "runs.csv").write_text("my edited table\n")
    assert _process(day, out, "--no-report", "--no-cache") == 2
    assert (out / "runs.csv").read_text() == "my edited table\n"


def test_a_symlink_with_an_output_name_is_not_followed(day, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    target = tmp_path / "precious.csv"
    target.write_text("precious")
    (out / "runs.csv").symlink_to(target)
    assert _process(day, out, "--no-report") == 2
    assert target.read_text() == "precious" and (out / "runs.csv").is_symlink()


# --------------------------------------------------------------- 2. synth never overwrites
@pytest.mark.heavy
def test_synth_refuses_a_folder_that_is_not_empty(tmp_path, capsys):
    real = tmp_path / "real_day"
    (real / "data").mkdir(parents=True)
    (real / "protocol.toml").write_text("# the lab's own protocol\n")
    (real / "data" / "run_001.csv").write_text("t,U\n0,0\n")
    assert main(["synth", str(real), "--day", "fin"]) == 2
    assert "is not empty" in capsys.readouterr().err
    assert main(["synth", str(real), "--day", "fin", "--force"]) == 2
    err = capsys.readouterr().err
    assert "protocol.toml" in err and "which synth did not write" in err
    assert (real / "protocol.toml").read_text() == "# the lab's own protocol\n"
    assert (real / "data" / "run_001.csv").read_text() == "t,U\n0,0\n"
    assert sorted(p.name for p in real.rglob("*")) == ["data", "protocol.toml", "run_001.csv"]
    # its own earlier day it may replace, with --force
    fake = tmp_path / "fake"
    assert main(["synth", str(fake), "--day", "hull", "--format", "csv"]) == 0
    assert main(["synth", str(fake), "--day", "hull", "--format", "csv", "--seed", "2",
                 "--force"]) == 0
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


# ------------------------------------------------------------ 4. the folder keeps its mode
@pytest.mark.heavy
def test_output_folder_keeps_its_mode_and_new_ones_follow_the_umask(day, tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o2775)
    assert _process(day, shared, "--no-report") == 0
    assert stat.S_IMODE(shared.stat().st_mode) == 0o2775
    old = os.umask(0o022)
    try:
        assert _process(day, tmp_path / "new", "--no-report") == 0
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "new").stat().st_mode) == 0o755


# ---------------------------------------------- 15. a kill between the renames loses nothing
def test_a_set_left_beside_a_missing_folder_is_put_back(day, tmp_path, capsys):
    out = tmp_path / "out"
    assert _process(day, out, "--no-report") == 0
    runs = (out / "runs.csv").read_bytes()
    os.rename(out, tmp_path / ".out.old-abc123")  # killed after the first rename
    (tmp_path / ".out.tmp-def456").mkdir()  # and a new set never finished (no manifest)
    bad = day.parent / "bad.toml"
    bad.write_text(day.read_text().replace("[model]", "[model]\nbogus = 1"))
    assert _process(bad, out, "--no-report") == 2  # the day fails: the old set is back
    assert (out / "runs.csv").read_bytes() == runs


@pytest.mark.heavy
def test_a_mixed_set_is_marked_until_it_is_complete(day, tmp_path, monkeypatch):
    from towtank.report import outputs

    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert _process(day, out, "--no-report") == 0
    real = os.replace

    def killed(src, dst):  # the kill comes while provenance.json is put in place
        if Path(dst).name == "provenance.json":
            raise KeyboardInterrupt
        return real(src, dst)

    monkeypatch.setattr(outputs.os, "replace", killed)
    with pytest.raises(KeyboardInterrupt):
        from towtank.api import process_day
        from towtank.report import write_outputs

        write_outputs(process_day(day, jobs=1), out, report=False)
    monkeypatch.setattr(outputs.os, "replace", real)
    assert "mix of two runs" in (out / "OUTPUTS-INCOMPLETE.txt").read_text()
    assert _process(day, out, "--no-report", "--no-cache") == 0  # its own files: replaced
    assert not (out / "OUTPUTS-INCOMPLETE.txt").exists()
    assert (out / "notes.txt").read_text() == "mine"
