"""Acquisitions appended in one run file (issue #23 item 6): the file's segments are found
where the time restarts or jumps (or at an LVM segment header where it does not continue),
the run sheet's ``segment`` column or ``[read] segment`` says which one is the run, and a file
with several and no choice is rejected in one sentence that lists them; a gap in the time is
said in a unit a person reads (77 s, not 7.7e+04 ms).
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from towtank.errors import ProtocolError, RunError
from towtank.ingest.protocol import ChannelMap, load_protocol
from towtank.ingest.runfile import load_run, time_base
from towtank.ingest.runsheet import read_run_sheet
from towtank.ingest.segments import find_segments, human_duration
from towtank.reduce.run import reduce_record
from towtank.runtime.cache import settings_key
from towtank.testing import synthetic as syn
from towtank.testing.layouts import (
    APPENDED_FIRST_S,
    APPENDED_GAP_S,
    layout_channels,
    protocol_sections,
    write_layout,
)

SEED = 5


def _day(root: Path, file_format: str = "lvm-appended") -> Path:
    syn.make_hull_day(root, seed=SEED, file_format=file_format, sheet_format="csv",
                      channel_style="lab")
    channels = layout_channels(file_format, syn.LabChannels())
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv", channels=channels,
                                          channel_style="lab")
    sections = protocol_sections(file_format, sections)
    return syn.write_protocol(root / "protocol.toml", **sections)


@pytest.fixture(scope="session")
def day(tmp_path_factory):
    root = tmp_path_factory.mktemp("appended")
    protocol = load_protocol(_day(root))
    truth = json.loads((root / "truth.json").read_text())
    sheet = read_run_sheet(root / "run_sheet.csv", 18.0)
    hull = next(r for r in sheet.to_dict("records")
                if r["config"] == "hull" and r["test"] == "steady" and r["speed_nominal"] >= 1.0)
    return root, protocol, truth, hull


# ------------------------------------------------------------------- the generated file
def test_the_second_acquisition_is_the_run_and_recovers_the_truth(day):
    root, protocol, truth, row = day
    assert row["segment"] == 2  # the layout's sheet says so
    run, red, reason, _ = reduce_record(protocol, row)
    assert reason is None, reason
    t = truth["runs"][str(run)]
    # the drag of the steady plateau: model and tare, as the plain day recovers them
    assert red.drag_mean_raw == pytest.approx(t["drag_model"] + t["tare_drag"], abs=3e-3)
    assert red.speed_mean == pytest.approx(t["speed"], rel=2e-3)
    assert red.n_samples == t["n_samples"]
    note = next(n for n in red.notes if n.startswith("segment 2 of 2 read"))
    assert "the file holds 2 acquisitions" in note


def test_without_a_choice_the_run_is_rejected_in_one_sentence(day):
    root, protocol, truth, row = day
    row = {k: v for k, v in row.items() if k != "segment"}
    run, red, reason, _ = reduce_record(protocol, row)
    assert red is None
    reason = str(reason)
    fs = truth["fs"]
    n1 = int(round(APPENDED_FIRST_S * fs))
    n2 = truth["runs"][str(run)]["n_samples"]
    t1 = (n1 - 1) / fs
    lvm_first = 24  # file header (13 lines), segment header (10), column names: data on 24
    assert reason == (
        f"run {run}: {row['file']} holds 2 segments (the time jumps by 77 s at row "
        f"{lvm_first + n1}, from t = {t1:.4f} s to {t1 + APPENDED_GAP_S:.4f} s: a clock "
        "reset, or acquisitions appended to one file): segment 1: rows "
        f"{lvm_first}–{lvm_first + n1 - 1}, {n1} samples, {human_duration(n1 / fs)} (t = "
        f"0.0000–{t1:.4f} s); segment 2: rows {lvm_first + n1}–{lvm_first + n1 + n2 - 1}, "
        f"{n2} samples, {human_duration(n2 / fs)} (t = {t1 + APPENDED_GAP_S:.4f}–"
        f"{t1 + APPENDED_GAP_S + (n2 - 1) / fs:.4f} s); say which one is the run in the run "
        "sheet's 'segment' column (1 = the first) or with [read] segment = N"
    )
    # a segment the file does not have names how many it has
    _, red, reason, _ = reduce_record(protocol, {**row, "segment": 3})
    assert red is None and "segment 3 is chosen, but the file holds 2 segments" in str(reason)


def test_read_segment_is_the_default_and_the_sheet_overrides_it(day, tmp_path):
    root, _, truth, row = day
    text = (root / "protocol.toml").read_text()
    (root / "with_read.toml").write_text(text + "\n[read]\nsegment = 2\n")
    protocol = load_protocol(root / "with_read.toml")
    assert protocol.read.segment == 2
    bare = {k: v for k, v in row.items() if k != "segment"}
    _, red, reason, _ = reduce_record(protocol, bare)
    assert reason is None and red.n_samples == truth["runs"][str(row["run"])]["n_samples"]
    # the sheet's 1 (the balance at rest, 2 s) wins over [read]: no run to reduce in it
    _, red, reason, _ = reduce_record(protocol, {**row, "segment": 1})
    assert red is None and reason is not None
    (root / "zero.toml").write_text(text + "\n[read]\nsegment = 0\n")
    with pytest.raises(ProtocolError, match="'segment' in \\[read\\] counts a file's "
                                            "acquisitions from 1"):
        load_protocol(root / "zero.toml")


def test_the_sheets_segment_is_checked_and_keys_the_cache(day, tmp_path):
    root, protocol, _, row = day
    sheet = pd.read_csv(root / "run_sheet.csv")
    sheet["segment"] = sheet["segment"].astype(object)
    sheet.loc[0, "segment"] = "two"
    sheet.loc[1, "segment"] = 0
    sheet.loc[2, "segment"] = ""
    sheet.to_csv(tmp_path / "sheet.csv", index=False)
    read = read_run_sheet(tmp_path / "sheet.csv", 18.0)
    assert "segment 'two' is not a whole number from 1" in read.loc[0, "sheet_error"]
    assert "segment '0' is not a whole number from 1" in read.loc[1, "sheet_error"]
    assert read.loc[2, "sheet_error"] == "" and pd.isna(read.loc[2, "segment"])
    assert read.loc[3, "segment"] == 2
    keys = {settings_key(protocol, {**row, "segment": k}) for k in (1, 2, math.nan, pd.NA)}
    assert len(keys) == 3  # none given: NaN and <NA> alike


# ------------------------------------------------------------------ segments in general
def _frame(n: int, t0: float = 0.0, fs: float = 200.0, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    return pd.DataFrame({"time": np.round(t0 + np.arange(n) / fs, 9),
                         "speed": np.round(rng.normal(1.0, 0.01, n), 6),
                         "drag": np.round(rng.normal(2.0, 0.05, n), 6)})


def _csv(frame: pd.DataFrame) -> bytes:
    return frame.to_csv(index=False, lineterminator="\n").encode()


def test_a_restart_of_the_clock_is_a_segment_a_lost_stretch_is_not():
    a, b = _frame(1000, seed=1), _frame(600, seed=2)  # the second restarts from 0
    data = _csv(pd.concat([a, b], ignore_index=True))
    for k, part in ((1, a), (2, b)):
        raw = load_run(Path("run.csv"), {}, data=data, segment=k)
        np.testing.assert_array_equal(raw.drag, part["drag"].to_numpy())
        np.testing.assert_allclose(raw.time, part["time"].to_numpy())
    with pytest.raises(RunError, match=r"^run\.csv holds 2 segments \(the time restarts at "
                                       r"row 1002, t = 0\.0000 s after 4\.9950 s"):
        load_run(Path("run.csv"), {}, data=data)
    # 0.5 s lost inside one acquisition: not a new acquisition, and said in ms
    lost = _frame(1000, seed=3).drop(index=range(500, 600))
    with pytest.raises(RunError, match="100 samples are missing after row 501 .*a step of "
                                       "505 ms where the rate is 200.0 Hz"):
        load_run(Path("run.csv"), {}, data=_csv(lost))
    # a one-sample glitch backwards is not a restart
    glitch = _frame(1000, seed=4)
    glitch.loc[700, "time"] = glitch.loc[690, "time"]
    with pytest.raises(RunError, match="time goes backwards at row 702"):
        load_run(Path("run.csv"), {}, data=_csv(glitch))


def test_lvm_segment_headers_split_where_the_time_does_not_continue(tmp_path):
    units = {"time": "s", "speed": "m/s", "drag": "N"}
    # LabVIEW writing each block under its own header, the time continuing: one acquisition
    joined = _frame(800, seed=5)
    write_layout("lvm", joined, tmp_path / "one.lvm", "time", units)
    raw = load_run(tmp_path / "one.lvm", {})
    assert raw.n == 800 and "2 LVM segments joined" in raw.notes
    # relative time: the second block's X_Value restarts from 0 under its header
    two = pd.concat([_frame(400, seed=6), _frame(400, seed=7)], ignore_index=True)
    write_layout("lvm", two, tmp_path / "two.lvm", "time", units)
    with pytest.raises(RunError, match=r"two\.lvm holds 2 segments \(the time restarts at "
                                       r"row 435, t = 0\.0000 s after 1\.9950 s"):
        load_run(tmp_path / "two.lvm", {})
    raw = load_run(tmp_path / "two.lvm", {}, segment=2)
    np.testing.assert_array_equal(raw.drag, two["drag"].to_numpy()[400:])
    # a short jump (0.3 s, under the 1 s of a DAQ restarted by hand) at a header: a segment
    short = pd.concat([_frame(400, seed=8), _frame(400, t0=2.295, seed=9)], ignore_index=True)
    write_layout("lvm", short, tmp_path / "short.lvm", "time", units)
    with pytest.raises(RunError, match="the time jumps by 300 ms at row 435"):
        load_run(tmp_path / "short.lvm", {})


def test_the_gap_is_said_in_a_unit_a_person_reads():
    assert human_duration(77.0005) == "77 s"
    assert human_duration(0.205) == "205 ms"
    assert human_duration(0.0005) == "0.5 ms"
    assert human_duration(119.4) == "119 s"
    assert human_duration(300.0) == "5 min"
    t = np.concatenate([np.arange(100) / 200.0, 0.495 + 77.0 + np.arange(100) / 200.0])
    with pytest.raises(RunError, match=r"a step of 77 s where the rate is 200\.0 Hz"):
        time_base(t, "x.csv", max_gap_s=0.05)
    jitter = np.arange(200) / 200.0
    jitter[100:] += 0.0029  # one step of 7.9 ms at 200 Hz
    with pytest.raises(RunError, match=r"irregular: a step of 7\.9 ms"):
        time_base(jitter, "x.csv")


# every acquisition: (samples, how it follows the previous: restart to 0, jump, continue)
_PIECES = st.lists(st.tuples(st.integers(2, 60), st.sampled_from(["restart", "jump", "on"])),
                   min_size=1, max_size=6)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pieces=_PIECES, fs=st.sampled_from([10.0, 200.0, 2000.0]),
       jump=st.floats(1.5, 1e5))
def test_segments_of_appended_acquisitions_are_found_exactly(pieces, fs, jump):
    """Blocks of regular samples one after another, each restarting the clock from 0,
    jumping forward by a DAQ restart's gap or continuing: a segment starts exactly where a
    block restarts or jumps."""
    times, starts, t_end = [], [], 0.0
    for k, (n, how) in enumerate(pieces):
        if k == 0 or how == "restart":
            t0 = 0.0
        elif how == "jump":
            t0 = t_end + max(jump, 25.0 / fs)
        else:
            t0 = t_end + 1.0 / fs
        if k == 0 or how != "on":
            starts.append(sum(x.size for x in times))
        block = t0 + np.arange(n) / fs
        times.append(block)
        t_end = float(block[-1])
    t = np.concatenate(times)
    segs = find_segments(t)
    assert [s.start for s in segs] == starts
    assert [s.stop for s in segs] == starts[1:] + [t.size]
    assert [s.kind for s in segs[1:]] == [how for k, (n, how) in enumerate(pieces)
                                          if k and how != "on"]


@settings(max_examples=300, deadline=None)
@given(t=st.lists(st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                            st.floats(-1e3, 1e3)), min_size=0, max_size=80),
       headers=st.lists(st.integers(-5, 90), max_size=5))
def test_the_splitter_never_crashes_and_covers_every_row_once(t, headers):
    arr = np.array(t, dtype=np.float64)
    segs = find_segments(arr, headers=np.array(headers, dtype=np.int64),
                         values=np.zeros(arr.size))
    if arr.size == 0:
        assert segs == []
        return
    covered = np.concatenate([np.arange(s.start, s.stop) for s in segs])
    np.testing.assert_array_equal(covered, np.arange(arr.size))
    assert all(s.n > 0 for s in segs)


# --------------------------------------------------------------------------- inspect
def test_inspect_lists_the_segments_and_proposes_the_key(tmp_path):
    from towtank.commands.inspect import inspect_run

    # the lab's names (no channel found): inspect describes the file and proposes a block
    frame = _frame(1200, seed=11).rename(columns={"speed": "Wagen", "drag": "Kraft"})
    write_layout("lvm-appended", frame, tmp_path / "run_001.lvm", "time",
                 {"time": "s", "Wagen": "m/s", "Kraft": "N"})
    out, err = io.StringIO(), io.StringIO()
    inspect_run(tmp_path / "run_001.lvm", png=tmp_path / "p.png", out=out, err=err)
    text = out.getvalue()
    n1 = int(round(APPENDED_FIRST_S * 200.0))
    assert "segments: 2 acquisitions one after another" in text
    assert f"segment 1: rows 24–{23 + n1}, {n1} samples" in text
    assert f"segment 2: rows {24 + n1}–{23 + n1 + 1200}, 1200 samples, 6 s" in text
    assert "segment = 1   # <- which of the file's 2 acquisitions is the run" in text
    # with a protocol that does not choose, the one sentence lists them too
    write_layout("lvm-appended", _frame(1200, seed=11), tmp_path / "run_001.lvm", "time",
                 {"time": "s", "speed": "m/s", "drag": "N"})
    (tmp_path / "p.toml").write_text(_protocol_text(tmp_path))
    out, err = io.StringIO(), io.StringIO()
    assert inspect_run(tmp_path / "run_001.lvm", tmp_path / "p.toml",
                       png=tmp_path / "q.png", out=out, err=err) == 1
    assert "run_001.lvm holds 2 segments (the time jumps by 77 s at row" in err.getvalue()
    assert "segment 2: rows" in err.getvalue()


def _protocol_text(root: Path) -> str:
    (root / "sheet.csv").write_text("run,file,config,angle_deg\n1,run_001.lvm,hull,0\n")
    return (f'[campaign]\nname = "x"\nrun_sheet = "sheet.csv"\ndata_dir = "{root}"\n'
            'output_dir = "out"\n\n[water]\ntemperature_C = 15.0\n\n'
            '[model]\nlength_m = 1.0\ndiameter_m = 0.1\nmass_kg = 8.0\n\n'
            '[tare]\nsource = "none"\n')


# ------------------------------------------------------------------ the real LVM file
KITE = Path(__file__).resolve().parents[2] / "shared" / "real" / "tudelft_kite_lvm"
VW10 = KITE / "normal_aoa_16_vw_10.lvm"


@pytest.mark.skipif(not VW10.exists(), reason="../shared/real/tudelft_kite_lvm is not present "
                    "(real recordings are not kept in the repository)")
def test_the_kite_balance_file_with_two_acquisitions(tmp_path):
    """TU Delft's vw_10 (LabVIEW LVM, 2 kHz, two acquisitions under one header; the time jumps
    from 9.8995 s to 86.9 s): each is read on its own with segment = 1 or 2, its F_X
    ('Untitled') the file's own rows (measured: 25.9934 N and 23.0453 N)."""
    mapping = {"drag": ChannelMap(column="Untitled")}
    with pytest.raises(RunError) as err:
        load_run(VW10, mapping, speed_nominal=10.0)
    assert str(err.value) == (
        "normal_aoa_16_vw_10.lvm holds 2 segments (the time jumps by 77 s at row 19823, from "
        "t = 9.8995 s to 86.9000 s: a clock reset, or acquisitions appended to one file): "
        "segment 1: rows 23–19822, 19800 samples, 9.9 s (t = 0.0000–9.8995 s); segment 2: "
        "rows 19823–39622, 19800 samples, 9.9 s (t = 86.9000–96.7995 s); say which one is the "
        "run in the run sheet's 'segment' column (1 = the first) or with [read] segment = N")
    lines = VW10.read_text().splitlines()
    head = next(k for k, line in enumerate(lines) if line.startswith("X_Value"))
    table = pd.read_csv(VW10, sep="\t", skiprows=head)
    for k, rows in ((1, slice(0, 19800)), (2, slice(19800, 39600))):
        raw = load_run(VW10, mapping, speed_nominal=10.0, segment=k)
        assert raw.n == 19800 and raw.fs == pytest.approx(2000.0)
        np.testing.assert_allclose(raw.time, table["X_Value"].to_numpy()[rows])
        assert raw.drag.mean() == pytest.approx(table["Untitled"].to_numpy()[rows].mean(),
                                                rel=1e-9)


