"""Days at the edges of what a lab hands in (issue 2 follow-ups).

A hand-set steady window must rescue a run whose plateau the detection cannot use, and be
checked when it is wrong; short plateaus and deceleration windows against the truth; a model
run faster than its tare runs is flagged; a day with too few runs for any coefficient still
writes its outputs; a voided row is never an error; out-of-range [processing] values stop the
protocol; runs.csv's water properties are those of each run's own temperature; an output
folder holding the user's own files keeps them.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import Day, process, write_hull_protocol

from towtank.errors import ProtocolError
from towtank.ingest.protocol import load_protocol
from towtank.reference.water import water_properties
from towtank.results import STAGES, Notice
from towtank.testing import synthetic as syn

HIGH = 0.5  # [m/s²] set acceleration of the steady runs
STINGS = [syn.RunSpec("sting", 0.0, v, HIGH) for v in (0.8, 1.2, 1.6, 2.0)] + [
    syn.RunSpec("sting", 0.0, 2.0, 1.0, test="accel")
]
SHORT_RUN = 6  # hull, 0°, 1.2 m/s with a 0.9 s plateau: too short to detect, set by hand
OVERLAP_RUN = 7  # hull, 0°, 1.6 m/s: its hand window starts inside the acceleration
FAST_RUN = 8  # hull, 0°, 2.4 m/s: faster than every tare run (0.8-2.0 m/s)
PLATEAU_RUNS = {9: 1.3, 10: 1.6, 11: 2.0}  # run: plateau length [s] at 1.0 m/s
NO_ACCEL_RUN = 12  # hull, 0°, made for its acceleration, but too slow to have a usable one
SLIGHT_RUN = 13  # hull, 0°, 1.2 m/s at a gentle 0.1 m/s²: a hand window a little too early
STILL_RUN = 14  # hull, 0°, 1.6 m/s: a hand window before the carriage moves
TINY_RUN = 15  # hull, 0°, 1.6 m/s: a hand window of two samples
STING_WINDOW_RUN = 16  # a sting run whose hand window is the whole run
PLAN = STINGS + [
    syn.RunSpec("hull", 0.0, 1.2, HIGH, plateau_s=0.9),
    syn.RunSpec("hull", 0.0, 1.6, HIGH),
    syn.RunSpec("hull", 0.0, 2.4, HIGH),
    *[syn.RunSpec("hull", 0.0, 1.0, HIGH, plateau_s=p) for p in PLATEAU_RUNS.values()],
    syn.RunSpec("hull", 0.0, 0.2, 0.5, test="accel"),
    syn.RunSpec("hull", 0.0, 1.2, 0.1),
    syn.RunSpec("hull", 0.0, 1.6, HIGH),
    syn.RunSpec("hull", 0.0, 1.6, HIGH),
    syn.RunSpec("sting", 0.0, 1.2, HIGH),
]


def _hand_windows(day_dir: Path) -> None:
    truth = syn.load_truth(day_dir)["runs"]
    sheet_path = day_dir / "run_sheet.csv"
    sheet = pd.read_csv(sheet_path, dtype=str, keep_default_na=False)
    sheet["window_start_s"] = ""
    sheet["window_end_s"] = ""
    short = truth[str(SHORT_RUN)]
    rows = sheet["run"].astype(int)
    sheet.loc[rows == SHORT_RUN, "window_start_s"] = f"{short['t_plateau_start'] + 0.1:.3f}"
    sheet.loc[rows == SHORT_RUN, "window_end_s"] = f"{short['t_plateau_end'] - 0.1:.3f}"
    over = truth[str(OVERLAP_RUN)]
    sheet.loc[rows == OVERLAP_RUN, "window_start_s"] = f"{over['t_const_accel_start'] + 0.5:.3f}"
    sheet.loc[rows == OVERLAP_RUN, "window_end_s"] = f"{over['t_plateau_end'] - 1.0:.3f}"
    slight = truth[str(SLIGHT_RUN)]  # 0.6 s early: into the trimmed acceleration window
    sheet.loc[rows == SLIGHT_RUN, "window_start_s"] = f"{slight['t_plateau_start'] - 0.6:.3f}"
    sheet.loc[rows == SLIGHT_RUN, "window_end_s"] = f"{slight['t_plateau_end'] - 1.0:.3f}"
    sheet.loc[rows == STILL_RUN, "window_start_s"] = "0.5"
    sheet.loc[rows == STILL_RUN, "window_end_s"] = "2.5"
    tiny = truth[str(TINY_RUN)]
    sheet.loc[rows == TINY_RUN, "window_start_s"] = f"{tiny['t_plateau_start'] + 1.0:.3f}"
    sheet.loc[rows == TINY_RUN, "window_end_s"] = f"{tiny['t_plateau_start'] + 1.005:.3f}"
    whole = truth[str(STING_WINDOW_RUN)]
    sheet.loc[rows == STING_WINDOW_RUN, "window_start_s"] = "2.0"
    sheet.loc[rows == STING_WINDOW_RUN, "window_end_s"] = f"{whole['t_decel_end']:.3f}"
    sheet.to_csv(sheet_path, index=False, lineterminator="\n")


@pytest.fixture(scope="session")
def edge_day(tmp_path_factory) -> Day:
    day_dir = tmp_path_factory.mktemp("edge_day")
    syn.make_hull_day(day_dir, seed=21, runs=PLAN, sheet_format="csv", file_format="csv",
                      channel_style="canonical")
    _hand_windows(day_dir)
    protocol = write_hull_protocol(day_dir, sheet_format="csv", channel_style="canonical")
    return Day(day_dir, protocol, syn.load_truth(day_dir), process(protocol))


def _row(day: Day, run: int) -> pd.Series:
    return day.result.runs.set_index("run").loc[run]


def test_plateau_too_short_to_detect_is_rejected_without_a_hand_window(tmp_path):
    syn.make_hull_day(tmp_path, seed=21, runs=PLAN, sheet_format="csv", file_format="csv",
                      channel_style="canonical")
    protocol = write_hull_protocol(tmp_path, sheet_format="csv", channel_style="canonical")
    result = process(protocol)
    assert SHORT_RUN in result.rejected
    assert "plateau" in str(result.rejected[SHORT_RUN])
    # the run was read: its traces are kept for the report's appendix, at 10 Hz
    preview = result.previews[SHORT_RUN]
    truth = syn.load_truth(tmp_path)["runs"][str(SHORT_RUN)]
    assert np.median(np.diff(preview["t"])) == pytest.approx(0.1)
    assert np.nanmax(preview["U"]) == pytest.approx(truth["speed"], rel=0.05)
    assert set(result.previews) == set(result.rejected)

    from towtank.report import pdf

    grid = pdf.ThumbGrid()
    grid.draw(result, [SHORT_RUN, SHORT_RUN + 1])
    ax, twin = grid.cells[0]
    assert ax.axison and twin.get_visible()
    assert len(ax.lines) == 1 and len(twin.lines) >= 1  # speed; drag (and lift)
    assert any("rejected" in t.get_text() and "plateau" in t.get_text() for t in ax.texts)


def test_hand_window_rescues_a_run_the_detection_cannot_use(edge_day: Day):
    row = _row(edge_day, SHORT_RUN)
    truth = edge_day.run_truth(SHORT_RUN)
    assert row["status"] == "ok", row["reason"]
    assert row["window_source"].startswith("manual")
    assert "no plateau detected" in row["window_source"]
    # the window lies in the short plateau: the mean is the steady drag
    assert abs(row["drag_mean"] - truth["drag_model"]) <= max(0.01 * truth["drag_model"], 0.002)
    assert row["speed_mean"] == pytest.approx(truth["speed"], rel=3e-3)


def test_hand_window_spanning_the_acceleration_is_rejected(edge_day: Day):
    """A window from the middle of the acceleration to the plateau's end: its speed varies by
    ~0.6 m/s, twenty plateau bands; used, it would bias the steady drag. The run is rejected."""
    reason = str(edge_day.result.rejected[OVERLAP_RUN])
    assert reason.startswith(f"run {OVERLAP_RUN}: run_{OVERLAP_RUN:03d}.csv: the speed varies by")
    assert reason.endswith("the window is not steady")


@pytest.mark.parametrize(("run", "words"), [
    (STILL_RUN, "lies where the carriage is (nearly) still"),
    (TINY_RUN, "shorter than the 0.5 s a steady mean needs"),
    (STING_WINDOW_RUN, "the window is not steady"),
])
def test_hand_windows_that_cannot_be_steady_reject_their_run(edge_day: Day, run, words):
    assert words in str(edge_day.result.rejected[run])
    assert STING_WINDOW_RUN not in edge_day.result.tares["A"].runs  # it feeds no tare


def test_hand_window_a_little_early_is_used_and_warned(edge_day: Day):
    """0.6 s before the plateau at 0.1 m/s²: 0.06 m/s of spread, within five plateau bands,
    reaching into the detected acceleration: used, with both warnings on the terminal."""
    row = _row(edge_day, SLIGHT_RUN)
    assert row["status"] == "ok", row["reason"]
    warned = [str(w) for w in edge_day.result.warnings if w.run == SLIGHT_RUN]
    assert any("overlaps the detected constant acceleration" in w for w in warned)
    assert any("speed varies" in w for w in warned)
    # the good hand window raises no such warning
    assert not any(w.run == SHORT_RUN and ("overlaps" in str(w) or "varies" in str(w))
                   for w in edge_day.result.warnings)


def test_the_day_warnings_are_notices_with_their_stage_run_and_file(edge_day: Day):
    """Each warning of the day is a Notice: its sentence, the stage it comes from and, for a
    run's own warning, that run and its file (as the sheet names them)."""
    notes = edge_day.result.warnings
    assert notes and all(isinstance(n, Notice) and n.stage in STAGES for n in notes)
    runs = edge_day.result.runs
    files = dict(zip(runs["run"].astype(int), runs["file"], strict=True))
    own = [n for n in notes if n.run is not None]
    assert {SLIGHT_RUN, NO_ACCEL_RUN, FAST_RUN} <= {n.run for n in own}
    for n in own:
        assert str(n).startswith(f"run {n.run}: ") and n.stage in ("reduce", "sheet")
        assert n.file is None or n.file == files[n.run]
    assert {n.file for n in own if n.stage == "reduce"} >= {files[SLIGHT_RUN]}


