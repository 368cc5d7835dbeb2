"""Runs without a measured speed (issue 23 item 2): `[processing] speed_source = "nominal"`.

The run sheet's set speed is the run's speed, over the sheet's steady window or the force's own
plateau; runs.csv says `speed_source = nominal` with `speed_u = speed_tolerance·U/√3`; such
runs give no added mass. Synthetic: the generator's hull day with the speed column taken out
of every run file (the set speeds are the generated ones). Real: the UNH-RVAT run (no speed
channel, 1.0 m/s nominal) from ../shared/real when present.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import towtank
from towtank.errors import RunError
from towtank.signal.conditioning import lowpass
from towtank.signal.phases import force_plateau
from towtank.testing import synthetic as syn

SEED = 5
SPEED = "Carriage speed (m/s)"
UNH = Path(__file__).resolve().parents[2] / "shared" / "real" / "unh_rvat_2013" / "test.tdms"


def _make_files(root: Path) -> dict:
    """The hull day's files without speed columns. Returns the truth."""
    syn.make_hull_day(root, seed=SEED, sheet_format="csv")
    truth = json.loads((root / "truth.json").read_text())
    for run in truth["runs"].values():
        path = root / "data" / run["file"]
        frame = pd.read_csv(path)
        frame.drop(columns=[SPEED]).to_csv(path, index=False)  # gzipped as named
    return truth


def _add_windows(root: Path, truth: dict) -> None:
    """The sheet gives each run's steady window (the generator's plateau, 0.6 s in from each
    end)."""
    sheet = pd.read_csv(root / "run_sheet.csv")
    runs = truth["runs"]
    sheet["window_start_s"] = [runs[str(r)]["t_plateau_start"] + 0.6 for r in sheet["run"]]
    sheet["window_end_s"] = [runs[str(r)]["t_plateau_end"] - 0.6 for r in sheet["run"]]
    sheet.to_csv(root / "run_sheet.csv", index=False)


@pytest.fixture(scope="session")
def speedless_files(tmp_path_factory) -> Path:
    """The day's files without speed columns, made once for this module; each test copies
    them."""
    root = tmp_path_factory.mktemp("speedless")
    _make_files(root)
    return root


@pytest.fixture(scope="session")
def windowed_files(tmp_path_factory, speedless_files) -> Path:
    """The same files with sheet windows, made once for this module; each test copies them."""
    root = tmp_path_factory.mktemp("windowed")
    shutil.copytree(speedless_files, root, dirs_exist_ok=True)
    _add_windows(root, json.loads((root / "truth.json").read_text()))
    return root


@pytest.fixture
def day_files(windowed_files, speedless_files):
    """``day_files(root, windows=..., **processing)``: the hull day without speed columns in
    ``root`` (a copy of the module's day, with or without sheet windows) and its protocol with
    ``speed_source = "nominal"``; returns (protocol, truth)."""

    def make(root: Path, *, windows: bool, **processing) -> tuple[Path, dict]:
        shutil.copytree(windowed_files if windows else speedless_files, root, dirs_exist_ok=True)
        truth = json.loads((root / "truth.json").read_text())
        sections = syn.hull_protocol_sections(".", "out", sheet_format="csv")
        del sections["channels"]["speed"]
        sections.setdefault("processing", {}).update(speed_source="nominal", **processing)
        return syn.write_protocol(root / "protocol.toml", **sections), truth

    return make


@pytest.fixture(scope="session")
def measured(tmp_path_factory):
    root = tmp_path_factory.mktemp("measured")
    syn.make_hull_day(root, seed=SEED, sheet_format="csv")
    syn.write_protocol(root / "p.toml", **syn.hull_protocol_sections(".", "out",
                                                                     sheet_format="csv"))
    return towtank.process_day(root / "p.toml", jobs=1, report=False)


