"""One front door (issue #34 item 1): ``towtank process``, :func:`towtank.process_day` and
``towtank watch`` run a day through :mod:`towtank.runner` and write the same outputs; and
:func:`towtank.read_run` / :func:`towtank.reduce_run` read and reduce a run as the day does.

The three front doors are driven in this process on both sample days, with the report, and
every file of the three output folders is compared byte for byte. What legitimately differs,
and only that, is set aside by name:

- :data:`BOOKKEEPING`: towtank's own folders beside the outputs (the run cache with the
  replay record, watch's live page), which are not outputs;
- the manifest's times (:data:`MANIFEST_TIMES`): when each file was written;
- provenance.json's ``watch`` entry (:data:`WATCH_ENTRY`): which runs watch's PDF covers
  (and so the manifest's size and sha256 of watch's provenance.json).

The command and the watch start from a copy of the API's run cache (the runs are then not
reduced three times; the cache gives the runs as they were reduced). On the sample days the
API's folder is the session's ``sample_report`` (the day written once, shared with the golden
comparison).
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import towtank
from towtank.commands.cli import main
from towtank.ingest.protocol import load_protocol
from towtank.ingest.runsheet import read_run_sheet
from towtank.live.session import WatchSession, watch_options
from towtank.reduce.run import reduce_record
from towtank.runner import prepare
from towtank.runtime.manifest import MANIFEST
from towtank.testing import synthetic as syn
from towtank.testing.layouts import layout_channels, protocol_sections

ROOT = Path(__file__).resolve().parents[1]
SAMPLE_DAYS = ("sut2_hull.toml", "naca0015_fin.toml")

#: Folders beside the outputs that are towtank's bookkeeping, not outputs.
BOOKKEEPING = (".cache", ".live")
#: The manifest's entries that say when a file was written.
MANIFEST_TIMES = ("mtime_ns", "written")
#: provenance.json's entry that only watch writes.
WATCH_ENTRY = "watch"
#: Bounds a hang of the watch session only.
HANG_S = 120.0


def _files(out: Path) -> dict[str, bytes]:
    """Every file in ``out`` (the bookkeeping folders aside) by its path in ``out``."""
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and p.relative_to(out).parts[0] not in BOOKKEEPING}


def _without_times(value: object) -> object:
    if isinstance(value, dict):
        return {k: _without_times(v) for k, v in value.items() if k not in MANIFEST_TIMES}
    if isinstance(value, list):
        return [_without_times(v) for v in value]
    return value


def _seed_cache(src: Path, dst: Path) -> None:
    shutil.copytree(src / ".cache", dst / ".cache", ignore=shutil.ignore_patterns("day.json"))


def _watch(protocol: Path, out: Path, *, report: bool = True) -> None:
    """``towtank watch`` of a day whose files are all there, until its outputs and report
    cover every run of the sheet; one job, as the other two doors are run here."""
    plan = prepare(protocol, out, watch_options(jobs=1, report=report))
    lines: list[str] = []
    session = WatchSession(plan, echo=lines.append, live_figures=False)
    try:
        end = time.monotonic() + HANG_S
        session.step()
        while session.day is None or len(session.day.runs) < len(session.sheet):
            assert time.monotonic() < end, lines
            session.clock = lambda: time.time() + 3600.0  # the files have settled
            session.step()
        session.finish()
    finally:
        session.close()
    assert not session.pdf_stale


def _three_front_doors(protocol: Path, root: Path, *, report: bool = True,
                       api: Path | None = None) -> dict[str, Path]:
    """The day written by ``towtank process``, :func:`towtank.process_day` and the watch;
    ``api``: the folder :func:`towtank.process_day` already wrote (with its run cache)."""
    cli, watched = root / "cli", root / "watch"
    if api is None:
        api = root / "api"
        towtank.process_day(protocol, out=api, report=report, jobs=1)
    # one job, as the API's day was run: the runs come from its run cache, so a worker pool
    # would be started for nothing (the outputs do not depend on the jobs)
    flags = ["--jobs", "1", *([] if report else ["--no-report"])]
    _seed_cache(api, cli)
    assert main(["process", str(protocol), "--out", str(cli), "-q", *flags]) in (0, 1)
    _seed_cache(api, watched)
    _watch(protocol, watched, report=report)
    return {"cli": cli, "api": api, "watch": watched}


def _assert_the_same_files(cli: Path, api: Path, watched: Path) -> None:
    """Every file of the three output folders the same, byte for byte, but for what is set
    aside by name (the module's text)."""
    want = _files(cli)
    for out in (api, watched):
        got = _files(out)
        assert sorted(got) == sorted(want), out.name
        for rel, data in want.items():
            if rel == MANIFEST:
                listed, wanted = json.loads(got[rel]), json.loads(data)
                if out is watched:  # provenance.json with its watch entry, listed as it is
                    (mine,) = listed["files"].pop("provenance.json")
                    assert mine["sha256"] == hashlib.sha256(got["provenance.json"]).hexdigest()
                    del wanted["files"]["provenance.json"]
                assert _without_times(listed) == _without_times(wanted), out.name
            elif rel == "provenance.json" and out is watched:
                entries = json.loads(got[rel])
                entry = entries.pop(WATCH_ENTRY)
                assert entry["pdf_current"] is ("report.pdf" in want)  # the PDF: every run
                assert entries == json.loads(data)
            else:
                assert got[rel] == data, f"{out.name}/{rel}"


@pytest.mark.heavy
@pytest.mark.parametrize("name", SAMPLE_DAYS)
def test_process_the_api_and_watch_write_the_same_files(name, tmp_path, capsys, sample_report):
    api = sample_report(name.removesuffix(".toml")).out  # towtank.process_day, report=True
    outs = _three_front_doors(ROOT / "protocols" / name, tmp_path, api=api)
    assert {"report.pdf", "report.xlsx", "provenance.json", MANIFEST} <= set(_files(outs["cli"]))
    _assert_the_same_files(outs["cli"], outs["api"], outs["watch"])


@pytest.mark.heavy
def test_every_front_door_records_a_file_only_the_protocol_names(tmp_path, capsys):
    """A tare table ([tare] source = "table"): read when the protocol is loaded, named by no
    run; it is an input of the day in provenance.json whichever front door ran the day."""
    syn.make_hull_day(tmp_path, seed=3, file_format="csv", sheet_format="csv")
    u = np.linspace(0.2, 2.2, 6)
    (tmp_path / "tare.csv").write_text("speed_m_s,drag_N\n" + "".join(
        f"{x},{0.02 * x * x + 0.01 * x}\n" for x in u))
    protocol = syn.write_protocol(tmp_path / "p.toml", **syn.hull_protocol_sections(
        ".", "out", sheet_format="csv"))
    protocol.write_text(protocol.read_text() + '\n[tare]\nsource = "table"\n'
                        'table = "tare.csv"\n')
    outs = _three_front_doors(protocol, tmp_path / "outs", report=False)
    for name, out in outs.items():
        inputs = json.loads((out / "provenance.json").read_text())["inputs"]
        assert str(tmp_path / "tare.csv") in [i["path"] for i in inputs], name
    _assert_the_same_files(outs["cli"], outs["api"], outs["watch"])


# ------------------------------------------------------------------ one run, as the day
def _pre_tare(protocol: Path, run: int):  # noqa: ANN202 - RunReduction
    """The day's reduction of ``run`` before its tare: the work unit of the day's workers
    on the run sheet's row."""
    p = load_protocol(protocol)
    sheet = read_run_sheet(p.campaign.run_sheet, p.water.temperature_C, p.sheet,
                           air=p.water.is_air)
    row = next(r for r in sheet.to_dict("records") if int(r["run"]) == run)
    _, red, reason, _ = reduce_record(p, row)
    assert reason is None, reason
    return red, row


def _assert_same_reduction(api_red, day_red) -> None:  # noqa: ANN001
    assert api_red.drag_mean_raw == day_red.drag_mean_raw
    assert api_red.speed_mean == day_red.speed_mean
    assert api_red.windows == day_red.windows
    assert api_red.notes == day_red.notes
    assert api_red.warnings == day_red.warnings
    assert api_red.units == day_red.units


@pytest.mark.parametrize("run", [21, 41])  # a steady run and an accel run
def test_read_run_and_reduce_run_give_the_days_reduction(run):
    protocol = ROOT / "protocols" / "sut2_hull.toml"
    day_red, row = _pre_tare(protocol, run)
    path = load_protocol(protocol).campaign.data_dir / str(row["file"])
    red = towtank.reduce_run(towtank.read_run(path, protocol, run=run), protocol, run=run)
    _assert_same_reduction(red, day_red)
    assert red.file == day_red.file


def test_an_unmapped_force_channel_is_noted_as_the_day_notes_it(tmp_path):
    """A two-cell day with only the left cell mapped: the right cell's note and warning."""
    syn.make_hull_day(tmp_path, seed=7, file_format="two-cell", sheet_format="csv",
                      channel_style="lab")
    sections = protocol_sections("two-cell", syn.hull_protocol_sections(
        ".", "out", sheet_format="csv", channels=layout_channels("two-cell", syn.LabChannels()),
        channel_style="lab"))
    sections["channels"]["drag"] = {"column": "DragL (V)", "gain": 20.0}
    protocol = syn.write_protocol(tmp_path / "half.toml", **sections)
    day_red, row = _pre_tare(protocol, 21)
    assert any("'DragR (V)' looks like a force" in w for w in day_red.warnings)
    raw = towtank.read_run(tmp_path / "data" / str(row["file"]), protocol)  # run: the sheet's
    _assert_same_reduction(towtank.reduce_run(raw, protocol, run=21), day_red)


def test_the_run_number_comes_from_the_sheet_not_the_file_name(tmp_path):
    """Carriage logs named by run number (``log_{run}.csv``) and a run file whose name has
    other digits (``take9.csv`` is run 5): read_run finds run 5's log, as the day does."""
    syn.make_hull_day(tmp_path, seed=11, file_format="speed-log", sheet_format="csv",
                      channel_style="lab")
    sections = protocol_sections("speed-log", syn.hull_protocol_sections(
        ".", "out", sheet_format="csv", channels=layout_channels("speed-log",
                                                                 syn.LabChannels()),
        channel_style="lab"))
    sections["speed_log"]["file"] = "log_{run}.csv"
    data = tmp_path / "data"
    sheet = pd.read_csv(tmp_path / "run_sheet.csv", dtype=str, keep_default_na=False)
    for run, file in zip(sheet["run"], sheet["file"], strict=True):
        stem = file.split(".", 1)[0]
        if (data / f"{stem}_carriage.csv").is_file():
            (data / f"{stem}_carriage.csv").rename(data / f"log_{int(run)}.csv")
    i = int(sheet.index[sheet["run"].astype(int) == 5][0])
    (data / sheet.loc[i, "file"]).rename(data / "take9.csv")
    sheet.loc[i, "file"] = "take9.csv"
    sheet.to_csv(tmp_path / "run_sheet.csv", index=False)
    protocol = syn.write_protocol(tmp_path / "logs.toml", **sections)
    day_red, _row = _pre_tare(protocol, 5)
    raw = towtank.read_run(data / "take9.csv", protocol)
    red = towtank.reduce_run(raw, protocol, run=5)
    _assert_same_reduction(red, day_red)
    assert math.isfinite(red.speed_mean) and np.isfinite(raw.speed).all()


# ------------------------------------------------------------------ nothing changes a result
def test_writing_with_an_export_leaves_the_given_day_as_it_was(tmp_path, monkeypatch,
                                                                sample_report):
    """A run that cannot be exported is a warning of the day as written (its summary says
    it), on a new DayResult: the day given to the writers is not changed."""
    from towtank.report import outputs
    from towtank.runner import summary

    day = sample_report("naca0015_fin").day
    before = [str(w) for w in day.warnings]
    planted = "run 3: run_003.csv: could not be exported (planted)"
    monkeypatch.setattr(outputs, "export_runs", lambda d, folder, formats: [planted])
    written = outputs.write_day_outputs(day, tmp_path / "out", report=False, export=("mat",))
    assert [str(w) for w in day.warnings] == before
    assert [str(w) for w in written.warnings] == [*before, planted]
    assert f"warning: {planted}" in summary(written, tmp_path / "out")