def test_accel_run_without_acceleration_stretch_is_warned(edge_day: Day):
    """A run made for its acceleration (test = accel) that has none usable is said on the
    terminal, not only in runs.csv's notes; a steady run's missing stretch stays a note."""
    row = _row(edge_day, NO_ACCEL_RUN)
    assert row["status"] == "ok" and "no usable constant-acceleration" in row["notes"]
    assert any(w.run == NO_ACCEL_RUN and "no usable constant-acceleration" in str(w)
               for w in edge_day.result.warnings)
    steady_notes = [r for r in PLATEAU_RUNS if "no usable" in _row(edge_day, r)["notes"]]
    assert not any(w.run == r and "no usable" in str(w)
                   for r in steady_notes for w in edge_day.result.warnings)


def test_model_run_faster_than_its_tare_runs_is_flagged(edge_day: Day):
    fast = _row(edge_day, FAST_RUN)
    assert fast["status"] == "ok"
    assert "outside the tare runs' range" in fast["notes"]
    assert any(w.run == FAST_RUN and "outside the tare" in str(w)
               for w in edge_day.result.warnings)
    for run in PLATEAU_RUNS:
        assert "outside the tare" not in _row(edge_day, run)["notes"]


@pytest.mark.parametrize("run", sorted(PLATEAU_RUNS))
def test_short_plateaus_are_found_inside_the_truth(edge_day: Day, run: int):
    """Plateaus of 1.3-2 s at 1 m/s: found, trimmed inside the true plateau, drag within 1 %."""
    row = _row(edge_day, run)
    truth = edge_day.run_truth(run)
    assert row["status"] == "ok", row["reason"]
    assert truth["t_plateau_end"] - truth["t_plateau_start"] == pytest.approx(PLATEAU_RUNS[run])
    assert truth["t_plateau_start"] <= row["steady_start_s"] < row["steady_end_s"]
    assert row["steady_end_s"] <= truth["t_plateau_end"]
    assert abs(row["drag_mean"] - truth["drag_model"]) <= max(0.01 * truth["drag_model"], 0.002)