@pytest.mark.heavy
def test_the_set_speed_and_the_sheet_window_give_the_damping(tmp_path, measured, day_files):
    protocol, truth = day_files(tmp_path, windows=True, speed_tolerance=0.01)
    day = towtank.process_day(protocol, jobs=1, report=False)
    assert not day.rejected, day.rejected
    got = day.coefficients.set_index("symbol")["value"]
    for sym in ("X_u|u|", "Y_v|v|"):
        assert got[sym] == pytest.approx(truth["coefficients"][sym], rel=0.02), sym
        ref = measured.coefficients.set_index("symbol")["value"][sym]
        assert got[sym] == pytest.approx(ref, rel=0.01), sym
    # the small C_D(α) terms rest on the drift removed to the file's end (at rest): their
    # intervals hold the truth (held zeros left X_v|v| at -87 % of it)
    table = day.coefficients.set_index("symbol")
    for sym in ("X_v|v|", "X_uv"):
        assert table.loc[sym, "ci_low"] <= truth["coefficients"][sym] <= table.loc[sym,
                                                                                  "ci_high"]
    red = day.reductions[16]
    assert red.drift_drag != 0.0
    assert any("the drift is taken to the file's last" in n for n in red.notes)
    # no acceleration without a speed: the added masses are omitted, and said so
    assert "X_udot" not in set(got.index) or math.isnan(got.get("X_udot", math.nan))
    assert any("X_udot needs accelerated hull runs" in w for w in map(str, day.warnings))
    runs = day.runs.set_index("run")
    ok = runs[runs["status"] == "ok"]
    assert (ok["speed_source"] == "nominal").all()
    np.testing.assert_allclose(ok["speed_mean"], ok["speed_nominal"])
    np.testing.assert_allclose(ok["speed_u"], 0.01 * ok["speed_nominal"] / math.sqrt(3))
    assert ok["accel_mean"].isna().all()
    assert (measured.runs.set_index("run").loc[ok.index, "speed_source"] == "measured").all()


def test_the_steady_window_is_found_from_the_force(tmp_path, day_files):
    """Without sheet windows the model runs' plateaus are found from the drag: every hull run is
    reduced, each window lies within the generator's plateau, the steady drag is the truth's
    within 1 % (or 2 mN: the zero is held, the balance drift of up to 5 mN is not removed), and
    X_u|u|, Y_v|v| within 2 %."""
    protocol, truth = day_files(tmp_path, windows=False)
    day = towtank.process_day(protocol, jobs=1, report=False)
    hull = [int(k) for k, r in truth["runs"].items()
            if r["config"] == "hull" and r["status"] != "void"]
    assert not set(hull) & set(day.rejected), day.rejected
    got = day.coefficients.set_index("symbol")["value"]
    for sym in ("X_u|u|", "Y_v|v|"):
        assert got[sym] == pytest.approx(truth["coefficients"][sym], rel=0.02), sym
    checked = 0
    for run, red in day.reductions.items():
        t_run = truth["runs"][str(run)]
        if t_run["config"] != "hull" or abs(t_run["drag_model"]) < 0.05:
            continue
        w = red.windows["steady"]
        assert t_run["t_plateau_start"] - 0.05 <= w[0] < w[1] <= t_run["t_plateau_end"] + 0.05
        assert red.window_source.startswith("from the force")
        assert red.drag_mean_raw == pytest.approx(
            t_run["drag_model"] + t_run["tare_drag"], rel=0.01, abs=3e-3), run
        checked += 1
    assert checked >= 10


def test_a_run_without_set_speed_is_rejected_in_one_sentence(tmp_path, day_files):
    protocol, _ = day_files(tmp_path, windows=True)
    sheet = pd.read_csv(tmp_path / "run_sheet.csv")
    sheet.loc[sheet["run"] == 14, "speed_nominal"] = np.nan
    sheet.to_csv(tmp_path / "run_sheet.csv", index=False)
    day = towtank.process_day(protocol, jobs=1, report=False)
    assert "has no speed_nominal" in str(day.rejected[14])


def test_force_plateau_without_one_says_so():
    t = np.arange(0, 10, 0.005)
    with pytest.raises(RunError, match="window_start_s and window_end_s"):
        force_plateau(np.zeros(t.size), 200.0, zero=0.0)
    frame, truth = syn.simulate_run("hull", 0.0, 1.2, 0.5, fs=200.0, rng=3)
    drag = lowpass(frame["drag"].to_numpy(), 200.0, 4.0)
    i0, i1 = force_plateau(drag, 200.0, zero=truth["zero_drag"])
    tt = frame["time"].to_numpy()
    assert truth["t_plateau_start"] <= tt[i0] and tt[i1 - 1] <= truth["t_plateau_end"]


@pytest.mark.heavy
@pytest.mark.skipif(not UNH.exists(), reason="../shared/real/unh_rvat_2013/test.tdms is not "
                    "present (real recordings are not kept in the repository)")
