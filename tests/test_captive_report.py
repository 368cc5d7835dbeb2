"""What users see of a captive day: the PDF's captive pages, the workbook's Captive and PMM
sheets, the run table, ``inspect``, ``watch`` and ``--export simman`` (issue #35 items 8, 9).

One generated captive day is processed once (module fixture) and every test reads it.
"""

from __future__ import annotations

import math
import shutil
import subprocess

import numpy as np
import pandas as pd
import pytest
from conftest import draw_only_pages

from towtank.testing.captive import captive_day_plan, make_captive_day


@pytest.fixture(scope="session")
def captive_day(tmp_path_factory):
    """A generated horizontal captive day processed with its reports: (DayResult, out). Of the
    PDF only the pages the tests read are drawn (the captive pages and the runs' table; the
    others are blank pages), and no PNG figure is written (none is read)."""
    from towtank.api import process_day
    from towtank.report import figures

    folder = tmp_path_factory.mktemp("captive_day")
    make_captive_day(folder, seed=3)
    out = folder / "out"
    with pytest.MonkeyPatch.context() as mp:
        draw_only_pages(mp, lambda page: page.section.startswith("Captive")
                        or page.kind == "runs")
        mp.setattr(figures, "write_figures", lambda day, folder: [])
        day = process_day(folder / "protocol.toml", out, jobs=2)
    return day, out


@pytest.fixture(scope="session")
def vertical_day(tmp_path_factory):
    """A small vertical-plane captive day (drift, arm and PMM runs), processed without files."""
    from towtank.api import process_day

    folder = tmp_path_factory.mktemp("captive_vertical")
    plan = [s for s in captive_day_plan() if s.test in ("drift", "arm", "sway", "yaw")]
    make_captive_day(folder, seed=4, plane="vertical", plan=plan)
    return process_day(folder / "protocol.toml", jobs=2)


# ------------------------------------------------------------------------------ the PDF
@pytest.mark.heavy
def test_pdf_has_a_captive_section_with_table_and_figure(captive_day):
    from towtank.report.pdf import page_plan

    day, _ = captive_day
    plan = page_plan(day)
    captive = [p for p in plan if p.section == "Captive"]
    assert [p.kind for p in captive] == ["captive", "figure"]
    assert captive[1].payload[0] == "captive"


@pytest.mark.heavy
def test_captive_pages_drawn_in_the_pdf(captive_day):
    from pypdf import PdfReader

    day, out = captive_day
    text = [p.extract_text() for p in PdfReader(out / "report.pdf").pages]
    table = next(t for t in text if "derivative" in t and "95 % interval" in t)
    assert "Reduced chi^2" in table
    assert "agree" in table  # the fit's agreement lines over omega'
    assert any("Static drift" in t and "Rotating arm" in t and "PMM run" in t for t in text)
    runs = next(t for t in text if "X or drag [N]" in t)
    y = float(day.runs.loc[day.runs["run"] == 1, "captive_Y_N"].iloc[0])
    assert f"{y:.4g}".replace("-", "\u2212") in runs


def test_drift_curve_goes_through_the_drift_runs(captive_day):
    from towtank.report.captive_figure import drift_curve, static_points

    day, _ = captive_day
    fit = day.captive
    pts = static_points(fit, ("drift",), 90.0)
    assert len(pts) == 9
    for eq, moment in (("Y", False), ("N", True)):
        mean, half = drift_curve(fit, pts["drift_deg"].to_numpy(float), 90.0, eq, moment,
                                 fit.runs[0])
        scale = np.max(np.abs(pts[eq]))
        assert np.all(np.abs(mean - pts[eq]) < 0.02 * scale)
        assert np.all(np.isfinite(half)) and np.all(half > 0)