def test_deceleration_windows_lie_inside_the_true_deceleration(hull_day: Day):
    """Every detected constant-deceleration window lies within the truth's constant part."""
    found = 0
    for run, red in hull_day.result.reductions.items():
        w = red.windows.get("decel")
        if w is None:
            continue
        truth = hull_day.run_truth(run)
        dt = 1.0 / truth["fs"]
        assert truth["t_decel_start"] - dt <= w[0] < w[1] <= truth["t_decel_end"] + dt, run
        found += 1
    assert found >= 20


def test_runs_csv_water_properties_at_each_runs_temperature(hull_day: Day):
    runs = hull_day.result.runs
    ok = runs[runs["status"] == "ok"]
    temps = ok["water_temp_C"].to_numpy(float)
    assert np.ptp(temps) > 0.2, "the generated day spreads the water temperature"
    for _, row in ok.iterrows():
        wp = water_properties(row["water_temp_C"], "fresh")
        rho, nu = float(wp.rho), float(wp.nu)
        truth = hull_day.run_truth(row["run"])
        assert row["rho"] == pytest.approx(rho, rel=1e-12)
        assert row["nu"] == pytest.approx(nu, rel=1e-12)
        assert row["rho"] == pytest.approx(truth["rho"], rel=1e-9)
        length = 0.353
        assert row["re"] == pytest.approx(row["speed_mean"] * length / nu, rel=1e-9)


