"""Issue 33 ("Trust, third round"), the readers' part: an HDF5 dataset whose values live in
another file (external raw storage, a virtual dataset) rejects its run in one sentence and is
never read, a FIFO behind it included (item 1); a file of very many columns is named in a
sentence by a few of them and their count (item 6; its reading time is measured by
``python -m towtank.testing.bench_read --wide-columns 40000``, not here); a damaged TDMS file
writes nothing to stderr beside its one sentence (item 14); ``towtank inspect`` proposes no
digital input as the speed (item 17).
"""

from __future__ import annotations

import io
import logging
import os
import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from towtank.commands.cli import main
from towtank.errors import ProtocolError, RunError
from towtank.ingest.arrayfiles import read_hdf5_columns, read_mat_columns
from towtank.ingest.describe import describe_file, digital_channel, protocol_block
from towtank.ingest.protocol_types import ChannelMap, SpeedLog
from towtank.ingest.readers import (
    NAMES_SHOWN,
    ReadOptions,
    name_list,
    read_lvm_columns,
    read_tdms_columns,
)
from towtank.ingest.runfile import load_run, map_channels
from towtank.ingest.runsheet import SHEET_COLUMNS_SHOWN, read_run_sheet
from towtank.ingest.speedlog import read_speed_log
from towtank.testing import synthetic as syn
from towtank.testing.bench_read import wide_csv, wide_lvm
from towtank.testing.child import run_in_child
from towtank.testing.days import reading_day_plan
from towtank.testing.layouts import layout_channels, protocol_sections
from towtank.testing.truth import FileFormat

SEED = 33
REAL = Path(__file__).resolve().parents[2] / "shared" / "real"
DIGITAL_TDMS = REAL / "nptdms" / "Digital_Input.tdms"
MARIN = REAL / "marin_fsi_h5m" / "C_SPEED.h5m"
#: Bound on a test that runs towtank in a child process (a hang fails it instead) [s].
CHILD_TIMEOUT_S = 120
#: The day of the tests that process one: they test how run 21's file is read, not the fit,
#: so eleven runs carry it as well as 42; "the rest of the day" is every other run.
PLAN = reading_day_plan()


def _day(root: Path, file_format: FileFormat) -> Path:
    """A synthetic hull day in ``root`` (run files in ``file_format``); its protocol."""
    syn.make_hull_day(root, seed=SEED, file_format=file_format, sheet_format="csv",
                      runs=PLAN)
    channels = layout_channels(file_format, syn.LabChannels())
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv", channels=channels)
    laid_out: dict[str, Any] = protocol_sections(file_format, sections)
    return syn.write_protocol(root / "protocol.toml", **laid_out)


def _process(protocol: Path) -> int:
    return main(["process", str(protocol), "--out", str(protocol.parent / "out"), "-q",
                 "--jobs", "1", "--no-report"])


def _runs(protocol: Path) -> pd.DataFrame:
    return pd.read_csv(protocol.parent / "out" / "runs.csv").set_index("run")


def _only_rejected(protocol: Path, run: int) -> str:
    """The reason of ``run``, after checking that it is the day's only rejected run and that
    the rest of the day was processed."""
    runs = _runs(protocol)
    rejected = runs.index[runs["status"] == "rejected"].tolist()
    assert rejected == [run], runs.loc[rejected, "reason"].to_dict()
    assert (runs["status"] == "ok").sum() == len(PLAN) - 1
    return str(runs.loc[run, "reason"])


def _one_sentence(text: str) -> None:
    assert "\n" not in text.strip() and "Traceback" not in text
    assert "internal error" not in text and "please report" not in text


def _inspect(path: Path, protocol: Path, tmp_path: Path, capsys) -> str:  # noqa: ANN001
    """``towtank inspect`` of one file, in this process: exit 1 and its one sentence."""
    rc = main(["inspect", str(path), "--protocol", str(protocol), "--png",
               str(tmp_path / "x.png")])
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert rc == 1 and len(lines) == 1, err
    assert not (tmp_path / "x.png").exists()
    return lines[0]


