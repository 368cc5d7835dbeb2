"""Issue 4: a generated fin day is reduced to the section data it was made from.

The generator's truth is the 2-D Sandia NACA 0015 data at each run's Reynolds number with a tare
on the fin's post; the pipeline must recover C_L within 0.01 (or 2 %) and C_D within 0.002 (or
3 %) up to 25°, and fins.csv must carry the Sandia values at each run's Re.
"""

from __future__ import annotations

import json
import math
import shutil
import warnings

import numpy as np
import pandas as pd
import pytest

from towtank.analysis import fins
from towtank.pipeline import process_day
from towtank.reference import sandia
from towtank.testing.synthetic import (
    LabChannels,
    RunSpec,
    fin_day_plan,
    fin_protocol_sections,
    make_fin_day,
    write_protocol,
)

FINS_COLUMNS = ["run", "angle_deg", "speed_mean", "re", "cl", "cd", "cl_sandia", "cd_sandia"]


@pytest.fixture(scope="session")
def fin_day(tmp_path_factory):
    d = tmp_path_factory.mktemp("fin_day")
    make_fin_day(d, seed=41)
    sections = fin_protocol_sections(".", "out")
    write_protocol(d / "p.toml", **sections)
    truth = json.loads((d / "truth.json").read_text())
    day = process_day(d / "p.toml", jobs=1)
    return d, truth, day


def test_every_fin_run_is_reduced(fin_day):
    _, truth, day = fin_day
    runs = day.runs
    assert (runs["status"] == "ok").all(), runs.loc[runs["status"] != "ok", "reason"].tolist()
    n_fin = sum(1 for r in truth["runs"].values() if r["config"] == "fin")
    assert len(day.fins.table) == n_fin


def test_cl_cd_recovered_up_to_25_deg(fin_day):
    _, truth, day = fin_day
    t = day.fins.table
    t = t[t["angle_deg"] <= 25.0]
    assert len(t) >= 16
    for row in t.itertuples():
        tr = truth["runs"][str(row.run)]
        assert abs(row.cl - tr["cl"]) <= max(0.01, 0.02 * abs(tr["cl"])), row
        assert abs(row.cd - tr["cd"]) <= max(0.002, 0.03 * abs(tr["cd"])), row


def test_fins_csv_carries_sandia_at_run_re(fin_day):
    _, _, day = fin_day
    t = day.fins.table
    assert list(t.columns[: len(FINS_COLUMNS)]) == FINS_COLUMNS
    cl, cd = sandia.section_coefficients(t["angle_deg"].to_numpy(), t["re"].to_numpy())
    np.testing.assert_allclose(t["cl_sandia"], cl, rtol=0, atol=1e-12)
    np.testing.assert_allclose(t["cd_sandia"], cd, rtol=0, atol=1e-12)
    # Re is on the chord at the run's water temperature
    fin = day.protocol.fin
    runs = day.runs.set_index("run")
    for row in t.itertuples():
        nu = runs.loc[row.run, "nu"]
        assert row.re == pytest.approx(row.speed_mean * fin.chord_m / nu, rel=1e-12)


def test_generated_truth_is_the_sandia_section(fin_day):
    """The comparison is meaningful: the measured C_L tracks the 2-D data, not the 3-D one."""
    _, _, day = fin_day
    t = day.fins.table
    small = t[t["angle_deg"] <= 10]
    assert np.all(np.abs(small["cl"] - small["cl_sandia"]) < 0.01)
    # the finite-span expectation of this low-aspect-ratio fin is far lower (away from 0 deg)
    lifting = small[small["angle_deg"] > 0]
    assert np.all(lifting["cl_3d"] < 0.8 * lifting["cl_sandia"])


