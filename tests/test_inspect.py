"""Tests of ``towtank inspect``: one run file's phases, means and plot."""

from __future__ import annotations

import gzip
import io
from pathlib import Path

import pandas as pd
import pytest

from towtank.commands.cli import main
from towtank.commands.inspect import inspect_run, plot_name
from towtank.testing import synthetic

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="session")
def day(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("inspect") / "hull"
    synthetic.make_hull_day(root, seed=5)
    synthetic.write_protocol(root / "p.toml", **synthetic.hull_protocol_sections(".", "out"))
    return root


def test_cli_inspect_prints_phases_and_writes_png(day, tmp_path, capsys):
    png = tmp_path / "plots" / "run13.png"
    rc = main(["inspect", str(day / "data" / "run_013.csv.gz"), "--protocol",
               str(day / "p.toml"), "--png", str(png)])
    out = capsys.readouterr().out
    assert rc == 0
    for word in ("phases", "zero (still)", "acceleration", "steady", "deceleration",
                 "steady means", "speed", "drag", "lift", "zero", "drift", "200 Hz", "notes"):
        assert word in out, word
    assert f"plot: {png}" in out
    assert png.read_bytes()[:8] == PNG


def test_inspect_without_protocol_uses_canonical_channels(day, tmp_path, capsys):
    lab = pd.read_csv(day / "data" / "run_014.csv.gz")
    canonical = pd.DataFrame({
        "time": lab["Time (s)"],
        "speed": lab["Carriage speed (m/s)"],
        "drag": 20.0 * lab["Fx load cell (V)"],
    })
    path = tmp_path / "raw" / "run_014.csv"
    path.parent.mkdir()
    canonical.to_csv(path, index=False)
    png = tmp_path / "out.png"
    assert inspect_run(path, png=png) == 0
    out = capsys.readouterr().out
    assert "steady" in out and "lift" not in out.split("steady means")[1].split("acceleration")[0]
    assert png.exists()


def _paste(protocol_text: str, block: str) -> str:
    """The protocol with its [channels] table replaced by inspect's proposed block."""
    head, rest = protocol_text.split("[channels]\n", 1)
    tail = rest[rest.index("\n["):]
    return head + block + tail


@pytest.mark.heavy
def test_lab_columns_without_protocol_are_reduced_with_the_proposed_block(day, tmp_path):
    """Issue 22: a run in the lab's column names (load cells in volts), no --protocol: inspect
    names the time column, proposes [read]/[channels], reduces the run with that block (forces
    in V at the provisional gain 1.0, exit 0, nothing on stderr), and the block pasted into the
    day's protocol processes the day: its drag coefficients are the calibrated day's divided by
    the drag gain (20 N/V; Y_v|v| from the transverse tows' drag), since every step of the
    reduction is linear in force (the added masses are not: the model's mass is subtracted)."""
    import tomllib

    import towtank

    out, err = io.StringIO(), io.StringIO()
    rc = inspect_run(day / "data" / "run_014.csv.gz", png=tmp_path / "x.png", out=out, err=err)
    text = out.getvalue()
    assert rc == 0, err.getvalue()
    assert err.getvalue() == ""
    assert "timing: time column 'Time (s)'" in text and "the time channel is missing" not in text
    assert "reduced with the block above" in text and "steady means" in text
    assert (tmp_path / "x.png").read_bytes()[:8] == PNG
    block = text[text.index("[read]"):text.index("reduced with the block above")]
    parsed = tomllib.loads(block)
    assert parsed["channels"]["drag"] == {"column": "Fx load cell (V)", "gain": 1.0,
                                          "offset": 0.0}
    # the steady drag inspect prints is in volts, and says so: the calibrated one over 20 N/V
    volts = float(text.split("  drag ")[1].split(" V ")[0])
    ref = io.StringIO()
    assert inspect_run(day / "data" / "run_014.csv.gz", day / "p.toml",
                       png=tmp_path / "y.png", out=ref) == 0
    newtons = float(ref.getvalue().split("  drag ")[1].split("N")[0])
    assert volts == pytest.approx(newtons / 20.0, abs=2e-4)
    # pasted as printed, the block processes the day
    pasted = tmp_path / "pasted.toml"
    pasted.write_text(_paste((day / "p.toml").read_text(), block).replace(
        'data_dir = "./data"', f'data_dir = "{day / "data"}"').replace(
        'run_sheet = "./run_sheet.xlsx"', f'run_sheet = "{day / "run_sheet.xlsx"}"'))
    got = towtank.process_day(pasted, jobs=1, report=False)
    base = towtank.process_day(day / "p.toml", jobs=1, report=False)
    assert not got.rejected and not base.rejected
    g = got.coefficients.set_index("symbol")["value"]
    b = base.coefficients.set_index("symbol")["value"]
    for sym, gain in (("X_u|u|", 20.0), ("X_v|v|", 20.0), ("Y_v|v|", 20.0)):
        assert g[sym] == pytest.approx(b[sym] / gain, rel=1e-6), sym


def test_a_file_whose_channels_cannot_be_guessed_says_so(tmp_path):
    """No --protocol and no channel named like time, speed or a force: the file is described,
    the block names no channel, and one sentence asks for the protocol (exit 1)."""
    path = tmp_path / "raw" / "run_001.csv"
    path.parent.mkdir()
    path.write_text("ch0,ch1,ch2\n" + "".join(f"{k},0,0\n" for k in range(50)))
    out, err = io.StringIO(), io.StringIO()
    assert inspect_run(path, png=tmp_path / "x.png", out=out, err=err) == 1
    assert "# not recognised: 'ch0', 'ch1', 'ch2'" in out.getvalue()
    assert "--protocol" in err.getvalue() and err.getvalue().count("\n") == 1


def test_default_png_goes_to_the_current_folder(day, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    rc = main(["inspect", str(day / "data" / "run_015.csv.gz"), "--protocol",
               str(day / "p.toml")])
    assert rc == 0
    assert (tmp_path / "run_015.png").read_bytes()[:8] == PNG
    assert not list((day / "data").glob("*.png"))


def test_never_writes_beside_the_raw_data(day, monkeypatch, capsys):
    monkeypatch.chdir(day / "data")
    rc = main(["inspect", "run_016.csv.gz", "--protocol", str(day / "p.toml")])
    assert rc == 0
    assert "not written" in capsys.readouterr().out
    assert not list((day / "data").glob("*.png"))
    # asked for by name, a plot may go anywhere (issue 16) ...
    target = day / "data" / "x.png"
    rc = main(["inspect", "run_016.csv.gz", "--protocol", str(day / "p.toml"), "--png",
               str(target)])
    assert rc == 0 and target.read_bytes()[:8] == PNG
    target.unlink()
    # ... but never over a file that is not inspect's plot of this run: the run file itself
    before = (day / "data" / "run_017.csv.gz").read_bytes()
    rc = main(["inspect", "run_016.csv.gz", "--protocol", str(day / "p.toml"), "--png",
               str(day / "data" / "run_017.csv.gz")])
    assert rc == 1 and "not written" in capsys.readouterr().err
    assert (day / "data" / "run_017.csv.gz").read_bytes() == before
    assert not list((day / "data").glob("*.png"))


@pytest.mark.parametrize("content", [
    b"not a gzip file at all",
    gzip.compress(b"Time (s),Carriage speed (m/s),Fx load cell (V)\n", mtime=0)[:25],
    gzip.compress(b"Time (s),Carriage speed (m/s),Fx load cell (V)\n0,0,0\n", mtime=0),
], ids=["not-gzip", "truncated-gzip", "one-row"])
def test_damaged_file_gives_one_sentence_and_exit_1(day, tmp_path, capsys, content):
    path = tmp_path / "run_099.csv.gz"
    path.write_bytes(content)
    rc = main(["inspect", str(path), "--protocol", str(day / "p.toml"), "--png",
               str(tmp_path / "x.png")])
    captured = capsys.readouterr()
    assert rc == 1
    lines = [ln for ln in captured.err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("towtank: ") and lines[0].endswith(".")
    assert "Traceback" not in captured.err and "run_099" in lines[0]
    assert not (tmp_path / "x.png").exists()


def test_wrong_channels_name_the_missing_column(day, tmp_path):
    """With --protocol, a mapping that names a column the file lacks is one sentence naming it
    (no guessing: the protocol is the user's word)."""
    bad = tmp_path / "bad.toml"
    bad.write_text((day / "p.toml").read_text().replace(
        '"Carriage speed (m/s)"', '"Speed (m/s)"').replace('"./', f'"{day}/'))
    err = io.StringIO()
    rc = inspect_run(day / "data" / "run_013.csv.gz", bad, png=tmp_path / "x.png",
                     out=io.StringIO(), err=err)
    assert rc == 1
    assert "missing" in err.getvalue() and "Speed (m/s)" in err.getvalue()


def test_plot_name():
    assert plot_name("data/run_020.csv.gz") == "run_020.png"
    assert plot_name("run_7.tdms") == "run_7.png"
    assert plot_name("day3.run.12.csv") == "day3.run.12.png"


def test_a_problem_run_is_plotted_with_its_reason_and_same_names_do_not_clash(
        day, tmp_path, monkeypatch, capsys):
    """Issue 16: a run that is read but cannot be reduced is drawn (its calibrated traces)
    with its reason; a second day's run_015 does not overwrite the first day's plot."""
    import pandas as pd

    monkeypatch.chdir(tmp_path)
    assert main(["inspect", str(day / "data" / "run_015.csv.gz"), "--protocol",
                 str(day / "p.toml")]) == 0
    other = tmp_path / "other_day"
    other.mkdir()
    frame = pd.read_csv(day / "data" / "run_015.csv.gz")
    frame[frame.columns[1]] *= -1  # the speed channel's sign slipped
    frame.to_csv(other / "run_015.csv.gz", index=False)
    first = (tmp_path / "run_015.png").read_bytes()
    rc = main(["inspect", str(other / "run_015.csv.gz"), "--protocol", str(day / "p.toml")])
    captured = capsys.readouterr()
    assert rc == 1 and "speed is negative" in captured.err
    assert "run_015-2.png" in captured.out
    assert (tmp_path / "run_015-2.png").read_bytes()[:8] == PNG
    assert (tmp_path / "run_015.png").read_bytes() == first


@pytest.mark.heavy
def test_inspect_into_a_closed_pipe_ends_quietly(day, tmp_path):
    """`towtank inspect … | head -1`: no 'internal error (BrokenPipeError)'."""
    import subprocess
    import sys

    code = "from towtank.commands.cli import entry; entry()"
    cmd = [sys.executable, "-c", code, "inspect", str(day / "data" / "run_015.csv.gz"),
           "--protocol", str(day / "p.toml"), "--png", str(tmp_path / "p.png")]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # the reader is gone before towtank prints its first line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 0
    assert "internal error" not in err and "Traceback" not in err


def test_inspect_help_names_every_format_the_readers_accept(capsys):
    """`inspect --help` names every extension a reader accepts, not only .csv, .csv.gz and
    .tdms."""
    from towtank.ingest.readers import EXTENSIONS, file_format

    with pytest.raises(SystemExit):
        main(["inspect", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for ext in EXTENSIONS:
        assert ext in text, ext
    for ext in (".csv.gz", ".txt.gz", ".lvm.gz"):
        assert ext in text
        assert file_format(Path("run" + ext), b"\x1f\x8b", None)[1]  # read gzipped indeed
