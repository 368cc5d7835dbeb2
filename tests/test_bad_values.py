"""Issue 14, items 8-14 and 16: one bad value (a damaged file, a typo, an impossible setting,
Ctrl-C, a killed parent) never takes the day down with exit 3, and never leaves workers behind.

Each test builds its case on an unchanged synthetic day and fails on any of exit 3, a
traceback, a hang or a raw library message.
"""

from __future__ import annotations

import errno
import gzip
import json
import os
import signal
import subprocess
import sys
import time
import warnings
import zipfile
from dataclasses import replace
from pathlib import Path
from typing import Any, Literal

import pandas as pd
import pytest
from conftest import draw_only_pages

from towtank.commands.cli import main
from towtank.errors import ProtocolError
from towtank.ingest.protocol import load_protocol
from towtank.ingest.runsheet import MAX_SHEET_ROWS, read_run_sheet
from towtank.testing import synthetic as syn

SEED = 11


def _day(root: Path, sheet_edit=None, *, sheet_format: Literal["csv", "xlsx"] = "csv",
         **sections) -> Path:
    """A hull day (CSV run files) in ``root``; its protocol path. ``sections`` update the
    protocol's sections (``model={...}``, ``processing={...}``)."""
    syn.make_hull_day(root, seed=SEED, file_format="csv", sheet_format=sheet_format)
    sec: dict[str, Any] = syn.hull_protocol_sections(".", "out", sheet_format=sheet_format)
    for name, values in sections.items():
        sec.setdefault(name, {}).update(values)
    if sheet_edit is not None:
        sheet = root / "run_sheet.csv"
        frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
        sheet_edit(frame, root)
        frame.to_csv(sheet, index=False)
    return syn.write_protocol(root / "protocol.toml", **sec)


def _row(frame: pd.DataFrame, i: int) -> tuple[int, str]:
    return int(frame.loc[i, "run"]), str(frame.loc[i, "file"])


# ----------------------------------------------- 8, 9, 10, 16: one bad run, the day goes on
BAD: dict[int, str] = {}  # run -> words its reason must hold


def _damage(frame: pd.DataFrame, root: Path) -> None:
    hull = frame.index[(frame.config == "hull") & (frame.status != "void")]
    data = root / "data"
    # 9: a water temperature typed 180 (for 18.0), 1e308, -300
    for i, value, words in ((hull[0], "180", "a typo for 18"),
                            (hull[1], "1e308", "not a water temperature"),
                            (hull[2], "-300", "-300 °C is outside")):
        frame.loc[i, "water_temp_C"] = value
        BAD[_row(frame, i)[0]] = words
    # 10: a symlink loop named by a run row
    os.symlink("loop.csv", data / "loop.csv")
    frame.loc[hull[3], "file"] = "loop.csv"
    BAD[_row(frame, hull[3])[0]] = "symlink loop"
    # 8: a control character in a CSV header; binary without NUL bytes
    run, name = _row(frame, hull[4])
    text = (data / name).read_text(encoding="utf-8")
    (data / name).write_text(text.replace("Time (s)", "Ti\x07me\x1b[31m (s)", 1), encoding="utf-8")
    BAD[run] = "time channel is missing"
    run, name = _row(frame, hull[5])
    (data / name).write_bytes(bytes(range(1, 256)) * 400)
    BAD[run] = name
    # 16: the speed column negated (a sign or gain slip)
    run, name = _row(frame, hull[6])
    df = pd.read_csv(data / name)
    df["Carriage speed (m/s)"] *= -1
    df.to_csv(data / name, index=False)
    BAD[run] = "speed is negative"
    # 16: a FIFO as a run file
    os.mkfifo(data / "pipe.csv")
    frame.loc[hull[7], "file"] = "pipe.csv"
    BAD[_row(frame, hull[7])[0]] = "not a regular file"
    # 8: control characters and U+FFFE in a remark
    frame.loc[hull[8], "remarks"] = "bell\x07 \ufffe\uffff remark\x1b[2J"