def test_pmm_prediction_follows_the_cycle_averaged_loads(captive_day):
    from towtank.report.captive_figure import pmm_prediction, shown_pmm_run

    day, _ = captive_day
    fit = day.captive
    run = shown_pmm_run(fit)
    assert run is not None and run.cycles_used >= 3
    rows, pred = pmm_prediction(fit, run, 90.0)
    for eq in ("Y", "N"):
        measured = rows[eq].to_numpy(float)
        rms = math.sqrt(np.mean((pred[eq][0] - measured) ** 2))
        assert rms < 0.05 * np.max(np.abs(measured))


@pytest.mark.heavy
def test_vertical_day_gets_its_captive_page(vertical_day):
    from towtank.report.captive_figure import fig_captive
    from towtank.report.pdf import _draw_captive, _page, page_plan

    plan = page_plan(vertical_day)
    pages = [p for p in plan if p.section == "Captive, vertical plane"]
    assert [p.kind for p in pages] == ["captive", "figure"]
    fig = _page()
    _draw_captive(fig, vertical_day.captive_vertical)
    texts = " ".join(t.get_text() for t in fig.texts)
    assert "vertical plane (Z, M)" in texts
    assert fig_captive(vertical_day.captive_vertical, page=True) is not None


# -------------------------------------------------------------------------- the workbook
def test_workbook_has_captive_and_pmm_sheets(captive_day):
    from openpyxl import load_workbook

    day, out = captive_day
    wb = load_workbook(out / "report.xlsx")
    assert {"Captive", "PMM"} <= set(wb.sheetnames)
    ws = wb["Captive"]
    cells = {ws.cell(r, 1).value: ws.cell(r, 2).value for r in range(1, ws.max_row + 1)}
    coef = day.coefficients.set_index("symbol")
    assert cells["Y_uv"] == coef.at["Y_uv", "value"]
    assert cells["N_rdot"] == coef.at["N_rdot", "value"]
    pmm = wb["PMM"]
    assert pmm.cell(1, 1).value == "run"
    runs = [pmm.cell(r, 1).value for r in range(2, pmm.max_row + 1)]
    assert [r for r in runs if isinstance(r, int)] == day.pmm["run"].tolist()
    for sheet in ("Captive", "PMM"):
        for row in wb[sheet].iter_rows():
            assert all(c.data_type != "f" for c in row)


def test_captive_sheet_text_is_never_a_formula(captive_day, tmp_path):
    from dataclasses import replace

    from openpyxl import load_workbook

    from towtank.report.workbook import write_workbook

    day, _ = captive_day
    evil = replace(day.captive, notes=("=HYPERLINK(\"http://x\",\"y\")", "+1+2"))
    write_workbook(replace(day, captive=evil), tmp_path)
    ws = load_workbook(tmp_path / "report.xlsx")["Captive"]
    values = [c for row in ws.iter_rows() for c in row if c.value is not None]
    texts = {c.value: c.data_type for c in values}
    assert texts["=HYPERLINK(\"http://x\",\"y\")"] == "s"
    assert texts["+1+2"] == "s"


@pytest.mark.skipif(shutil.which("soffice") is None, reason="LibreOffice not installed")
def test_libreoffice_opens_the_captive_workbook(captive_day, tmp_path):
    day, out = captive_day
    book = tmp_path / "report.xlsx"
    shutil.copy(out / "report.xlsx", book)
    every_sheet = "csv:Text - txt - csv (StarCalc):44,34,76,1,,0,false,true,false,false,false,-1"
    subprocess.run(["soffice", "--headless", f"-env:UserInstallation=file://{tmp_path}/lo",
                    "--convert-to", every_sheet, "--outdir", str(tmp_path), str(book)],
                   check=True, capture_output=True, timeout=180)
    captive = pd.read_csv(tmp_path / "report-Captive.csv", skiprows=1)
    got = captive.dropna(subset=["value [SI]"]).set_index("symbol")["value [SI]"]
    coef = day.coefficients.set_index("symbol")["value"]
    assert got.loc["Y_uv"] == pytest.approx(coef.loc["Y_uv"], rel=1e-12)
    pmm = pd.read_csv(tmp_path / "report-PMM.csv")
    runs = pd.to_numeric(pmm["run"], errors="coerce").dropna().astype(int).tolist()
    assert runs == day.pmm["run"].tolist()


