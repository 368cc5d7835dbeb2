"""The command line as a newcomer meets it: help, synth → process, exit statuses."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from towtank.commands.cli import main


def test_help_names_every_command(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    for cmd in ("process", "inspect", "scale", "synth"):
        assert cmd in text
    assert "exit status" in text


@pytest.mark.heavy
def test_synth_writes_a_day_that_processes(tmp_path, capsys):
    day = tmp_path / "day"
    assert main(["synth", str(day), "--day", "hull", "--seed", "7"]) == 0
    assert "towtank process" in capsys.readouterr().out
    assert (day / "protocol.toml").is_file() and (day / "truth.json").is_file()
    assert main(["process", str(day / "protocol.toml"), "--no-report", "-q"]) == 0
    coef = pd.read_csv(day / "out" / "coefficients.csv").set_index("symbol")
    truth = json.loads((day / "truth.json").read_text())["coefficients"]
    assert coef.loc["X_u|u|", "value"] == pytest.approx(truth["X_u|u|"], rel=0.01)


@pytest.mark.heavy
@pytest.mark.parametrize(("day_kind", "file_format", "sheet"),
                         [("hull", "tdms", "csv"), ("fin", "csv", "xlsx")])
def test_synth_writes_the_formats_asked_for(tmp_path, capsys, day_kind, file_format, sheet):
    day = tmp_path / "day"
    assert main(["synth", str(day), "--day", day_kind, "--format", file_format,
                 "--sheet", sheet]) == 0
    files = sorted((day / "data").iterdir())
    assert files and all(f.name.endswith("." + file_format) for f in files)
    assert (day / f"run_sheet.{sheet}").is_file()
    assert main(["process", str(day / "protocol.toml"), "--no-report", "-q", "--jobs", "1"]) == 0
    runs = pd.read_csv(day / "out" / "runs.csv")
    assert set(runs["status"]) <= {"ok", "void"}


@pytest.mark.heavy
def test_jobs_from_the_protocol_unless_given(tmp_path, capsys, monkeypatch):
    from towtank.runtime import parallel

    day = tmp_path / "day"
    assert main(["synth", str(day), "--day", "hull", "--seed", "3"]) == 0
    proto = day / "protocol.toml"
    text = proto.read_text()
    assert text.count("[processing]\n") == 1
    proto.write_text(text.replace("[processing]\n", "[processing]\njobs = 1\n"))
    asked: list = []
    real = parallel.prestart
    monkeypatch.setattr(parallel, "prestart", lambda jobs=None: asked.append(jobs) or real(jobs))
    assert main(["process", str(proto), "--no-report", "-q", "--no-cache"]) == 0
    assert main(["process", str(proto), "--no-report", "-q", "--no-cache", "-j", "2"]) == 0
    assert asked == [1, 2]


def test_the_progress_bar_leaves_no_thread_behind(tmp_path, capsys, monkeypatch):
    """The report's writers fork, which is safe (and done) only when no other thread runs:
    the terminal's progress bar must not leave its monitor thread behind."""
    import sys
    import threading

    from towtank.report import outputs

    day = tmp_path / "day"
    assert main(["synth", str(day), "--day", "fin", "--seed", "2"]) == 0
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)  # a terminal: the bar is shown
    seen = []
    real = outputs.write_day_outputs

    def spy(*args, **kwargs):
        seen.append([t.name for t in threading.enumerate()])
        return real(*args, **kwargs)

    monkeypatch.setattr(outputs, "write_day_outputs", spy)
    assert main(["process", str(day / "protocol.toml"), "--no-report"]) == 0
    assert seen == [["MainThread"]]


@pytest.mark.parametrize(
    ("terminal", "flags", "bar"),
    [(True, [], True), (True, ["--quiet"], False), (False, [], False)],
)
def test_progress_bar_only_on_a_terminal_and_never_with_quiet(tmp_path, capsys, monkeypatch,
                                                              terminal, flags, bar):
    import sys

    day = tmp_path / "day"
    assert main(["synth", str(day), "--day", "fin", "--seed", "2"]) == 0
    capsys.readouterr()
    monkeypatch.setattr(sys.stderr, "isatty", lambda: terminal)
    code = main(["process", str(day / "protocol.toml"), "--no-report", "--no-cache", *flags])
    assert code == 0
    captured = capsys.readouterr()
    if bar:
        assert "reducing" in captured.err and "run" in captured.err
    else:
        assert captured.err == ""
    assert (captured.out == "") == ("--quiet" in flags)


def test_process_without_a_command_or_protocol(tmp_path, capsys):
    assert main([]) == 2
    assert main(["process", str(tmp_path / "missing.toml")]) == 2
    err = capsys.readouterr().err
    assert "does not exist" in err and "Traceback" not in err


@pytest.mark.heavy
def test_sheet_disagreements_are_warned_on_the_terminal(tmp_path, capsys):
    """A set speed the carriage did not run at, and a temperature in °F, reach the user."""
    from towtank.testing.synthetic import hull_protocol_sections, make_hull_day, write_protocol

    make_hull_day(tmp_path, seed=11, sheet_format="csv")
    write_protocol(tmp_path / "p.toml", **hull_protocol_sections(".", "out", sheet_format="csv"))
    sheet = pd.read_csv(tmp_path / "run_sheet.csv")
    hull = sheet.index[(sheet.config == "hull") & (sheet.status != "void")]
    wrong_speed, fahrenheit = int(sheet.loc[hull[0], "run"]), int(sheet.loc[hull[1], "run"])
    sheet.loc[hull[0], "speed_nominal"] = sheet.loc[hull[0], "speed_nominal"] * 1.5
    sheet.loc[hull[1], "water_temp_C"] = 64.4
    sheet.to_csv(tmp_path / "run_sheet.csv", index=False)
    assert main(["process", str(tmp_path / "p.toml"), "--no-report"]) == 0
    out = capsys.readouterr().out
    assert f"warning: run {wrong_speed}: measured plateau speed" in out
    assert f"warning: run {fahrenheit}: water temperature 64.4 °C is outside 0–40 °C" in out