def test_stall_found_at_the_last_angle_before_the_fall(fin_day):
    """Sandia's C_L peaks near 9 deg at Re ≈ 1.1e5 and at 10 deg from 1.7e5 to 2.9e5.

    The tested angles step 7.5 -> 10 -> 15 deg, so the first local maximum of the measured
    C_L(α) is 7.5 deg at 1.0 m/s and 10 deg at the three higher speeds; the least drag is at
    the zero-lift runs.
    """
    _, _, day = fin_day
    curves = day.fins.curves
    assert curves["stall_reached"].all()
    assert curves["stall_angle_deg"].tolist() == [7.5, 10.0, 10.0, 10.0]
    assert (curves["cd_min_angle_deg"] == 0.0).all()
    slow = curves.iloc[0]
    cl_75, _ = sandia.section_coefficients(7.5, slow["re_mean"])
    assert slow["cl_max"] == pytest.approx(float(cl_75), abs=0.01)


def test_lift_slope_interval_contains_sandia_slope(fin_day):
    """The slope comes from the linear range, below each speed's stall: at 1.0 m/s 0-5 deg, at
    the others 0-7.5 deg; three or more angles, so an intercept and a finite interval."""
    _, _, day = fin_day
    curves = day.fins.curves
    assert curves["slope_angles_deg"].tolist() == ["0 2.5 5"] + ["0 2.5 5 7.5"] * 3
    for row in curves.itertuples():
        assert row.lift_slope_ci_low <= row.lift_slope_sandia_2d <= row.lift_slope_ci_high
        assert row.lift_slope == pytest.approx(row.lift_slope_sandia_2d, rel=0.02)
        assert row.lift_slope_3d < 0.5 * row.lift_slope  # AR = 1.25: lifting line far lower
    assert not [w for w in map(str, day.warnings) if w.startswith("fin lift slope")]


LOW_RE_PLAN = [
    RunSpec("sting", 0.0, v, 0.3, tare_group="post") for v in (0.3, 0.5, 0.8)
] + [
    RunSpec("fin", a, v, 0.3, tare_group="post")
    for a in (0.0, 2.5, 5.0, 7.5)
    for v in (0.3, 0.5, 0.8)
]


def test_low_reynolds_runs_are_warned(tmp_path):
    """At 0.3-0.8 m/s the 0.12 m chord runs at Re ≈ 3.4e4-9.1e4: every fin run is warned."""
    make_fin_day(tmp_path, seed=5, runs=LOW_RE_PLAN)
    sections = fin_protocol_sections(".", "out")
    write_protocol(tmp_path / "p.toml", **sections)
    day = process_day(tmp_path / "p.toml", jobs=1)
    t = day.fins.table
    low = t[t["re"] < 1e5]
    assert len(low) == len(t) == 12
    warned = [w for w in map(str, day.warnings) if "below 1e5" in w]
    assert len(warned) == len(low) > 0
    for run, re in zip(low["run"], low["re"], strict=True):
        mine = [w for w in warned if w.startswith(f"run {run}: Re = ")]
        assert len(mine) == 1, (run, warned)
        assert f"Re = {re:.1e}".replace("e+0", "e") in mine[0]
    assert warned == list(day.fins.warnings[: len(warned)])


def test_sandia_re_clamp_reaches_the_day_warnings():
    """A run below the table's Re = 1e4 is clamped; the day (report, provenance) says so."""
    from types import SimpleNamespace

    from towtank.ingest.protocol import Fin
    from towtank.pipeline import fin_stage

    angles = [0.0, 2.5, 5.0, 7.5, 10.0]
    runs = pd.DataFrame({
        "run": range(1, 11), "config": "fin", "status": "ok", "angle_deg": angles * 2,
        "speed_mean": [0.06] * 5 + [1.0] * 5, "re": [6.9e3] * 5 + [1.14e5] * 5,
        "cl": 0.1, "cd": 0.02, "drag_mean": 0.01, "lift_mean": 0.01, "rho": 998.6,
    })
    day = SimpleNamespace(protocol=SimpleNamespace(fin=Fin(0.12, 0.15, x_m=-0.61)), runs=runs,
                          warnings=[], fin_result=None)
    with warnings.catch_warnings():
        warnings.simplefilter("error", sandia.SandiaRangeWarning)  # none escapes to stderr
        day.fin_result, warns = fin_stage(day.protocol, day.runs)
        day.warnings.extend(warns)
    clamp = [w for w in day.warnings if w.startswith("fin: Reynolds number")]  # said once
    assert len(clamp) == 1, day.warnings
    assert clamp[0] == (
        "fin: Reynolds number 6.9e3 is below the Sandia NACA 0015 table's lowest Re = 1.0e4; "
        "the section data at Re = 1.0e4 are used instead."
    )
    assert clamp[0] in day.fin_result.warnings