@pytest.mark.heavy
def test_bad_runs_are_rejected_one_by_one_and_the_report_is_written(tmp_path, capsys):
    BAD.clear()
    # the PDF and the workbook (what is read below); the PNGs draw the PDF's figures again
    protocol = _day(tmp_path, _damage, report={"figures": False})
    out = tmp_path / "out"
    # the PDF's pages that show the bad runs: their text (runs, quality, summary) and the
    # thumbnails of the damaged runs; the fits' figures and the other thumbnails are blank
    with pytest.MonkeyPatch.context() as mp:
        draw_only_pages(mp, lambda page: page.kind in ("title", "summary", "runs", "quality")
                        or (page.kind == "thumbs" and bool(set(page.payload) & set(BAD))))
        assert main(["process", str(protocol), "--out", str(out)]) == 1  # not 3: day done
    captured = capsys.readouterr()
    runs = pd.read_csv(out / "runs.csv")
    for run, words in BAD.items():
        reason = runs.loc[runs["run"] == run, "reason"].iloc[0]
        assert runs.loc[runs["run"] == run, "status"].iloc[0] == "rejected"
        assert words in reason, (run, reason)
    assert (runs["status"] == "ok").sum() == len(runs) - len(BAD) - (runs["status"] == "void").sum()
    import openpyxl

    openpyxl.load_workbook(out / "report.xlsx")  # valid XML despite U+FFFE in a remark
    assert (out / "report.pdf").stat().st_size > 10_000
    terminal = captured.out + captured.err
    assert "\x1b" not in terminal and "\x07" not in terminal  # nothing from a file echoed raw
    assert "Traceback" not in terminal and ".py:" not in terminal


# ------------------------------------------------------------ 11: exit 2, not exit 3
@pytest.mark.parametrize("section, key, value, words", [
    ("model", "depth_m", 0.0, "'depth_m' in [model] must be positive"),
    ("model", "depth_m", -1.0, "'depth_m' in [model] must be positive"),
    ("water", "temperature_C", 100.0, "liquid water"),
    ("water", "temperature_C", -273.16, "liquid water"),
    ("prototype", "speeds_m_s", [1e308], "speeds up to 100 m/s"),
    ("processing", "filter_order", 1_000_000, "'filter_order' in [processing] must lie in 1–10"),
    ("processing", "cutoff_hz", 1e-300, "'cutoff_hz' in [processing] must lie in"),
])
def test_impossible_protocol_values_stop_the_day_with_exit_2(tmp_path, capsys, section, key,
                                                            value, words):
    protocol = _day(tmp_path, **{section: {key: value}})
    assert main(["process", str(protocol), "--no-report", "-q"]) == 2
    err = capsys.readouterr().err
    assert words in err and "internal error" not in err and "TypeError" not in err
    assert not (tmp_path / "out").exists()


def test_deeply_nested_toml_is_exit_2(tmp_path, capsys):
    path = tmp_path / "deep.toml"
    path.write_text("x = " + "[" * 2000 + "]" * 2000 + "\n", encoding="utf-8")
    assert main(["process", str(path), "-q"]) == 2
    assert "nested too deeply" in capsys.readouterr().err


def test_a_run_number_beyond_any_integer_type_is_exit_2(tmp_path):
    def big(frame, root):
        frame.loc[3, "run"] = str(2**63)

    protocol = _day(tmp_path, big)
    with pytest.raises(ProtocolError, match="not a whole number from 0 to 999999999"):
        read_run_sheet(tmp_path / "run_sheet.csv", 18.0)
    assert main(["process", str(protocol), "--no-report", "-q"]) == 2


@pytest.mark.parametrize("where", ["/proc/towtank-out", "/dev/null/out"])
def test_an_output_folder_that_cannot_be_written_is_exit_2(tmp_path, capsys, where):
    protocol = _day(tmp_path)
    assert main(["process", str(protocol), "--out", where, "-q", "--no-report"]) == 2
    assert "cannot be written" in capsys.readouterr().err


def test_a_full_disk_while_writing_is_exit_2_and_the_old_outputs_stay(tmp_path, capsys,
                                                                       monkeypatch):
    protocol = _day(tmp_path)
    out = tmp_path / "out"
    assert main(["process", str(protocol), "--out", str(out), "-q", "--no-report"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}

    from towtank.report import tables

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(tables, "write_tables", full)
    assert main(["process", str(protocol), "--out", str(out), "--no-cache", "-q",
                 "--no-report"]) == 2
    assert "No space left on device" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]


