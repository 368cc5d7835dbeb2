"""Captive days through the front doors (issue #35): generated horizontal days in csv-units and
LVM, a vertical day, rejected runs with their sentences, the [captive] cycle options, the real
KVLCC2 table of means, and ``towtank process`` writing what :func:`towtank.process_day` writes.

The days are small plans (a dozen runs, each a few seconds of data) so that each test takes a
few seconds; the large programme is :func:`towtank.testing.captive.captive_day_plan`'s.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from conftest import draw_only_pages
from openpyxl import load_workbook
from pypdf import PdfReader

import towtank
from towtank.commands.cli import main
from towtank.errors import RunError
from towtank.reduce.captive import CaptiveRun
from towtank.report import figures
from towtank.report.captive_figure import arm_curve, static_points
from towtank.report.simman import particulars
from towtank.runner import summary
from towtank.runtime.cache import settings_key
from towtank.testing.captive import (
    HORIZONTAL_SYMBOLS,
    VERTICAL_SYMBOLS,
    CaptiveRunSpec,
    make_captive_day,
)

#: Relative tolerance of a derivative against the truth (Y_r|r| / Z_q|q|, weakly excited by
#: the arm runs, 3 %).
TOL, TOL_WEAK = 0.01, 0.03
WEAK = ("Y_r|r|", "Z_q|q|")
#: The run whose PMM holds two steady cycles, and the one whose sheet frequency is 10 % off.
FEW_CYCLES, FREQUENCY_OFF = 15, 16
KVLCC2 = (Path(__file__).resolve().parents[2] / "shared" / "real" / "kvlcc2_hmri_captive"
          / "captive.csv")  # ../shared beside the repository


def small_plan() -> list[CaptiveRunSpec]:
    """14 runs that determine the 14 derivatives, then a PMM run with two steady cycles and
    one whose sheet frequency the test changes by 10 %."""
    specs = [{"test": "drift", "drift_deg": b} for b in (-8, -4, 0, 4, 8)]
    specs += [{"test": "rudder", "rudder_deg": d} for d in (-10, 10)]
    specs += [{"test": "arm", "radius_m": r} for r in (-3, 3, 6)]
    specs += [{"test": t, "amplitude_m": a, "frequency_hz": f} for t in ("sway", "yaw")
              for a, f in ((0.1, 0.2), (0.2, 0.35))]
    specs += [{"test": "sway", "amplitude_m": 0.15, "frequency_hz": 0.3, "steady_cycles": 2},
              {"test": "sway", "amplitude_m": 0.15, "frequency_hz": 0.3}]
    return [CaptiveRunSpec(run=i + 1, **s) for i, s in enumerate(specs)]


def write_day(folder: Path, *, layout: str = "csv-units", plane: str = "horizontal",
              seed: int = 3) -> tuple[Path, dict]:
    """The small day on disk, run :data:`FREQUENCY_OFF`'s sheet frequency 10 % high."""
    truth = make_captive_day(folder, plan=small_plan(), seed=seed, layout=layout, plane=plane)
    sheet_path = folder / "run_sheet.csv"
    sheet = pd.read_csv(sheet_path)
    sheet.loc[sheet["run"] == FREQUENCY_OFF, "pmm_frequency_hz"] *= 1.1
    sheet.to_csv(sheet_path, index=False)
    return folder / "protocol.toml", truth


def with_captive_options(protocol: Path, text: str) -> None:
    """``text`` added to the protocol's [captive] section."""
    body = protocol.read_text(encoding="utf-8")
    protocol.write_text(body.replace("[captive]\n", f"[captive]\n{text}\n"), encoding="utf-8")


def assert_derivatives(fit, truth: dict, symbols) -> None:
    """Every derivative within :data:`TOL` of the truth and inside its 95 % interval."""
    for s in symbols:
        e, true = fit.estimates[s], truth["derivatives"][s]
        assert e.value == pytest.approx(true, rel=TOL_WEAK if s in WEAK else TOL), s
        assert e.ci_low <= true <= e.ci_high, s