def _in_child(*commands: list[str]) -> list[tuple[int, str]]:
    """(exit status, stderr) of each of ``commands`` run in one child process (one start-up
    and import for all) within CHILD_TIMEOUT_S."""
    return [(done.returncode, done.stderr)
            for done in run_in_child(commands, timeout=CHILD_TIMEOUT_S)]


# ========================================== item 1: HDF5 values stored in other files
@pytest.fixture(scope="session")
def hdf5_day(tmp_path_factory) -> tuple[Path, Path]:
    """An HDF5 day written once (copied per test): (its folder, its protocol)."""
    root = tmp_path_factory.mktemp("h5day")
    return root, _day(root, "hdf5")


def _copy_day(src: Path, dst: Path) -> Path:
    import shutil

    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("out"))
    return dst / "protocol.toml"


DRAG = "Fx load cell (V)"


def _external(group, source: Path) -> None:  # noqa: ANN001 - an h5py Group
    """The drag dataset re-made with HDF5 external raw storage in ``source``."""
    values = group[DRAG][()]
    attrs = dict(group[DRAG].attrs)
    if not source.exists():
        source.write_bytes(values.astype("<f8").tobytes())
    del group[DRAG]
    dset = group.create_dataset(DRAG, shape=values.shape, dtype="<f8",
                                external=[(str(source), 0, values.size * 8)])
    dset.attrs.update(attrs)


def _virtual(group, source: Path) -> None:  # noqa: ANN001 - an h5py Group
    """The drag dataset re-made as a virtual dataset mapping the dataset 'x' of ``source``."""
    import h5py

    values = group[DRAG][()]
    attrs = dict(group[DRAG].attrs)
    if not source.exists():
        with h5py.File(source, "w") as fh:
            fh["x"] = values
    layout = h5py.VirtualLayout(shape=values.shape, dtype="f8")
    layout[:] = h5py.VirtualSource(str(source), "x", shape=values.shape)
    del group[DRAG]
    group.create_virtual_dataset(DRAG, layout, fillvalue=0.0)
    group[DRAG].attrs.update(attrs)


def _edit_h5(path: Path, edit, source: Path) -> None:  # noqa: ANN001
    import h5py

    with h5py.File(path, "a") as fh:
        edit(fh["data"], source)


@pytest.mark.parametrize("edit, how", [(_external, "HDF5 external storage in"),
                                       (_virtual, "a virtual dataset mapped from")],
                         ids=["external", "virtual"])
def test_a_dataset_whose_values_are_in_another_file_rejects_its_run(
        hdf5_day, tmp_path, capsys, edit, how):
    """process rejects the run in one sentence naming the dataset and the other file, the rest
    of the day processed; inspect says the same sentence; the other file is never read (its
    edits could never be noticed by the run cache), so editing it changes nothing."""
    protocol = _copy_day(hdf5_day[0], tmp_path / "day")
    run_file = protocol.parent / "data" / "run_021.h5"
    source = tmp_path / "elsewhere.bin"
    _edit_h5(run_file, edit, source)
    assert _process(protocol) == 1
    reason = _only_rejected(protocol, 21)
    _one_sentence(reason)
    assert reason.startswith("run 21: run_021.h5")
    assert f"the dataset '/data/{DRAG}' keeps its values outside the file ({how} " \
           f"'{source}')" in reason, reason
    line = _inspect(run_file, protocol, tmp_path, capsys)
    assert "keeps its values outside the file" in line and str(source) in line