def test_inspect_reads_the_segment_the_run_sheet_gives(day, tmp_path):
    from towtank.commands.inspect import inspect_run

    root, _, truth, row = day
    out, err = io.StringIO(), io.StringIO()
    code = inspect_run(root / "data" / row["file"], root / "protocol.toml",
                       png=tmp_path / "r.png", out=out, err=err)
    assert code == 0, err.getvalue()
    n = truth["runs"][str(row["run"])]["n_samples"]
    assert f"{row['file']}: {n} samples at 200 Hz" in out.getvalue()
    assert "segment 2 of 2 read" in out.getvalue()


def _european(frame: pd.DataFrame) -> bytes:
    body = "\n".join(";".join(f"{v:.9g}".replace(".", ",") for v in row)
                     for row in frame.to_numpy())
    return ("Versuch 12;;\nDatum: 21.05.2024;;\ntime;speed;drag\n" + body + "\n").encode()


def _tdms(frame: pd.DataFrame, path: Path) -> bytes:
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    with TdmsWriter(str(path)) as writer:
        writer.write_segment([RootObject(), GroupObject("data")] + [
            ChannelObject("data", c, frame[c].to_numpy(np.float64)) for c in frame.columns])
    return path.read_bytes()


@pytest.mark.parametrize("layout", ["european text", "tdms"])
def test_every_reader_path_splits_appended_acquisitions(layout, tmp_path):
    a, b = _frame(900, seed=21), _frame(700, t0=40.0, seed=22)  # the second 35.5 s later
    both = pd.concat([a, b], ignore_index=True)
    name, data = (("run.txt", _european(both)) if layout == "european text" else
                  ("run.tdms", _tdms(both, tmp_path / "run.tdms")))
    first, label = (904, "row") if layout == "european text" else (901, "sample")
    with pytest.raises(RunError, match=rf"^{name.replace('.', '[.]')} holds 2 segments \(the "
                                       rf"time jumps by 35\.5 s at {label} {first}, from "
                                       r"t = 4\.4950 s to 40\.0000 s"):
        load_run(Path(name), {}, data=data)
    raw = load_run(Path(name), {}, data=data, segment=2)
    np.testing.assert_allclose(raw.drag, b["drag"].to_numpy())
    assert raw.time[0] == 40.0 and raw.n == 700