@pytest.fixture(scope="session")
def horizontal_day(tmp_path_factory):
    folder = tmp_path_factory.mktemp("captive_h")
    protocol, truth = write_day(folder)
    out = folder / "api"
    day = towtank.process_day(protocol, out=out, report=False, jobs=1)
    return SimpleNamespace(protocol=protocol, truth=truth, day=day, out=out)


# ================================================================== the horizontal day

def test_horizontal_day_derivatives_within_tolerance_and_intervals(horizontal_day):
    """csv-units: 14 derivatives within 1 % (Y_r|r| 3 %) and inside their 95 % intervals;
    the fit's reduced chi^2 near 1 (the model is the truth) with no chi^2 warning."""
    fit = horizontal_day.day.captive
    assert_derivatives(fit, horizontal_day.truth, HORIZONTAL_SYMBOLS)
    assert all(0.3 < c < 2.0 for c in fit.chi2_reduced.values()), fit.chi2_reduced
    assert not any("reduced chi^2" in str(w) for w in horizontal_day.day.warnings)


def test_a_captive_day_names_its_stage(horizontal_day):
    """The day's one line and its summary's notes list the captive stage (they said
    "stages: none" on a day whose coefficients are all captive)."""
    day = horizontal_day.day
    assert "stages: captive." in repr(day)
    assert "stages: captive." in day.summary().notes[-1]


def test_small_day_pmm_runs_agree_over_omega(horizontal_day):
    """The truth does not change with omega': no derivative "differs" over the PMM runs
    (the per-run standard errors hold the other terms' uncertainty and the test the heavy
    tails of 5-cycle standard errors)."""
    fit = horizontal_day.day.captive
    assert not [w for w in fit.warnings if ": differ (" in w]


def test_bad_pmm_runs_rejected_with_their_sentence_the_rest_processed(horizontal_day):
    day = horizontal_day.day
    assert set(day.rejected) == {FEW_CYCLES, FREQUENCY_OFF}
    few = str(day.rejected[FEW_CYCLES])
    assert f"run {FEW_CYCLES}" in few and "run_015.csv" in few
    assert "has 2 whole steady PMM cycles; at least 3 are needed" in few
    off = str(day.rejected[FREQUENCY_OFF])
    assert "0.3 Hz" in off and "pmm_frequency_hz 0.33 Hz" in off  # both values named
    assert len(day.captive.runs) == len(small_plan()) - 2


def test_pmm_csv_runs_csv_and_provenance(horizontal_day):
    out = horizontal_day.out
    pmm = pd.read_csv(out / "pmm.csv")
    assert list(pmm["run"]) == [11, 12, 13, 14]
    assert (pmm["cycles_used"] == 5).all()
    speed = pd.read_csv(out / "runs.csv").set_index("run").loc[pmm["run"], "speed_mean"]
    omega_prime = 2 * math.pi * pmm["frequency_hz"].to_numpy() * 1.33 / speed.to_numpy()
    assert pmm["omega_prime"].to_numpy() == pytest.approx(omega_prime, rel=1e-3)
    runs = pd.read_csv(out / "runs.csv").set_index("run")
    assert {"captive_X_N", "captive_Y_N", "captive_N_Nm", "pmm_cycles"} <= set(runs.columns)
    ok = runs[runs["status"] == "ok"]
    assert ok["captive_Y_N"].notna().all() and ok["captive_N_Nm"].notna().all()
    assert ok.loc[[11, 12, 13, 14], "pmm_cycles"].eq(5).all()
    captive = json.loads((out / "provenance.json").read_text())["captive"]
    assert captive["pmm_cycles_used"] == {"11": 5, "12": 5, "13": 5, "14": 5}
    assert captive["fit"]["horizontal"]["reduced_chi2"].keys() == {"Y", "N"}


def test_agreement_notes_are_notes_not_day_warnings(horizontal_day):
    """The fit's "agree" sentences are its notes; the day's warnings hold none of them."""
    fit, warnings = horizontal_day.day.captive, [str(w) for w in horizontal_day.day.warnings]
    agree = [n for n in fit.notes if ": agree (" in n]
    assert agree and not set(agree) & set(warnings)
    assert set(fit.warnings) <= set(warnings)
    assert not any(": agree (" in w for w in warnings)