# ------------------------------------------------------------ 14: bounded work per input
def test_jobs_beyond_the_cores_are_capped_with_a_note(tmp_path, capsys, monkeypatch):
    from towtank.runtime.parallel import default_jobs, fork_beside, usable_jobs

    monkeypatch.delenv("TOWTANK_JOBS", raising=False)  # the default itself: every core
    assert usable_jobs(100_000) == default_jobs() and usable_jobs(0) == 1
    # one job is one process: nothing forked beside it, whatever the machine
    assert not fork_beside(1) and not fork_beside(0)
    assert fork_beside(2) == fork_beside(None) == (default_jobs() > 1)
    protocol = _day(tmp_path)
    assert main(["process", str(protocol), "--jobs", "100000", "--no-report"]) == 0
    assert f"{default_jobs()} jobs are used" in capsys.readouterr().err


def test_towtank_jobs_sets_the_default_and_a_bad_value_is_a_note(tmp_path, capsys,
                                                                  monkeypatch):
    """TOWTANK_JOBS gives the processes when neither --jobs nor the protocol's [processing]
    jobs says; a value that is not a number of processes is left aside with a note, one larger
    than the cores is capped with the note --jobs gets."""
    from towtank.ingest.protocol import load_protocol
    from towtank.runner import settle_jobs
    from towtank.runtime.parallel import default_jobs, fork_beside, usable_jobs

    protocol = _day(tmp_path)
    loaded = load_protocol(protocol)
    pinned = replace(loaded, processing=replace(loaded.processing, jobs=1))
    cores = default_jobs()
    monkeypatch.setenv("TOWTANK_JOBS", "1")
    assert usable_jobs(None) == 1 and not fork_beside(None)
    assert settle_jobs(None, loaded) == (1, None)
    assert settle_jobs(2, loaded)[0] == min(2, cores)  # --jobs first
    monkeypatch.setenv("TOWTANK_JOBS", "2")
    assert settle_jobs(None, pinned) == (1, None)  # then the protocol
    assert usable_jobs(None) == min(2, cores) and usable_jobs(1) == 1
    monkeypatch.setenv("TOWTANK_JOBS", "100000")
    jobs, note = settle_jobs(None, loaded)
    assert jobs == cores and f"{cores} jobs are used" in (note or "")
    for bad in ("abc", "0", "-2", "1.5", "¹", "２", "99" * 30):
        monkeypatch.setenv("TOWTANK_JOBS", bad)
        assert usable_jobs(None) == cores
        assert settle_jobs(None, loaded) == (None, f"note: TOWTANK_JOBS={bad[:40]!r} is not a "
                                             "whole number of at least 1: it is left aside and "
                                             "every core is used.")
    monkeypatch.setenv("TOWTANK_JOBS", " ")
    assert settle_jobs(None, loaded) == (None, None)  # set to nothing: as if unset
    monkeypatch.setenv("TOWTANK_JOBS", "abc")
    assert main(["process", str(protocol), "--no-report"]) == 0
    err = capsys.readouterr().err
    assert "TOWTANK_JOBS='abc' is not a whole number of at least 1" in err


def _xlsx_day(tmp_path: Path, edit_xml) -> Path:
    protocol = _day(tmp_path, sheet_format="xlsx")
    sheet = tmp_path / "run_sheet.xlsx"
    with zipfile.ZipFile(sheet) as zin:
        parts = [(i, zin.read(i)) for i in zin.infolist()]
    with zipfile.ZipFile(sheet, "w", zipfile.ZIP_DEFLATED) as zout:
        for info, data in parts:
            if info.filename.startswith("xl/worksheets/sheet1"):
                data = edit_xml(data)
            zout.writestr(info, data)
    return protocol


@pytest.mark.heavy
def test_a_merged_range_to_the_sheets_end_is_cut_to_the_used_area(tmp_path):
    """A 7 kB workbook whose merged range is L1:XFD1048576 (17 billion cells, which the
    reader would create one by one until the memory runs out) is read as the lab sees it."""
    def merge(xml: bytes) -> bytes:
        cells = b'<mergeCells count="1"><mergeCell ref="L1:XFD1048576"/></mergeCells>'
        return xml.replace(b"</sheetData>", b"</sheetData>" + cells, 1)

    protocol = _xlsx_day(tmp_path, merge)
    assert (tmp_path / "run_sheet.xlsx").stat().st_size < 20_000
    sheet = read_run_sheet(tmp_path / "run_sheet.xlsx", 18.0)
    assert len(sheet) == 42
    assert main(["process", str(protocol), "--no-report", "-q"]) == 0