def test_external_storage_naming_a_system_file_is_refused_without_reading_it(tmp_path):
    """/etc/passwd (or any file) as the raw storage of a channel: refused from the dataset's
    creation properties, whatever that file holds."""
    import h5py

    path = tmp_path / "run.h5"
    with h5py.File(path, "w") as fh:
        fh["time"] = np.arange(64) / 100.0
        fh.create_dataset("drag", shape=(8,), dtype="u1", external=[("/etc/passwd", 0, 8)])
    with pytest.raises(RunError, match=r"the dataset '/drag' keeps its values outside the "
                                       r"file \(HDF5 external storage in '/etc/passwd'\)"):
        read_hdf5_columns(path.read_bytes(), "run.h5")


@pytest.fixture(scope="session")
def fifo_days(hdf5_day, tmp_path_factory) -> dict[str, tuple[Path, Path, list]]:
    """A copy of the HDF5 day per way of keeping run 21's drag in a FIFO, and what
    ``inspect`` of that run and ``process`` of the day did in a child process (one for
    both ways: one start-up and import), under a time limit so that a hang fails the tests
    instead of stopping the suite: {way: (protocol, fifo, [(status, stderr) of each])}."""
    days, commands = {}, []
    for way, edit in (("external", _external), ("virtual", _virtual)):
        root = tmp_path_factory.mktemp(f"fifo_{way}")
        protocol = _copy_day(hdf5_day[0], root / "day")
        run_file = protocol.parent / "data" / "run_021.h5"
        fifo = root / "pipe"
        os.mkfifo(fifo)
        _edit_h5(run_file, edit, fifo)
        days[way] = (protocol, fifo)
        commands += [["inspect", str(run_file), "--protocol", str(protocol), "--png",
                      str(root / "x.png")],
                     ["process", str(protocol), "--out", str(protocol.parent / "out"), "-q",
                      "--no-report", "--jobs", "1"]]
    done = _in_child(*commands)
    return {way: (*days[way], done[2 * i : 2 * i + 2]) for i, way in enumerate(days)}


@pytest.mark.heavy
@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes on this system")
@pytest.mark.parametrize("way", ["external", "virtual"])
def test_a_fifo_behind_a_dataset_does_not_hang_inspect_or_process(fifo_days, way):
    """Reading a FIFO blocks until something writes into it: a towtank that read the dataset
    would hang (the commands run in a child process under a time limit: :func:`fifo_days`)."""
    protocol, fifo, [(code, said), (process_code, process_said)] = fifo_days[way]
    assert code == 1, said
    assert "keeps its values outside the file" in said and str(fifo) in said
    assert process_code == 1, process_said
    assert "keeps its values outside the file" in _only_rejected(protocol, 21)


@pytest.mark.skipif(not MARIN.is_file(), reason="../shared/real/marin_fsi_h5m is not present "
                    "(real recordings are not part of the repository)")
def test_the_real_marin_file_still_reads():
    from towtank.ingest.runfile import read_columns

    cols, _ = read_columns(MARIN)
    assert cols["C.SPEED"].size == 357113


# ====================================== item 6: a few names and the count in a sentence
def test_name_list_names_a_few_and_counts_the_rest():
    names = [f"c{i}" for i in range(1, 40_001)]
    assert name_list(names, 3) == "'c1', 'c2', 'c3' and 39,997 more"
    assert name_list(names[:3], 3) == "'c1', 'c2', 'c3'"
    assert name_list([]) == "none"
    assert name_list(["a\nb"]) == "'a\\nb'"  # one line, whatever a name holds


@given(st.lists(st.text(max_size=30), max_size=60), st.integers(1, 10))
def test_name_list_is_one_line_with_at_most_limit_names(names, limit):
    text = name_list(names, limit)
    assert "\n" not in text and "\r" not in text
    rest = len(names) - limit
    assert text.endswith(f" and {rest:,} more") == (rest > 0)


def _listed(sentence: str) -> int:
    """How many quoted names a sentence lists."""
    return len(re.findall(r"'c\d+'", sentence))


def _check_bounded(sentence: str, total: int, shown: int = NAMES_SHOWN) -> None:
    _one_sentence(sentence)
    assert _listed(sentence) <= shown, sentence
    assert f" and {total - shown:,} more" in sentence, sentence
    assert len(sentence) < 600, len(sentence)


