"""Channels without a unit label (issue 23 item 8): each channel read records where its unit came
from (the file, the protocol, or assumed: SI), and the day says once which channels had no unit
label in which files and what was taken; a protocol that states the unit silences it.

Synthetic: the generator's run in every layout (units in a units row, TDMS ``unit_string``, LVM
``Y_Unit_Label``, HDF5 attributes; none in a plain CSV or a MATLAB v5 struct), and the hull day
written as plain CSV with canonical headers (``time,speed,drag,lift``: no unit anywhere). Real:
the TU Delft kite LVM (six channels without unit labels) from ../shared/real when present.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

import towtank
from towtank.commands.inspect import inspect_run
from towtank.errors import ProtocolError
from towtank.ingest.protocol import ChannelMap, ReadOptions, load_protocol
from towtank.ingest.runfile import load_run
from towtank.testing import synthetic as syn
from towtank.testing.layouts import LAYOUTS

KITE = Path(__file__).resolve().parents[2] / "shared" / "real" / "tudelft_kite_lvm"
SILENCE = "state `unit` in [channels] to silence this"


@pytest.fixture(scope="session")
def frame():
    return syn.simulate_run("hull", 0.0, 1.2, 0.5, fs=200.0, rng=3)[0]


@pytest.mark.parametrize("layout, expected", [
    ("lvm", {"time": "file", "speed": "file", "drag": "file", "lift": "file"}),
    ("txt-eu", {"time": "file", "speed": "file", "drag": "file", "lift": "file"}),
    ("hdf5", {"time": "file", "speed": "file", "drag": "file", "lift": "file"}),
    ("tdms-waveform", {"time": "file", "speed": "file", "drag": "file", "lift": "file"}),
    ("mat", {"time": "assumed", "speed": "assumed", "drag": "assumed", "lift": "assumed"}),
    ("mat73", {"time": "file", "speed": "assumed", "drag": "assumed", "lift": "assumed"}),
    ("csv", {"time": "assumed", "speed": "assumed", "drag": "assumed", "lift": "assumed"}),
    ("tdms", {"time": "file", "speed": "file", "drag": "file", "lift": "file"}),
])
def test_each_reader_says_where_each_unit_came_from(tmp_path, frame, layout, expected):
    if layout in LAYOUTS:
        path = syn.write_run_file(frame, tmp_path / f"run_001.{LAYOUTS[layout]}", layout=layout)
    else:
        path = syn.write_run_file(frame, tmp_path / f"run_001.{layout}")
    raw = load_run(path, {}, options=ReadOptions())
    assert {c: src for c, (_, src) in raw.units.items()} == expected
    si = {"time": "s", "speed": "m/s", "drag": "N", "lift": "N"}
    for c, (unit, src) in raw.units.items():
        if src == "assumed":
            assert unit == si[c]
    if layout == "txt-eu":  # the speed in mm/s, stated in the units row, converted
        assert raw.units["speed"] == ("mm/s", "file")
        np.testing.assert_allclose(raw.speed.max(), frame["speed"].max(), rtol=1e-3)


def test_a_unit_stated_in_the_protocol_is_used_and_recorded(tmp_path, frame):
    path = syn.write_run_file(frame, tmp_path / "run_001.csv")
    plain = load_run(path, {}, options=ReadOptions())
    kilo = load_run(path, {"drag": ChannelMap(column="drag", unit="kN")}, options=ReadOptions())
    assert kilo.units["drag"] == ("kN", "protocol") and plain.units["drag"] == ("N", "assumed")
    np.testing.assert_allclose(kilo.drag, 1000.0 * plain.drag, rtol=1e-12)
    assert kilo.units["lift"] == ("N", "assumed")
    # a gain is the protocol's calibration too: not an assumption
    gained = load_run(path, {"drag": ChannelMap(column="drag", gain=2.0, calibrated=True)},
                      options=ReadOptions())
    assert gained.units["drag"][1] == "protocol"
    # the API's reduction carries them, and the run's note names what was assumed
    red = towtank.reduce_run(kilo, file="run_001.csv")
    assert red.units == kilo.units
    assert "time, speed and lift had no unit label: time taken as s; speed taken as m/s; lift " \
        "taken as N" in red.notes


def test_the_protocol_unit_replaces_the_files_with_a_note(tmp_path, frame):
    path = syn.write_run_file(frame, tmp_path / "run_001.txt", layout="txt-eu")  # speed in mm/s
    read = load_run(path, {}, options=ReadOptions())
    told = load_run(path, {"speed": ChannelMap(column="speed", unit="cm/s")},
                    options=ReadOptions())
    assert told.units["speed"] == ("cm/s", "protocol")
    np.testing.assert_allclose(told.speed, 10.0 * read.speed, rtol=1e-12)
    assert 'speed: the file states mm/s; [channels] unit = "cm/s" is used' in told.notes


def test_a_label_towtank_does_not_convert_is_said(tmp_path, frame):
    """'lbs' is not a unit towtank converts (lbf is): the values are taken as N, and the run's
    note and the day's sentence say so (not "from the file")."""
    path = tmp_path / "run_001.csv"
    frame.rename(columns={"drag": "drag (lbs)"}).to_csv(path, index=False)
    raw = load_run(path, {"drag": ChannelMap(column="drag (lbs)")}, options=ReadOptions())
    assert raw.units["drag"] == ("lbs", "unknown")
    np.testing.assert_allclose(raw.drag, frame["drag"], atol=1e-9)  # taken as N
    red = towtank.reduce_run(raw, file="run_001.csv")
    assert "drag's unit label 'lbs' is not one towtank converts: taken as N" in red.notes
    from towtank.analysis.daywide import unit_label_sentences

    said = unit_label_sentences([(r, f"run_{r:03d}.csv", raw.units) for r in (1, 2, 3)])
    assert said == [
        f"time, speed and lift had no unit label in 3 run files (run_001.csv … run_003.csv): "
        f"time taken as s; speed taken as m/s; lift taken as N; {SILENCE}.",
        f"drag's unit label 'lbs' is not one towtank converts in 3 run files (run_001.csv … "
        f"run_003.csv): taken as N; {SILENCE}."]