def test_wall_mounting_doubles_the_aspect_ratio(fin_day, tmp_path):
    d, _, day = fin_day
    sections = fin_protocol_sections(str(d), str(tmp_path / "out"))
    sections["fin"]["mounting"] = "wall"
    write_protocol(tmp_path / "wall.toml", **sections)
    wall = process_day(tmp_path / "wall.toml", jobs=1)
    assert wall.fins.aspect_ratio == pytest.approx(2 * day.fins.aspect_ratio)
    # in the attached-flow range a larger effective aspect ratio lifts the finite-span
    # expectation toward the 2-D data (past stall the effective angle decides, not the slope);
    # at 0 deg both are zero
    angle = day.fins.table["angle_deg"]
    attached = (angle > 0.0) & (angle <= 5.0)
    w, f = wall.fins.table[attached], day.fins.table[attached]
    assert np.all(w["cl_3d"] > f["cl_3d"])
    assert np.all(w["cl_3d"] < w["cl_sandia"])


def test_control_derivatives_follow_the_measured_slope(fin_day):
    """c_La is the mean of the per-speed linear-range slopes, and the table says so."""
    _, _, day = fin_day
    ctrl = day.fins.control.set_index("symbol")
    fin = day.protocol.fin
    rho = day.runs.loc[day.runs["config"] == "fin", "rho"].mean()
    slope = float(np.nanmean(day.fins.curves["lift_slope"]))
    np.testing.assert_allclose(ctrl["lift_slope"], slope, rtol=1e-12)
    assert ctrl["lift_slope_source"].str.startswith(
        "mean of the measured linear-range lift slopes (|α| ≤ 10°, below stall) of the speed "
        "groups 1.00 m/s (0 2.5 5°), 1.50 m/s (0 2.5 5 7.5°)"
    ).all()
    assert ctrl.loc["Y_uudr", "value"] == pytest.approx(rho * slope * fin.area)
    assert ctrl.loc["Z_uuds", "value"] == pytest.approx(-rho * slope * fin.area)
    assert ctrl.loc["N_uudr", "value"] == pytest.approx(rho * slope * fin.area * fin.x_m)
    assert ctrl.loc["M_uuds", "value"] < 0  # fins aft of the centre


def test_sample_fin_day_cli(sample_outputs):
    code, out = sample_outputs("naca0015_fin").code, sample_outputs("naca0015_fin").out
    assert code == 0
    t = pd.read_csv(out / "fins.csv")
    assert list(t.columns[: len(FINS_COLUMNS)]) == FINS_COLUMNS
    # one row per fin run of the plan: 10 angles (0, 2.5, 5, 7.5, then 10-35 deg) x 4 speeds;
    # the 5 post (sting) tares are not fin runs
    n_fin = sum(spec.config == "fin" for spec in fin_day_plan())
    assert len(t) == n_fin == 40
    assert np.all(np.abs(t["cl"] - t["cl_sandia"]) < 0.01)
    curves = pd.read_csv(out / "fin_curves.csv")
    assert len(curves) == 4 and (curves["n_runs"] == 10).all()
    # every speed resolves the slope: >= 3 angles below its stall, a finite interval
    assert curves[["lift_slope", "lift_slope_ci_low", "lift_slope_ci_high"]].notna().all().all()
    assert (curves["lift_slope_ci_high"] - curves["lift_slope_ci_low"] < 3.0).all()
    # past stall no finite-span value is given (lifting line needs attached flow)
    assert t.loc[t["angle_deg"] >= 25, "cl_3d"].isna().all()
    assert t.loc[t["angle_deg"] <= 15, "cl_3d"].notna().all()