def test_hull_day_has_no_captive_sheets_or_pages(captive_day):
    from dataclasses import replace

    from towtank.report.pdf import page_plan
    from towtank.report.workbook import sheet_names

    day, _ = captive_day
    plain = replace(day, captive=None, captive_vertical=None)
    assert "Captive" not in sheet_names(plain) and "PMM" not in sheet_names(plain)
    assert not [p for p in page_plan(plain) if p.section.startswith("Captive")]


# ------------------------------------------------------------------------ --export simman
@pytest.fixture(scope="session")
def simman(captive_day, tmp_path_factory):
    """The captive day written with ``--export simman`` only: its export/simman folder."""
    from towtank.report import write_outputs

    day, _ = captive_day
    out = tmp_path_factory.mktemp("simman") / "out"
    write_outputs(day, out, report=False, export=("simman",))
    return day, out / "export" / "simman"


def test_simman_export_writes_static_means_periods_and_particulars(simman):
    day, folder = simman
    static = pd.read_csv(folder / "static.csv")
    statics = day.runs[day.runs["test"].isin(["drift", "rudder", "arm"])]
    assert static["run"].tolist() == statics["run"].tolist()
    merged = static.merge(day.runs, on="run")
    assert np.allclose(merged["Y"], merged["captive_Y_N"], rtol=1e-12)
    assert np.allclose(merged["N"], merged["captive_N_Nm"], rtol=1e-12)
    part = pd.read_csv(folder / "particulars.csv").set_index("quantity")["value"]
    model = day.protocol.model
    assert part["length_m"] == model.length_m and part["izz_kg_m2"] == model.izz_kg_m2
    assert part["sample_rate_hz"] == pytest.approx(100.0, rel=1e-9)
    assert part["water_temperature_C"] == pytest.approx(18.0)
    pmm_runs = day.pmm["run"].tolist()
    assert sorted(p.name for p in folder.glob("pmm_run_*.csv")) == [
        f"pmm_run_{r:03d}.csv" for r in pmm_runs]


def test_simman_period_and_fourier_agree_with_the_pmm_harmonics(simman):
    day, folder = simman
    run = int(day.pmm["run"].iloc[0])
    period = pd.read_csv(folder / f"pmm_run_{run:03d}.csv")
    assert list(period.columns) == ["t", "X", "Y", "N", "x", "y", "psi", "u", "v", "r",
                                    "udot", "vdot", "rdot"]
    f = float(day.pmm["frequency_hz"].iloc[0])
    assert period["t"].iloc[-1] < 1.0 / f <= period["t"].iloc[-1] + 2.0 / len(period) / f
    fourier = pd.read_csv(folder / "pmm_fourier.csv")
    y = fourier[(fourier["run"] == run) & (fourier["quantity"] == "Y")].iloc[0]
    row = day.pmm.iloc[0]
    # the period's first harmonic is the cycles' mean first harmonic (phase bins blur it
    # by sinc(pi/72), 0.03 %)
    assert y["sin1"] == pytest.approx(row["fy_in"], rel=2e-3)
    assert y["cos1"] == pytest.approx(row["fy_quad"], rel=2e-3)
    assert y["cycle_sin"] == row["fy_in"] and y["cycle_cos_se"] == row["fy_quad_se"]


def test_simman_export_of_a_day_without_captive_runs_says_so(captive_day, tmp_path):
    from dataclasses import replace

    from towtank.report.simman import write_simman

    day, _ = captive_day
    said = write_simman(replace(day, captive=None, captive_vertical=None), tmp_path)
    assert said and "no captive results" in said[0]
    assert not (tmp_path / "export").exists()


def test_cli_accepts_export_simman():
    from towtank.commands.cli import _parser

    args = _parser().parse_args(["process", "p.toml", "--export", "simman"])
    assert args.export == ["simman"]