def test_a_unit_towtank_cannot_convert_is_refused(tmp_path):
    syn.make_hull_day(tmp_path, seed=3, file_format="csv", sheet_format="csv",
                      channel_style="canonical")
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv",
                                          channel_style="canonical")
    sections["channels"] = {"drag": {"column": "drag", "unit": "V"}}
    path = syn.write_protocol(tmp_path / "p.toml", **sections)
    with pytest.raises(ProtocolError, match=r"'unit' in \[channels.drag\] is 'V'.*gain"):
        load_protocol(path)
    sections["channels"] = {"drag": {"column": "drag", "unit": "V", "gain": 20.0}}
    assert load_protocol(syn.write_protocol(path, **sections)).channels["drag"].unit == "V"


@pytest.fixture(scope="session")
def bare_day(tmp_path_factory):
    """The hull day as plain CSV with canonical headers: no unit label anywhere."""
    root = tmp_path_factory.mktemp("bare")
    syn.make_hull_day(root, seed=3, file_format="csv", sheet_format="csv",
                      channel_style="canonical")
    return root


def _protocol(root: Path, name: str, units: dict[str, str]) -> Path:
    sections = syn.hull_protocol_sections(".", f"out_{name}", sheet_format="csv",
                                          channel_style="canonical")
    if units:
        sections["channels"] = {c: {"column": c, "unit": u} for c, u in units.items()}
    return syn.write_protocol(root / f"{name}.toml", **sections)