N_WIDE = 3000
LAB_MAP = {k: ChannelMap(**v) for k, v in syn.LabChannels().protocol_section().items()}


@pytest.mark.parametrize("make, name", [(wide_lvm, "wide.lvm"), (wide_csv, "wide.csv")])
def test_a_wide_run_file_is_rejected_naming_a_few_columns_and_the_count(make, name):
    with pytest.raises(RunError) as info:
        load_run(Path(name), LAB_MAP, data=make(N_WIDE, 50))
    assert "channel is missing" in str(info.value) and "columns found: " in str(info.value)
    _check_bounded(str(info.value), N_WIDE)


def test_the_wide_lvm_file_reads_every_column():
    cols, _ = read_lvm_columns(wide_lvm(N_WIDE, 50), "wide.lvm")
    names = [c for c in cols if not c.startswith("__")]
    assert names == ["X_Value", *(f"c{j}" for j in range(2, N_WIDE + 1))]
    assert all(cols[c].shape == (50,) for c in names)
    np.testing.assert_allclose(cols["X_Value"], np.arange(50) / 1000.0)


def _wide_cols(n: int = N_WIDE) -> dict[str, np.ndarray]:
    return {f"c{i}": np.zeros(10) for i in range(1, n + 1)}


def test_a_missing_load_cell_of_a_summed_force_names_a_few_columns():
    mapping = {"time": ChannelMap(column="c1"), "speed": ChannelMap(column="c2"),
               "drag": ChannelMap(column="DragL", columns=("DragL", "DragR"))}
    with pytest.raises(RunError) as info:
        map_channels(_wide_cols(), mapping, "run.csv")
    assert "the column 'DragL' of the drag channel is missing" in str(info.value)
    _check_bounded(str(info.value), N_WIDE)


def test_a_speed_log_without_its_column_names_a_few_columns(tmp_path):
    path = tmp_path / "log.csv"
    path.write_bytes(wide_csv(N_WIDE, 20))
    spec = SpeedLog(file="log.csv", time=("time", 1.0, 0.0), speed=("speed", 1.0, 0.0))
    with pytest.raises(RunError) as info:
        read_speed_log(path, spec, path.read_bytes())
    assert "has no column 'speed'" in str(info.value)
    _check_bounded(str(info.value), N_WIDE)


def test_an_hdf5_file_of_many_groups_names_a_few():
    import h5py

    buf = io.BytesIO()
    with h5py.File(buf, "w") as fh:
        for i in range(1, 201):
            fh.create_group(f"c{i}")
    with pytest.raises(RunError) as info:
        read_hdf5_columns(buf.getvalue(), "run.h5", ReadOptions(group="nope"))
    assert "has no group 'nope' (groups: " in str(info.value)
    _check_bounded(str(info.value), 201)  # the root, then c1 ... c200


def test_a_tdms_file_of_many_groups_names_a_few():
    from nptdms import ChannelObject, TdmsWriter

    buf = io.BytesIO()
    with TdmsWriter(buf) as writer:
        writer.write_segment([ChannelObject(f"c{i}", "x", np.zeros(4)) for i in range(1, 201)])
    with pytest.raises(RunError) as info:
        read_tdms_columns(buf.getvalue(), "run.tdms", ReadOptions(group="nope"))
    assert "has no TDMS group 'nope' (groups: " in str(info.value)
    _check_bounded(str(info.value), 200)


def test_a_mat_file_of_many_structs_or_variables_names_a_few():
    import scipy.io

    buf = io.BytesIO()
    scipy.io.savemat(buf, {f"c{i}": {"x": np.zeros(3)} for i in range(1, 201)})
    with pytest.raises(RunError) as info:
        read_mat_columns(buf.getvalue(), "run.mat", ReadOptions(group="nope"))
    assert "has no struct 'nope' (structs: " in str(info.value)
    _check_bounded(str(info.value), 200)
    buf = io.BytesIO()
    scipy.io.savemat(buf, {f"c{i}": "text" for i in range(1, 201)})
    with pytest.raises(RunError) as info:
        read_mat_columns(buf.getvalue(), "run.mat")
    assert len(re.findall(r"c\d+", str(info.value))) <= NAMES_SHOWN
    assert "and 194 more" in str(info.value)