def test_unh_rvat_with_its_nominal_speed_gives_the_labs_drag(tmp_path):
    """UNH-RVAT 2013 (petebachant/pyTDMS test/test.tdms): inspect's block, the run sheet's
    1.0 m/s and the lab's window 13–29.89 s, each cell zeroed on its first second
    (zero_window_s = 1): the steady drag is the lab's 601.4 N within 0.1 %."""
    import io
    import tomllib

    from towtank.commands.inspect import inspect_run
    from towtank.ingest.protocol import load_protocol
    from towtank.reduce.run import reduce_record

    out = io.StringIO()
    inspect_run(UNH, png=tmp_path / "x.png", out=out, err=io.StringIO())
    block = out.getvalue()[out.getvalue().index("[read]"):]
    assert tomllib.loads(block)["channels"]["drag"] == {"columns": ["DragL", "DragR"]}
    (tmp_path / "sheet.csv").write_text(
        "run,file,config,angle_deg,speed_nominal,window_start_s,window_end_s\n"
        f"1,{UNH.name},hull,0,1.0,13.0,29.89\n")
    (tmp_path / "protocol.toml").write_text(
        f'[campaign]\nname = "UNH-RVAT"\nrun_sheet = "sheet.csv"\ndata_dir = "{UNH.parent}"\n'
        'output_dir = "out"\n\n[water]\ntemperature_C = 15.0\n\n'
        '[model]\nlength_m = 1.0\ndiameter_m = 0.2\nmass_kg = 20.0\n\n'
        + block + '\n[processing]\nspeed_source = "nominal"\nzero_at = "file_start"\n'
        'zero_window_s = 1.0\n\n[tare]\nsource = "none"\n')
    protocol = load_protocol(tmp_path / "protocol.toml")
    row = {"run": 1, "file": UNH.name, "speed_nominal": 1.0, "window_start_s": 13.0,
           "window_end_s": 29.89}
    run, red, reason, _ = reduce_record(protocol, row)
    assert reason is None, reason
    assert red.speed_source == "nominal" and red.speed_mean == 1.0
    assert red.drag_mean_raw == pytest.approx(601.4, rel=1e-3)  # measured: 601.46 N


def test_a_measured_speed_and_the_nominal_one_together_are_refused(tmp_path, day_files):
    from towtank.errors import ProtocolError
    from towtank.ingest.protocol import load_protocol

    protocol, _ = day_files(tmp_path, windows=True)
    text = protocol.read_text()
    (tmp_path / "both.toml").write_text(text.replace(
        "[channels]\n", '[channels]\nspeed = { column = "Carriage speed (m/s)" }\n'))
    with pytest.raises(ProtocolError, match="keep one of the two"):
        load_protocol(tmp_path / "both.toml")
    (tmp_path / "bad.toml").write_text(text.replace('speed_source = "nominal"',
                                                    'speed_source = "set"'))
    with pytest.raises(ProtocolError, match="speed_source"):
        load_protocol(tmp_path / "bad.toml")


def test_the_drift_is_removed_only_when_the_file_ends_at_rest():
    """A run without a speed that ends at rest has its drift removed to the file's end; one cut
    while braking keeps its zero (the braking force is no drift)."""
    from towtank.ingest.protocol import Processing
    from towtank.ingest.runfile import RawRun
    from towtank.reduce.run import reduce_nominal

    frame, truth = syn.simulate_run("hull", 0.0, 1.2, 0.5, fs=200.0, rng=6)

    def reduce(part):
        raw = RawRun(time=part["time"].to_numpy(), speed=np.zeros(len(part)),
                     drag=part["drag"].to_numpy(), lift=part["lift"].to_numpy(), fs=200.0,
                     speed_nominal=1.2)
        return reduce_nominal(raw, Processing(), run=1, file="run_001.csv")

    whole = reduce(frame)
    assert whole.drift_drag == pytest.approx(truth["drift_drag"], abs=1e-3)
    assert whole.drag_mean_raw == pytest.approx(truth["drag_model"], abs=1e-3)
    braking = reduce(frame[frame["time"] <= truth["t_decel_start"] + 1.0])
    assert braking.drift_drag == 0.0
    assert any("held constant" in n for n in braking.notes)