def test_cli_process_exit_code_and_files_the_same_as_process_day(horizontal_day, tmp_path):
    """``towtank process`` exits 1 (runs rejected) and writes, byte for byte, the CSV tables
    and provenance :func:`towtank.process_day` wrote (the manifest aside: its times)."""
    cli = tmp_path / "cli"
    code = main(["process", str(horizontal_day.protocol), "--out", str(cli), "-q",
                 "--no-report"])
    assert code == 1
    names = ("coefficients.csv", "pmm.csv", "runs.csv", "provenance.json")
    for name in names:
        assert (cli / name).read_bytes() == (horizontal_day.out / name).read_bytes(), name


# ================================================================ other layouts and planes

def test_lvm_day_gives_the_same_derivatives(tmp_path):
    protocol, truth = write_day(tmp_path, layout="lvm", seed=4)
    day = towtank.process_day(protocol, jobs=1)
    assert set(day.rejected) == {FEW_CYCLES, FREQUENCY_OFF}
    assert_derivatives(day.captive, truth, HORIZONTAL_SYMBOLS)


def test_vertical_day_without_iyy_uses_izz_with_a_note(tmp_path):
    """A vertical day whose [model] has no iyy_kg_m2 (the generator's I_yG equals I_zG):
    the 12 vertical derivatives within tolerance, each run noting izz_kg_m2 used once."""
    protocol, truth = write_day(tmp_path, plane="vertical", seed=5)
    text = protocol.read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if not ln.startswith("iyy_kg_m2")]
    protocol.write_text("\n".join(lines) + "\n", encoding="utf-8")
    day = towtank.process_day(protocol, jobs=1)
    assert day.captive is None and day.captive_vertical is not None
    assert_derivatives(day.captive_vertical, truth, VERTICAL_SYMBOLS)
    for red in day.reductions.values():
        said = [n for n in red.notes if "iyy_kg_m2 not given" in n]
        assert len(said) == 1 and "izz_kg_m2 used as the pitch inertia" in said[0]


# ======================================================================= [captive] options

@pytest.mark.heavy
def test_captive_cycle_options_decide_which_runs_are_kept(tmp_path):
    """amplitude_tolerance = 0.12 accepts the run 10 % off the sheet; min_cycles = 6 rejects
    every PMM run of five steady cycles, naming six."""
    protocol, _ = write_day(tmp_path)
    with_captive_options(protocol, "amplitude_tolerance = 0.12")
    day = towtank.process_day(protocol, jobs=1, cache=False)
    assert FREQUENCY_OFF not in day.rejected and FEW_CYCLES in day.rejected
    protocol, _ = write_day(tmp_path / "six")
    with_captive_options(protocol, "min_cycles = 6")
    day = towtank.process_day(protocol, jobs=1, cache=False)
    assert {11, 12, 13, 14} <= set(day.rejected)
    assert "at least 6 are needed" in str(day.rejected[11])


def test_cycle_options_are_in_the_run_cache_key(tmp_path):
    protocol, _ = write_day(tmp_path)
    p = towtank.load_protocol(protocol)
    row = {"file": "run_011.csv", "test": "sway", "pmm_frequency_hz": 0.2,
           "pmm_amplitude_m": 0.1}
    from dataclasses import replace
    keys = {settings_key(replace(p, captive=replace(p.captive, **opt)), row)
            for opt in ({}, {"min_cycles": 4}, {"amplitude_tolerance": 0.1},
                        {"moment_ref": "balance"})}
    assert len(keys) == 4