def test_lifting_line_against_closed_form():
    """Elliptic wing, AR = 6, e = 1, thin-aerofoil section: a = 2π/(1 + 2/AR)."""

    def thin(alpha_deg, re):
        a = np.radians(np.asarray(alpha_deg, dtype=float))
        return 2 * np.pi * a, np.full(np.shape(a), 0.01)

    cl, cd = fins.finite_span_coefficients(np.array([2.0, 4.0]), np.array([1e6, 1e6]), 6.0,
                                           section=thin)
    expected = 2 * np.pi / (1 + 2 * np.pi / (np.pi * 6.0))
    np.testing.assert_allclose(cl / np.radians([2.0, 4.0]), expected, rtol=1e-9)
    np.testing.assert_allclose(cd, 0.01 + cl**2 / (math.pi * 6.0), rtol=1e-9)


def test_fin_run_beyond_180_deg_is_left_out_with_a_warning():
    """The section data end at ±180 deg (ValueError): such a run must not stop the day."""
    from types import SimpleNamespace

    from towtank.ingest.protocol import Fin
    from towtank.pipeline import fin_stage

    runs = pd.DataFrame({
        "run": [1, 2, 3, 4], "config": "fin", "status": "ok",
        "angle_deg": [0.0, 2.5, 5.0, 200.0], "speed_mean": 1.0, "re": 1.14e5, "cl": 0.1,
        "cd": 0.02, "drag_mean": 0.01, "lift_mean": 0.01, "rho": 998.6,
    })
    day = SimpleNamespace(protocol=SimpleNamespace(fin=Fin(0.12, 0.15)), runs=runs,
                          warnings=[], fin_result=None)
    day.fin_result, warns = fin_stage(day.protocol, day.runs)
    day.warnings.extend(warns)
    assert day.fin_result.table["run"].tolist() == [1, 2, 3]
    assert day.warnings[0] == (
        "run 4: fin angle 200° is outside −180…180°, the range of the Sandia section data; "
        "the run is left out of the fin analysis."
    )


def test_protocol_linear_max_deg_sets_the_linear_range(fin_day, tmp_path):
    from towtank.errors import ProtocolError
    from towtank.ingest.protocol import load_protocol

    d, _, day = fin_day
    sections = fin_protocol_sections(str(d), str(tmp_path / "out"))
    for bad in (0.0, -5.0, 95.0):
        sections["fin"]["linear_max_deg"] = bad
        write_protocol(tmp_path / "bad.toml", **sections)
        with pytest.raises(ProtocolError, match="linear_max_deg"):
            load_protocol(tmp_path / "bad.toml")
    sections["fin"]["linear_max_deg"] = 5.0
    write_protocol(tmp_path / "five.toml", **sections)
    five = process_day(tmp_path / "five.toml", jobs=1)
    assert five.protocol.fin.linear_max_deg == 5.0
    assert five.fins.curves["slope_angles_deg"].tolist() == ["0 2.5 5"] * 4
    assert "(|α| ≤ 5°, below stall)" in five.fins.control["lift_slope_source"].iloc[0]
    # 0-5 deg is the straight part of the section at every speed: close to its 0.11/deg
    assert five.fins.curves["lift_slope"].to_numpy() == pytest.approx(6.3, abs=0.2)


# ------------------------------------------------------------- a lab's slips on the fin's lift
def _fin_warnings(day) -> list[str]:
    """The day's sentences of the fin plausibility check."""
    return [w for w in map(str, day.warnings) if w.startswith("fin lift slope = ")]


def test_correct_fin_day_is_plausible(fin_day):
    _, _, day = fin_day
    assert _fin_warnings(day) == []
    assert not [w for w in day.fins.warnings if "swapped" in w or "gain left out" in w]