def test_inspect_takes_the_set_speed_and_window_from_the_sheet(tmp_path, day_files):
    import io

    from towtank.commands.inspect import inspect_run

    protocol, truth = day_files(tmp_path, windows=True)
    out, err = io.StringIO(), io.StringIO()
    rc = inspect_run(tmp_path / "data" / "run_016.csv.gz", protocol, png=tmp_path / "x.png",
                     out=out, err=err)
    assert rc == 0, err.getvalue()
    text = out.getvalue()
    assert "speed: the set speed 2 m/s of the run sheet" in text
    assert "manual" in text and "set speed, no speed channel" in text
    speed = float(text.split("  speed ")[1].split("m/s")[0])
    assert speed == pytest.approx(truth["runs"]["16"]["speed_nominal"])


def test_the_api_reads_a_run_at_its_set_speed(tmp_path, day_files):
    protocol, truth = day_files(tmp_path, windows=True)
    path = tmp_path / "data" / "run_016.csv.gz"
    elsewhere = tmp_path / "elsewhere.csv.gz"  # a file no row of the run sheet names
    elsewhere.write_bytes(path.read_bytes())
    with pytest.raises(RunError, match="speed_nominal=U"):
        towtank.read_run(elsewhere, protocol)
    raw = towtank.read_run(path, protocol, speed_nominal=2.0)
    run = truth["runs"]["16"]
    red = towtank.reduce_run(raw, protocol, run=16, file=path.name,
                             window_s=(run["t_plateau_start"] + 0.6, run["t_plateau_end"] - 0.6))
    assert red.speed_source == "nominal" and red.speed_mean == 2.0
    assert red.speed_u == pytest.approx(0.005 * 2.0 / math.sqrt(3))
    assert red.drag_mean_raw == pytest.approx(run["drag_model"] + run["tare_drag"], abs=3e-3)


KITE = Path(__file__).resolve().parents[2] / "shared" / "real" / "tudelft_kite_lvm"


@pytest.mark.skipif(not (KITE / "normal_aoa_16_vw_20.lvm").exists(),
                    reason="../shared/real/tudelft_kite_lvm is not present (real recordings are "
                    "not kept in the repository)")
def test_kite_balance_with_its_wind_off_zeros_file(tmp_path):
    """TU Delft kite load balance (LabVIEW LVM, 2 kHz, no speed channel, unnamed channels):
    vw_20 at its lab-book 19.8 m/s with vw_00 as its zeros file gives F_X (column 'Untitled')
    over 1–9 s within 0.1 % of the mean computed directly from the two files (measured:
    74.258 N against 74.280 N)."""
    from towtank.ingest.protocol import load_protocol
    from towtank.reduce.run import reduce_record

    (tmp_path / "sheet.csv").write_text(
        "run,file,config,angle_deg,speed_nominal\n1,normal_aoa_16_vw_20.lvm,hull,0,19.8\n")
    (tmp_path / "p.toml").write_text(
        f'[campaign]\nname = "kite"\nrun_sheet = "sheet.csv"\ndata_dir = "{KITE}"\n'
        'output_dir = "out"\n\n[water]\ntemperature_C = 15.0\n\n'
        '[model]\nlength_m = 1.0\ndiameter_m = 0.2\nmass_kg = 20.0\n\n'
        '[channels]\ndrag = { column = "Untitled" }\n\n'
        '[zeros]\nfile = "normal_aoa_16_vw_00.lvm"\n\n'
        '[processing]\nspeed_source = "nominal"\n\n[tare]\nsource = "none"\n')
    protocol = load_protocol(tmp_path / "p.toml")
    row = {"run": 1, "file": "normal_aoa_16_vw_20.lvm", "speed_nominal": 19.8,
           "window_start_s": 1.0, "window_end_s": 9.0}
    _, red, reason, _ = reduce_record(protocol, row)
    assert reason is None, reason

    def column(name: str) -> pd.DataFrame:
        lines = (KITE / name).read_text().splitlines()
        head = next(k for k, line in enumerate(lines) if line.startswith("X_Value"))
        return pd.read_csv(KITE / name, sep="\t", skiprows=head)

    run, zero = column("normal_aoa_16_vw_20.lvm"), column("normal_aoa_16_vw_00.lvm")
    inside = (run["X_Value"] >= 1.0) & (run["X_Value"] <= 9.0)
    direct = run["Untitled"][inside].mean() - zero["Untitled"].mean()
    assert red.drag_mean_raw == pytest.approx(direct, rel=1e-3)
    assert red.speed_mean == 19.8 and red.speed_source == "nominal"