@pytest.mark.heavy
def test_a_day_whose_moments_are_about_the_balance_point(tmp_path):
    """``[captive] moment_ref = "balance"`` (FORMATS section 8) with the balance 0.30 m ahead
    of O: a generated day whose truth refers to the balance point B (its sway velocity
    v_B = v + x_B r, its moments about B) gives the 14 derivatives there within tolerance and
    inside their intervals; provenance.json and the report say that no moment was moved. The
    same files processed with ``moment_ref = "origin"`` give the derivatives about O, which
    for this programme (no run has both v and r at O, so v|v| stays v|v|) are N_uv(O) =
    N_uv(B) + x_B Y_uv(B) and Y_ur(O) = Y_ur(B) + x_B Y_uv(B) (N_O = N_B + x_B Y,
    v_B = v + x_B r), each within 1 %, while Y_uv is the same at both points."""
    from towtank.testing.captive import CaptiveTruth

    x_b = 0.30
    truth = make_captive_day(tmp_path, plan=small_plan()[:14], seed=4, truth=CaptiveTruth(
        balance_x_m=x_b, moment_ref="balance"))
    protocol = tmp_path / "protocol.toml"
    assert 'moment_ref = "balance"' in protocol.read_text(encoding="utf-8")
    with pytest.MonkeyPatch.context() as mp:
        draw_only_pages(mp, lambda page: page.section.startswith("Captive")
                        or page.kind == "runs")
        mp.setattr(figures, "write_figures", lambda day, folder: [])
        day = towtank.process_day(protocol, out=tmp_path / "out", jobs=1)
    assert not day.rejected
    assert_derivatives(day.captive, truth, HORIZONTAL_SYMBOLS)
    said = json.loads((tmp_path / "out" / "provenance.json").read_text())["captive"]
    assert said["moment_reference"] == "balance" and said["moment_transfer"].startswith("none")
    # what the outputs say of the moments: about B wherever they are named, never about O
    about_b = "about the balance point (x = 0.3 m from O)"
    assert day.captive.ref_x_m == x_b and day.captive.moment_point() == about_b
    pages = [p.extract_text() for p in PdfReader(tmp_path / "out" / "report.pdf").pages]
    said_pages = " ".join(" ".join(t.split()) for t in pages)
    assert "moment N " + about_b in said_pages  # the runs table's caption
    assert "moment " + about_b + ")" in said_pages  # the captive figure's caption
    assert "about O" not in said_pages
    book = load_workbook(tmp_path / "out" / "report.xlsx", read_only=True)
    notes = {name: " ".join(str(c) for row in book[name].iter_rows(values_only=True)
                            for c in row if isinstance(c, str)) for name in ("Captive", "PMM")}
    assert all(about_b in text and "about O" not in text for text in notes.values())
    assert particulars(day).set_index("quantity").at["moment_ref_x_m", "value"] == x_b
    # the figure's rotating-arm curve is drawn at B too (v_B = x_B r at zero drift): through
    # the arm runs, 2 % of the largest (drawn at O: Y' off by 170 % of it, N' by 60 %)
    arm = static_points(day.captive, ("arm",), 90.0)
    r_prime = (day.captive.length_m / arm["radius_m"]).to_numpy(dtype=float)
    for eq, moment in (("Y", False), ("N", True)):
        mean, _ = arm_curve(day.captive, r_prime, 0.0, 90.0, eq, moment, day.captive.runs[0])
        scale = float(np.max(np.abs(arm[eq])))
        assert np.max(np.abs(mean - arm[eq].to_numpy(dtype=float))) < 0.02 * scale, eq

    text = protocol.read_text(encoding="utf-8").replace('moment_ref = "balance"',
                                                        'moment_ref = "origin"')
    protocol.write_text(text, encoding="utf-8")
    about_o = towtank.process_day(protocol, out=tmp_path / "out_o", report=False, jobs=1)
    assert about_o.captive.ref_x_m == 0.0 and about_o.captive.moment_point() == "about O"
    d, est = truth["derivatives"], about_o.captive.estimates
    assert est["Y_uv"].value == pytest.approx(d["Y_uv"], rel=TOL)
    assert est["N_uv"].value == pytest.approx(d["N_uv"] + x_b * d["Y_uv"], rel=TOL)
    assert est["Y_ur"].value == pytest.approx(d["Y_ur"] + x_b * d["Y_uv"], rel=TOL)
    assert abs(est["N_uv"].value - d["N_uv"]) > 10 * est["N_uv"].std_error


# ==================================================================== the real KVLCC2 table