def test_a_sheet_with_a_million_rows_is_refused_in_one_sentence(tmp_path):
    def far(xml: bytes) -> bytes:
        row = b'<row r="1000000"><c r="A1000000" t="n"><v>1</v></c></row>'
        return xml.replace(b"</sheetData>", row + b"</sheetData>", 1)

    _xlsx_day(tmp_path, far)
    with pytest.raises(ProtocolError, match=r"has 1,000,000 rows, but towtank reads run "):
        read_run_sheet(tmp_path / "run_sheet.xlsx", 18.0)
    csv_sheet = tmp_path / "long.csv"
    body = "run,file,config,angle_deg,status\n" + "".join(
        f"{i},f{i}.csv,hull,0,void\n" for i in range(MAX_SHEET_ROWS + 5))
    csv_sheet.write_text(body, encoding="utf-8")
    with pytest.raises(ProtocolError, match="rows, but towtank reads run sheets"):
        read_run_sheet(csv_sheet, 18.0)


def test_a_huge_sheet_or_run_file_is_refused_before_it_is_read(tmp_path):
    """A 1 GB remark, a 10-hour 1 kHz recording: refused with a sentence, never read (sparse
    files here: their size is what is checked)."""
    sheet = tmp_path / "huge.csv"
    with open(sheet, "wb") as fh:
        fh.truncate(100 << 20)
    with pytest.raises(ProtocolError, match="MiB, but towtank reads run sheets up to 64 MiB"):
        read_run_sheet(sheet, 18.0)

    def long_run(frame, root):
        run, name = _row(frame, 3)
        with open(root / "data" / name, "r+b") as fh:
            fh.truncate(3 << 30)

    protocol = _day(tmp_path / "day", long_run)
    assert main(["process", str(protocol), "--no-report", "-q"]) == 1
    runs = pd.read_csv(tmp_path / "day" / "out" / "runs.csv")
    reason = runs.loc[3, "reason"]
    assert "too large for one run" in reason and "3.0 GiB" in reason
    # nor read to be hashed for provenance.json: its sha256 is left empty
    inputs = json.loads((tmp_path / "day" / "out" / "provenance.json").read_text())["inputs"]
    sha = {Path(i["path"]).name: i["sha256"] for i in inputs}
    assert sha[runs.loc[3, "file"]] == "" and len(sha[runs.loc[2, "file"]]) == 64


def test_a_gzip_bomb_is_refused(tmp_path):
    from towtank.ingest import readers, runfile

    path = tmp_path / "bomb.csv.gz"
    with gzip.open(path, "wb", compresslevel=9) as fh:
        block = b"0" * (1 << 20)
        for _ in range(40):
            fh.write(block)
    old = readers.MAX_RUN_FILE_BYTES
    try:
        readers.MAX_RUN_FILE_BYTES = 16 << 20
        with pytest.raises(runfile.RunError, match="too large for one run"):
            runfile.read_columns(path)
    finally:
        readers.MAX_RUN_FILE_BYTES = old


# ------------------------------------------------------------------------ 16: messages
def test_a_fifo_or_device_as_run_sheet_is_named_as_such(tmp_path, capsys):
    protocol = _day(tmp_path)
    os.mkfifo(tmp_path / "pipe.csv")
    text = protocol.read_text(encoding="utf-8").replace("run_sheet.csv", "pipe.csv")
    protocol.write_text(text, encoding="utf-8")
    assert main(["process", str(protocol), "-q"]) == 2
    assert "is not a regular file (a pipe or a device)" in capsys.readouterr().err


def test_a_toml_date_is_a_date_and_an_impossible_one_is_refused(tmp_path, capsys):
    protocol = _day(tmp_path)
    text = protocol.read_text(encoding="utf-8")
    dated = text.replace("[campaign]\n", "[campaign]\ntest_date = 2024-01-01\n", 1)
    protocol.write_text(dated, encoding="utf-8")
    assert load_protocol(protocol).campaign.test_date == "2024-01-01"
    protocol.write_text(text.replace("[campaign]\n", '[campaign]\ntest_date = "2024-02-30"\n', 1),
                        encoding="utf-8")
    with pytest.raises(ProtocolError, match="not a date that exists"):
        load_protocol(protocol)
    protocol.write_text(dated, encoding="utf-8")
    with pytest.raises(SystemExit) as exit_:
        main(["process", str(protocol), "--date", "2024-02-30"])
    assert exit_.value.code == 2
    assert "'2024-02-30' is not a date that exists" in capsys.readouterr().err


