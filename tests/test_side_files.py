"""Files kept beside each run: the carriage speed in its own file ([speed_log]: the motion
controller's log at 100 Hz on another clock, as speed or as the encoder's position) and the
balance zero in its own file ([zeros]).

The coefficients of the same day with its speed logged apart are those of the plain day
(tests/test_readers.py, layouts speed-log and position-log); here: the log's clock offset is
applied, a log that is missing or does not cover the run rejects that run only with a sentence
naming it, a changed log is never replayed from the cache, and the protocol's section is
checked.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import towtank
from towtank.errors import ProtocolError, RunError
from towtank.ingest.speedlog import SpeedLog, log_path, speed_on_run_time
from towtank.testing import synthetic as syn
from towtank.testing.layouts import CARRIAGE_OFFSET_S, layout_channels, protocol_sections

SEED = 11


def _day(root: Path, layout: str = "speed-log", **speed_log) -> Path:
    syn.make_hull_day(root, seed=SEED, file_format=layout, sheet_format="csv",
                      channel_style="lab")
    channels = layout_channels(layout, syn.LabChannels())
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv", channels=channels,
                                          channel_style="lab")
    sections = protocol_sections(layout, sections)
    sections["speed_log"].update(speed_log)
    return syn.write_protocol(root / "protocol.toml", **sections)


def test_the_log_is_put_on_the_run_files_clock(tmp_path):
    protocol = _day(tmp_path)
    truth = json.loads((tmp_path / "truth.json").read_text())
    raw = towtank.read_run(tmp_path / "data" / "run_005.csv", protocol)
    assert any("speed log run_005_carriage.csv" in n for n in raw.notes)
    log = pd.read_csv(tmp_path / "data" / "run_005_carriage.csv")
    # the carriage starts at the same instant on both clocks once offset_s is applied
    moving = raw.time[np.argmax(raw.speed > 0.05)]
    moving_log = log["t (s)"].to_numpy()[np.argmax(log["v (m/s)"].to_numpy() > 0.05)]
    assert moving == pytest.approx(moving_log + CARRIAGE_OFFSET_S, abs=0.011)
    plateau = truth["runs"]["5"]["speed_true"] if "speed_true" in truth["runs"]["5"] else \
        truth["runs"]["5"]["speed_nominal"]
    assert np.nanmax(raw.speed) == pytest.approx(plateau, rel=0.03)


def test_a_wrong_offset_rejects_the_runs_with_a_sentence(tmp_path):
    day = towtank.process_day(_day(tmp_path, offset_s=-200.0), jobs=1, report=False)
    assert day.rejected
    reason = str(next(iter(day.rejected.values())))
    assert "speed log" in reason and "offset_s" in reason and "\n" not in reason


def test_a_missing_log_rejects_its_run_only(tmp_path):
    protocol = _day(tmp_path)
    (tmp_path / "data" / "run_007_carriage.csv").unlink()
    day = towtank.process_day(protocol, jobs=1, report=False)
    assert set(day.rejected) == {7}
    assert "run_007_carriage.csv" in str(day.rejected[7]) and "speed log" in str(day.rejected[7])
    assert len(day.reductions) == 40


def test_a_changed_log_is_never_replayed_from_the_cache(tmp_path):
    protocol = _day(tmp_path)
    first = towtank.process_day(protocol, jobs=1, report=False)
    u1 = first.reductions[5].speed_mean
    path = tmp_path / "data" / "run_005_carriage.csv"
    log = pd.read_csv(path)
    log["v (m/s)"] *= 1.1  # the controller's scale corrected
    path.write_text(log.to_csv(index=False))
    second = towtank.process_day(protocol, jobs=1, report=False)
    assert second.reductions[5].speed_mean == pytest.approx(1.1 * u1, rel=2e-3)
    assert str(path) in second.inputs  # the log is an input of the day


def test_position_log_is_differentiated(tmp_path):
    protocol = _day(tmp_path, layout="position-log")
    raw = towtank.read_run(tmp_path / "data" / "run_005.csv", protocol)
    plain = pd.read_csv(tmp_path / "data" / "run_005_carriage.csv")
    assert list(plain.columns) == ["t (s)", "x (mm)"]
    nominal = json.loads((tmp_path / "truth.json").read_text())["runs"]["5"]["speed_nominal"]
    steady = raw.speed[np.abs(raw.speed - nominal) < 0.05 * nominal]
    assert steady.size > 0.2 * raw.speed.size  # the plateau is found at its speed
    assert np.median(steady) == pytest.approx(nominal, rel=0.005)


def test_log_path_fills_the_pattern(tmp_path):
    spec = SpeedLog(file="{dir}/logs/{stem}-{run:03d}.txt", time=("t", 1.0, 0.0),
                    speed=("v", 1.0, 0.0))
    assert log_path(spec, tmp_path, "day2/run_7.csv.gz", 7) == \
        tmp_path / "day2" / "logs" / "run_7-007.txt"


def test_a_log_ending_while_the_carriage_moves_is_refused():
    t_log = np.linspace(0.0, 5.0, 501)
    u_log = np.clip(t_log - 1.0, 0.0, 1.0)  # still moving at 5 s
    t_run = np.linspace(0.0, 8.0, 8001)
    with pytest.raises(RunError, match="moves at its end"):
        speed_on_run_time(t_run, t_log, u_log, "x.csv")
    u_still = np.where(t_log < 4.0, u_log, 0.0)
    u = speed_on_run_time(t_run, t_log, u_still, "x.csv")
    assert u[-1] == 0.0 and u.size == t_run.size


@pytest.mark.parametrize("section, match", [
    ({"file": "{stem}.csv", "time": "t"}, "either 'speed' or 'position'"),
    ({"file": "{stem}.csv", "time": "t", "speed": "v", "position": "x"}, "either"),
    ({"file": "{stm}.csv", "time": "t", "speed": "v"}, "can be filled in"),
    ({"time": "t", "speed": "v"}, "needs 'file'"),
    ({"file": "{stem}.csv", "time": "t", "speed": {"column": "v", "gain": 0}}, "gain"),
    ({"file": "{stem}.csv", "time": "t", "speed": "v", "ofset_s": 1}, "did you mean 'offset_s'"),
    ({"file": "{stem}.csv", "time": "t", "speed": "v", "offset_s": "1 s"}, "offset_s"),
])
def test_bad_sections_are_one_sentence(tmp_path, section, match):
    protocol = _day(tmp_path)
    text = protocol.read_text()
    head = text[:text.index("[speed_log]")]
    tail = text[text.index("[speed_log]"):]
    rest = tail[tail.index("\n[", 1) + 1:] if "\n[" in tail[1:] else ""
    while rest.startswith("[speed_log."):
        rest = rest[rest.index("\n[", 1) + 1:] if "\n[" in rest[1:] else ""
    lines = ["[speed_log]"]
    for k, v in section.items():
        text_v = json.dumps(v)
        lines.append(f"{k} = {text_v.replace(':', ' =') if isinstance(v, dict) else text_v}")
    protocol.write_text(head + "\n".join(lines) + "\n" + rest)
    with pytest.raises(ProtocolError, match=match):
        towtank.load_protocol(protocol)


# ------------------------------------------------------------------------------ zeros files
def _zero_day(root: Path, **processing) -> Path:
    syn.make_hull_day(root, seed=SEED, file_format="zero-file", sheet_format="csv",
                      channel_style="lab")
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv",
                                          channels=syn.LabChannels(), channel_style="lab")
    sections.setdefault("processing", {}).update(processing)
    return syn.write_protocol(root / "protocol.toml", **protocol_sections("zero-file", sections))


@pytest.mark.heavy
def test_the_zeros_file_gives_the_zero(tmp_path):
    """A zeros file whose drag reads δ higher moves the run's zeroed drag by −gain·δ (with
    drift = "none"; with the linear drift, by the zero line's value in the steady window)."""
    protocol = _zero_day(tmp_path, drift="none")
    lab = syn.LabChannels()
    first = towtank.process_day(protocol, jobs=1, report=False)
    red = first.reductions[5]
    assert any("zeros file run_005_zero.csv" in n for n in red.notes)
    path = tmp_path / "data" / "run_005_zero.csv"
    zero = pd.read_csv(path)
    delta_v = 0.0005
    zero[lab.drag] += delta_v
    path.write_text(zero.to_csv(index=False))
    second = towtank.process_day(protocol, jobs=1, report=False)
    shift = second.reductions[5].drag_mean - red.drag_mean
    assert shift == pytest.approx(-lab.drag_gain * delta_v, rel=1e-6, abs=1e-9)
    assert str(path) in second.inputs
    assert not any("run_005_zero.csv" in w for w in map(str, second.warnings))  # not "unlisted"