def test_swapped_lift_and_drag_channels_are_named(fin_day, tmp_path):
    """drag = { column = "lift" }, lift = { column = "drag" }: the lift slopes were 0.06-0.07
    /rad against the section's 5.9 and the fin's 2.42 (Y_uudr 1.2 for 107), with no warning
    at all (the finite-span sentence went too). Now one sentence names the slopes, the
    expectation and the swap."""
    d, _, day = fin_day
    sections = fin_protocol_sections(str(d), str(tmp_path / "out"))
    sections["channels"] = {"drag": {"column": "lift"}, "lift": {"column": "drag"}}
    write_protocol(tmp_path / "swapped.toml", **sections)
    swapped = process_day(tmp_path / "swapped.toml", jobs=1)
    slopes = swapped.fins.curves["lift_slope"]
    assert (slopes.abs() < 0.3).all()  # the drag's slope: the slip is there
    (text,) = _fin_warnings(swapped)
    assert "at U ≈ 1.00, 1.50, 2.00 and 2.50 m/s" in text
    assert f"{slopes.min():.2g}" in text and "expected of this fin" in text
    assert "lift and drag channels swapped?" in text
    assert text in swapped.fins.warnings  # the stage's warnings, the report's Quality page


@pytest.fixture(scope="module")
def lab_fin_day(tmp_path_factory):
    """A fin day recorded in volts: lift 25 N/V, drag 20 N/V (columns 'Fx load cell (V)',
    'Fy load cell (V)'), in CSV."""
    d = tmp_path_factory.mktemp("lab_fin_day")
    lab = LabChannels(lift_gain=25.0)
    make_fin_day(d, seed=41, file_format="csv", channel_style="lab", channels=lab)
    return d, lab


def _lab_protocol(day_dir, path, lab, **lift):
    sections = fin_protocol_sections(str(day_dir), str(path.parent / "out"))
    sections["channels"] = lab.protocol_section()
    sections["channels"]["lift"].update(lift)
    return write_protocol(path, **sections)


@pytest.mark.heavy
def test_lift_gain_left_out_is_named(lab_fin_day, tmp_path):
    """The lift in V with its 25 N/V left out (gain 1.0): slopes 0.23-0.24 /rad, Y_uudr 4.3
    for 107, and no warning. With the gain the same files are plausible."""
    d, lab = lab_fin_day
    right = process_day(_lab_protocol(d, tmp_path / "right.toml", lab), jobs=1)
    assert right.rejected == {} and _fin_warnings(right) == []
    assert right.fins.curves["lift_slope"].between(5.5, 6.5).all()
    wrong = process_day(_lab_protocol(d, tmp_path / "wrong.toml", lab, gain=1.0), jobs=1)
    np.testing.assert_allclose(wrong.fins.curves["lift_slope"],
                               right.fins.curves["lift_slope"] / 25.0, rtol=0.05)
    (text,) = _fin_warnings(wrong)
    assert "a lift gain left out" in text and "2.42 /rad expected of this fin" in text
    assert "C_D rises" not in text


def test_fin_run_with_a_blank_lift_column_is_rejected(lab_fin_day, tmp_path):
    """Run 14 (5° at 1.0 m/s) with every lift cell blank was kept as ok, its lift dropped with
    a note in runs.csv, and the 1.0 m/s group lost its slope to a warning blaming the stall.
    A fin run needs its lift: rejected in one sentence naming the run, the file and the
    channel, the rest of the day processed."""
    d, lab = lab_fin_day
    day_dir = tmp_path / "day"
    shutil.copytree(d, day_dir)
    path = day_dir / "data" / "run_014.csv"
    frame = pd.read_csv(path)
    frame[lab.lift] = np.nan  # written as empty cells
    frame.to_csv(path, index=False)
    day = process_day(_lab_protocol(day_dir, tmp_path / "p.toml", lab), jobs=1)
    assert list(day.rejected) == [14]
    reason = str(day.rejected[14])
    assert reason.startswith("run 14: run_014.csv: the lift channel (column 'Fy load cell (V)') "
                             "holds no numbers"), reason
    assert "a fin run needs its lift" in reason
    runs = day.runs.set_index("run")
    assert runs.loc[14, "status"] == "rejected" and runs.loc[14, "reason"] == reason
    assert (runs.drop(index=14)["status"] == "ok").all()
    assert len(day.fins.table) == 39 and 14 not in day.fins.table["run"].tolist()
    # the group without its 5° run has no slope, and the warning says which run is missing
    slow = [w for w in map(str, day.warnings) if w.startswith("fin lift slope at U ≈ 1.00")]
    assert len(slow) == 1 and slow[0].endswith("no slope (run 14 at 5° was rejected)."), slow
    assert day.fins.curves["lift_slope"].iloc[1:].notna().all()


