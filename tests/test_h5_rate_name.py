"""A sample rate written only in an HDF5 name (MARIN's ``/200.05 Hz/C.SPEED``), and what
``inspect`` says about a run's timing (#23 item 7): the rate is found from a group's or
dataset's name when the file states none, two different rates in names are refused in one
sentence, the source is in the run's notes and ``[read] sample_rate_hz`` outranks it; inspect
reports the timing used (never "none found" or 1000 Hz over a stated rate) and lists no
``time`` channel that an LVM file does not have.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import towtank
from towtank.commands.inspect import inspect_run
from towtank.errors import RunError
from towtank.ingest.arrayfiles import FS_NAME_KEY, rate_from_names, rates_in_name
from towtank.ingest.describe import describe_file, protocol_block
from towtank.ingest.protocol import ChannelMap
from towtank.ingest.readers import FS_ERROR_KEY, FS_KEY, ReadOptions
from towtank.ingest.runfile import load_run, read_columns
from towtank.testing import synthetic as syn
from towtank.testing.layouts import layout_channels, protocol_sections

REAL = Path(__file__).resolve().parents[1] / ".." / "shared" / "real"
MARIN = REAL / "marin_fsi_h5m" / "C_SPEED.h5m"
KITE = REAL / "tudelft_kite_lvm" / "normal_aoa_16_vw_20.lvm"


# ------------------------------------------------------------------ the parser of names
@pytest.mark.parametrize(("name", "rate"), [
    ("200.05 Hz", 200.05), ("200Hz", 200.0), ("fs=200", 200.0), ("1 kHz", 1000.0),
    ("FS = 1.2kHz", 1200.0), ("run_500Hz_b", 500.0), ("dt=5 ms", 200.0), ("dt=0.005", 200.0),
    ("sample_rate: 2e3", 2000.0), ("250 S/s", 250.0), ("2 MHz", 2e6),
])
def test_a_rate_written_in_a_name_is_read(name, rate):
    got = rates_in_name(name)
    assert len(got) == 1 and got[0][0] == pytest.approx(rate, rel=1e-12), got


@pytest.mark.parametrize("name", ["C.SPEED", "run 3", "x200Hz", "50 mHz", "0 Hz", "Hz",
                                  "fs=0", "dt=0 s", "1e999 Hz", "fs = fast", ""])
def test_names_without_a_rate_give_none(name):
    assert rates_in_name(name) == []


def test_two_different_rates_are_refused_and_the_same_rate_twice_is_one():
    rate, where, why = rate_from_names([("group", "/200 Hz"), ("dataset", "/200 Hz/Fx 100Hz")])
    assert rate is None and where is None
    assert why == ("its group and dataset names state different sample rates (200 Hz in the "
                   "name of the group '/200 Hz', 100Hz in the name of the dataset "
                   "'/200 Hz/Fx 100Hz')")
    rate, where, why = rate_from_names([("group", "/fs=200"), ("dataset", "/fs=200/Fx 200 Hz")])
    assert rate == 200.0 and why is None and where == "'fs=200' in the name of the group '/fs=200'"


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=60))
def test_any_name_gives_a_list_of_positive_rates_never_an_error(name):
    for rate, text in rates_in_name(name):
        assert np.isfinite(rate) and rate > 0 and text in name


_RATE = st.floats(min_value=1e-2, max_value=1e7, allow_nan=False, allow_infinity=False)
_FORMS = {
    "g Hz": lambda r: (f"{r:g} Hz", float(f"{r:g}")),
    "repr Hz": lambda r: (f"{r!r}Hz", r),
    "fs=": lambda r: (f"fs={r!r}", r),
    "kHz": lambda r: (f"{r / 1e3!r} kHz", float(repr(r / 1e3)) * 1e3),
    "dt=": lambda r: (f"dt={1 / r!r}", 1 / float(repr(1 / r))),
    "S/s": lambda r: (f"{r!r} S/s", r),
}


@settings(max_examples=200, deadline=None)
@given(rate=_RATE, form=st.sampled_from(sorted(_FORMS)),
       before=st.sampled_from(["", "run_", "C.SPEED ", "/", "Exp3 "]),
       after=st.sampled_from(["", "_x", " gain half", ")"]))
def test_a_formatted_rate_round_trips(rate, form, before, after):
    text, expected = _FORMS[form](rate)
    got = rates_in_name(before + text + after)
    assert len(got) == 1, (before + text + after, got)
    assert got[0][0] == pytest.approx(expected, rel=1e-12)


# ------------------------------------------------------------------ the HDF5 reader
def _h5(path: Path, group: str, datasets: dict[str, np.ndarray],
        attrs: dict[str, object] | None = None) -> Path:
    with h5py.File(path, "w") as fh:
        grp = fh.create_group(group) if group != "/" else fh
        for k, v in (attrs or {}).items():
            grp.attrs[k] = v
        for k, v in datasets.items():
            grp.create_dataset(k, data=v)
    return path


def _run_columns(n: int = 2000, fs: float = 200.0) -> dict[str, np.ndarray]:
    """A tow sampled at ``fs``: still, ramp to 1 m/s, steady, ramp down, still."""
    t = np.arange(n) / fs
    u = np.interp(t, [0, 2, 3, 7, 8, t[-1]], [0, 0, 1, 1, 0, 0])
    return {"speed": u, "drag": 5.0 * u * np.abs(u) + 0.3}


def test_the_rate_in_a_group_name_gives_the_time_and_is_noted(tmp_path):
    f = _h5(tmp_path / "run_001.h5m", "exp/200.05 Hz", _run_columns(fs=200.05))
    cols, _ = read_columns(f)
    assert float(cols[FS_KEY][0]) == 200.05
    raw = load_run(f, {})
    assert raw.fs == pytest.approx(200.05, rel=1e-9)
    assert raw.time[1] - raw.time[0] == pytest.approx(1 / 200.05, rel=1e-12)
    assert "time from the sample rate 200.05 Hz, '200.05 Hz' in the name of the group " \
           "'/exp/200.05 Hz' (the file has no time channel)" in raw.notes
    assert raw.time_source == "200.05 Hz, '200.05 Hz' in the name of the group '/exp/200.05 Hz'"


def test_a_rate_attribute_and_a_time_dataset_outrank_a_name(tmp_path):
    f = _h5(tmp_path / "a.h5", "100 Hz", _run_columns(), {"fs": 200.0})
    cols, _ = read_columns(f)
    assert float(cols[FS_KEY][0]) == 200.0 and FS_NAME_KEY not in cols
    assert not any("name" in n for n in load_run(f, {}).notes)
    cols = {**_run_columns(), "time": np.arange(2000) / 200.0}
    raw = load_run(_h5(tmp_path / "b.h5", "100 Hz", cols), {})
    assert raw.fs == pytest.approx(200.0) and raw.time_source == "the column 'time'"


def test_read_sample_rate_outranks_a_name_and_says_so(tmp_path):
    f = _h5(tmp_path / "r.h5", "100 Hz", _run_columns())
    raw = load_run(f, {}, options=ReadOptions(sample_rate_hz=200.0))
    assert raw.fs == pytest.approx(200.0)
    assert raw.time_source == "[read] sample_rate_hz = 200 Hz"
    assert any("[read] sample_rate_hz = 200 Hz" in n and "says 100 Hz" in n for n in raw.notes)


def test_two_rates_in_names_reject_the_run_in_one_sentence_unless_the_protocol_decides(
        tmp_path):
    cols = _run_columns()
    f = _h5(tmp_path / "run_021.h5m", "200 Hz", {"speed": cols["speed"],
                                                 "drag 100Hz": cols["drag"]})
    assert FS_ERROR_KEY in read_columns(f)[0]
    mapping = {"drag": ChannelMap(column="drag 100Hz")}
    with pytest.raises(RunError) as info:
        load_run(f, mapping)
    text = str(info.value)
    assert text.startswith("run_021.h5m has no time column, and its group and dataset names "
                           "state different sample rates (200 Hz in the name of the group "
                           "'/200 Hz', 100Hz in the name of the dataset '/200 Hz/drag 100Hz')")
    assert text.count(". ") == 0 and "sample_rate_hz" in text
    raw = load_run(f, mapping, options=ReadOptions(sample_rate_hz=200.0))
    assert raw.fs == pytest.approx(200.0)
    assert "time from [read] sample_rate_hz = 200 Hz (the file has no time channel, and its " \
           "group and dataset names state different sample rates (200 Hz in the name of the " \
           "group '/200 Hz', 100Hz in the name of the dataset '/200 Hz/drag 100Hz'))" in raw.notes


@pytest.mark.skipif(not MARIN.is_file(), reason="../shared/real/marin_fsi_h5m is not present "
                    "(real recordings are not part of the repository)")
def test_the_real_marin_file_rate_is_found_in_its_group_name():
    """MARIN basin export (EAGRE FSI_Experiments, C_SPEED.h5m): one dataset 'C.SPEED' in the
    group '/200.05 Hz', 357 113 samples, no attribute (the .pan summary says 200 Hz)."""
    cols, _ = read_columns(MARIN)
    assert float(cols[FS_KEY][0]) == 200.05
    assert cols[FS_NAME_KEY].item() == "'200.05 Hz' in the name of the group '/200.05 Hz'"
    assert cols["C.SPEED"].size == 357113
    desc = describe_file(MARIN)
    assert desc.fs == 200.05 and "none found" not in desc.timing
    assert desc.timing.startswith("200.05 Hz from '200.05 Hz' in the name of the group")
    block = protocol_block(desc)
    assert "sample_rate_hz" not in block and 'speed = { column = "C.SPEED" }' in block


# ------------------------------------------------------------------ the generated layout
def _day(root: Path, layout: str) -> Path:
    syn.make_hull_day(root, seed=5, file_format=layout, sheet_format="csv")
    channels = layout_channels(layout, syn.LabChannels())
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv", channels=channels)
    return syn.write_protocol(root / "protocol.toml", **protocol_sections(layout, sections))


@pytest.fixture(scope="session")
def rate_name_day(tmp_path_factory):
    root = tmp_path_factory.mktemp("rate_name")
    return root, _day(root, "hdf5-rate-name")


def test_the_generated_layout_has_its_rate_only_in_the_group_name(rate_name_day):
    root, protocol = rate_name_day
    f = root / "data" / "run_013.h5m"
    with h5py.File(f, "r") as fh:
        assert list(fh) == ["200.00 Hz"] and not dict(fh.attrs)
        assert not dict(fh["200.00 Hz"].attrs) and "time" not in " ".join(fh["200.00 Hz"])
    raw = towtank.read_run(f, protocol)
    assert raw.fs == pytest.approx(200.0)
    assert any("'200.00 Hz' in the name of the group '/200.00 Hz'" in n for n in raw.notes)


def test_the_generated_layout_recovers_the_truth(rate_name_day):
    root, protocol = rate_name_day
    day = towtank.process_day(protocol, jobs=1)
    assert not day.rejected, day.rejected
    truth = json.loads((root / "truth.json").read_text())["coefficients"]
    table = day.coefficients.set_index("symbol")
    for sym in ("X_u|u|", "Y_v|v|"):
        assert table.loc[sym, "ci_low"] <= truth[sym] <= table.loc[sym, "ci_high"], sym
        assert table.loc[sym, "value"] == pytest.approx(truth[sym], rel=0.02)


def test_one_file_per_channel_with_the_speed_file_as_a_log_without_time(tmp_path):
    """MARIN's one file per channel: the forces' file is the run file, the carriage speed's
    file (its own group '/200.00 Hz', no time) the [speed_log]; the day gives the truth."""
    import tomllib

    root = tmp_path / "day"
    protocol = _day(root, "hdf5-rate-name")
    speed_col = layout_channels("hdf5-rate-name", syn.LabChannels()).speed
    for f in sorted((root / "data").glob("run_*.h5m")):
        with h5py.File(f, "r+") as fh:
            grp = fh["200.00 Hz"]
            speed = grp[speed_col][()]
            del grp[speed_col]
        _h5(f.with_name(f"{f.name.split('.')[0]}_speed.h5m"), "200.00 Hz", {"C.SPEED": speed})
    text = protocol.read_text()
    sections = tomllib.loads(text)
    assert "speed" in sections["channels"]
    head, rest = text.split("[channels]\n", 1)
    body = "\n".join(ln for ln in rest.splitlines() if not ln.startswith("speed ="))
    protocol.write_text(head + "[channels]\n" + body + "\n\n[speed_log]\n"
                        'file = "{stem}_speed.h5m"\nspeed = { column = "C.SPEED" }\n')
    day = towtank.process_day(protocol, jobs=1)
    assert not day.rejected, day.rejected
    truth = json.loads((root / "truth.json").read_text())["coefficients"]
    table = day.coefficients.set_index("symbol")
    for sym in ("X_u|u|", "Y_v|v|"):
        assert table.loc[sym, "ci_low"] <= truth[sym] <= table.loc[sym, "ci_high"], sym


def test_a_speed_log_without_time_or_timing_is_one_sentence(tmp_path):
    from towtank.ingest.speedlog import SpeedLog, read_speed_log

    f = _h5(tmp_path / "log.h5", "carriage", {"v": np.linspace(0, 1, 50)})
    spec = SpeedLog(file="log.h5", time=None, speed=("v", 1.0, 0.0))
    with pytest.raises(RunError, match=r"^the speed log log\.h5 has no timing of its own: give "
                                       r"\[speed_log\] time = "):
        read_speed_log(f, spec, f.read_bytes())


# ------------------------------------------------------------------ inspect
def test_inspect_with_a_protocol_says_where_the_time_comes_from(rate_name_day, tmp_path):
    root, protocol = rate_name_day
    out = io.StringIO()
    assert inspect_run(root / "data" / "run_013.h5m", protocol, tmp_path / "p.png", out=out,
                       err=io.StringIO()) == 0
    text = out.getvalue()
    assert "timing: 200 Hz, '200.00 Hz' in the name of the group '/200.00 Hz'" in text
    given = tmp_path / "given.toml"
    given.write_text(protocol.read_text().replace("[channels]", "[read]\nsample_rate_hz = "
                                                  "200.0\n\n[channels]", 1))
    out = io.StringIO()
    assert inspect_run(root / "data" / "run_013.h5m", given, tmp_path / "q.png", out=out,
                       err=io.StringIO()) == 0
    assert "timing: [read] sample_rate_hz = 200 Hz" in out.getvalue()
    assert "none found" not in out.getvalue()


def test_describe_uses_the_protocols_rate_and_never_proposes_1000_hz_over_it(tmp_path):
    f = _h5(tmp_path / "bare.h5", "data", {"Speed": np.ones(300), "Drag": np.ones(300)})
    bare = describe_file(f)
    assert bare.timing.startswith("none found")
    assert "sample_rate_hz = 1000.0" in protocol_block(bare)
    desc = describe_file(f, ReadOptions(sample_rate_hz=250.0))
    assert desc.timing == "[read] sample_rate_hz = 250 Hz (the protocol's), no time channel"
    assert desc.fs == 250.0
    block = protocol_block(desc)
    assert "sample_rate_hz = 250.0\n" in block and "1000" not in block
    named = _h5(tmp_path / "named.h5", "500 Hz", {"Speed": np.ones(300)})
    desc = describe_file(named, ReadOptions(sample_rate_hz=250.0))
    assert desc.timing.endswith("'500 Hz' in the name of the group '/500 Hz' says 500 Hz")
    assert "none found" not in describe_file(named).timing
    assert "sample_rate_hz" not in protocol_block(describe_file(named))


def test_inspect_lists_no_time_channel_an_lvm_file_does_not_have(tmp_path):
    root = tmp_path / "lvm"
    _day(root, "lvm")
    f = root / "data" / "run_013.lvm"
    cols, _ = read_columns(f)
    assert "time" not in cols and "X_Value" in cols
    desc = describe_file(f)
    assert [c for c, _, _ in desc.channels][0] == "X_Value"
    assert "time" not in [c for c, _, _ in desc.channels]
    assert desc.timing.startswith("the column 'X_Value' (LabVIEW's X_Value, the time of the "
                                  "first channel), 200 Hz")
    lines = desc.lines()
    assert any("'X_Value'" in ln and ln.endswith("<- the time") for ln in lines)
    assert not any(ln.strip().startswith("'time'") for ln in lines)
    raw = load_run(f, {"speed": ChannelMap(column="Carriage speed (m/s)"),
                       "drag": ChannelMap(column="Fx load cell (V)", gain=20.0)})
    assert raw.fs == pytest.approx(200.0) and "time" not in raw.columns
    assert raw.time_source.startswith("the column 'X_Value' (LabVIEW's X_Value")


def test_an_lvm_time_computed_from_delta_x_is_described_as_such(tmp_path):
    head = ("LabVIEW Measurement\t\nSeparator\tTab\nDecimal_Separator\t.\n"
            "***End_of_Header***\t\n\nChannels\t2\t\nX0\t0.0\t0.0\nDelta_X\t0.005\t0.005\n"
            "***End_of_Header***\t\nX_Value\tspeed\tdrag\tComment\n")
    rows = "".join(f"\t{0.01 * k:.3f}\t{0.1 * k:.2f}\t\n" for k in range(100))
    f = tmp_path / "r.lvm"
    f.write_text(head + rows)
    desc = describe_file(f)
    assert "computed from the segment headers' X0 and Delta_X" in desc.timing
    assert "200 Hz" in desc.timing and "time" not in [c for c, _, _ in desc.channels]
    assert load_run(f, {}, do_despike=False).fs == pytest.approx(200.0)


@pytest.mark.skipif(not KITE.is_file(), reason="../shared/real/tudelft_kite_lvm is not present "
                    "(real recordings are not part of the repository)")
def test_the_real_kite_lvm_is_described_without_a_time_channel():
    desc = describe_file(KITE)
    names = [c for c, _, _ in desc.channels]
    assert "time" not in names and names[0] == "X_Value" and len(names) == 7
    assert desc.fs == pytest.approx(2000.0) and "X_Value" in desc.timing
    assert 'time = { column = "X_Value" }' in protocol_block(desc)


def test_every_nested_group_is_looked_at(tmp_path):
    """The group holding the most channels is found however deep (h5py's visit stops at the
    first callback that returns something: every group must be noted, not only the first)."""
    f = tmp_path / "nested.h5"
    with h5py.File(f, "w") as fh:
        fh.create_group("a").create_dataset("x", data=np.ones(20))
        deep = fh.create_group("b/c/500 Hz")
        for k in ("speed", "drag", "lift"):
            deep.create_dataset(k, data=np.ones(20))
    cols, _ = read_columns(f)
    assert {"speed", "drag", "lift"} <= set(cols) and float(cols[FS_KEY][0]) == 500.0
    cols, _ = read_columns(f, options=ReadOptions(group="/b/c/500 Hz"))
    assert "drag" in cols


def test_a_note_every_run_carries_is_listed_once_in_the_report():
    import pandas as pd

    from towtank.report.quality import shared_notes

    same = "time from the sample rate 200 Hz, '200.00 Hz' in the name of the group '/200.00 Hz'"
    notes = pd.DataFrame({"run": [1, 2, 3, 5], "notes": [
        same, f"{same}; 3 spikes removed", same, f"2 rows dropped; {same}"]})
    shared, own = shared_notes(notes)
    assert shared == {same: [1, 2, 3, 5]}
    assert own == {2: ["3 spikes removed"], 5: ["2 rows dropped"]}
    few = pd.DataFrame({"run": [1, 2], "notes": [same, same]})
    assert shared_notes(few) == ({}, {1: [same], 2: [same]})