def test_lvm_read_line_by_line_keeps_the_segments_and_the_files_rows(tmp_path):
    """A text cell sends an LVM file to the line-by-line reader (not pyarrow): the same
    segments, rows counted as the file's lines."""
    frame = _frame(1200, seed=31)
    path = tmp_path / "run.lvm"
    write_layout("lvm-appended", frame, path, "time", {"time": "s", "speed": "m/s", "drag": "N"})
    lines = path.read_text().splitlines()
    n1 = int(round(APPENDED_FIRST_S * 200.0))
    cells = lines[23 + n1 + 99].split("\t")  # the 100th row of the run
    cells[2] = "overload"
    lines[23 + n1 + 99] = "\t".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RunError, match=rf"jumps by 77 s at row {24 + n1}, .*segment 2: rows "
                                       rf"{24 + n1}–{23 + n1 + 1200}, 1199 samples"):
        load_run(path, {})
    raw = load_run(path, {}, segment=2)
    assert raw.n == 1200  # the dropped row's sample put back
    assert f"1 non-numeric row(s) dropped (row {24 + n1 + 99})" in raw.notes


@pytest.mark.skipif(not VW10.exists(), reason="../shared/real/tudelft_kite_lvm is not present "
                    "(real recordings are not kept in the repository)")
def test_the_kite_file_through_the_sheet_and_the_runs_note(tmp_path):
    """vw_10 as a run of a day: the sheet's segment = 2 picks the second acquisition, and the
    run's note says which rows were read."""
    (tmp_path / "sheet.csv").write_text(
        "run,file,config,angle_deg,speed_nominal,segment\n"
        "1,normal_aoa_16_vw_10.lvm,hull,0,10.0,2\n")
    (tmp_path / "p.toml").write_text(
        f'[campaign]\nname = "kite"\nrun_sheet = "sheet.csv"\ndata_dir = "{KITE}"\n'
        'output_dir = "out"\n\n[water]\ntemperature_C = 15.0\n\n'
        '[model]\nlength_m = 1.0\ndiameter_m = 0.2\nmass_kg = 20.0\n\n'
        '[channels]\ndrag = { column = "Untitled" }\n\n'
        '[processing]\nspeed_source = "nominal"\n\n[tare]\nsource = "none"\n')
    protocol = load_protocol(tmp_path / "p.toml")
    row = read_run_sheet(tmp_path / "sheet.csv", 15.0).to_dict("records")[0]
    row.update(window_start_s=88.0, window_end_s=96.0)
    _, red, reason, _ = reduce_record(protocol, row)
    assert reason is None, reason
    assert ("segment 2 of 2 read (rows 19823–39622, t = 86.9000–96.7995 s; the file holds 2 "
            "acquisitions)") in red.notes
    assert red.n_samples == 19800