def test_a_missing_zeros_file_rejects_its_run_only(tmp_path):
    protocol = _zero_day(tmp_path)
    (tmp_path / "data" / "run_009_zero.csv").unlink()
    day = towtank.process_day(protocol, jobs=1, report=False)
    assert set(day.rejected) == {9}
    assert "zeros file" in str(day.rejected[9]) and "run_009_zero.csv" in str(day.rejected[9])


@pytest.mark.parametrize("section, match", [
    ({}, "needs 'file'"),
    ({"file": "{stem}_zero.csv", "column": "x"}, "unknown key 'column'"),
    ({"file": "{step}.csv"}, "can be filled in"),
])
def test_bad_zeros_sections(tmp_path, section, match):
    protocol = _zero_day(tmp_path)
    text = protocol.read_text()
    head, tail = text.split("[zeros]", 1)
    rest = tail[tail.index("\n[") + 1:] if "\n[" in tail else ""
    body = "".join(f"{k} = {json.dumps(v)}\n" for k, v in section.items())
    protocol.write_text(head + "[zeros]\n" + body + rest)
    with pytest.raises(ProtocolError, match=match):
        towtank.load_protocol(protocol)


def test_inspect_reads_the_speed_log_as_process_does(tmp_path):
    """`towtank inspect RUN --protocol` on a run whose speed is in its carriage log: the log is
    read (named in the notes) and the plateau speed is the day's."""
    import io

    from towtank.commands.inspect import inspect_run

    protocol = _day(tmp_path)
    out, err = io.StringIO(), io.StringIO()
    rc = inspect_run(tmp_path / "data" / "run_005.csv", protocol, png=tmp_path / "x.png",
                     out=out, err=err)
    assert rc == 0, err.getvalue()
    assert "carriage speed from the speed log run_005_carriage.csv" in out.getvalue()
    day = towtank.process_day(protocol, jobs=1, report=False)
    speed = float(out.getvalue().split("  speed ")[1].split("m/s")[0])
    assert speed == pytest.approx(day.reductions[5].speed_mean, abs=1e-4)