def test_tare_fit_recovers_the_generators_coefficients(hull_day: Day):
    """t2, t1 and m_t of the drag tare within 2 % of the truth (the sting's own model)."""
    truth = hull_day.truth["tares"]["A"]
    fit = hull_day.result.tares["A"].drag
    t2, t1, m_t = (float(c) for c in fit.coef)
    assert t2 == pytest.approx(truth["t2"], rel=0.02)
    assert m_t == pytest.approx(truth["m_t"], rel=0.02)
    # t1 is small: within 2 % of the tare force it makes at 1 m/s
    assert abs(t1 - truth["t1"]) <= 0.02 * (truth["t2"] + truth["t1"])


def test_tare_within_two_percent_strictly(hull_day: Day):
    """The issue's 2 % on the tare, with no absolute floor, down to the 0.1 m/s tows."""
    runs = hull_day.result.runs
    ok = runs[(runs["status"] == "ok") & (runs["config"] == "hull")]
    for _, row in ok.iterrows():
        truth = hull_day.run_truth(row["run"])["tare_drag"]
        assert abs(row["tare_drag"] - truth) <= 0.02 * truth, (row["run"], row["tare_drag"], truth)


# ------------------------------------------------------------------------- thin days
def _tiny_day(tmp_path: Path, plan: list[syn.RunSpec]) -> Path:
    syn.make_hull_day(tmp_path, seed=5, runs=plan, sheet_format="csv", file_format="csv",
                      channel_style="canonical")
    return write_hull_protocol(tmp_path, sheet_format="csv", channel_style="canonical")


@pytest.mark.heavy
def test_day_without_any_coefficient_still_writes_its_outputs(tmp_path):
    """Tare runs and one hull run at 5°: no coefficient can be fitted; every output is written
    and the missing runs are named (exit 0, not an internal error)."""
    from towtank.commands import cli

    protocol = _tiny_day(tmp_path, STINGS[:2] + [syn.RunSpec("hull", 5.0, 1.2, HIGH)])
    out = tmp_path / "out"
    code = cli.main(["process", str(protocol), "--out", str(out), "--quiet", "--jobs", "1"])
    assert code == 0
    runs = pd.read_csv(out / "runs.csv")
    assert list(runs["status"]) == ["ok", "ok", "ok"]
    coef = pd.read_csv(out / "coefficients.csv")
    assert coef.empty and list(coef.columns[:3]) == ["symbol", "value", "unit"]
    assert (out / "report.pdf").is_file() and (out / "report.xlsx").is_file()


def test_void_row_with_a_sheet_fault_is_listed_not_rejected(tmp_path):
    protocol = _tiny_day(tmp_path, STINGS[:2] + [syn.RunSpec("hull", 0.0, 1.2, HIGH)])
    sheet_path = tmp_path / "run_sheet.csv"
    sheet = pd.read_csv(sheet_path, dtype=str, keep_default_na=False)
    extra = pd.DataFrame([
        {**{c: "" for c in sheet.columns}, "run": "10", "file": "", "config": "hull",
         "angle_deg": "0", "status": "void", "remarks": "aborted before logging"},
        {**{c: "" for c in sheet.columns}, "run": "11", "file": "run_099.csv", "config": "hul",
         "angle_deg": "0", "status": "void", "remarks": "typo row, voided"},
    ])
    pd.concat([sheet, extra]).to_csv(sheet_path, index=False, lineterminator="\n")
    result = process(protocol)
    assert result.rejected == {}
    runs = result.runs.set_index("run")
    assert runs.loc[10, "status"] == "void" and runs.loc[10, "reason"] == "aborted before logging"
    assert runs.loc[11, "status"] == "void"