@pytest.mark.skipif(not KVLCC2.is_file(), reason="the real KVLCC2 means are not here")
def test_real_kvlcc2_means_through_a_means_only_protocol(tmp_path):
    """The 63 runs of the HMRI KVLCC2 table: Y_uv < 0 (Y' > 0 at beta > 0 with
    v = -U sin beta), N_uv < 0, Y_uudr > 0, N_uudr < 0; the rotary and acceleration
    derivatives not determined, said as the day's warning."""
    protocol = tmp_path / "kvlcc2.toml"
    protocol.write_text(
        '[campaign]\nname = "KVLCC2 HMRI captive"\noutput_dir = "out"\n'
        "[water]\ntemperature_C = 15.0\n"
        "[model]\nlength_m = 6.8279\ndiameter_m = 1.249\nmass_kg = 3123.0\n"
        "balance_x_m = 0.0\ndraught_m = 0.448\n"
        f'[captive]\nmeans = "{KVLCC2}"\nmeans_prime = true\n', encoding="utf-8")
    day = towtank.process_day(protocol, jobs=1)
    fit = day.captive
    assert len(fit.runs) == 63
    # the day's count names the table's runs (it printed "0 runs, 0 ok, 0 rejected, 0 void")
    assert summary(day, tmp_path).splitlines()[0] == (
        "KVLCC2 HMRI captive: 0 runs, 0 ok, 0 rejected, 0 void, and 63 runs from the table "
        "of means captive.csv")
    est = fit.estimates
    assert est["Y_uv"].value < 0 and est["N_uv"].value < 0
    assert est["Y_uudr"].value > 0 and est["N_uudr"].value < 0
    for s in ("Y_ur", "N_ur", "Y_vdot", "N_rdot"):
        assert s not in est
    said = next(w for w in fit.warnings if "not determined" in w)
    assert "Y_ur" in said and "Y_vdot" in said
    assert "no yaw-rate runs" in said and "no PMM runs" in said
    assert said in [str(w) for w in day.warnings]


def test_a_captive_file_without_fx_is_rejected_for_its_missing_fx(tmp_path):
    """A pure-sway file recorded with fy, mz, sway and yaw but no fx: the run is rejected
    with the sentence that names the missing fx (not "drag channel shows no signal: it reads
    0", a channel the file never had), and the other 13 runs are processed."""
    make_captive_day(tmp_path, plan=small_plan()[:14], seed=4)
    path = tmp_path / "data" / "run_011.csv"
    lines = path.read_text(encoding="utf-8").splitlines()
    cells = [ln.split(",") for ln in lines]
    col = cells[0].index("fx")
    path.write_text("\n".join(",".join(c[:col] + c[col + 1:]) for c in cells) + "\n",
                    encoding="utf-8")
    day = towtank.process_day(tmp_path / "protocol.toml", out=tmp_path / "out", report=False,
                              jobs=1)
    assert set(day.rejected) == {11}
    reason = day.rejected[11].reason
    assert "no fx channel" in reason and "no signal" not in reason, reason
    assert len(day.captive.runs) == 13
    # the notebook's one-run reader and reducer (docs/api.md): the same sentence for run 11,
    # the day's loads for a drift, an arm and a PMM run
    protocol = tmp_path / "protocol.toml"
    with pytest.raises(RunError) as caught:
        towtank.read_run(path, protocol)
    assert caught.value.reason.endswith(reason) and caught.value.kind == "missing_channel"
    by_run = {r.run: r for r in day.captive.runs}
    for run in (1, 8, 12):
        file = tmp_path / "data" / f"run_{run:03d}.csv"
        raw = towtank.read_run(file, protocol)
        assert {"fx", "fy", "mz"} <= set(raw.extra)
        red = towtank.reduce_run(raw, protocol, run=run)
        rows = CaptiveRun.from_arrays(run, file.name, red.captive).rows
        pd.testing.assert_frame_equal(rows, by_run[run].rows)
    with pytest.raises(ValueError, match="run sheet's row"):
        towtank.reduce_run(raw, protocol, test="sway")