def test_fin_run_without_a_lift_column_is_rejected(tmp_path):
    """A protocol that names no lift column (the lift then optional) and run 14's file
    written without it: the run was kept "ok" with C_L empty. A fin run needs its lift:
    rejected in one sentence naming the file and the columns it has; the hull reading of the
    same file keeps it, and the rest of the day is processed."""
    from towtank.errors import RunError
    from towtank.ingest.runfile import RawRun
    from towtank.reduce.run import check_fin_lift

    make_fin_day(tmp_path, seed=41, file_format="csv")
    path = tmp_path / "data" / "run_014.csv"
    frame = pd.read_csv(path)
    frame.drop(columns=["lift"]).to_csv(path, index=False)
    protocol = write_protocol(tmp_path / "p.toml", **fin_protocol_sections(".", "out"))
    day = process_day(protocol, jobs=1)
    assert list(day.rejected) == [14]
    reason = str(day.rejected[14])
    assert reason == ("run 14: run_014.csv: the file has no lift column (columns found: "
                      "'time', 'speed', 'drag'), and a fin run needs its lift (a channel not "
                      "recorded, or a lift column under another name: map it under "
                      "[channels] lift)"), reason
    assert (day.runs.set_index("run").drop(index=14)["status"] == "ok").all()
    assert 14 not in day.fins.table["run"].tolist() and len(day.fins.table) == 39
    raw = RawRun(time=np.arange(3.0), speed=np.ones(3), drag=np.ones(3),
                 columns=("time", "speed", "drag"))
    check_fin_lift(raw, "hull", "run_014.csv")  # a hull's lift is a check: kept
    with pytest.raises(RunError, match="has no lift column"):
        check_fin_lift(raw, " Fin ", "run_014.csv")


def test_blank_lift_column_rejects_fin_runs_only(lab_fin_day, tmp_path):
    """The same file read for a hull run keeps it (a hull's lift is a check, in no
    coefficient), with the reader's note; read_run and reduce_run reject the fin run as the
    day does, and the cache keeps a fin run's reduction apart from a hull run's."""
    from towtank import read_run, reduce_run
    from towtank.errors import RunError
    from towtank.ingest.protocol import load_protocol
    from towtank.reduce.run import reduce_record
    from towtank.runtime.cache import settings_key

    d, lab = lab_fin_day
    data = tmp_path / "data"
    shutil.copytree(d / "data", data)
    path = data / "run_014.csv"
    frame = pd.read_csv(path)
    frame[lab.lift] = np.nan
    frame.to_csv(path, index=False)
    shutil.copy(d / "run_sheet.csv", tmp_path / "run_sheet.csv")
    protocol = load_protocol(_lab_protocol(tmp_path, tmp_path / "p.toml", lab))
    row = {"run": 14, "file": "run_014.csv", "speed_nominal": 1.0, "accel_nominal": 0.5,
           "test": "steady"}
    _, red, rejection, preview = reduce_record(protocol, {**row, "config": "fin"})
    assert red is None and "the lift channel" in str(rejection) and preview is not None
    _, red, rejection, _ = reduce_record(protocol, {**row, "config": "hull"})
    assert rejection is None and not red.has_lift
    assert "the lift column holds no numbers; the channel is ignored" in red.notes
    with pytest.raises(RunError, match="a fin run needs its lift"):
        reduce_run(read_run(path, protocol), protocol, run=14)
    assert settings_key(protocol, {**row, "config": "fin"}) != \
        settings_key(protocol, {**row, "config": "hull"})
