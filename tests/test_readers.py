"""Run files as other labs record them: each layout of the same synthetic day (file formats,
two load cells per force, a balance's interaction matrix) gives the same coefficients as the
plain CSV day, and the text, LVM, TDMS, MATLAB and HDF5 readers find what the lab wrote
(timing, separators, decimal commas, units) or say in one sentence what is wrong.
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import towtank
from towtank.errors import RunError
from towtank.ingest.protocol import ChannelMap
from towtank.ingest.readers import ReadOptions, read_text_columns, stated_units
from towtank.ingest.runfile import load_run, read_columns
from towtank.testing import synthetic as syn
from towtank.testing.layouts import LAYOUTS, layout_channels, protocol_sections

SEED = 5
TOLERANCE = 1e-3  # relative: "the same coefficients within 0.1 %"


def _day(root: Path, file_format: str, channel_style: str = "lab") -> Path:
    syn.make_hull_day(root, seed=SEED, file_format=file_format, sheet_format="csv",
                      channel_style=channel_style)
    channels = layout_channels(file_format, syn.LabChannels())
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv", channels=channels,
                                          channel_style=channel_style)
    sections = protocol_sections(file_format, sections)
    return syn.write_protocol(root / "protocol.toml", **sections)


@pytest.fixture(scope="session")
def plain(tmp_path_factory):
    root = tmp_path_factory.mktemp("csv")
    day = towtank.process_day(_day(root, "csv"), jobs=1)
    truth = json.loads((root / "truth.json").read_text())
    return day, truth


@pytest.mark.heavy
@pytest.mark.parametrize("layout", sorted(LAYOUTS))
def test_every_layout_gives_the_plain_days_coefficients(layout, plain, tmp_path):
    base, truth = plain
    day = towtank.process_day(_day(tmp_path, layout), jobs=1)
    assert not day.rejected, day.rejected
    got = day.coefficients.set_index("symbol")["value"]
    ref = base.coefficients.set_index("symbol")["value"]
    rel = ((got - ref) / ref.abs()).abs()
    if layout == "no-speed":
        # the sheet's set speeds and steady windows, no acceleration: no added masses; the
        # damping from other windows and a zero drifted by the force alone: each interval
        # overlaps the plain day's and holds the truth
        assert not {"X_udot", "Y_vdot"} & set(got.index)
        mine = day.coefficients.set_index("symbol")
        table = base.coefficients.set_index("symbol").loc[got.index]
        half = (table["ci_high"] - table["ci_low"] + mine["ci_high"] - mine["ci_low"]) / 2
        assert ((got - ref[got.index]).abs() / half).max() < 1.0, (
            (got - ref[got.index]).abs() / half).to_dict()
        for sym in got.index:
            assert mine.loc[sym, "ci_low"] <= truth["coefficients"][sym] <= mine.loc[sym,
                                                                                     "ci_high"]
        for sym in ("X_u|u|", "Y_v|v|"):
            assert got[sym] == pytest.approx(truth["coefficients"][sym], rel=0.02)
        return
    if layout == "zero-file":
        # a zeros file is another recording of the zero (other noise samples, the raw mean
        # of 1.5 s rather than the filtered still window): the same within half of
        # each coefficient's interval, not to 0.1 %
        table = base.coefficients.set_index("symbol")
        half = (table["ci_high"] - table["ci_low"]) / 2
        assert ((got - ref).abs() / half).max() < 0.5, ((got - ref).abs() / half).to_dict()
    else:
        assert rel.max() < TOLERANCE, rel.to_dict()
    # and the truth as the plain day finds it (the existing tolerances of tests/test_fit.py).
    # A zeros file of 1.5 s is a noisier zero than the run's 2 s filtered still window, and
    # X_udot, from six accelerated runs, carries it: its error on zero-file days is 1.2-1.3 %
    # rms (8 seeds, plain or tapered mean of the zeros file; -1.8 % and -2.1 % on this seed),
    # so it is held to the 5 % of tests/test_fit.py there, not 2 %
    for sym in ("X_udot", "Y_vdot", "X_u|u|", "Y_v|v|"):
        rel_tol = 0.05 if layout == "zero-file" and sym == "X_udot" else 0.02
        assert got[sym] == pytest.approx(truth["coefficients"][sym], rel=rel_tol)


@pytest.mark.heavy
def test_european_text_in_canonical_units_is_converted(tmp_path, plain):
    """';' separators, decimal commas, a preamble and a units row; the speed in mm/s."""
    protocol = _day(tmp_path, "txt-eu", channel_style="canonical")
    text = (tmp_path / "data" / "run_013.txt").read_text(encoding="latin-1").splitlines()
    assert text[0].startswith("Lab B") and text[4].split(";")[1] == "mm/s"
    assert "," in text[5] and ";" in text[5]
    raw = towtank.read_run(tmp_path / "data" / "run_013.txt", protocol)
    assert 0.5 < np.nanmax(raw.speed) < 3.0  # m/s, converted from mm/s
    assert any("mm/s" in n for n in raw.notes)
    day = towtank.process_day(protocol, jobs=1)
    ref = plain[0].coefficients.set_index("symbol")["value"]
    got = day.coefficients.set_index("symbol")["value"]
    assert (((got - ref) / ref.abs()).abs() < TOLERANCE).all()


def test_waveform_tdms_has_no_time_channel_and_is_timed_by_its_properties(tmp_path):
    from nptdms import TdmsFile

    protocol = _day(tmp_path, "tdms-waveform")
    f = tmp_path / "data" / "run_013.tdms"
    tdms = TdmsFile.read(f)
    names = [c.name for c in tdms.groups()[0].channels()]
    assert not any("time" in n.lower() for n in names)
    inc = tdms.groups()[0].channels()[0].properties["wf_increment"]
    raw = towtank.read_run(f, protocol)
    assert raw.fs == pytest.approx(1.0 / inc, rel=1e-9)
    assert raw.time[0] == pytest.approx(0.0, abs=1e-9)


def test_missing_time_names_every_way_to_give_it(tmp_path):
    f = tmp_path / "r.csv"
    f.write_text("speed,drag\n" + "\n".join(f"{i * 0.01},{i}" for i in range(50)) + "\n")
    with pytest.raises(RunError, match=r"waveform timing .* sample_rate_hz"):
        load_run(f, {})
    raw = load_run(f, {}, options=ReadOptions(sample_rate_hz=100.0))
    assert raw.fs == pytest.approx(100.0) and raw.time[-1] == pytest.approx(0.49)


def test_decimal_comma_is_named_not_counted_as_text(tmp_path):
    """A decimal comma in a ';' file is read (never "71800 of 71800 rows are not numeric")."""
    f = tmp_path / "r.csv"
    rows = "\n".join(f"{i / 100:.2f};{i / 1000:.3f};{i / 10:.1f}".replace(".", ",")
                     for i in range(200))
    f.write_text("time;speed;drag\n" + rows + "\n")
    raw = load_run(f, {}, do_despike=False)
    assert raw.fs == pytest.approx(100.0) and raw.drag[-1] == pytest.approx(19.9)


def test_wrong_group_and_unknown_extension_are_one_sentence(tmp_path):
    protocol = _day(tmp_path, "hdf5")
    f = tmp_path / "data" / "run_013.h5"
    with pytest.raises(RunError, match=r"no group 'nope' \(groups: "):
        read_columns(f, options=ReadOptions(group="nope"))
    odd = tmp_path / "r.xyz"
    odd.write_bytes(b"1,2,3\n")
    with pytest.raises(RunError, match=r"does not know the format of a '\.xyz' file"):
        read_columns(odd)
    assert towtank.read_run(f, protocol).fs == pytest.approx(200.0)


def test_drag_left_in_millivolts_is_caught(tmp_path):
    f = tmp_path / "r.csv"
    f.write_text("time,speed,drag (mV)\n" + "\n".join(f"{i / 100},{1.0},{i}" for i in range(50)))
    with pytest.raises(RunError, match=r"drag column 'drag \(mV\)' is recorded in mV: give its "
                                       r"calibration"):
        load_run(f, {"drag": ChannelMap(column="drag (mV)")})


def test_lvm_segments_are_joined(tmp_path):
    protocol = _day(tmp_path, "lvm")
    f = tmp_path / "data" / "run_013.lvm"
    assert f.read_text().count("***End_of_Header***") == 3  # file header and two segments
    cols, notes = read_columns(f)
    assert "2 LVM segments joined" in notes
    raw = towtank.read_run(f, protocol)
    assert np.all(np.diff(raw.time) > 0)
    assert stated_units(cols)["Carriage speed (m/s)"] == "m/s"


# ------------------------------------------------------------------ property: text detection
_field = st.floats(min_value=-1e4, max_value=1e4, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.lists(st.tuples(_field, _field, _field), min_size=5, max_size=40),
    delim=st.sampled_from([",", ";", "\t", " "]),
    decimal=st.sampled_from([".", ","]),
    preamble=st.lists(st.text(alphabet="abcdefghij :-/", min_size=1, max_size=20),
                      max_size=3),
    units=st.booleans(),
)
def test_text_layout_round_trips(data, delim, decimal, preamble, units):
    """Whatever separator, decimal mark, preamble and units row a lab's export uses, the
    columns come back as written."""
    if delim == "," and decimal == ",":
        decimal = "."
    if delim == " ":
        preamble = [p.replace(" ", "_") for p in preamble]

    def fmt(v: float) -> str:
        return repr(v).replace(".", decimal)

    lines = [p for p in preamble if p.strip()]
    lines.append(delim.join(["time", "speed", "drag"]))
    if units:
        lines.append(delim.join(["s", "m/s", "N"]))
    lines += [delim.join(fmt(v) for v in row) for row in data]
    cols, _ = read_text_columns(("\n".join(lines) + "\n").encode(), "x.txt")
    got = np.column_stack([cols["time"], cols["speed"], cols["drag"]]).astype(float)
    np.testing.assert_allclose(got, np.array(data), rtol=1e-12, atol=0)
    if units:
        assert stated_units(cols) == {"time": "s", "speed": "m/s", "drag": "N"}


def test_plain_csv_keeps_the_fast_path():
    from towtank.ingest.readers import plain_csv

    ok = b"time,speed,drag\n" + b"\n".join(b"%d,1.0,2.0" % i for i in range(20))
    assert plain_csv(ok)
    assert not plain_csv(b"Lab B\nDate: 1.1.2024\n" + ok)
    assert not plain_csv(b"time;speed;drag\n" + b"\n".join(b"%d;1,5;2,0" % i for i in range(20)))
    assert not plain_csv(ok.replace(b"time,speed,drag\n", b"time,speed,drag\ns,m/s,N\n"))
    frame = pd.read_csv(io.BytesIO(ok))
    assert list(frame.columns) == ["time", "speed", "drag"]


def test_inspect_says_what_an_unknown_file_holds_and_prints_a_protocol_block(tmp_path):
    """`towtank inspect` on a LabVIEW file without a protocol: format, timing, channels with
    units, and a [read]/[channels] block with which it reduces the run (issue 22: exit 0, no
    "time channel is missing" after naming the file's timing)."""
    import io as _io
    import tomllib

    from towtank.commands.inspect import inspect_run

    _day(tmp_path, "tdms-waveform")
    f = tmp_path / "data" / "run_013.tdms"
    out, err = _io.StringIO(), _io.StringIO()
    assert inspect_run(f, png=tmp_path / "x.png", out=out, err=err) == 0, err.getvalue()
    text = out.getvalue()
    assert "tdms file" in text and "LabVIEW waveform timing" in text and "200 Hz" in text
    assert "'Carriage speed (m/s)'" in text and "m/s" in text
    assert "reduced with the block above" in text and "steady means" in text
    block = text[text.index("[read]"):text.index("reduced with the block above")]
    parsed = tomllib.loads(block)
    assert parsed["read"]["format"] == "tdms"
    assert parsed["channels"]["speed"]["column"] == "Carriage speed (m/s)"
    assert parsed["channels"]["drag"]["column"] == "Fx load cell (V)"
    assert err.getvalue() == ""


def test_balance_matrix_and_summed_cells_are_validated(tmp_path):
    from towtank.ingest.protocol import load_protocol

    base = _day(tmp_path, "matrix").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(base.replace("matrix = [[20.0, 0.3], [-0.2, -25.0]]", "matrix = [[20.0, 0.3]]"))
    with pytest.raises(towtank.ProtocolError, match=r"'matrix' in \[balance\] must have one row "
                                                    r"per output \(2\)"):
        load_protocol(bad)
    bad.write_text(base + '\n[channels.drag]\ncolumn = "Fx (V)"\n')
    with pytest.raises(towtank.ProtocolError, match="given both by \\[balance\\] and by"):
        load_protocol(bad)
    both = _day(tmp_path / "cells", "two-cell").read_text().replace(
        'columns = ["DragL (V)", "DragR (V)"]', 'columns = ["DragL (V)"], column = "x"')
    bad.write_text(both)
    with pytest.raises(towtank.ProtocolError, match="either 'column' .* or 'columns'"):
        load_protocol(bad)


def test_two_cells_are_summed(tmp_path):
    protocol = _day(tmp_path, "two-cell")
    frame = pd.read_csv(tmp_path / "data" / "run_021.csv")
    left, right = frame["DragL (V)"].to_numpy(), frame["DragR (V)"].to_numpy()
    # the cells share the load unevenly, and the share changes with the lift
    assert np.mean(np.abs(left - right)) > 0.1 * np.mean(np.abs(left + right))
    assert np.std(left / (left + right)) > 0.01
    raw = towtank.read_run(tmp_path / "data" / "run_021.csv", protocol)
    np.testing.assert_allclose(raw.drag, 20.0 * (left + right), rtol=0, atol=1e-6)