def test_library_warnings_do_not_reach_the_terminal(capsys):
    from towtank.commands.cli import _warning_line
    from towtank.reference.water import WaterPropertyWarning

    with warnings.catch_warnings():
        warnings.showwarning = _warning_line
        warnings.simplefilter("always")
        warnings.warn("invalid value encountered in divide", RuntimeWarning, stacklevel=1)
        warnings.warn("Water temperature 45..45 °C lies outside 0-40 °C\nsecond line",
                      WaterPropertyWarning, stacklevel=1)
    err = capsys.readouterr().err
    assert "invalid value" not in err
    assert err == "towtank: warning: Water temperature 45..45 °C lies outside 0-40 °C\n"


# ------------------------------------------------------------ 12, 13: Ctrl-C and kills
def _towtank(*args: str, env: dict[str, str] | None = None) -> subprocess.Popen:
    code = "from towtank.commands.cli import entry; entry()"
    return subprocess.Popen([sys.executable, "-c", code, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            env=None if env is None else {**os.environ, **env})


def _descendants(pid: int) -> set[int]:
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            children.setdefault(ppid, []).append(int(entry.name))
    out, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            out.add(child)
            todo.append(child)
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _wait_for_workers(proc: subprocess.Popen, n: int, timeout: float = 60.0) -> set[int]:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        kids = _descendants(proc.pid)
        if len(kids) >= n:
            return kids
        time.sleep(0.05)
    raise AssertionError("the workers never started")


def _wait_for_pause(proc: subprocess.Popen, marker: Path, stage: str,
                    timeout: float = 120.0) -> None:
    """Until ``proc`` holds at ``stage`` (TOWTANK_TEST_PAUSE_AT, towtank.runtime.pause)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if marker.exists() and marker.read_text().startswith(f"{stage} "):
            return
        if proc.poll() is not None:
            raise AssertionError(f"ended before {stage!r}: {proc.communicate()[1]}")
        time.sleep(0.02)
    raise AssertionError(f"never reached {stage!r}")


@pytest.mark.heavy
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_ctrl_c_is_exit_130_in_one_line_and_the_old_outputs_stay(tmp_path):
    """Ctrl-C in the middle of the reduction: exit 130, one line, the old outputs kept. The
    process holds in the reduction (TOWTANK_TEST_PAUSE_AT) until the signal comes, so the signal
    always lands mid-day, however loaded the machine."""
    protocol = _day(tmp_path)
    out = tmp_path / "out"
    assert main(["process", str(protocol), "--out", str(out), "-q", "--no-report"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    marker = tmp_path / "paused"
    proc = _towtank("process", str(protocol), "--out", str(out), "--no-cache", "--jobs", "2",
                    env={"TOWTANK_TEST_PAUSE_AT": "reduce",
                         "TOWTANK_TEST_PAUSE_FILE": str(marker)})
    _wait_for_pause(proc, marker, "reduce")  # runs come back from the workers: reducing
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("towtank: interrupted"), err
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


@pytest.mark.heavy
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_workers_die_with_the_main_process(tmp_path, sig):
    protocol = _day(tmp_path)
    proc = _towtank("process", str(protocol), "--no-cache", "--jobs", "2", "--no-report")
    workers = _wait_for_workers(proc, 3)
    proc.send_signal(sig)
    proc.communicate(timeout=30)
    end = time.monotonic() + 10.0
    while time.monotonic() < end and any(_alive(p) for p in workers):
        time.sleep(0.1)
    assert not [p for p in workers if _alive(p)]


# ------------------------------------------------------------ 5, 6, 7: never a stale cache
def _runs(out: Path) -> pd.DataFrame:
    return pd.read_csv(out / "runs.csv").set_index("run")


def test_a_sheet_edited_while_the_day_runs_is_never_replayed(tmp_path, capsys, monkeypatch):
    """The angle of a run is changed (5 -> 7) after the sheet was read, into an empty folder:
    the outputs are not recorded as those of the edited sheet; the next run sees 7."""
    import towtank.pipeline as pipeline

    protocol = _day(tmp_path)
    out = tmp_path / "out"
    sheet = tmp_path / "run_sheet.csv"
    frame = pd.read_csv(sheet, dtype=str, keep_default_na=False)
    i = frame.index[(frame.config == "hull") & (frame.status != "void")][3]
    run = int(frame.loc[i, "run"])
    original = pipeline.process_day

    def edit_during(*args, **kwargs):
        day = original(*args, **kwargs)
        edited = frame.copy()
        edited.loc[i, "angle_deg"] = str(float(frame.loc[i, "angle_deg"]) + 2.0)
        edited.to_csv(sheet, index=False)
        return day

    monkeypatch.setattr(pipeline, "process_day", edit_during)
    assert main(["process", str(protocol), "--out", str(out), "--no-report"]) == 0
    assert "changed while towtank was working" in capsys.readouterr().err
    before = _runs(out).loc[run, "angle_deg"]
    monkeypatch.setattr(pipeline, "process_day", original)
    assert main(["process", str(protocol), "--out", str(out), "--no-report"]) == 0
    assert _runs(out).loc[run, "angle_deg"] == pytest.approx(before + 2.0)


def _scale_drag(path: Path, factor: float) -> None:
    df = pd.read_csv(path)
    df["Fx load cell (V)"] *= factor
    df.to_csv(path, index=False)


def test_a_run_file_outside_the_data_folder_is_checked_again(tmp_path):
    """A sheet row names a file by absolute path elsewhere; replaced after a run, the next
    run reads it again (new sha256, new drag), it does not replay the old outputs."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    moved = {}

    def point_away(frame, root):
        i = frame.index[(frame.config == "hull") & (frame.status != "void")][2]
        run, name = _row(frame, i)
        target = elsewhere / name
        (root / "data" / name).rename(target)
        frame.loc[i, "file"] = str(target)
        moved.update(run=run, path=target)

    protocol = _day(tmp_path / "day", point_away)
    out = tmp_path / "out"
    assert main(["process", str(protocol), "--out", str(out), "--no-report", "-q"]) == 0
    old = _runs(out).loc[moved["run"]]
    _scale_drag(moved["path"], 1.1)
    assert main(["process", str(protocol), "--out", str(out), "--no-report", "-q"]) == 0
    new = _runs(out).loc[moved["run"]]
    import hashlib

    assert new["sha256"] == hashlib.sha256(moved["path"].read_bytes()).hexdigest()
    assert new["sha256"] != old["sha256"]
    assert abs(new["drag_mean"] / old["drag_mean"] - 1.0) > 0.05  # the new file's drag


def test_a_file_changed_after_it_was_read_is_not_cached_as_the_new_one(tmp_path, monkeypatch):
    """The file changes between the reduction reading it and the cache recording its
    size/mtime: the cache must not pair the new file with the old reduction."""
    import towtank.pipeline as pipeline

    protocol = _day(tmp_path)
    out = tmp_path / "out"
    frame = pd.read_csv(tmp_path / "run_sheet.csv")
    i = frame.index[(frame.config == "hull") & (frame.status != "void")][1]
    run, name = int(frame.loc[i, "run"]), str(frame.loc[i, "file"])
    original = pipeline.reduce_record

    def change_after_read(protocol_, row, *args, **kwargs):
        result = original(protocol_, row, *args, **kwargs)
        if int(row["run"]) == run:
            _scale_drag(tmp_path / "data" / name, 1.1)
        return result

    monkeypatch.setattr(pipeline, "reduce_record", change_after_read)
    assert main(["process", str(protocol), "--out", str(out), "--no-report", "-q",
                 "--jobs", "1"]) == 0
    first = _runs(out).loc[run, "drag_mean"]
    monkeypatch.setattr(pipeline, "reduce_record", original)
    assert main(["process", str(protocol), "--out", str(out), "--no-report", "-q"]) == 0
    assert abs(_runs(out).loc[run, "drag_mean"] / first - 1.0) > 0.05  # read again


def test_scale_into_a_folder_that_does_not_exist_creates_nothing(tmp_path):
    """`towtank scale --out` into a folder that does not exist makes neither the folder nor a
    .cache in it."""
    protocol = _day(tmp_path)
    target = tmp_path / "nowhere" / "out"
    assert main(["scale", str(protocol), "--out", str(target)]) == 0
    assert not (tmp_path / "nowhere").exists()