def test_a_day_without_unit_labels_says_so_once(bare_day):
    day = towtank.process_day(_protocol(bare_day, "bare", {}), jobs=1, report=False)
    said = [w for w in map(str, day.warnings) if "had no unit label" in w]
    files = sorted(r.file for r in day.reductions.values())
    n = len(files)
    assert n > 3
    assert said == [
        f"time, speed, drag and lift had no unit label in {n} run files ({files[0]} … "
        f"{files[-1]}): time taken as s; speed taken as m/s; drag and lift taken as N; "
        f"{SILENCE}."]
    assert all(r.units["drag"] == ("N", "assumed") for r in day.reductions.values())
    notes = day.runs.set_index("run")["notes"]
    assert all("had no unit label" in notes[r] for r in day.reductions)
    # the report's quality page: the day's sentence once, not once more per run
    from towtank.report.quality import quality_flow

    items = [text for _, text in quality_flow(day).items]
    assert [t for t in items if "had no unit label" in t] == said
    # time and speed stated: the sentence names only the forces
    day = towtank.process_day(_protocol(bare_day, "forces", {"time": "s", "speed": "m/s"}),
                              jobs=1, report=False)
    said = [w for w in map(str, day.warnings) if "had no unit label" in w]
    assert said == [f"drag and lift had no unit label in {n} run files ({files[0]} … "
                    f"{files[-1]}): taken as N; {SILENCE}."]


def test_units_stated_in_the_protocol_silence_the_note(bare_day):
    units = {"time": "s", "speed": "m/s", "drag": "N", "lift": "N"}
    day = towtank.process_day(_protocol(bare_day, "stated", units), jobs=1, report=False)
    assert not [w for w in map(str, day.warnings) if "unit label" in w]
    assert not any("unit label" in str(n) for n in day.runs["notes"])
    assert all(src == "protocol" for r in day.reductions.values()
               for _, src in r.units.values())


def test_a_day_with_labelled_units_has_no_note(tmp_path):
    syn.make_hull_day(tmp_path, seed=3, file_format="tdms", sheet_format="csv",
                      channel_style="canonical")
    day = towtank.process_day(_protocol(tmp_path, "tdms", {}), jobs=1, report=False)
    assert not [w for w in map(str, day.warnings) if "unit label" in w]
    assert all(src == "file" for r in day.reductions.values() for _, src in r.units.values())


def _kite_protocol(root: Path) -> Path:
    (root / "sheet.csv").write_text(
        "run,file,config,angle_deg,speed_nominal,window_start_s,window_end_s\n"
        "1,normal_aoa_16_vw_20.lvm,hull,0,19.8,1.0,9.0\n")
    path = root / "p.toml"
    path.write_text(
        f'[campaign]\nname = "kite"\nrun_sheet = "sheet.csv"\ndata_dir = "{KITE}"\n'
        'output_dir = "out"\n\n[water]\ntemperature_C = 15.0\n\n'
        '[model]\nlength_m = 1.0\ndiameter_m = 0.2\nmass_kg = 20.0\n\n'
        '[channels]\ndrag = { column = "Untitled" }\nlift = { column = "Untitled 2" }\n\n'
        '[zeros]\nfile = "normal_aoa_16_vw_00.lvm"\n\n'
        '[processing]\nspeed_source = "nominal"\n\n[tare]\nsource = "none"\n')
    return path


@pytest.mark.skipif(not (KITE / "normal_aoa_16_vw_20.lvm").exists(),
                    reason="../shared/real/tudelft_kite_lvm is not present (real recordings are "
                    "not kept in the repository)")
def test_kite_lvm_channels_without_unit_labels_are_named(tmp_path):
    """TU Delft kite balance (LVM, no Y_Unit_Label): inspect lists drag and lift as assumed
    newtons (the time, LVM's X_Value, is in s by the format); process says it once."""
    protocol = _kite_protocol(tmp_path)
    out, err = io.StringIO(), io.StringIO()
    code = inspect_run(KITE / "normal_aoa_16_vw_20.lvm", protocol, png=tmp_path / "k.png",
                       out=out, err=err)
    assert code == 0, err.getvalue()
    text = out.getvalue()
    assert ("units: time s (from the file), drag N (assumed: no unit label), lift N (assumed: "
            "no unit label)") in text
    assert "drag and lift had no unit label: taken as N" in text
    day = towtank.process_day(protocol, jobs=1, report=False)
    assert [w for w in map(str, day.warnings) if "unit label" in w] == [
        f"drag and lift had no unit label in 1 run file (normal_aoa_16_vw_20.lvm): taken as N; "
        f"{SILENCE}."]