@pytest.mark.parametrize(
    ("key", "value", "words"),
    [
        ("trim_s", -1.0, "trim_s"),
        ("cutoff_hz", 0.0, "cutoff_hz"),
        ("min_steady_s", -0.5, "min_steady_s"),
        ("steady_tolerance", 2.0, "steady_tolerance"),
        ("max_bad_row_fraction", 0.9, "max_bad_row_fraction"),
        ("damping_alpha_max_deg", 120.0, "damping_alpha_max_deg"),
        ("jobs", 0, "jobs"),
    ],
)
def test_out_of_range_processing_values_stop_the_protocol(tmp_path, key, value, words):
    syn.make_hull_day(tmp_path, seed=5, runs=STINGS[:1], sheet_format="csv",
                      file_format="csv", channel_style="canonical")
    protocol = write_hull_protocol(tmp_path, sheet_format="csv", channel_style="canonical",
                                   processing={key: value})
    with pytest.raises(ProtocolError, match=words):
        load_protocol(protocol)


def test_cutoff_above_nyquist_rejects_each_run_with_that_reason(tmp_path):
    protocol = _tiny_day(tmp_path, STINGS[:2])
    text = protocol.read_text(encoding="utf-8")
    protocol.write_text(text.replace("[processing]", "[processing]\ncutoff_hz = 150.0")
                        if "[processing]" in text else text + "\n[processing]\ncutoff_hz = 150.0\n",
                        encoding="utf-8")
    result = process(protocol)
    assert set(result.rejected) == {1, 2}
    for reason in result.rejected.values():
        assert "cutoff_hz = 150 Hz is not below half the file's sample rate" in str(reason)


def test_output_folder_with_the_users_files_keeps_them(tmp_path):
    from towtank.commands import cli
    from towtank.runtime import manifest

    protocol = _tiny_day(tmp_path, STINGS[:2] + [syn.RunSpec("hull", 0.0, 1.2, HIGH),
                                                  syn.RunSpec("hull", 0.0, 1.6, HIGH)])
    out = tmp_path / "shared_folder"
    (out / "notes").mkdir(parents=True)
    (out / "notes" / "day.txt").write_text("the carriage squeaked", encoding="utf-8")
    (out / "junk.txt").write_text("mine", encoding="utf-8")
    (out / "fins.csv").write_text("stale output of an earlier fin day\n", encoding="utf-8")
    (out / "fin_curves.csv").write_text("stale too\n", encoding="utf-8")
    # written by an earlier towtank run (its manifest says so): they may be replaced
    manifest.write_manifest(out, manifest.describe(out, {"fins.csv", "fin_curves.csv"}))
    for _ in range(2):  # the second time over its own outputs too
        code = cli.main(["process", str(protocol), "--out", str(out), "--quiet",
                         "--no-report", "--jobs", "1"])
        assert code == 0
        assert (out / "junk.txt").read_text(encoding="utf-8") == "mine"
        assert (out / "notes" / "day.txt").read_text(encoding="utf-8") == "the carriage squeaked"
        assert (out / "runs.csv").is_file() and (out / "provenance.json").is_file()
        # fins.csv of the earlier fin day is replaced by this hull day's (header only)
        assert (out / "fins.csv").read_text(encoding="utf-8").startswith("run,angle_deg,")
        assert len((out / "fins.csv").read_text(encoding="utf-8").splitlines()) == 1
        assert not (out / "fin_curves.csv").exists()
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]
    leftovers += [p.name for p in out.iterdir() if p.name.startswith(".")
                  and p.name not in (".cache", manifest.MANIFEST)]
    assert leftovers == []
    assert not math.isnan(pd.read_csv(out / "runs.csv")["drag_mean"].iloc[-1])