def test_a_run_sheet_of_many_columns_names_a_few(tmp_path):
    path = tmp_path / "sheet.csv"
    columns = ["run", "file", "config"] + [f"c{i}" for i in range(1, 2001)]
    path.write_text(",".join(columns) + "\n" + ",".join(["1", "r.csv", "hull"] + ["0"] * 2000)
                    + "\n")
    with pytest.raises(ProtocolError) as info:
        read_run_sheet(path, 18.0)
    text = str(info.value)
    assert "lacks the required column(s) angle_deg" in text
    assert len(re.findall(r"\bc\d+\b", text)) <= SHEET_COLUMNS_SHOWN - 3
    assert f"and {len(columns) - SHEET_COLUMNS_SHOWN:,} more" in text and len(text) < 600


def test_inspect_of_a_wide_file_lists_a_few_unrecognised_columns(tmp_path):
    path = tmp_path / "wide.lvm"
    path.write_bytes(wide_lvm(N_WIDE, 50))
    block = protocol_block(describe_file(path))
    line = next(ln for ln in block.splitlines() if ln.startswith("# not recognised"))
    assert _listed(line) <= NAMES_SHOWN and "more" in line and len(line) < 300


# ============================================== item 14: a damaged TDMS file is quiet
@pytest.fixture(scope="session")
def tdms_day(tmp_path_factory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("tdmsday")
    return root, _day(root, "tdms")


SEGMENT_ROWS = 25


def _in_segments(data: bytes) -> bytes:
    """The TDMS file rewritten as LabVIEW streams it: one segment per ``SEGMENT_ROWS``
    samples (a run of 3500 samples: 140 segments)."""
    from nptdms import ChannelObject, TdmsFile, TdmsWriter

    tdms = TdmsFile.read(io.BytesIO(data))
    channels = [(g.name, c.name, c[:], dict(c.properties)) for g in tdms.groups()
                for c in g.channels()]
    n = min(c[2].size for c in channels)
    buf = io.BytesIO()
    with TdmsWriter(buf) as writer:
        for i in range(0, n, SEGMENT_ROWS):
            writer.write_segment([ChannelObject(g, c, v[i:i + SEGMENT_ROWS],
                                                properties=p if i == 0 else None)
                                  for g, c, v, p in channels])
    return buf.getvalue()


def _segments(data: bytes) -> list[int]:
    return [m.start() for m in re.finditer(b"TDSm", data)]


def _cut_mid_segment(data: bytes) -> bytes:
    starts = _segments(data)
    middle = starts[len(starts) // 2]
    return data[: middle + 28 + (starts[len(starts) // 2 + 1] - middle - 28) // 2]


def _bad_next_offset(data: bytes) -> bytes:
    """The lead-in of a segment in the middle declaring its segment runs past the file's end."""
    out = bytearray(data)
    at = _segments(data)[len(_segments(data)) // 3]
    out[at + 12 : at + 20] = (len(data) * 4).to_bytes(8, "little")
    return bytes(out)


def _bad_versions(data: bytes) -> bytes:
    """The version number of every segment's lead-in but the first changed (npTDMS warns once
    per segment), the data left whole."""
    out = bytearray(data)
    for at in _segments(data)[1:]:
        out[at + 8 : at + 12] = (4713).to_bytes(4, "little")  # npTDMS writes 4712
    return bytes(out)


def _bad_tags(data: bytes) -> bytes:
    out = bytearray(data)
    for at in _segments(data)[1:]:
        out[at : at + 4] = b"TDSx"
    return bytes(out)


def _quiet(capfd, caplog) -> None:  # noqa: ANN001
    """Nothing of npTDMS on stderr (its own handler) or in the log records (root's)."""
    err = capfd.readouterr().err
    assert "nptdms" not in err.lower() and "segment" not in err.lower(), err[:2000]
    assert not [r for r in caplog.records if r.name.startswith("nptdms")]


@pytest.mark.parametrize("damage, words", [
    (_cut_mid_segment, "is cut short inside a TDMS segment (npTDMS: 'Last segment of file has "
                       "less data than expected"),
    (_bad_next_offset, "is cut short inside a TDMS segment (npTDMS: 'Last segment of file has "
                       "less data than expected"),
    (_bad_tags, "is not a readable TDMS file (ValueError: Segment does not start with"),
], ids=["cut", "lead-in-offset", "lead-in-tag"])
def test_a_damaged_tdms_file_gives_its_sentence_and_nothing_on_stderr(
        tdms_day, tmp_path, capfd, caplog, damage, words):
    protocol = _copy_day(tdms_day[0], tmp_path / "day")
    run_file = protocol.parent / "data" / "run_021.tdms"
    run_file.write_bytes(damage(_in_segments(run_file.read_bytes())))
    caplog.set_level(logging.DEBUG)
    capfd.readouterr()
    assert _process(protocol) == 1
    _quiet(capfd, caplog)
    reason = _only_rejected(protocol, 21)
    _one_sentence(reason)
    assert words in reason, reason
    assert "finished?" in reason or "ValueError" in reason
    rc = main(["inspect", str(run_file), "--protocol", str(protocol), "--png",
               str(tmp_path / "x.png")])
    captured = capfd.readouterr()
    lines = [ln for ln in captured.err.splitlines() if ln.strip()]
    assert rc == 1 and len(lines) == 1 and words in lines[0], captured.err[:2000]
    assert "nptdms" not in captured.out.lower()
    assert not [r for r in caplog.records if r.name.startswith("nptdms")]


def test_npTDMS_warnings_on_a_file_read_whole_are_one_note(tdms_day, tmp_path, capfd, caplog):
    """Every segment's lead-in with the wrong version number: the values are read whole, so
    the run is used; npTDMS's 139 warnings are one note, none on stderr."""
    caplog.set_level(logging.DEBUG)
    run_file = tdms_day[0] / "data" / "run_021.tdms"
    segmented = _in_segments(run_file.read_bytes())
    good, _ = read_tdms_columns(segmented, "run_021.tdms")
    capfd.readouterr()
    cols, notes = read_tdms_columns(_bad_versions(segmented), "run_021.tdms")
    _quiet(capfd, caplog)
    n = len(_segments(segmented)) - 1
    assert notes == [f"npTDMS: 'Segment version mismatch, 4713 != 4712' and {n - 1:,} more "
                     "warnings"]
    for key in good:
        if not key.startswith("__"):
            np.testing.assert_array_equal(cols[key], good[key])


def test_other_log_records_of_npTDMS_still_reach_their_handlers(caplog):
    """Outside a towtank read, npTDMS's loggers are as npTDMS made them."""
    caplog.set_level(logging.WARNING)
    read_tdms_columns(_bad_versions(_in_segments(_tiny_tdms())), "x.tdms")
    logging.getLogger("nptdms.reader").warning("a record outside a read")
    assert [r.getMessage() for r in caplog.records if r.name.startswith("nptdms")] == \
        ["a record outside a read"]


def _tiny_tdms() -> bytes:
    from nptdms import ChannelObject, TdmsWriter

    buf = io.BytesIO()
    with TdmsWriter(buf) as writer:
        writer.write_segment([ChannelObject("g", "x", np.arange(100.0))])
    return buf.getvalue()


# ============================================= item 17: a digital input is not a speed
@pytest.mark.parametrize("name, values, digital", [
    ("Carriage start", np.r_[np.zeros(50), np.ones(50)].astype(np.uint8), True),
    ("Trigger level", np.r_[np.zeros(50), np.ones(50)], True),
    ("Encoder state", np.tile([0.0, 1.0, 2.0, 3.0], 25), True),
    ("Dev1/port0/line3", np.zeros(100), True),
    ("Dev1_port3_line7 - line 0", np.zeros(100), True),
    ("Digital in", np.linspace(0, 1, 100), True),
    ("flag", np.zeros(100, dtype=bool), True),
    ("Carriage speed (m/s)", np.r_[np.zeros(20), np.linspace(0, 1.5, 60), np.full(20, 1.5)],
     False),
    ("Carriage speed (m/s)", np.zeros(100), False),  # at rest all along: a speed still
    ("Fx (N)", np.round(np.random.default_rng(0).normal(size=100) * 100), False),
    ("Fx (N)", np.array(["a", "b"], dtype=object), False),
    ("Velocità di carrello (m/s)", np.linspace(0, 1, 100), False),  # "di": a word, not DI0
    ("Speed (m/s)", np.array([0.0, 1.0, 1.0]), False),  # too few samples to say
])
def test_digital_channels(name, values, digital):
    assert digital_channel(name, values) is digital


def _tdms_with_a_digital_line(path: Path) -> Path:
    """A run's channels with a digital input first, named as a carriage line, recorded as
    LabVIEW stores a digital line (uint8, 0 and 1)."""
    from nptdms import ChannelObject, TdmsWriter

    n = 400
    t = np.arange(n) / 100.0
    speed = np.clip((t - 1.0) * 0.5, 0.0, 1.0)
    with TdmsWriter(path) as writer:
        writer.write_segment([
            ChannelObject("g", "Carriage start", (t > 1.0).astype(np.uint8)),
            ChannelObject("g", "Trigger level", (t > 1.5).astype(np.uint8)),
            ChannelObject("g", "Time (s)", t),
            ChannelObject("g", "Carriage speed (m/s)", speed),
            ChannelObject("g", "Fx (N)", 2.0 * speed**2),
        ])
    return path


def test_inspect_proposes_the_analog_speed_not_a_digital_line(tmp_path):
    desc = describe_file(_tdms_with_a_digital_line(tmp_path / "run.tdms"))
    assert desc.guesses["speed"] == "Carriage speed (m/s)"
    assert desc.digital == ["Carriage start", "Trigger level"]
    block = protocol_block(desc)
    assert 'speed = { column = "Carriage speed (m/s)" }' in block
    assert "# digital inputs, mapped to no channel: 'Carriage start', 'Trigger level'" in block


@pytest.mark.skipif(not DIGITAL_TDMS.is_file(), reason="../shared/real/nptdms is not present "
                    "(real recordings are not part of the repository)")
def test_the_real_digital_input_file_proposes_no_speed():
    """npTDMS's Digital_Input.tdms: one DAQmx digital line (uint8 0/1) in three groups, one
    of them 'Decimated Data_Level1' (the 'vel' in 'Level' once made it the speed)."""
    desc = describe_file(DIGITAL_TDMS)
    assert "speed" not in desc.guesses and len(desc.digital) == 4
    assert "speed =" not in protocol_block(desc)


def test_inspect_of_a_wide_file_prints_a_bounded_account(tmp_path, capsys):
    """inspect of a 2,000-column file: its channel listing and its summary stop after a few
    dozen names and count the rest; no line of what it prints carries the whole list."""
    path = tmp_path / "wide.lvm"
    path.write_bytes(wide_lvm(2000, 50))
    main(["inspect", str(path), "--png", str(tmp_path / "wide.png")])
    out = capsys.readouterr()
    text = out.out + out.err
    assert "and 1,936 more channels (not listed)" in text
    assert len(text.splitlines()) < 120 and max(len(ln) for ln in text.splitlines()) < 700
